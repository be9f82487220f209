#include "patch_line_samples.h"

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace msii::detail {

std::size_t totalSize(const SampleParts& parts)
{
    std::size_t total = 0;
    for (const auto& part : parts) total += part.size();
    return total;
}

SampleParts finestSamples(const TriMesh& mesh, double h0, int coarsestLevel)
{
    const std::size_t nt = mesh.numTriangles();
    std::vector<std::uint64_t> first(nt + 1, 0);
    std::vector<int> sides(nt);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            sides[t] = piecesPerSide({mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]}, h0);
            if (sides[t] > 0x7fff) throw InvalidInputError("a triangle is too large for the sample cells");
        }
    });
    for (std::size_t t = 0; t < nt; ++t) first[t + 1] = first[t] + std::uint64_t(sides[t]) * sides[t];

    std::vector<Piece> pieces(first[nt]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            const std::array<Vec3, 3> v{mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]};
            const int m = sides[t];
            std::uint64_t k = first[t];
            for (int i = 0; i < m; ++i)
                for (int j = 0; i + j < m; ++j)
                    for (int down = 0; down < 2; ++down) {
                        if (down && i + j > m - 2) continue;
                        const std::uint32_t sub = std::uint32_t(i) << 16 | std::uint32_t(j) << 1 | std::uint32_t(down);
                        const auto c = pieceCorners(v, m, sub);
                        const CellCoord cell = cellOf((c[0] + c[1] + c[2]) / 3.0, h0);
                        pieces[k++] = {morton(std::uint64_t(cell.x), std::uint64_t(cell.y), std::uint64_t(cell.z)),
                                       std::uint32_t(t), sub};
                    }
        }
    });
    tbb::parallel_sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) {
        return a.key != b.key ? a.key < b.key : a.triangle != b.triangle ? a.triangle < b.triangle : a.sub < b.sub;
    });

    // One sample per run of equal keys; chunks aligned to runs (of coarsest cells) keep the
    // sums deterministic.
    const int alignBits = 3 * coarsestLevel;
    const auto chunks =
        runAlignedChunks(pieces.size(), 256, [&](std::size_t i) { return pieces[i].key >> alignBits; });
    SampleParts parts(chunks.size() - 1);
    tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
        auto& out = parts[c];
        for (std::size_t i = chunks[c]; i < chunks[c + 1]; ++i) {
            const Piece& p = pieces[i];
            const auto& tri = mesh.triangles[p.triangle];
            const std::array<Vec3, 3> v{mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]};
            const int m = sides[p.triangle];
            const auto c3 = pieceCorners(v, m, p.sub);
            const Vec3 normalArea = cross(v[1] - v[0], v[2] - v[0]) * (0.5 / (double(m) * m));
            const double a = norm(normalArea);
            const Vec3 nrm = a > 0 ? normalArea / a : Vec3();
            const Vec3 centroid = (c3[0] + c3[1] + c3[2]) / 3.0;
            if (out.empty() || out.back().key != p.key) out.push_back(SampleSums{p.key, 0, {}, {}, {}, centroid});
            // ∫ (x − o)(x − o)ᵀ dA over the piece: a (v vᵀ + Σ_k e_k e_kᵀ / 12), v = c − o,
            // e_k = corner k − c.
            const Vec3 offset = centroid - out.back().origin;
            std::array<double, 6> second = outer(offset, offset);
            for (const Vec3& corner : c3) {
                const auto ee = outer(corner - centroid, corner - centroid);
                for (std::size_t q = 0; q < 6; ++q) second[q] += ee[q] / 12.0;
            }
            SampleSums& s = out.back();
            s.area += a;
            s.moment += centroid * a;
            const auto nn = outer(nrm, nrm);
            for (std::size_t q = 0; q < 6; ++q) {
                s.normalTensor[q] += a * nn[q];
                s.secondMoment[q] += a * second[q];
            }
        }
    });
    return parts;
}

SampleParts coarser(const SampleParts& fine)
{
    SampleParts coarse(fine.size());
    tbb::parallel_for(std::size_t(0), fine.size(), [&](std::size_t c) {
        auto& out = coarse[c];
        std::size_t count = 0;  // parents, to allocate once
        for (std::size_t i = 0; i < fine[c].size(); ++i)
            count += i == 0 || (fine[c][i].key >> 3) != (fine[c][i - 1].key >> 3);
        out.reserve(count);
        for (const SampleSums& s : fine[c]) {
            const std::uint64_t key = s.key >> 3;
            if (out.empty() || out.back().key != key) out.push_back(SampleSums{key, 0, {}, {}, {}, s.origin});
            SampleSums& to = out.back();
            addSecondMoment(to, s);
            to.area += s.area;
            to.moment += s.moment;
            for (std::size_t q = 0; q < 6; ++q) to.normalTensor[q] += s.normalTensor[q];
        }
    });
    return coarse;
}

Level makeLevel(const SampleParts& parts, double h0, int index)
{
    Level level;
    level.index = index;
    level.h = h0 * double(1 << index);
    std::vector<std::size_t> first(parts.size() + 1, 0);  // each part's first sample
    for (std::size_t c = 0; c < parts.size(); ++c) first[c + 1] = first[c] + parts[c].size();
    const std::size_t n = first.back();
    level.key.resize(n);
    level.cx.resize(n), level.cy.resize(n), level.cz.resize(n);
    level.area.resize(n);
    for (auto& t : level.tensor) t.resize(n);
    for (auto& t : level.covariance) t.resize(n);
    tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
        for (std::size_t k = 0; k < parts[c].size(); ++k) {
            const SampleSums& s = parts[c][k];
            const std::size_t i = first[c] + k;
            level.key[i] = s.key;
            const Vec3 m = s.area > 0 ? s.moment / s.area : Vec3();
            level.cx[i] = m.x, level.cy[i] = m.y, level.cz[i] = m.z;
            level.area[i] = float(s.area);
            const Vec3 v = m - s.origin;  // covariance = S/a − v vᵀ about the origin o
            const auto cc = outer(v, v);
            for (std::size_t q = 0; q < 6; ++q) {
                level.tensor[q][i] = s.area > 0 ? float(s.normalTensor[q] / s.area) : 0.0f;
                level.covariance[q][i] = s.area > 0 ? float(s.secondMoment[q] / s.area - cc[q]) : 0.0f;
            }
        }
    });
    for (std::size_t i = 0; i < n;) {
        std::size_t e = i;
        while (e < n && (level.key[e] >> 9) == (level.key[i] >> 9)) ++e;
        level.blocks.emplace(level.key[i] >> 9, std::make_pair(std::uint32_t(i), std::uint32_t(e)));
        i = e;
    }
    return level;
}

} // namespace msii::detail
