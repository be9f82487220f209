#pragma once
/// @file scales.h
/// @brief The nested radii of MSII (paper §3, Eq. 3 and 5): r_j = j·R/N, j = 1..N.

#include <vector>

namespace msii {

/// Radii r_j = j·R/N for j = 1..N, ascending. @pre R > 0, N >= 1.
std::vector<double> equidistantRadii(double largestRadius, int scales);

/// @throw InvalidInputError if @p radii are empty, not positive and finite, or not strictly
/// ascending (one sentence, for every algorithm that takes a list of radii).
void validateRadii(const std::vector<double>& radii);

/// The grid level of each radius for grid-based invariants: radius r goes to the coarsest
/// level l (cell edge h0·2^l) with r / (h0·2^l) >= minCellsPerRadius, level 0 if none.
/// Errors of voxel and sample sums follow h/r, so this keeps them flat across scales while
/// large radii stay cheap.
std::vector<int> gridLevelOfRadius(const std::vector<double>& radii, double h0,
                                   double minCellsPerRadius);

/// How far from a vertex its values may depend on the mesh, at most: max over the radii of
/// r + max(4 h_l + 2 h0, min(r, 6 h_l) + (2 + √3) h_l + h0): V and S's stencils and
/// interpolation reach r + 4 h_l + 2 h0; P and L's values come from samples within 2 h_l,
/// whose kernels reach at most r + min(r, 6 h_l) (L's: r + 4w, w <= r/4 and 1.5 cells)
/// over cells of extent √3·h_l (patch_line.h). Border distances are searched a little beyond this, and tiles' halos
/// reach past it, so that a tile's own values are exactly those of the whole mesh.
double dependenceReach(const std::vector<double>& radii, double h0, double minCellsPerRadius);

} // namespace msii
