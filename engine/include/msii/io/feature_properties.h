#pragma once
/// @file feature_properties.h
/// @brief The per-vertex features of `msii compute` as named output properties, the same
/// for every writer: V_01 … V_NN, then S_01 … S_NN (radius ascending, r_j = j·R/N), then
/// `quality` = V_NN (the volume fraction at the largest radius). NaN marks a masked value.

#include <msii/invariants/volume_sphere.h>
#include <msii/mesh/trimesh.h>

#include <vector>

namespace msii {

/// Copies the features of @p invariants into properties (S only if it was computed).
std::vector<VertexProperty> featureProperties(const VolumeSphereResult& invariants);

} // namespace msii
