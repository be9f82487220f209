#pragma once
/// @file invariants.h
/// @brief The invariants of a prepared mesh: check it, plan the scales (voxel size, grid
/// levels, reach), build the level set and compute V, S, P and L at N radii, fast or exact,
/// with values masked where a ball reaches a border. The whole pipeline, from a mesh as read
/// to values per input vertex, is pipeline/compute.h; tiles (tiling/) and DEM windows
/// (terrain/) are pieces computed here with one shared plan.

#include <msii/core/diagnostics.h>
#include <msii/core/feature_set.h>
#include <msii/core/run_context.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/mesh_check.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/trimesh.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace msii {

struct InvariantsOptions {
    double radius = 0;              ///< largest radius R (mesh units); required
    int scales = 16;                ///< N: radii r_j = j·R/N
    /// Finest voxel edge; 0 = automatic (chooseVoxelSize).
    double voxelSize = 0;
    /// Precision knob: each radius is evaluated on the coarsest grid where r/h >= this.
    double minVoxelsPerRadius = 6.0;
    /// The same for P and L (their sample cells); 0 = 4/3 · minVoxelsPerRadius (8 by
    /// default). P and L are blurred by their kernels over about a cell; at sharp edges (a
    /// slab's walls, a wedge's rim) that blur dominates their error, and 8 cells per radius
    /// are what brings their mean differences from the exact mode on closed and scan-like
    /// slabs within 1e-3 (P) and 3e-3 (L) (docs/accuracy.md).
    double patchLinePrecision = 0;
    /// P and L: compare the kernels of two widths, and evaluate exactly from the triangles the
    /// (vertex, radius) pairs where they disagree (PatchLineOptions::exactWhereBlurred;
    /// docs/method.md, Exact where the kernels blur). Off: the kernel sums alone, faster on
    /// scans with many thin parts, within the bounds of docs/accuracy.md only on average.
    bool patchLineExactWhereBlurred = true;
    /// Which invariants (paper Eq. 2). V and S share the level set and one stencil pass;
    /// P and L share one pass over the surface samples.
    bool computeVolume = true, computeSphere = true, computePatch = true, computeLine = true;
    /// Exact reference mode (invariants/exact.h): all four from the triangles themselves, at
    /// exactVertices only (all vertices if empty); the others are NaN. Slow: for checking.
    bool exact = false;
    std::vector<std::uint32_t> exactVertices;
    /// A plan made beforehand (planInvariants) on the whole surface, for its pieces computed
    /// apart (tiles, DEM windows): with it every piece's values are those of one piece, bit
    /// for bit. Unset: planned on this mesh (voxelSize, precisions and radius as above).
    std::optional<ScalePlan> plan;
    /// Mask (NaN) the values whose ball reaches a border of an open mesh (docs/method.md,
    /// Border masks). Off for a mesh continued past its borders (mesh/extend_borders.h),
    /// whose few borders left (where skirts meet) are taken as the surface.
    bool maskBorders = true;
    /// Only the first this many vertices get values (the rest NaN, and their work skipped
    /// where the computation allows); 0 = all. The continuation's vertices, appended after the
    /// surface's, need none. Pieces (tiles) compute all of theirs.
    std::size_t evaluatedVertices = 0;
    /// Bytes the computation may take (0: no check). Before it allocates, the level set's
    /// size is estimated from the surface's area and the voxel size (surfaceBytesEstimate):
    /// beyond this, the computation is refused with the estimate, at once.
    double memoryLimit = 0;

    /// Selects the invariants of @p list (and no others).
    void select(const std::vector<Invariant>& list);
    /// The selected invariants, in the order V, S, P, L.
    std::vector<Invariant> selected() const;
};

