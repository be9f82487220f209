#include <msii/mesh/mesh_stats.h>

#include "blocks.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace msii {

BoundingBox boundingBox(const std::vector<Vec3>& points)
{
    std::vector<BoundingBox> blocks(detail::numBlocks(points.size()));
    detail::forEachBlock(points.size(), [&](std::size_t b, std::size_t begin, std::size_t end) {
        BoundingBox& box = blocks[b];
        for (std::size_t i = begin; i < end; ++i) {
            const Vec3& p = points[i];
            if (isFinite(p)) box.add(p);
        }
    });
    BoundingBox box;
    for (const BoundingBox& block : blocks)
        for (int k = 0; k < 3; ++k) {
            box.min[k] = std::min(box.min[k], block.min[k]);
            box.max[k] = std::max(box.max[k], block.max[k]);
        }
    return box;
}

MeshStats computeMeshStats(const TriMesh& mesh)
{
    MeshStats stats;
    stats.numVertices = mesh.numVertices();
    stats.numTriangles = mesh.numTriangles();
    const auto& points = mesh.points;
    const auto& triangles = mesh.triangles;

    const BoundingBox box = boundingBox(points);
    if (!box.empty()) {
        stats.bboxMin = box.min;
        stats.bboxMax = box.max;
        stats.diagonal = box.diagonal();
    }

    // Edge lengths (every edge of every face, so interior edges count twice) and areas.
    // Edges with a non-finite or out-of-range end are left out, as are such faces' areas.
    struct FaceSums {
        double edgeSum = 0, area = 0;
        std::size_t numEdges = 0;
    };
    std::vector<double> lengths(3 * triangles.size(), -1.0);
    std::vector<FaceSums> faceBlocks(detail::numBlocks(triangles.size()));
    detail::forEachBlock(triangles.size(), [&](std::size_t b, std::size_t begin, std::size_t end) {
        FaceSums& sums = faceBlocks[b];
        for (std::size_t f = begin; f < end; ++f) {
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
    for (const FaceSums& sums : faceBlocks) {
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
