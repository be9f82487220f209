#pragma once
// Private to the engine: the OpenVDB grid behind msii::LevelSet.
#include <msii/levelset/levelset.h>

#include "mesh_distance.h"

#include <openvdb/openvdb.h>

#include <memory>

namespace msii {

struct LevelSet::Impl {
    openvdb::FloatGrid::Ptr grid;  ///< world distance values, voxel (i,j,k) centred at (i,j,k)*h
    LevelSetInfo info;
    std::shared_ptr<const detail::MeshDistance> distance;  ///< exact distances off the band
    /// Band voxels beyond an open border (closest feature on the border): side is a guess.
    std::shared_ptr<const openvdb::MaskTree> guessedSide;
};

} // namespace msii
