#pragma once
// Private to the engine: the narrow band of exact signed distances, rasterised from the mesh.
#include "mesh_distance.h"

#include <openvdb/openvdb.h>

#include <array>
#include <cstdint>

namespace msii::detail {

struct BandOptions {
    double voxelSize = 0;  ///< h, in mesh units
    /// Voxel (i, j, k)'s centre lies at (i, j, k) + originIndex times h: positions are
    /// computed from the whole (global) index, so a part of a mesh with another shift gets
    /// bit-identical distances.
    std::array<std::int64_t, 3> originIndex{};
    double halfWidth = 2;  ///< voxels closer to the mesh than halfWidth·h form the band
};

struct Band {
    /// Band voxels: active, exact signed distance (world units, negative inside). Other
    /// voxels of the leaves are inactive at +halfWidth·h (no side yet; see levelset.cpp).
    openvdb::FloatTree::Ptr distance;
    /// Band voxels beyond an open border (closest feature on the border, to the side of it):
    /// their sign is a guess.
    openvdb::MaskTree::Ptr guessedSide;
};

/// Every voxel centre closer than halfWidth·h to the mesh gets its exact distance and the
/// sign of its closest feature's pseudo-normal.
///
/// Triangles are binned to the 8³ blocks their band reaches. In each block, a branch-free
/// approximate distance, eight voxels of a row at once, keeps for every voxel the triangles
/// within rounding of its least; those alone then get the exact distance, in ascending face
/// order, and the closest wins (ties keep the lowest face index), as if every triangle had
/// been tried. So every voxel is exact whatever the shape, the cost is proportional to the
/// band's size, and the result depends neither on the number of threads nor on the
/// processor's vector width.
Band rasterizeBand(const TriMesh& mesh, const MeshDistance& distance, const BandOptions& options);

} // namespace msii::detail
