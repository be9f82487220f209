#include <msii/mesh/border_distance.h>

#include <msii/mesh/mesh_stats.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <unordered_map>
#include <vector>

namespace msii {

namespace {

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
    struct Cell {
        std::vector<std::uint32_t> edges;
        BoundingBox box;  // of the edges (tighter than the cell)
    };
    std::unordered_map<std::uint64_t, Cell> grid;
    for (std::size_t e = 0; e < borderEdges.size(); ++e) {
        const Vec3& a = mesh.points[borderEdges[e][0]];
        const Vec3& b = mesh.points[borderEdges[e][1]];
        for (auto x = cellOf(std::min(a.x, b.x)); x <= cellOf(std::max(a.x, b.x)); ++x)
            for (auto y = cellOf(std::min(a.y, b.y)); y <= cellOf(std::max(a.y, b.y)); ++y)
                for (auto z = cellOf(std::min(a.z, b.z)); z <= cellOf(std::max(a.z, b.z)); ++z) {
                    Cell& c = grid[cellKey(x, y, z)];
                    c.edges.push_back(std::uint32_t(e));
                    c.box.add(a);
                    c.box.add(b);
                }
    }
    // Per vertex: its own cell first, then the neighbours whose edges' box is nearer than
    // the nearest edge so far; squared distances, one square root at the end (the same value).
    std::vector<std::array<std::int64_t, 3>> order;  // the 27 cells, fewest offset axes first
    for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
            for (std::int64_t dz = -1; dz <= 1; ++dz) order.push_back({dx, dy, dz});
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
        return std::abs(a[0]) + std::abs(a[1]) + std::abs(a[2]) < std::abs(b[0]) + std::abs(b[1]) + std::abs(b[2]);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.numVertices()), [&](const auto& r) {
        // The 27 cells' edge lists, looked up once per run of vertices in the same cell
        // (neighbouring indices mostly are; most cells have no border edge near them).
        std::array<const Cell*, 27> lists{};
        std::int64_t listed[3] = {0, 0, 0};
        bool any = false, valid = false;
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3& p = mesh.points[i];
            const std::int64_t c[3] = {cellOf(p.x), cellOf(p.y), cellOf(p.z)};
            if (!valid || c[0] != listed[0] || c[1] != listed[1] || c[2] != listed[2]) {
                any = false;
                for (std::size_t k = 0; k < order.size(); ++k) {
                    const auto& o = order[k];
                    const auto it = grid.find(cellKey(c[0] + o[0], c[1] + o[1], c[2] + o[2]));
                    lists[k] = it == grid.end() ? nullptr : &it->second;
                    any = any || lists[k];
                }
                std::copy(c, c + 3, listed);
                valid = true;
            }
            if (!any) continue;  // result[i] = cap
            double best2 = cap * cap;
            for (std::size_t k = 0; k < order.size(); ++k) {
                if (!lists[k]) continue;
                const Cell& near = *lists[k];
                if (near.box.squaredDistance(p) >= best2) continue;
                for (auto e : near.edges)
                    best2 = std::min(best2, pointSegmentDistance2(p, mesh.points[borderEdges[e][0]],
                                                                  mesh.points[borderEdges[e][1]]));
            }
            result[i] = std::min(cap, std::sqrt(best2));
        }
    });
    return result;
}

} // namespace msii
