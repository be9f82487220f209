#pragma once
/// @file patch_line.h
/// @brief The patch-area (P) and intersection-line-length (L) integral invariants of paper
/// Eq. 2 for all N nested radii, from a sampled surface.
///
/// How (details in src/invariants/patch_line*.cpp; docs/method.md, Patch area and line length):
/// 1. Samples: the triangles are cut into pieces no larger than the finest cell h0 (slivers
///    along the cells' planes), and the pieces are gathered per cell into one sample: area, centroid, covariance of position
///    and mean normal tensor. Coarser levels (cells 2h0, 4h0, ...) merge 2×2×2 cells exactly.
/// 2. Each radius uses the coarsest level with r/h >= minCellsPerRadius (gridLevelOfRadius),
///    except a coarsest level that would hold a single radius (patchLineLevelOfRadius).
/// 3. Per point p and level, one pass over the samples within reach builds histograms over
///    the distance d = |x − p| of area, and of area·g with g = |∇_M d| = sqrt(1 − (û·n)²)
///    (û = (x − p)/d). Then P(r) = Σ a·F((r − d)/w) and, by the coarea formula
///    L = ∫_M δ(|x − p| − r)·|∇_M |x − p|| dA, L(r) = Σ a·g·K((d − r)/w)/w (paper Eq. 2),
///    with K a kernel of knot spacing w and F its integral, and all radii of a level share
///    the pass. P's K comes from the cubic B-spline with w = 1 cell (at most r/3), L's from
///    the quintic one, smoother, with w = 1.25 cells, 1.5 on the finest level (at most
///    r/4): narrow kernels blur the kinks and onsets of P(r) and L(r) less, and L, a
///    density, needs the smoother kernel for the samples' shapes to average out.
/// 4. K = (1 + σ²) B(t) − σ²/2 (B(t + 1) + B(t − 1)), B the B-spline (variance σ²): ∫K = 1,
///    zero second moment, support ±3w (cubic) or ±4w (quintic). So the blur across r leaves
///    any locally quadratic P(r) and L(r) unchanged (planes, spheres, cones of edges and
///    corners) without a correction.
/// 5. Each sample stands for its area spread with its covariance: a second-order quadrature
///    (the mean distance d + (tr C − ûᵀCû)/(2d), and f″/2·ûᵀCû in channels of their own).
/// 6. Coarse levels with fewer samples than vertices evaluate at the samples and fit a plane
///    to the vertices from the samples on the vertex's side of the surface, weighted
///    towards those within about h/2; vertices on creases and corners, where that fails,
///    are evaluated where they are.
/// 7. The check: the same histograms weighed with kernels 1.5 times narrower, at r and
///    halfway to the radius below. Where P(r) or L(r) changes abruptly within a kernel's
///    width (a sphere meeting a new sheet of the surface, or a crease), the blur differs
///    between the two widths; a (vertex, radius) pair where P̂ or L̂ differ by more than a
///    threshold is flagged. Fitted vertices whose fit bends more than that are evaluated
///    where they are, as in 6.
/// 8. The flagged pairs are evaluated exactly from the triangles (src/invariants/
///    patch_line_exact.h), in one walk per vertex over its flagged radii, with sums that do
///    not depend on the order of the triangles, so tiles and windows keep to one piece's
///    values bit for bit.

#include <msii/core/run_context.h>
#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace msii {

/// The check's default thresholds, derived in docs/method.md (Exact where the kernels
/// blur): a pair whose fast value may be off by more than about a tenth of the stated bounds
/// (P̂ 5e-3, L̂ 1.5e-2) is evaluated exactly.
constexpr double kCheckThresholdPatch = 1e-3;
constexpr double kCheckThresholdLine = 3e-3;

