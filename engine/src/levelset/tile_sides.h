#pragma once
// Private to the engine: the side (inside/outside) of the space off the narrow band.
#include <openvdb/openvdb.h>

namespace msii::detail {

/// Gives every leaf-sized block of @p tree inside @p voxelBox that is not a leaf node the
/// side of its nearest band, as a tile of value @p outside (positive side) or @p inside.
///
/// OpenVDB's signed flood fill infers the side of tiles by scanning along the index axes,
/// which assumes a closed surface: next to an open, tilted sheet (a rotated one-sided scan)
/// it puts whole tiles below the sheet "outside". Here the side spreads instead from the
/// faces of the band's leaf nodes, breadth first over blocks, so each tile takes the side of
/// the band region it is nearest to (in block steps), for closed and open surfaces alike.
/// Beyond the border of an open surface, where the two sides meet, the side is arbitrary;
/// results there are masked. Deterministic (serial). Leaf nodes are left as they are.
void fillTileSides(openvdb::FloatTree& tree, const openvdb::CoordBBox& voxelBox, float outside,
                   float inside, const openvdb::MaskTree* guessed = nullptr);

/// Gives every inactive voxel of every leaf node of @p tree the side (sign, with magnitude
/// @p magnitude) of the nearest active voxel of its leaf, in steps between face neighbours
/// (breadth first; ties go to the first found, in a fixed order).
///
/// OpenVDB's signed flood fill scans each leaf along its axes instead, which assumes that
/// the band separates the two sides everywhere: next to an open border, where the surface
/// ends, its scan lines wrap around the border and can mark voxels above the surface as
/// inside (how depends on the grid's orientation). The nearest band voxel lies next to the
/// nearest surface point, so its side is the right one there. Deterministic.
void fillLeafSides(openvdb::FloatTree& tree, float magnitude);

} // namespace msii::detail
