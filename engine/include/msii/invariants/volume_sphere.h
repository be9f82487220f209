#pragma once
/// @file volume_sphere.h
/// @brief The volume (V) and sphere-area (S) integral invariants of paper Eq. 1–3 for all
/// N nested radii, by convolving nested-ball stencils over the level set.
///
/// How (details in volume_sphere.cpp; docs/method.md, Volume and sphere area):
/// 1. Occupancy: each voxel of the fine level set gets the fraction of its cube inside the
///    solid, exact for a plane through the voxel (cube/half-space volume from the distance
///    and its gradient) with a second-order correction for the surface's mean curvature.
/// 2. Pyramid: coarser grids (voxel 2h, 4h, ...) by averaging 2×2×2 children, which keeps
///    occupancy exact as a volume fraction.
/// 3. Each radius r_j is evaluated on the coarsest grid where r_j/h >= minVoxelsPerRadius,
///    so cost and error stay flat across scales, R one level finer unless that level is the
///    finest (volumeSphereLevels). There, fixed stencils at voxel centres:
///    anti-aliased ball weights (cube/ball fraction) for V, and for S = dV/dr the
///    difference of two such balls at r ± h/2. Both are normalised by the stencil's own sum,
///    so a full ball gives exactly 1 and a plane through a voxel centre exactly 1/2.
/// 4. Vertices: trilinear interpolation from the 8 surrounding voxel centres after moving
///    each centre onto the surface with a second-order model (a ball centre x·r outside a
///    surface of curvature κ: V̂(x) = V̂(0) − 3x/4 + 3κr x²/8 + x³/4, and likewise Ŝ), where
///    x·r, the centre's distance from the surface, is the vertex normal's plane plus a
///    curvature fitted to the centres' exact distances (capped at 0.5/r).
/// 5. The voxel sums blur V̂ by a tent of variance h²/6 per axis; the resulting bias,
///    (h²/12)·ΔV̂ = h²Ŝ'/(4r) for V and (h²/12)(4Ŝ'/r + 3Ŝ''/2) for S, is removed with Ŝ'
///    and Ŝ'' from the neighbouring radii.
/// All radii of one level share one pass over each stencil.

#include <msii/core/run_context.h>
#include <msii/levelset/levelset.h>
#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <vector>

namespace msii {

struct VolumeSphereOptions {
    std::vector<double> radii;       ///< ascending radii (mesh units), e.g. equidistantRadii()
    /// Precision knob: a radius is evaluated on the coarsest grid with r/h at least this
    /// (errors fall roughly like (h/r)^2; cost per vertex grows like its cube).
    double minVoxelsPerRadius = 6.0;
    /// The grid level of each radius (ScalePlan::volumeSphereLevels); empty =
    /// volumeSphereLevels(radii, level set voxel, minVoxelsPerRadius).
    std::vector<int> levelOfRadius;
    bool computeSphere = true;       ///< also S (shares the stencil pass with V)
    /// Per-vertex distance to the nearest border (mesh/border_distance.h); empty = closed.
    /// Radius r_j of vertex i is masked (NaN) when r_j + 4 h_level + 2 h_0 > borderDistance[i].
    std::vector<double> borderDistance;
};

struct VolumeSphereResult {
    std::vector<double> radii;                 ///< as given
    std::vector<std::vector<float>> volume;    ///< [j][vertex]: V/|B_r| (plane 0.5), NaN = masked
    std::vector<std::vector<float>> sphere;    ///< [j][vertex]: S/(4π r²) (plane 0.5), NaN = masked
    std::vector<int> levelOfRadius;            ///< grid level used for each radius (voxel h·2^level)
    int numLevels = 0;
    std::size_t numNodes = 0;                  ///< stencil evaluations (voxel centres), all levels
    double occupancySeconds = 0, stencilSeconds = 0, interpolationSeconds = 0;
};

/// Computes V̂ and Ŝ for every vertex of @p mesh at every radius.
/// @pre @p levelSet was built from @p mesh.
/// @throw InvalidInputError if radii are empty, not ascending or not positive.
VolumeSphereResult computeVolumeSphere(const TriMesh& mesh, const LevelSet& levelSet,
                                       const VolumeSphereOptions& options,
                                       RunContext* context = nullptr);

} // namespace msii
