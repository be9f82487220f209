#include "patch_line_samples.h"

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
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

namespace {

/// Adds a sliver's part of area @p a, centroid @p centroid, normal @p nrm and second moment
/// @p about its centroid to @p s: ∫ (x − o)(x − o)ᵀ dA = about + a v vᵀ, v = centroid − o.
void add(SampleSums& s, double a, const Vec3& centroid, const Vec3& nrm, const std::array<double, 6>& about)
{
    const Vec3 offset = centroid - s.origin;
    const auto oo = outer(offset, offset);
    const auto nn = outer(nrm, nrm);
    s.area += a;
    s.moment += centroid * a;
    for (std::size_t q = 0; q < 6; ++q) {
        s.normalTensor[q] += a * nn[q];
        s.secondMoment[q] += about[q] + a * oo[q];
    }
}

double coordinate(const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }

/// A convex polygon: a triangle clipped by the six planes of a cell has at most 9 corners
/// (rounding can make a nearly flat one cross a plane more often: the rest is dropped).
struct Polygon {
    std::array<Vec3, 16> corner;
    int n = 0;
    void add(const Vec3& p)
    {
        if (n < int(corner.size())) corner[std::size_t(n++)] = p;
    }
};

/// The part of @p in with coordinate @p axis at least @p bound (@p above) or at most it
/// (Sutherland–Hodgman: one plane adds at most one corner).
Polygon clipped(const Polygon& in, int axis, double bound, bool above)
{
    Polygon out;
    for (int i = 0; i < in.n; ++i) {
        const Vec3& a = in.corner[std::size_t(i)];
        const Vec3& b = in.corner[std::size_t((i + 1) % in.n)];
        const double da = above ? coordinate(a, axis) - bound : bound - coordinate(a, axis);
        const double db = above ? coordinate(b, axis) - bound : bound - coordinate(b, axis);
        if (da >= 0) out.add(a);
        if ((da >= 0) != (db >= 0)) out.add(a + (b - a) * (da / (da - db)));
    }
    return out;
}

/// The part of a sliver in one cell: its area, centroid and ∫ (x − c)(x − c)ᵀ dA about the
/// centroid c (xx, yy, zz, xy, xz, yz).
struct CellPiece {
    std::uint64_t key;
    double area = 0;
    Vec3 centroid;
    std::array<double, 6> secondMoment{};
};

/// The area, centroid and second moment of the convex polygon @p poly, from its fan of
/// triangles (each: a (c cᵀ + Σ_k e_k e_kᵀ / 12) about the origin, e_k = corner k − c).
CellPiece polygonPiece(const Polygon& poly)
{
    CellPiece piece;
    std::array<double, 6> about0{};  // about corner 0, which keeps the digits
    for (int i = 1; i + 1 < poly.n; ++i) {
        const std::array<Vec3, 3> t{Vec3(), poly.corner[std::size_t(i)] - poly.corner[0],
                                    poly.corner[std::size_t(i + 1)] - poly.corner[0]};
        const double a = 0.5 * norm(cross(t[1], t[2]));
        const Vec3 c = (t[1] + t[2]) / 3.0;
        std::array<double, 6> second = outer(c, c);
        for (const Vec3& corner : t) {
            const auto ee = outer(corner - c, corner - c);
            for (std::size_t q = 0; q < 6; ++q) second[q] += ee[q] / 12.0;
        }
        for (std::size_t q = 0; q < 6; ++q) about0[q] += a * second[q];
        piece.area += a;
        piece.centroid += c * a;
    }
    if (!(piece.area > 0)) return piece;
    const Vec3 c = piece.centroid / piece.area;  // relative to corner 0
    const auto cc = outer(c, c);
    for (std::size_t q = 0; q < 6; ++q) piece.secondMoment[q] = about0[q] - piece.area * cc[q];
    piece.centroid = poly.corner[0] + c;
    return piece;
}

/// The parts of polygon @p poly in the cells of @p h0, cut along axis @p axis and those
/// after it (the cell's coordinates on the axes before it in @p cell), appended to @p out;
/// parts without area are left out.
void cutAlongCells(const Polygon& poly, int axis, std::array<std::int64_t, 3>& cell, double h0,
                   std::vector<CellPiece>& out)
{
    if (axis == 3) {
        CellPiece piece = polygonPiece(poly);
        piece.key = morton(std::uint64_t(cell[0]), std::uint64_t(cell[1]), std::uint64_t(cell[2]));
        if (piece.area > 0) out.push_back(piece);
        return;
    }
    double lo = coordinate(poly.corner[0], axis), hi = lo;
    for (int i = 1; i < poly.n; ++i)
        lo = std::min(lo, coordinate(poly.corner[std::size_t(i)], axis)), hi = std::max(hi, coordinate(poly.corner[std::size_t(i)], axis));
    const std::int64_t first = std::int64_t(std::floor(lo / h0)), last = std::int64_t(std::floor(hi / h0));
    for (std::int64_t k = first; k <= last; ++k) {
        const Polygon part = first == last ? poly : clipped(clipped(poly, axis, double(k) * h0, true), axis, double(k + 1) * h0, false);
        if (part.n < 3) continue;
        cell[std::size_t(axis)] = k + kOffset;
        cutAlongCells(part, axis + 1, cell, h0, out);
    }
}

/// Pieces per side of the m² congruent pieces of @p t, or 0 for a sliver (or a triangle too
/// large for the sub's 15 bits), which is cut along the cells instead: cut into m² pieces, a
/// needle of a DEM's spike (5 km long, 1 m wide) would give (5 km / h0)² pieces where the
/// ~2 · 5 km / h0 cells it crosses are enough (docs/limits.md, Memory rule).
int piecesPerSideOrSliver(const std::array<Vec3, 3>& t, double h0)
{
    const int m = piecesPerSide(t, h0);
    if (m <= 8) return m;  // 64 pieces or fewer: cut as they are
    const double area = 0.5 * norm(cross(t[1] - t[0], t[2] - t[0]));
    const double perimeter = norm(t[1] - t[0]) + norm(t[2] - t[1]) + norm(t[0] - t[2]);
    const double pieces = double(m) * m, cells = area / (h0 * h0) + perimeter / h0;
    return m > 0x7fff || pieces > 16 * cells ? 0 : m;
}

} // namespace

