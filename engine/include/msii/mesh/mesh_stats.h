#pragma once
/// @file mesh_stats.h
/// @brief Size and resolution of a mesh: bounding box, edge lengths, area. Used to suggest
/// a radius, to choose voxel sizes and for the sidecar record.

#include <msii/mesh/trimesh.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace msii {

struct MeshStats {
    std::size_t numVertices = 0, numTriangles = 0;
    Vec3 bboxMin, bboxMax;           ///< axis-aligned bounding box
    double diagonal = 0;             ///< bounding box diagonal
    /// Over every edge of every face (interior edges count twice); the median is the lower one.
    double minEdge = 0, medianEdge = 0, meanEdge = 0, maxEdge = 0;
    double area = 0;                 ///< total surface area
};

/// Computes the statistics (parallel, deterministic). Non-finite points are skipped.
MeshStats computeMeshStats(const TriMesh& mesh);

/// Axis-aligned bounding box of the finite points among @p points (parallel).
struct BoundingBox {
    Vec3 min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};  ///< +infinity while empty
    Vec3 max = -min;
    bool empty() const { return !(min.x <= max.x); }
    double diagonal() const { return empty() ? 0.0 : norm(max - min); }
    /// Grows the box to hold @p p.
    void add(const Vec3& p)
    {
        for (int k = 0; k < 3; ++k) {
            min[k] = std::min(min[k], p[k]);
            max[k] = std::max(max[k], p[k]);
        }
    }
    /// Squared distance from @p p to the box (0 inside it).
    double squaredDistance(const Vec3& p) const
    {
        const double dx = std::max({0.0, min.x - p.x, p.x - max.x}), dy = std::max({0.0, min.y - p.y, p.y - max.y}),
                     dz = std::max({0.0, min.z - p.z, p.z - max.z});
        return dx * dx + dy * dy + dz * dz;
    }
};
BoundingBox boundingBox(const std::vector<Vec3>& points);

} // namespace msii
