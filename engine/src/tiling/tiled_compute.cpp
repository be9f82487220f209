#include <msii/tiling/tiled_compute.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/mesh_stats.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

namespace msii {
namespace {

/// The tiles of a grid over axes a and b (the two longest), as index boxes.
struct TileGrid {
    int axisA = 0, axisB = 1, n = 1;
    double minA = 0, minB = 0, sizeA = 1, sizeB = 1;  // tile sizes
    int cell(double v, double lo, double size) const
    {
        return std::clamp(int(std::floor((v - lo) / size)), 0, n - 1);
    }
    int tileOf(const Vec3& p) const { return cell(p[axisA], minA, sizeA) * n + cell(p[axisB], minB, sizeB); }
};

TileGrid makeGrid(const MeshStats& stats, int n)
{
    const Vec3 ext = stats.bboxMax - stats.bboxMin;
    std::array<int, 3> axes{0, 1, 2};
    std::sort(axes.begin(), axes.end(), [&](int i, int j) { return ext[i] > ext[j]; });
    TileGrid g;
    g.axisA = axes[0], g.axisB = axes[1], g.n = n;
    g.minA = stats.bboxMin[g.axisA], g.minB = stats.bboxMin[g.axisB];
    g.sizeA = std::max(ext[g.axisA], 1e-300) / n;
    g.sizeB = std::max(ext[g.axisB], 1e-300) / n;
    return g;
}

/// Whether p lies in tile t grown by the halo.
bool inGrownTile(const TileGrid& g, int t, const Vec3& p, double halo)
{
    const int ia = t / g.n, ib = t % g.n;
    const double a = p[g.axisA], b = p[g.axisB];
    return a >= g.minA + ia * g.sizeA - halo && a <= g.minA + (ia + 1) * g.sizeA + halo &&
           b >= g.minB + ib * g.sizeB - halo && b <= g.minB + (ib + 1) * g.sizeB + halo;
}

/// Vertices inside each grown tile (an estimate of the tile's size with its halo).
std::vector<std::size_t> grownTileSizes(const TriMesh& mesh, const TileGrid& g, double halo)
{
    std::vector<std::size_t> count(std::size_t(g.n) * g.n, 0);
    for (const Vec3& p : mesh.points) {
        const int a0 = g.cell(p[g.axisA] - halo, g.minA, g.sizeA), a1 = g.cell(p[g.axisA] + halo, g.minA, g.sizeA);
        const int b0 = g.cell(p[g.axisB] - halo, g.minB, g.sizeB), b1 = g.cell(p[g.axisB] + halo, g.minB, g.sizeB);
        for (int a = a0; a <= a1; ++a)
            for (int b = b0; b <= b1; ++b) ++count[std::size_t(a * g.n + b)];
    }
    return count;
}

std::string gigabytes(double bytes)
{
    std::ostringstream s;
    s.precision(2);
    s << std::fixed << bytes / 1e9 << " GB";
    return s.str();
}

} // namespace

std::vector<int> tileOfVertices(const TriMesh& mesh, int tilesPerAxis)
{
    if (tilesPerAxis < 1 || tilesPerAxis > 1024) throw InvalidInputError("the tiles per axis must be between 1 and 1024");
    const TileGrid grid = makeGrid(computeMeshStats(mesh), tilesPerAxis);
    std::vector<int> tile(mesh.numVertices());
    for (std::size_t i = 0; i < tile.size(); ++i) tile[i] = grid.tileOf(mesh.points[i]);
    return tile;
}

namespace {

/// The tiled computation; with @p keepColumns the result columns for the whole mesh count
/// against the memory budget (computeTiled), else not (computeTiles).
ComputeResult runTiles(TriMesh& mesh, const ComputeOptions& options, const TilingOptions& tiling, bool keepColumns,
                       const TileSink& sink, TiledComputeInfo* info, Progress* progress)
{
    const Stopwatch total;
    if (options.exact) throw InvalidInputError("the exact mode is not tiled (restrict it with --vertices)");
    if (tiling.memoryBudget < 0 || !std::isfinite(tiling.memoryBudget))
        throw InvalidInputError("the memory budget must be a positive number of bytes");
    if (tiling.tilesPerAxis < 0 || tiling.tilesPerAxis > 1024)
        throw InvalidInputError("the tiles per axis must be between 1 and 1024");
    ComputeResult plan = prepareComputation(mesh, options);
    const std::vector<double> radii = equidistantRadii(options.radius, options.scales);
    const std::vector<int> levels = gridLevelOfRadius(radii, plan.voxelSize, options.minVoxelsPerRadius);
    const double h0 = plan.voxelSize, hCoarse = h0 * double(1 << *std::max_element(levels.begin(), levels.end()));
    // Border distances are searched up to 2R; balls with their margin reach R + 4 h_L + 2 h_0.
    const double halo = std::max(2.0 * options.radius, options.radius + 4.0 * hCoarse + 2.0 * h0) + 2.0 * h0;

    // Memory: the mesh (points, triangles, tile of each vertex, local indices) stays whole,
    // and with keepColumns its result columns; each tile's computation comes on top.
    const std::size_t nv = mesh.numVertices();
    const int invariants = int(options.computeVolume) + int(options.computeSphere) +
                           int(options.computePatch) + int(options.computeLine);
    const double fixedBytes = double(nv) * (32.0 + (keepColumns ? 4.0 * invariants * options.scales : 0.0)) +
                              double(mesh.numTriangles()) * 12.0;
    const double perVertex = kBytesPerTileVertex * std::max(1.0, options.scales / 16.0);
    int n = tiling.tilesPerAxis;
    std::vector<std::size_t> sizes;
    TileGrid grid;
    if (n == 0) {
        if (tiling.memoryBudget > 0 && tiling.memoryBudget <= fixedBytes)
            throw InvalidInputError("the memory budget of " + gigabytes(tiling.memoryBudget) +
                                    " is too small for even one tile: the mesh" +
                                    (keepColumns ? " and its results" : "") + " alone take " + gigabytes(fixedBytes));
        const double allowed = tiling.memoryBudget > 0 ? (tiling.memoryBudget - fixedBytes) / perVertex
                                                       : std::numeric_limits<double>::max();
        const Vec3 ext = plan.stats.bboxMax - plan.stats.bboxMin;
        const double longest = std::max({ext.x, ext.y, ext.z});
        for (n = 1;; ++n) {
            grid = makeGrid(plan.stats, n);
            sizes = grownTileSizes(mesh, grid, halo);
            if (double(*std::max_element(sizes.begin(), sizes.end())) <= allowed) break;
            // Tiles much narrower than their halo would be mostly halo: give up.
            if (longest / n < 0.5 * halo || n >= 1024) {
                const double needed = fixedBytes + perVertex * double(*std::max_element(sizes.begin(), sizes.end()));
                throw InvalidInputError("the memory budget of " + gigabytes(tiling.memoryBudget) +
                                        " is too small for even one tile (tiles narrower than their halo of " +
                                        std::to_string(halo) + " would still need about " + gigabytes(needed) +
                                        "); raise the budget or use a smaller radius");
            }
        }
    } else {
        grid = makeGrid(plan.stats, n);
        sizes = grownTileSizes(mesh, grid, halo);
    }
    if (tiling.onlyTile >= n * n)
        throw InvalidInputError("tile " + std::to_string(tiling.onlyTile) + " does not exist (there are " +
                                std::to_string(n * n) + " tiles, 0 to " + std::to_string(n * n - 1) + ")");

    ComputeResult result = plan;
    result.invariants.radii = result.patchLine.radii = radii;
    result.invariants.levelOfRadius = result.patchLine.levelOfRadius = levels;
    result.invariants.numLevels = *std::max_element(levels.begin(), levels.end()) + 1;

    std::vector<int> tileOf(nv);
    std::vector<bool> tileHasVertices(std::size_t(n) * std::size_t(n), false);
    for (std::size_t i = 0; i < nv; ++i) tileHasVertices[std::size_t(tileOf[i] = grid.tileOf(mesh.points[i]))] = true;
    const std::size_t tilesWithVertices = std::size_t(std::count(tileHasVertices.begin(), tileHasVertices.end(), true));
    ComputeOptions tileOptions = options;
    tileOptions.voxelSize = plan.voxelSize;  // the whole mesh's grid, so that tiles agree
    tileOptions.repair = false;              // already done on the whole mesh
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::size_t computed = 0, masked = 0;
    std::vector<std::uint32_t> local;
    for (int t = 0; t < n * n; ++t) {
        if (tiling.onlyTile >= 0 && t != tiling.onlyTile) continue;
        TileResult part;
        part.tile = t;
        if (!tileHasVertices[std::size_t(t)]) continue;
        for (std::size_t i = 0; i < nv; ++i)
            if (tileOf[i] == t) part.vertices.push_back(std::uint32_t(i));
        // The tile's triangles: those with a vertex in the grown tile.
        TriMesh tile;
        local.assign(nv, kNone);
        for (const Triangle& tri : mesh.triangles) {
            if (!inGrownTile(grid, t, mesh.points[tri[0]], halo) && !inGrownTile(grid, t, mesh.points[tri[1]], halo) &&
                !inGrownTile(grid, t, mesh.points[tri[2]], halo))
                continue;
            Triangle lt;
            for (int k = 0; k < 3; ++k) {
                std::uint32_t& l = local[tri[std::size_t(k)]];
                if (l == kNone) {
                    l = std::uint32_t(tile.points.size());
                    tile.points.push_back(mesh.points[tri[std::size_t(k)]]);
                }
                lt[std::size_t(k)] = l;
            }
            tile.triangles.push_back(lt);
        }
        if (progress) {
            const std::size_t tiles = tiling.onlyTile >= 0 ? 1 : tilesWithVertices;
            progress->setPrefix("tile " + std::to_string(computed + 1) + " of " + std::to_string(tiles) + ": ");
        }
        ComputeResult values = computeInvariants(tile, tileOptions, progress);
        if (progress) progress->setPrefix("");
        tile = TriMesh();
        // Keep the rows of the tile's own vertices, in their global order.
        const auto own = [&](std::vector<std::vector<float>>& columns) {
            for (std::vector<float>& column : columns) {
                std::vector<float> kept(part.vertices.size());
                for (std::size_t l = 0; l < kept.size(); ++l) {
                    const std::uint32_t li = local[part.vertices[l]];
                    kept[l] = li == kNone ? nan : column[li];
                }
                column.swap(kept);
            }
        };
        own(values.invariants.volume);
        own(values.invariants.sphere);
        own(values.patchLine.patch);
        own(values.patchLine.line);
        for (const auto* columns : {&values.invariants.volume, &values.invariants.sphere})
            for (const auto& column : *columns)
                for (float v : column) masked += std::isnan(v);
        const ComputeTimings& pt = values.timings;
        ComputeTimings& rt = result.timings;
        rt.levelSet += pt.levelSet, rt.occupancy += pt.occupancy, rt.stencils += pt.stencils;
        rt.interpolation += pt.interpolation, rt.samples += pt.samples, rt.patchLine += pt.patchLine;
        result.levelSetVoxels += values.levelSetVoxels;
        result.levelSetBytes = std::max(result.levelSetBytes, values.levelSetBytes);
        result.bandHalfWidth = values.bandHalfWidth;
        part.values = std::move(values);
        sink(part);
        ++computed;
    }
    result.invariants.numMaskedValues = masked;
    if (info) {
        info->tilesPerAxis = n;
        info->tiles = computed;
        info->largestTileVertices = *std::max_element(sizes.begin(), sizes.end());
        info->haloWidth = halo;
        info->estimatedPeakBytes = fixedBytes + perVertex * double(info->largestTileVertices);
    }
    result.timings.total = total.seconds();
    return result;
}

} // namespace

ComputeResult computeTiles(TriMesh& mesh, const ComputeOptions& options, const TilingOptions& tiling,
                           const TileSink& sink, TiledComputeInfo* info, Progress* progress)
{
    return runTiles(mesh, options, tiling, false, sink, info, progress);
}

ComputeResult computeTiled(TriMesh& mesh, const ComputeOptions& options, const TilingOptions& tiling,
                           TiledComputeInfo* info, Progress* progress)
{
    // Result columns for the whole mesh, NaN until a tile fills them.
    const std::size_t nv = mesh.numVertices();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    VolumeSphereResult vs;
    PatchLineResult pl;
    const auto scatter = [&](std::vector<std::vector<float>>& to, const std::vector<std::vector<float>>& from,
                             const std::vector<std::uint32_t>& vertices) {
        if (to.empty()) to.assign(from.size(), std::vector<float>(nv, nan));
        for (std::size_t j = 0; j < from.size(); ++j)
            for (std::size_t l = 0; l < vertices.size(); ++l) to[j][vertices[l]] = from[j][l];
    };
    ComputeResult result = runTiles(
        mesh, options, tiling, true,
        [&](const TileResult& part) {
            scatter(vs.volume, part.values.invariants.volume, part.vertices);
            scatter(vs.sphere, part.values.invariants.sphere, part.vertices);
            scatter(pl.patch, part.values.patchLine.patch, part.vertices);
            scatter(pl.line, part.values.patchLine.line, part.vertices);
        },
        info, progress);
    result.invariants.volume = std::move(vs.volume);
    result.invariants.sphere = std::move(vs.sphere);
    result.patchLine.patch = std::move(pl.patch);
    result.patchLine.line = std::move(pl.line);
    return result;
}

} // namespace msii
