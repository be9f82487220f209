#pragma once
/// @file compute.h
/// @brief The whole per-mesh job of `msii compute`: check the mesh, choose the voxel size,
/// build the level set, compute the invariants, mask what reaches a border. I/O is left to
/// the caller (tools/msii), so tests and other programs run exactly what users run.

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
    /// Which invariants (paper Eq. 2). V and S share the level set and one stencil pass;
    /// P and L share one pass over the surface samples.
    bool computeVolume = true, computeSphere = true, computePatch = true, computeLine = true;
    /// Exact reference mode (invariants/exact.h): all four from the triangles themselves, at
    /// exactVertices only (all vertices if empty); the others are NaN. Slow: for checking.
    bool exact = false;
    std::vector<std::uint32_t> exactVertices;
    /// The whole mesh's median edge length, for P and L's choice of route per level
    /// (PatchLineOptions::vertexSpacing); 0 = this mesh's. Tiles get the whole mesh's.
    double vertexSpacing = 0;
    /// Near where the local frame's origin goes (ScalePlan::origin, rounded to 1024 voxels);
    /// unset: the mesh's bounding-box centre. Pieces of one surface computed apart (the
    /// windows of a DEM) pass the same point, so that their values are those of one piece.
    std::optional<Vec3> localOrigin;
    /// Tiling, for meshes larger than memory (tiling/tiled_compute.h): tiles whose
    /// computation fits in this many bytes, or tilesPerAxis × tilesPerAxis tiles; 0 and 0:
    /// one piece. The values equal those of one piece bit for bit. Not with `exact`.
    double memoryBudget = 0;
    int tilesPerAxis = 0;
};

/// What a computation cost: sizes, counts and time per stage (not results).
struct InvariantsCost {
    double bandHalfWidth = 0;                         ///< of the level set, voxels
    std::size_t levelSetVoxels = 0, levelSetBytes = 0;
    std::size_t stencilNodes = 0;                     ///< V and S stencil evaluations, all levels
    std::size_t numSamples = 0;                       ///< P and L samples on the finest level
    std::size_t directEvaluations = 0;                ///< PatchLineResult::directEvaluations
    std::size_t maskedValues = 0;                     ///< vertex·radius pairs of V masked (NaN)
    /// Seconds per stage; P and L: sampling the surface, kernel sums.
    double check = 0, levelSet = 0, occupancy = 0, stencils = 0, interpolation = 0;
    double samples = 0, patchLine = 0, exact = 0;
    double total = 0;
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

/// The checks and set-up of computeInvariants without the computation: parameters, mesh
/// check, statistics, the scale plan and diagnostics, in a result without features. The
/// tiled computation plans on the whole mesh with it.
/// @throw InvalidInputError as computeInvariants.
InvariantsResult prepareComputation(const TriMesh& mesh, const InvariantsOptions& options);

/// computeInvariants on one piece (untiled, not exact) with a plan made beforehand: the
/// tiles of a tiled computation, which all take the whole mesh's plan.
/// @throw InvalidInputError as computeInvariants.
InvariantsResult computeWithPlan(const TriMesh& mesh, const InvariantsOptions& options, const ScalePlan& plan,
                                 RunContext* context = nullptr);

/// Adds to @p counts (resized to the radii) the vertices whose value is NaN at each radius,
/// in the first invariant computed (V, S, P, L): the masked ones, for a sum over tiles.
void countMaskedVertices(const FeatureSet& features, std::vector<std::size_t>& counts);

/// The "mostly_masked" diagnostic when more than half of @p numVertices are masked at the
/// largest radius (their ball reaches a border of the open mesh: many holes, or a radius
/// large for the patch), with the largest radius at which at least half have values
/// (figure radius_with_half, 0 if none); none otherwise.
std::optional<Diagnostic> mostlyMasked(const std::vector<double>& radii,
                                       const std::vector<std::size_t>& maskedPerRadius, std::size_t numVertices);

/// Runs the job on @p mesh, which must be usable as it is: prepare scans first with
/// mesh/prepare_mesh.h (repair, hole filling), which is what `msii compute` does. The one
/// entry point for fast, exact and tiled runs (options.exact, options.memoryBudget /
/// tilesPerAxis); tiling/tiled_compute.h also streams tiles to a sink.
/// @throw InvalidInputError for unusable meshes or parameters, with one clear sentence.
InvariantsResult computeInvariants(const TriMesh& mesh, const InvariantsOptions& options,
                                RunContext* context = nullptr);

} // namespace msii
