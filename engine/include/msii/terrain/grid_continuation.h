#pragma once
/// @file grid_continuation.h
/// @brief A DEM's heights made whole for the height-field kernel (terrain/height_field.h),
/// as mesh preparation and the skirt make a DEM's mesh whole for the level set
/// (docs/method.md, Height fields: holes and borders):
/// - a nodata gap whose border (its cell edges next to heights, half as long again for the
///   staircase) is at most the fill limit, and that does not reach the grid's edge, is filled
///   by the smoothest surface through its rim (the discrete biharmonic equation, Δ²z = 0, the
///   grid's form of the fairing of filled holes in meshes);
/// - past the grid's edge and the gaps left open, each cell within the margin takes, from
///   the nearest cell with a height b, the plane fitted to the heights within the fit radius
///   of b, plus half the relief of its mirror point through b over that plane: the tangent
///   plane and half the mirrored relief of the mesh's skirt.
/// Each filled or continued height depends only on the heights within the margin plus the
/// fit radius (the mirror point, the plane) or on its gap and the gap's rim, so that windows
/// that read that far agree with the whole raster, bit for bit.

#include <msii/terrain/height_field.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace msii {

struct GridContinuationOptions {
    double cellWidth = 1, cellHeight = 1;
    /// Gaps whose border is at most this long are filled (ground units); 0: none.
    double maxHolePerimeter = 0;
    /// Continue past the grid's edge and the gaps left open; false: they stay NaN.
    bool continueBorders = true;
    /// Cells added on every side of the grid; cells farther than this from every height are
    /// not continued.
    int margin = 0;
    double fitRadius = 0;  ///< ρ, ground units (at least the nearest neighbours are fitted)
};

/// What a cell of the continued grid holds.
enum class GridCell : std::uint8_t { Height = 0, Filled = 1, Continued = 2, None = 3 };

struct GridContinuationResult {
    /// The heights with the margin on every side: cell (c, r) of the input is (c + margin,
    /// r + margin) here; NaN where nothing was filled or continued.
    HeightGrid grid;
    std::vector<GridCell> kind;  ///< per cell of grid
    std::size_t gapsFilled = 0, cellsFilled = 0, cellsContinued = 0;
    double largestFilledPerimeter = 0;  ///< ground units
};

/// Fills the small gaps of @p heights and continues it past its edge and the gaps left open.
GridContinuationResult continueGrid(const HeightGrid& heights, const GridContinuationOptions& options);

} // namespace msii
