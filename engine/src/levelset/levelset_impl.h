#pragma once
// Private to the engine: the OpenVDB grid behind msii::LevelSet.
#include <msii/levelset/levelset.h>

#include "mesh_distance.h"

#include <openvdb/openvdb.h>

#include <array>
#include <cstdint>
#include <memory>

namespace msii {

struct LevelSet::Impl {
    /// World distance values. Voxel (i,j,k) is centred at (i,j,k)·h plus a shift of whole
    /// 512-voxel blocks, so voxel centres lie at multiples of h in world coordinates.
    openvdb::FloatGrid::Ptr grid;
    /// The shift in voxels (a multiple of 512): voxel i's centre is at (i + shiftIndex) · h.
    /// Positions computed this way, rather than through the grid's transform, are the same
    /// in a tile and in the whole mesh.
    std::array<std::int64_t, 3> shiftIndex{};
    LevelSetInfo info;
    std::shared_ptr<const detail::MeshDistance> distance;  ///< exact distances off the band
    /// Band voxels beyond an open border (closest feature on the border): side is a guess.
    std::shared_ptr<const openvdb::MaskTree> guessedSide;
};

const LevelSet::Impl& levelSetImpl(const LevelSet& levelSet);

} // namespace msii
