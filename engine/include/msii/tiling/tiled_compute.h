#pragma once
/// @file tiled_compute.h
/// @brief The invariants of a large mesh tile by tile: the mesh is split into spatial tiles
/// (a grid over its two longest extents), each tile is computed on its own together with a
/// halo of the triangles that its vertices' balls and border tests can reach, and the values
/// of each tile's own vertices are merged. With the voxel size of the whole mesh and a halo
/// of the dependence reach plus 4 h_0 (invariants/scales.h), every value depends only on
/// triangles inside the tile with its halo, so the merged result equals the untiled one bit
/// for bit (docs/method.md, Tiling).

#include <msii/core/run_context.h>
#include <msii/invariants/compute.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace msii {

struct TilingOptions {
    /// Memory for the computation in bytes; tiles are made small enough that one tile's
    /// computation fits (about kBytesPerTileVertex per vertex, halo included) next to the
    /// mesh and its results. 0: no limit (with tilesPerAxis = 0, a single tile).
    double memoryBudget = 0;
    /// Tiles along each of the two longest axes of the mesh; 0 = from the budget.
    int tilesPerAxis = 0;
    /// Compute only this tile (0 … tiles − 1; its own vertices, the others stay NaN), e.g. one
    /// job per tile on a cluster; -1 = all. Merge the parts with tileOfVertices().
    int onlyTile = -1;
};

/// Which tile (0 … K² − 1) owns each vertex when @p mesh is cut into K × K tiles, as
/// computeTiled cuts it.
std::vector<int> tileOfVertices(const TriMesh& mesh, int tilesPerAxis);

/// Peak bytes per vertex of one computation at N = 16 with all four invariants, used to size
/// tiles: a little above the peak memory per vertex of the 1.1M-vertex benchmark
/// (docs/performance.md), so that a tile sized by it fits its budget.
constexpr double kBytesPerTileVertex = 1700.0;

struct TiledComputeInfo {
    int tilesPerAxis = 1;
    std::size_t tiles = 0;              ///< tiles with at least one vertex of their own
    std::size_t largestTileVertices = 0; ///< halo included
    double haloWidth = 0;               ///< mesh units
    double estimatedPeakBytes = 0;
};

/// One tile's results, as handed to a TileSink when the tile is done.
struct TileResult {
    int tile = 0;
    /// The tile's own vertices (global indices, ascending).
    std::vector<std::uint32_t> vertices;
    /// Their values: each feature column has one entry per
    /// vertices[i] (NaN for a vertex in no triangle); radii, levels, voxel size as the plan.
    InvariantsResult values;
};
using TileSink = std::function<void(const TileResult&)>;

/// Computes @p options on @p mesh tile by tile (see the file comment) and hands each tile's
/// results to @p sink instead of keeping them, so memory is bounded by one tile's
/// computation next to the mesh (e.g. io/write_ply.h's PlyPieceWriter writes them straight
/// to the output). Returns the plan, timings and counts, with empty feature columns.
/// @throw as computeTiled, and whatever @p sink throws.
InvariantsResult computeTiles(const TriMesh& mesh, const InvariantsOptions& options, const TilingOptions& tiling,
                           const TileSink& sink, TiledComputeInfo* info = nullptr, RunContext* context = nullptr);

/// Computes @p options on @p mesh tile by tile (see the file comment); the result has the
/// same columns as computeInvariants (the exact mode is not tiled).
/// @throw InvalidInputError as computeInvariants, and when the budget is too small for even
/// one tile (the message says how much is needed).
InvariantsResult computeTiled(const TriMesh& mesh, const InvariantsOptions& options, const TilingOptions& tiling,
                           TiledComputeInfo* info = nullptr, RunContext* context = nullptr);

} // namespace msii
