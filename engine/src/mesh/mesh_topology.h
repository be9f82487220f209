#pragma once
// Private to the engine: the mesh topology that mesh preparation and hole filling share
// (connected parts, triangles around each vertex).
#include <msii/mesh/trimesh.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace msii::detail {

/// Root of @p v in a union-find forest (with path halving).
inline std::uint32_t findRoot(std::vector<std::uint32_t>& parent, std::uint32_t v)
{
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
}

/// Joins the sets of @p a and @p b; the smaller root stays the root, so every set's root is
/// its smallest member whatever the order of the joins.
inline void unite(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b)
{
    a = findRoot(parent, a), b = findRoot(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

/// For each vertex, the smallest vertex of its connected part (parts joined through
/// triangles, i.e. through shared vertices).
inline std::vector<std::uint32_t> vertexParts(const TriMesh& mesh)
{
    std::vector<std::uint32_t> part(mesh.numVertices());
    std::iota(part.begin(), part.end(), 0u);
    for (const Triangle& t : mesh.triangles) {
        unite(part, t[0], t[1]);
        unite(part, t[0], t[2]);
    }
    for (std::uint32_t v = 0; v < part.size(); ++v) part[v] = findRoot(part, v);
    return part;
}

/// The triangles around each vertex, in triangle order: triangles[offsets[v] ... offsets[v + 1]).
struct VertexTriangles {
    std::vector<std::uint32_t> offsets, triangles;
};

inline VertexTriangles vertexTriangles(const TriMesh& mesh)
{
    VertexTriangles vt;
    const std::size_t nv = mesh.numVertices();
    vt.offsets.assign(nv + 1, 0);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t v : t) ++vt.offsets[v + 1];
    for (std::size_t v = 0; v < nv; ++v) vt.offsets[v + 1] += vt.offsets[v];
    vt.triangles.resize(3 * mesh.numTriangles());
    std::vector<std::uint32_t> fill(vt.offsets.begin(), vt.offsets.end() - 1);
    for (std::size_t f = 0; f < mesh.numTriangles(); ++f)
        for (std::uint32_t v : mesh.triangles[f]) vt.triangles[fill[v]++] = std::uint32_t(f);
    return vt;
}

} // namespace msii::detail
