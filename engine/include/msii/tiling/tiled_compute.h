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
#include <msii/invariants/invariants.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace msii {

/// How a computation is split to fit in memory: one meaning of the memory budget for meshes
/// (tiles) and DEMs (windows, terrain/dem_compute.h).
struct TilingOptions {
    /// Memory for the whole computation in bytes: pieces (tiles, DEM windows) are made small
    /// enough that one piece's computation (computationBytesPerVertex per vertex, halo
    /// included) fits next to what stays whole. 0: no limit, so a mesh is one piece; a DEM,
    /// read in windows and never held whole, is then sized for defaultDemMemoryBudget().
    double memoryBudget = 0;
    /// Tiles along each of the two longest axes of the mesh; 0 = from the budget.
    int tilesPerAxis = 0;
    /// Compute only this tile (0 … tiles − 1; its own vertices, the others stay NaN), e.g. one
    /// job per tile on a cluster; -1 = all. Merge the parts with tileOfVertices().
    int onlyTile = -1;
    /// Bytes that the caller holds while the tiles are computed (such as results kept for
    /// the whole mesh), counted against memoryBudget.
    double reservedBytes = 0;

    /// Whether the mesh is split (a budget or a number of tiles given).
    bool tiled() const { return memoryBudget != 0 || tilesPerAxis != 0; }
};

/// The memory budget of a DEM computed without one (TilingOptions::memoryBudget = 0), on a
/// machine of 4 GB or more (defaultDemMemoryBudget).
constexpr double kDefaultDemMemoryBudget = 3e9;

/// The memory a computation without a budget may take: three quarters of the machine's
/// (InvariantsOptions::memoryLimit).
double defaultMemoryLimit();

/// The memory budget of a DEM computed without one: kDefaultDemMemoryBudget, or
/// defaultMemoryLimit on a machine with less. The values do not depend on it, only how many
/// windows there are.
double defaultDemMemoryBudget();

/// Peak bytes per vertex of one piece's computation with these options: 1,700 with P or L at
/// N = 16 (a little above the 1.1M-vertex benchmark's, docs/performance.md), 1,200 with V
/// and S alone (measured on 1M-cell DEMs, docs/terrain.md), in proportion above N = 16. Tiles
/// and DEM windows are sized by it.
double computationBytesPerVertex(const InvariantsOptions& options);

/// How far beyond its own vertices a piece of a surface (a tile, a DEM window) must reach so
/// that its own values are those of the whole: everything they depend on (the plan's
/// reach), and 4 voxels to spare; border distances are searched up to reach + 2 h_0.
double haloWidth(const ScalePlan& plan);

/// Which tile (0 … K² − 1) owns each vertex when @p mesh is cut into K × K tiles, as
/// computeTiles cuts it.
std::vector<int> tileOfVertices(const TriMesh& mesh, int tilesPerAxis);

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
    /// Their values: each feature column has one entry per vertices[i] (NaN for a vertex in
    /// no triangle); radii, levels, voxel size as the plan.
    InvariantsResult values;
};
using TileSink = std::function<void(const TileResult&)>;

/// Computes @p options on the prepared @p mesh tile by tile (see the file comment) and hands
/// each tile's results to @p sink instead of keeping them, so memory is bounded by one tile's
/// computation next to the mesh. pipeline/compute.h maps them to the input's vertices and
/// either keeps them or hands them on (msii compute writes them straight to its output).
/// Returns the whole mesh's plan, check and statistics and the summed cost, without features.
/// @throw InvalidInputError as computeInvariants, and when the budget is too small for even
///        one tile (the message says how much is needed); whatever @p sink throws.
InvariantsResult computeTiles(const TriMesh& mesh, const InvariantsOptions& options, const TilingOptions& tiling,
                              const TileSink& sink, TiledComputeInfo* info = nullptr, RunContext* context = nullptr);

} // namespace msii
