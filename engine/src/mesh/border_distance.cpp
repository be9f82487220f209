#include <msii/mesh/border_distance.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace msii {

namespace {

double pointSegmentDistance(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 ab = b - a;
    const double len2 = squaredNorm(ab);
    const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    return norm(p - (a + ab * t));
}

std::uint64_t cellKey(std::int64_t x, std::int64_t y, std::int64_t z)
{
    const std::uint64_t m = (1u << 21) - 1;
    return (std::uint64_t(x) & m) << 42 | (std::uint64_t(y) & m) << 21 | (std::uint64_t(z) & m);
}

} // namespace

std::vector<double> borderDistance(const TriMesh& mesh,
                                   const std::vector<std::array<std::uint32_t, 2>>& borderEdges,
                                   double cap)
{
    std::vector<double> result(mesh.numVertices(), cap);
    if (borderEdges.empty() || !(cap > 0)) return result;

    // Each border edge goes into every cell its bounding box touches (cell size = cap), so
    // the 27 cells around a vertex hold every edge closer than cap.
    const double cell = cap;
    const auto cellOf = [&](double v) { return std::int64_t(std::floor(v / cell)); };
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
    for (std::size_t e = 0; e < borderEdges.size(); ++e) {
        const Vec3& a = mesh.points[borderEdges[e][0]];
        const Vec3& b = mesh.points[borderEdges[e][1]];
        for (auto x = cellOf(std::min(a.x, b.x)); x <= cellOf(std::max(a.x, b.x)); ++x)
            for (auto y = cellOf(std::min(a.y, b.y)); y <= cellOf(std::max(a.y, b.y)); ++y)
                for (auto z = cellOf(std::min(a.z, b.z)); z <= cellOf(std::max(a.z, b.z)); ++z)
                    grid[cellKey(x, y, z)].push_back(std::uint32_t(e));
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.numVertices()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3& p = mesh.points[i];
            const auto cx = cellOf(p.x), cy = cellOf(p.y), cz = cellOf(p.z);
            double best = cap;
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const auto it = grid.find(cellKey(cx + dx, cy + dy, cz + dz));
                        if (it == grid.end()) continue;
                        for (auto e : it->second)
                            best = std::min(best, pointSegmentDistance(
                                                      p, mesh.points[borderEdges[e][0]],
                                                      mesh.points[borderEdges[e][1]]));
                    }
            result[i] = best;
        }
    });
    return result;
}

} // namespace msii
