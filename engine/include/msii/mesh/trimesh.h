#pragma once
/// @file trimesh.h
/// @brief The plain triangle mesh every stage of msii works on: a vertex array and a
/// triangle array (indices into it), nothing else. Topology (borders, manifoldness,
/// orientation) is derived where needed (mesh/mesh_check.h), not stored.

#include <msii/core/vec3.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace msii {

using Triangle = std::array<std::uint32_t, 3>;

struct TriMesh {
    std::vector<Vec3> points;         ///< vertex positions, in the input's units (usually mm)
    std::vector<Triangle> triangles;  ///< counter-clockwise seen from outside (normal = right hand)

    std::size_t numVertices() const { return points.size(); }
    std::size_t numTriangles() const { return triangles.size(); }
    bool empty() const { return points.empty() || triangles.empty(); }
};

/// Per-vertex float properties that travel with a mesh through I/O (e.g. "V_01", "quality").
/// Values are stored column-wise: one vector of numVertices() floats per property.
struct VertexProperty {
    std::string name;
    std::vector<float> values;
    /// Whole numbers (labels, counts), written to PLY as `int`; read back as such from any
    /// PLY integer type. Values up to 2^24 are exact in float.
    bool integer = false;
};

} // namespace msii
