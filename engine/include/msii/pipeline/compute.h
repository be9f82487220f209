#pragma once
/// @file compute.h
/// @brief The whole pipeline in one function, the entry point of every door: `msii compute`,
/// Python's `msii.compute`, the windows of a DEM (terrain/dem_compute.h) and examples/ all run
/// it, and differ only in how they read and write (docs/architecture.md):
///   1. prepare the mesh as read (repair, orientation, hole filling; mesh/prepare_mesh.h),
///      and continue it past the borders left open (mesh/extend_borders.h), so that every
///      vertex gets values (BorderHandling);
///   2. compute its invariants, fast or exact (invariants/invariants.h), in one piece or in
///      tiles that equal one piece bit for bit (tiling/tiled_compute.h);
///   3. map every value back to the input's vertices (a vertex in no face gets NaN);
///   4. count the masked values, and the values resting partly on surface not in the input,
///      over the input's vertices (pipeline/masked_values.h).
/// The parts stay public for programs that want them.

#include <msii/core/diagnostics.h>
#include <msii/core/feature_set.h>
#include <msii/core/run_context.h>
#include <msii/invariants/invariants.h>
#include <msii/mesh/extend_borders.h>
#include <msii/mesh/fill_holes.h>
#include <msii/mesh/trimesh.h>
#include <msii/pipeline/masked_values.h>
#include <msii/tiling/tiled_compute.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace msii {

/// What happens where a ball reaches a border of an open surface (docs/method.md, Values up
/// to the border).
enum class BorderHandling {
    /// The surface is continued past its borders for the computation: every vertex gets
    /// values, and filledShare says how much of its ball rests on the continuation.
    Continue,
    /// Values whose ball reaches a border are NaN: only values from the input's own surface.
    Mask,
};

/// "continue" or "mask" (the names every door uses: --border, border=).
/// @throw InvalidInputError naming both for anything else.
BorderHandling parseBorderHandling(const std::string& name);
const char* borderHandlingName(BorderHandling border);

struct ComputeOptions {
    /// Radius, scales, precision, which invariants, the exact mode. Its exactVertices are
    /// numbers of the input's vertices.
    InvariantsOptions invariants;
    /// Repair what mesh preparation repairs (PrepareMeshOptions::repair); false refuses such
    /// meshes instead.
    bool repair = true;
    /// Leave out the faces of spikes (PrepareMeshOptions::leaveOutSpikes); off for DEM windows.
    bool leaveOutSpikes = true;
    /// Fill holes whose border is at most this long (mesh units); -1 = πR
    /// (defaultMaxHolePerimeter), 0 = none.
    double maxHolePerimeter = -1;
    /// At borders left open after hole filling.
    BorderHandling border = BorderHandling::Continue;
    /// Input vertices on cuts through a larger surface (a DEM window's inner edges): a border
    /// edge between two of them is no border of the surface (ExtendBordersOptions::onCut).
    std::vector<std::uint32_t> cutVertices;
    /// Where values are wanted (a DEM window's own cells), if not everywhere: once the
    /// continuation is built from the whole input, the surface farther than the halo
    /// (haloWidth) from this box is dropped, so that a wide window read for the continuation
    /// costs no more to compute than a narrow one. Values outside the box are NaN or partial.
    BoundingBox valuesWithin;
    /// In tiles, to fit a memory budget (not with the exact mode).
    TilingOptions tiling;
};

/// The radius over which the continuation past a border fits its tangent plane and
/// averages its direction (ExtendBordersOptions::fitRadius): R/4, at least 3 vertex
/// spacings (docs/method.md, Values up to the border).
double continuationFitRadius(const ScalePlan& plan);
/// How far from a vertex the continuation it sees depends on the mesh: its ball's reach to
/// a border, the skirt's width from there and the mirror points as far inside (each
/// haloWidth), and the fit radius (ExtendBordersOptions). A DEM window
/// whose own cells are this far from its cut edges builds the same continuation as the
/// whole raster.
double continuationReach(const ScalePlan& plan);

/// What mesh preparation did (PrepareMeshResult without the prepared mesh).
struct PreparationSummary {
    std::vector<Diagnostic> changes;      ///< one per kind of change made
    FillHolesResult holes;
    double maxHolePerimeter = 0;          ///< the holes' size limit, as applied
    ExtendBordersResult borders;          ///< the continuation past borders (BorderHandling::Continue)
    std::size_t isolatedVertices = 0;     ///< input vertices in no face
    std::size_t vertices = 0, faces = 0;  ///< of the prepared mesh
    double seconds = 0;
};

struct ComputeResult {
    /// V, S, P and L per input vertex and radius (radii as the plan's), NaN where masked and
    /// for vertices in no face; no columns for invariants not asked for, nor when streamed.
    FeatureSet features;
    /// Per input vertex: the share of its largest ball's surface that is not in the input,
    /// filled holes and the continuation past borders together (area in the ball / πR²,
    /// at most 1; fillShare), NaN for vertices in no face; empty when streamed.
    std::vector<float> filledShare;
    ScalePlan plan;            ///< radii, voxel size, levels, reach, local frame
    MeshStats stats;           ///< of the prepared mesh
    MeshCheckResult check;     ///< of the prepared mesh
    PreparationSummary preparation;
    /// What the user should know: preparation's changes, then the computation's remarks.
    std::vector<Diagnostic> diagnostics;
    InvariantsCost cost;       ///< of the computation (preparation: preparation.seconds)
    bool tiled = false;
    TiledComputeInfo tiling;   ///< when tiled
    MaskedValues masked;       ///< over the input's vertices in a face (fast mode)
};

/// Values of some of the input's vertices, as handed to a PieceSink.
struct ComputedPiece {
    std::vector<std::uint32_t> vertices;  ///< input vertex numbers
    FeatureSet features;                  ///< one row per entry of vertices
    std::vector<float> filledShare;       ///< one per entry of vertices
    ScalePlan plan;                       ///< the computation's (the same for every piece)
};
using PieceSink = std::function<void(const ComputedPiece&)>;

/// Runs the pipeline (see the file comment) on @p input, a mesh as read.
/// @throw InvalidInputError for input that cannot be repaired or computed, or unusable
///        options, with one clear sentence; Cancelled when @p context is cancelled.
ComputeResult compute(const TriMesh& input, const ComputeOptions& options, RunContext* context = nullptr);

/// compute, with the values handed to @p sink piece by piece (a tile's vertices at a time
/// when tiled, else all at once) instead of kept, so that a tiled computation never holds
/// the whole mesh's values: msii compute writes them straight to its output. Vertices in no
/// face are in no piece.
ComputeResult computeStreamed(const TriMesh& input, const ComputeOptions& options, const PieceSink& sink,
                              RunContext* context = nullptr);

} // namespace msii
