#pragma once
/// @file border_distance.h
/// @brief Euclidean distance from every vertex to the nearest border edge of an open mesh,
/// used to mask the radii whose ball reaches a border or a hole (docs/method.md, Border
/// masks).

#include <msii/mesh/trimesh.h>

#include <array>
#include <cstdint>
#include <vector>

namespace msii {

/// Distance of each vertex to the nearest border edge (segment), or @p cap if that is
/// farther (and for closed meshes). Uniform hash grid with cell size cap: O(V + B).
std::vector<double> borderDistance(const TriMesh& mesh,
                                   const std::vector<std::array<std::uint32_t, 2>>& borderEdges,
                                   double cap);

} // namespace msii