/// What a computation cost: sizes, counts and time per stage (not results).
struct InvariantsCost {
    double bandHalfWidth = 0;                         ///< of the level set, voxels
    std::size_t levelSetVoxels = 0, levelSetBytes = 0;
    std::size_t stencilNodes = 0;                     ///< V and S stencil evaluations, all levels
    std::size_t numSamples = 0;                       ///< P and L samples on the finest level
    std::size_t directEvaluations = 0;                ///< PatchLineResult::directEvaluations
    /// P and L (vertex, radius) pairs given a value, of them those evaluated exactly where
    /// the kernels blur, and the vertices with such a pair (PatchLineResult).
    std::size_t patchLinePairs = 0, patchLinePairsExact = 0, patchLineVerticesExact = 0;
    /// Seconds per stage; P and L: sampling the surface, kernel sums (the check's kernels
    /// included, patchLineCheck of them), exact sums where the kernels blur.
    double check = 0, levelSet = 0, occupancy = 0, stencils = 0, interpolation = 0;
    double samples = 0, patchLine = 0, patchLineCheck = 0, patchLineExact = 0, exact = 0;
    double total = 0;

    /// Adds the cost of another piece: counts and seconds summed, the largest level set's
    /// bytes (pieces are computed one after the other).
    InvariantsCost& operator+=(const InvariantsCost& piece);
};

struct InvariantsResult {
    /// V, S, P and L per vertex and radius (those not asked for have no columns), NaN where
    /// masked; radii as the plan's.
    FeatureSet features;
    ScalePlan plan;                       ///< radii, voxel size, levels, reach
    MeshStats stats;
    MeshCheckResult check;
    std::vector<Diagnostic> diagnostics;  ///< what the user should know (core/diagnostics.h)
    InvariantsCost cost;
};

/// Cells per radius of P and L: patchLinePrecision, or 4/3 · minVoxelsPerRadius if that is 0.
double patchLinePrecision(const InvariantsOptions& options);

/// The automatic voxel size: fine enough that the first radius of at least 3 median edge
/// lengths has r/h >= minVoxelsPerRadius, but not finer than half the median edge (the mesh
/// holds no detail below that, and the level set's cost grows with its resolution;
/// docs/method.md, Voxel size).
double chooseVoxelSize(double medianEdge, const std::vector<double>& radii,
                       double minVoxelsPerRadius);

/// Bytes V and S take per voxel of surface (area / h_0²) at the finest level: the level
/// set's narrow band, the coarser levels and the stencils' passes. Measured where the
/// surface dominates, on a DEM whose spikes make it 760 times its extent: 1.34 GB for 16.6
/// million voxels of surface, continuation included.
constexpr double kBytesPerSurfaceVoxel = 80.0;

/// Bytes P and L take per cell of surface (area / h_0²): the pieces of the triangles, the
/// sums of the finest samples (a surface crossing the cells obliquely, and the continuation,
/// give up to 3 samples per cell of area) and the coarser levels. Measured where the
/// surface dominates, on a DEM whose spikes make it 1000 times its extent: 6.8 GB for about
/// 17 million cells of surface (docs/limits.md, Memory rule); on a scan all costs together
/// take 1.3 kB per cell (126 MB for 95,000).
constexpr double kBytesPerSurfaceSample = 400.0;

/// The estimate of a computation's memory that its surface alone sets (area / h_0² ·
/// kBytesPerSurfaceVoxel, or kBytesPerSurfaceSample when P or L is computed: they do not
/// run at once): a lower bound, close for surfaces much larger than their extent (spikes,
/// noise), below the per-vertex cost otherwise.
double surfaceBytesEstimate(double area, double voxelSize, const InvariantsOptions& options);

/// The checks and the plan of computeInvariants without the computation: parameters, mesh
/// check, statistics, the scale plan and its diagnostics, in a result without features. A
/// surface computed in pieces is planned whole with it, and each piece gets the plan
/// (InvariantsOptions::plan).
/// @throw InvalidInputError as computeInvariants.
InvariantsResult planInvariants(const TriMesh& mesh, const InvariantsOptions& options);

/// Computes the invariants of @p mesh, which must be usable as it is (consistently
/// oriented, no degenerate or duplicate faces): pipeline/compute.h prepares a mesh as read
/// and maps the values back to its vertices, which is what `msii compute` runs. Fast or
/// exact (options.exact), in one piece; pipeline/compute.h also computes in tiles.
/// @throw InvalidInputError for unusable meshes or parameters, with one clear sentence.
InvariantsResult computeInvariants(const TriMesh& mesh, const InvariantsOptions& options,
                                RunContext* context = nullptr);

} // namespace msii