struct PatchLineOptions {
    std::vector<double> radii;       ///< ascending radii (mesh units)
    double cellSize = 0;             ///< h0, the finest sample cell (msii uses the voxel size)
    /// A radius is evaluated on the coarsest level with r/h at least this (as for V and S).
    double minCellsPerRadius = 6.0;
    /// The sample level of each radius (ScalePlan::patchLineLevels); empty =
    /// patchLineLevelOfRadius(radii, cellSize, minCellsPerRadius).
    std::vector<int> levelOfRadius;
    bool computePatch = true;        ///< P
    bool computeLine = true;         ///< L
    /// Per-vertex distance to the nearest border (mesh/border_distance.h); empty = closed.
    /// Radius r_j of vertex i is masked (NaN) when r_j + max(4 w_j, 4 h_level) + 2 h_0 >
    /// borderDistance[i] (w_j the knot spacing of L's kernel, the wider, at most r_j/4): the
    /// reach of the kernels. Each invariant is masked by its own reach, and P and L's levels
    /// are finer than V and S's by default (4/3 of the precision), so P and L can have a
    /// value at a radius where V and S are masked.
    std::vector<double> borderDistance;
    /// Decides, per level, where P and L are evaluated: at the vertices where the level's
    /// cells are no larger than this spacing, else at the samples (then fewer than the
    /// vertices) with a fit to the vertices. It must describe the whole mesh, so that a tile
    /// takes the route the whole mesh takes (tiles pass the whole mesh's); 0 = this mesh's
    /// median edge length.
    double vertexSpacing = 0;
    /// Steps 7 and 8: re-evaluate exactly the pairs where the kernels of two widths disagree
    /// (docs/method.md, Exact where the kernels blur).
    bool exactWhereBlurred = true;
    /// Flag a pair where |P̂ − P̂_narrow| exceeds this (and P is computed).
    double checkThresholdPatch = kCheckThresholdPatch;
    /// Flag a pair where |L̂ − L̂_narrow| exceeds this (and L is computed).
    double checkThresholdLine = kCheckThresholdLine;
    /// Keep the check's figures per pair (PatchLineResult::flagged, patchDifference and
    /// lineDifference), e.g. to study it; they are computed also without exactWhereBlurred.
    bool keepCheck = false;
};

struct PatchLineResult {
    std::vector<double> radii;                ///< as given
    std::vector<std::vector<float>> patch;    ///< [j][vertex]: P/(π r²) (plane 1), NaN = masked
    std::vector<std::vector<float>> line;     ///< [j][vertex]: L/(2π r) (plane 1), NaN = masked
    std::vector<int> levelOfRadius;           ///< sample level of each radius (cell h0·2^level)
    std::size_t numSamples = 0;               ///< samples on the finest level
    /// Vertices evaluated where they are on a coarse level instead of interpolated from the
    /// samples (creases, corners), summed over the levels.
    std::size_t directEvaluations = 0;
    /// (vertex, radius) pairs given a value, and of them those the check flagged and the
    /// exact sums evaluated; the vertices with at least one such pair.
    std::size_t pairs = 0, pairsExact = 0, verticesExact = 0;
    /// With PatchLineOptions::keepCheck, per [j][vertex]: 1 where the check flagged the pair,
    /// and its differences D of P̂ and L̂ (NaN where masked or not computed).
    std::vector<std::vector<std::uint8_t>> flagged;
    std::vector<std::vector<float>> patchDifference, lineDifference;
    double samplingSeconds = 0, gatherSeconds = 0;
    /// Of gatherSeconds, the check's narrow kernels (an estimate: their share of the kernel
    /// sums' work); and the exact sums of the flagged pairs.
    double checkSeconds = 0, exactSeconds = 0;
};

/// The sample level of each radius: gridLevelOfRadius, except that a coarsest level
/// holding a single radius r joins the level below when that costs no more
/// (docs/method.md, Sample levels). Its own pass would reach up to r + 5 of its cells (L's
/// kernel knots 1.25 cells) for one radius; extending the level below from the radius before
/// reaches only a little further, on 4 times as many points and samples, and halves the
/// kernel there.
std::vector<int> patchLineLevelOfRadius(const std::vector<double>& radii, double h0,
                                        double minCellsPerRadius);

/// @p levels (patchLineLevelOfRadius) with a radius whose level has cells larger than
/// kFittedCellsPerSpacing vertex spacings @p vertexSpacing moved to finer levels, while r
/// keeps at most kMaxCellsPerRadiusFactor × @p minCellsPerRadius of their cells: fitted from
/// samples that coarse to the vertices, the values blur creases and onsets that the check
/// then sends to the exact sums, so a finer level costs less in all (docs/method.md, Sample
/// levels).
constexpr double kFittedCellsPerSpacing = 1.5;
constexpr double kMaxCellsPerRadiusFactor = 4;
std::vector<int> patchLineLevelsNearVertices(std::vector<int> levels, const std::vector<double>& radii, double h0,
                                             double vertexSpacing, double minCellsPerRadius);

/// Computes P̂ and L̂ for every vertex of @p mesh at every radius.
/// @throw InvalidInputError if radii are empty, not ascending or not positive, or the cell
/// size is not positive or too small for the mesh's extent.
PatchLineResult computePatchLine(const TriMesh& mesh, const PatchLineOptions& options,
                                 RunContext* context = nullptr);

} // namespace msii
