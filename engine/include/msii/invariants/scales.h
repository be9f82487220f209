#pragma once
/// @file scales.h
/// @brief The nested radii of MSII (paper §3, Eq. 3 and 5): r_j = j·R/N, j = 1..N.

#include <msii/core/vec3.h>

#include <vector>

namespace msii {

/// Radii r_j = j·R/N for j = 1..N, ascending. @pre R > 0, N >= 1.
std::vector<double> equidistantRadii(double largestRadius, int scales);

/// @throw InvalidInputError if @p radii are empty, not positive and finite, or not strictly
/// ascending (one sentence, for every algorithm that takes a list of radii).
void validateRadii(const std::vector<double>& radii);

/// The grid level of each radius for grid-based invariants: radius r goes to the coarsest
/// level l (cell edge h0·2^l) with r / (h0·2^l) >= minCellsPerRadius, level 0 if none
/// (docs/method.md, Radii and grid levels).
/// Errors of voxel and sample sums follow h/r, so this keeps them flat across scales while
/// large radii stay cheap.
std::vector<int> gridLevelOfRadius(const std::vector<double>& radii, double h0,
                                   double minCellsPerRadius);

/// The grid level of each radius for V and S: gridLevelOfRadius, except that the largest
/// radius R goes one level finer (at least 2·minVoxelsPerRadius voxels) when that level is
/// not the finest and R spans at most 8/3·minVoxelsPerRadius voxels there. V̂ at R is the
/// `quality` users look at first, and its largest errors fall about 3× from R/h = 8 to 16
/// (docs/accuracy.md). The level below already holds radii of up to 2·minVoxelsPerRadius
/// voxels, so its stencil grows by at most (4/3)³ in volume, on a level with a quarter of
/// the finest level's nodes or fewer; on the finest level the cost would be several times
/// the whole stencil stage, so R stays where it is.
std::vector<int> volumeSphereLevels(const std::vector<double>& radii, double h0,
                                    double minVoxelsPerRadius);

/// How far from a vertex its values may depend on the mesh, at most: max over the radii of
/// r + max(4 h_l + 2 h0, min(r, 6 h_l) + (2 + √3) h_l + h0): V and S's stencils and
/// interpolation reach r + 4 h_l + 2 h0; P and L's values come from samples within 2 h_l,
/// whose kernels reach at most r + min(r, 6 h_l) (L's: r + 4w, w <= r/4 and 1.5 cells)
/// over cells of extent √3·h_l (patch_line.h). Border distances are searched a little
/// beyond this, and tiles' halos reach past it, so that a tile's own values are exactly
/// those of the whole mesh (docs/method.md, Tiling).
double dependenceReach(const std::vector<double>& radii, double h0, double minCellsPerRadius);

/// Everything the scales decide, worked out once per computation (makeScalePlan) and passed
/// to V and S, P and L, the border mask and every tile, so that they cannot disagree.
struct ScalePlan {
    std::vector<double> radii;               ///< r_j = j·R/N, ascending (mesh units)
    double voxelSize = 0;                    ///< h0: the finest voxel edge and sample cell
    double volumeSpherePrecision = 0;        ///< V and S: voxels per radius at least
    double patchLinePrecision = 0;           ///< P and L: sample cells per radius at least
    std::vector<int> volumeSphereLevels;     ///< per radius: V and S's grid level (volumeSphereLevels)
    std::vector<int> patchLineLevels;        ///< per radius: P and L's sample level (patchLineLevelsNearVertices)
    /// How far from a vertex its values may depend on the mesh (dependenceReach at the
    /// smaller precision, whose coarser levels reach farther).
    double reach = 0;
    /// The computation's local frame: every stage sees the mesh moved by −origin, so that
    /// georeferenced meshes (UTM: x ≈ 500 000 m, y ≈ 5 500 000 m) compute as meshes at the
    /// origin do. It is the whole mesh's bounding-box centre rounded to a multiple of
    /// 1024 h0, so the voxel grid keeps its place relative to the mesh, and every tile
    /// takes the whole mesh's (docs/method.md, Local frame). Outputs keep the input's
    /// coordinates.
    Vec3 origin;
    /// The whole mesh's median edge length: P and L choose their route per level by it
    /// (PatchLineOptions::vertexSpacing), so every piece of one surface chooses alike.
    double vertexSpacing = 0;
    int numVolumeSphereLevels() const;
};

/// The local frame's origin (ScalePlan::origin) for a surface about @p centre: @p centre
/// rounded to a multiple of 1024 h0 along each axis.
Vec3 localOrigin(const Vec3& centre, double h0);

/// The plan for @p radii with finest voxel @p h0, the two precisions and the whole mesh's
/// median edge @p vertexSpacing (0: unknown, P and L's levels by precision alone).
/// @throw InvalidInputError for invalid radii (validateRadii) or a non-positive h0.
ScalePlan makeScalePlan(const std::vector<double>& radii, double h0, double volumeSpherePrecision,
                        double patchLinePrecision, double vertexSpacing = 0);

} // namespace msii
