#include <msii/mesh/mesh_stats.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace msii {

namespace {

/// Work is split into blocks of this many items whatever the thread count, and partial
/// results are combined in block order: the sums do not depend on scheduling.
constexpr std::size_t kBlock = 1 << 14;

bool isFinite(const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

struct BlockSums {
    Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
    Vec3 hi = -lo;
    double edgeSum = 0, area = 0;
    std::size_t numEdges = 0;
};

} // namespace

MeshStats computeMeshStats(const TriMesh& mesh)
{
    MeshStats stats;
    stats.numVertices = mesh.numVertices();
    stats.numTriangles = mesh.numTriangles();
    const auto& points = mesh.points;
    const auto& triangles = mesh.triangles;

    // Bounding box over finite points.
    const std::size_t numPointBlocks = (points.size() + kBlock - 1) / kBlock;
    std::vector<BlockSums> pointBlocks(numPointBlocks);
    tbb::parallel_for(std::size_t(0), numPointBlocks, [&](std::size_t b) {
        BlockSums& sums = pointBlocks[b];
        const std::size_t end = std::min(points.size(), (b + 1) * kBlock);
        for (std::size_t i = b * kBlock; i < end; ++i) {
            const Vec3& p = points[i];
            if (!isFinite(p)) continue;
            for (int k = 0; k < 3; ++k) {
                sums.lo[k] = std::min(sums.lo[k], p[k]);
                sums.hi[k] = std::max(sums.hi[k], p[k]);
            }
        }
    });
    BlockSums box;
    for (const BlockSums& sums : pointBlocks) {
        for (int k = 0; k < 3; ++k) {
            box.lo[k] = std::min(box.lo[k], sums.lo[k]);
            box.hi[k] = std::max(box.hi[k], sums.hi[k]);
        }
    }
    if (box.lo.x <= box.hi.x) {
        stats.bboxMin = box.lo;
        stats.bboxMax = box.hi;
        stats.diagonal = norm(box.hi - box.lo);
    }

    // Edge lengths (every edge of every face, so interior edges count twice) and areas.
    // Edges with a non-finite or out-of-range end are left out, as are such faces' areas.
    std::vector<double> lengths(3 * triangles.size(), -1.0);
    const std::size_t numFaceBlocks = (triangles.size() + kBlock - 1) / kBlock;
    std::vector<BlockSums> faceBlocks(numFaceBlocks);
    tbb::parallel_for(std::size_t(0), numFaceBlocks, [&](std::size_t b) {
        BlockSums& sums = faceBlocks[b];
        const std::size_t end = std::min(triangles.size(), (b + 1) * kBlock);
        for (std::size_t f = b * kBlock; f < end; ++f) {
            const Triangle& t = triangles[f];
            bool valid[3];
            for (int k = 0; k < 3; ++k) valid[k] = t[k] < points.size() && isFinite(points[t[k]]);
            for (int k = 0; k < 3; ++k) {
                const int l = (k + 1) % 3;
                if (!valid[k] || !valid[l]) continue;
                const double length = norm(points[t[l]] - points[t[k]]);
                lengths[3 * f + std::size_t(k)] = length;
                sums.edgeSum += length;
                ++sums.numEdges;
            }
            if (valid[0] && valid[1] && valid[2]) {
                const Vec3& a = points[t[0]];
                sums.area += 0.5 * norm(cross(points[t[1]] - a, points[t[2]] - a));
            }
        }
    });
    double edgeSum = 0, area = 0;
    std::size_t numEdges = 0;
    for (const BlockSums& sums : faceBlocks) {
        edgeSum += sums.edgeSum;
        area += sums.area;
        numEdges += sums.numEdges;
    }
    stats.area = area;
    if (numEdges == 0) return stats;

    // Drop the skipped edges (marked -1), then min, max and median.
    if (numEdges != lengths.size())
        lengths.erase(std::remove(lengths.begin(), lengths.end(), -1.0), lengths.end());
    const auto [minIt, maxIt] = std::minmax_element(lengths.begin(), lengths.end());
    stats.minEdge = *minIt;
    stats.maxEdge = *maxIt;
    stats.meanEdge = edgeSum / double(numEdges);
    const auto middle = lengths.begin() + std::ptrdiff_t(lengths.size() / 2);
    std::nth_element(lengths.begin(), middle, lengths.end());
    stats.medianEdge = *middle;
    return stats;
}

} // namespace msii
