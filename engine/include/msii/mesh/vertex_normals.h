#pragma once
/// @file vertex_normals.h
/// @brief Unit vertex normals: the normalised sum of the incident triangles' vector areas
/// (area-weighted), as the P/L interpolation and the feature maps use them.

#include <msii/mesh/trimesh.h>

#include <vector>

namespace msii {

/// One unit normal per vertex; vertices without incident area (unreferenced, or only
/// degenerate faces) get @p whenNoArea.
std::vector<Vec3> vertexNormals(const TriMesh& mesh, const Vec3& whenNoArea = Vec3());

} // namespace msii
