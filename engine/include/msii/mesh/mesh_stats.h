#pragma once
/// @file mesh_stats.h
/// @brief Size and resolution of a mesh: bounding box, edge lengths, area. Used to suggest
/// a radius, to choose voxel sizes and for the sidecar record.

#include <msii/mesh/trimesh.h>

namespace msii {

struct MeshStats {
    std::size_t numVertices = 0, numTriangles = 0;
    Vec3 bboxMin, bboxMax;           ///< axis-aligned bounding box
    double diagonal = 0;             ///< bounding box diagonal
    double minEdge = 0, medianEdge = 0, meanEdge = 0, maxEdge = 0; ///< over unique... all face edges
    double area = 0;                 ///< total surface area
};

/// Computes the statistics (parallel, deterministic). Non-finite points are skipped.
MeshStats computeMeshStats(const TriMesh& mesh);

} // namespace msii