SampleParts finestSamples(const TriMesh& mesh, double h0, int coarsestLevel)
{
    const std::size_t nt = mesh.numTriangles();
    std::vector<std::uint64_t> first(nt + 1, 0);
    std::vector<int> sides(nt);
    const auto corners = [&](std::size_t t) {
        const auto& tri = mesh.triangles[t];
        return std::array<Vec3, 3>{mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]};
    };
    // sides[t]: m, or −(k + 1) for the k-th sliver.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) sides[t] = piecesPerSideOrSliver(corners(t), h0);
    });
    std::vector<std::uint32_t> slivers;
    for (std::size_t t = 0; t < nt; ++t)
        if (sides[t] == 0) {
            slivers.push_back(std::uint32_t(t));
            sides[t] = -int(slivers.size());
        }
    // Slivers are cut along the cells, each into its own list (in parallel); the pieces are
    // then numbered in the triangles' order, so that they do not depend on the threads.
    std::vector<std::vector<CellPiece>> sliverPieces(slivers.size());
    tbb::parallel_for(std::size_t(0), slivers.size(), [&](std::size_t k) {
        const std::array<Vec3, 3> v = corners(slivers[k]);
        Polygon poly;
        poly.corner = {v[0], v[1], v[2]};
        poly.n = 3;
        std::array<std::int64_t, 3> cell{};
        cutAlongCells(poly, 0, cell, h0, sliverPieces[k]);
    });
    for (std::size_t t = 0; t < nt; ++t) {
        const int m = sides[t];
        const std::size_t count = m > 0 ? std::size_t(m) * std::size_t(m) : sliverPieces[std::size_t(-m - 1)].size();
        if (m < 0 && count > 0xffffffffu) throw InvalidInputError("a triangle is too large for the sample cells");
        first[t + 1] = first[t] + count;
    }

    std::vector<Piece> pieces(first[nt]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            const int m = sides[t];
            std::uint64_t k = first[t];
            if (m < 0) {
                std::uint32_t c = 0;
                for (const CellPiece& piece : sliverPieces[std::size_t(-m - 1)]) pieces[k++] = {piece.key, std::uint32_t(t), c++};
                continue;
            }
            const std::array<Vec3, 3> v = corners(t);
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
    // By (key, triangle, sub), compared as one 128-bit number: no branches to mispredict.
    __extension__ typedef unsigned __int128 Rank;
    const auto rank = [](const Piece& p) {
        return Rank(p.key) << 64 | Rank(std::uint64_t(p.triangle) << 32 | std::uint64_t(p.sub));
    };
    tbb::parallel_sort(pieces.begin(), pieces.end(), [&](const Piece& a, const Piece& b) { return rank(a) < rank(b); });

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
            const int m = sides[p.triangle];
            if (m < 0) {  // a sliver's part in the cell: its sums, with the triangle's normal
                const CellPiece& piece = sliverPieces[std::size_t(-m - 1)][p.sub];
                const std::array<Vec3, 3> v = corners(p.triangle);
                const Vec3 nrm = normalized(cross(v[1] - v[0], v[2] - v[0]));
                if (out.empty() || out.back().key != p.key) out.push_back(SampleSums{p.key, 0, {}, {}, {}, piece.centroid});
                add(out.back(), piece.area, piece.centroid, nrm, piece.secondMoment);
                continue;
            }
            const std::array<Vec3, 3> v = corners(p.triangle);
            const auto c3 = pieceCorners(v, m, p.sub);
            const Vec3 normalArea = cross(v[1] - v[0], v[2] - v[0]) * (0.5 / (double(m) * m));
            const double a = norm(normalArea);
            const Vec3 nrm = a > 0 ? normalArea / a : Vec3();
            const Vec3 centroid = (c3[0] + c3[1] + c3[2]) / 3.0;
            if (out.empty() || out.back().key != p.key) out.push_back(SampleSums{p.key, 0, {}, {}, {}, centroid});
            // ∫ (x − o)(x − o)ᵀ dA over the piece: a (v vᵀ + Σ_k e_k e_kᵀ / 12), v = c − o,
            // e_k = corner k − c (what add() does, summed in this order to keep the bits).
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
