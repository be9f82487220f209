#include <msii/tiling/tiled_compute.h>

#include <unistd.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/patch_line.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/mesh_stats.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
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

/// Whether coordinate v lies in cell i (of size @p size from @p lo) grown by the halo.
bool inGrownCell(double v, double lo, double size, int i, double halo)
{
    return v >= lo + i * size - halo && v <= lo + (i + 1) * size + halo;
}

/// The grown tiles containing p, as a box of tile rows [r[0], r[1]] (along a) and columns
/// [r[2], r[3]] (along b), decided by inGrownCell axis by axis.
std::array<int, 4> grownTilesOf(const TileGrid& g, const Vec3& p, double halo)
{
    std::array<int, 4> r{};
    const auto range = [&](double v, double lo, double size, int& first, int& last) {
        // Candidates: the cells of v -+ halo, one more each side against rounding.
        const int c0 = std::max(0, g.cell(v - halo, lo, size) - 1);
        const int c1 = std::min(g.n - 1, g.cell(v + halo, lo, size) + 1);
        first = g.n, last = -1;
        for (int i = c0; i <= c1; ++i)
            if (inGrownCell(v, lo, size, i, halo)) first = std::min(first, i), last = i;
    };
    range(p[g.axisA], g.minA, g.sizeA, r[0], r[1]);
    range(p[g.axisB], g.minB, g.sizeB, r[2], r[3]);
    return r;
}

/// Items of each tile as lists: tile t's are ids[offsets[t] ... offsets[t + 1]), ascending.
struct Buckets {
    std::vector<std::size_t> offsets;
    std::vector<std::uint32_t> ids;
    const std::uint32_t* begin(int t) const { return ids.data() + offsets[std::size_t(t)]; }
    const std::uint32_t* end(int t) const { return ids.data() + offsets[std::size_t(t) + 1]; }
};

/// Counting sort of items 0 … count − 1 into tiles: forTiles(i, add) calls add(t) for each
/// tile t of item i (at most once per tile).
template <class ForTiles>
Buckets bucketize(std::size_t numTiles, std::size_t count, const ForTiles& forTiles)
{
    Buckets b;
    b.offsets.assign(numTiles + 1, 0);
    for (std::size_t i = 0; i < count; ++i) forTiles(i, [&](int t) { ++b.offsets[std::size_t(t) + 1]; });
    for (std::size_t t = 0; t < numTiles; ++t) b.offsets[t + 1] += b.offsets[t];
    b.ids.resize(b.offsets.back());
    std::vector<std::size_t> fill(b.offsets.begin(), b.offsets.end() - 1);
    for (std::size_t i = 0; i < count; ++i)
        forTiles(i, [&](int t) { b.ids[fill[std::size_t(t)]++] = std::uint32_t(i); });
    return b;
}

/// The triangles of each grown tile, in mesh order, in one pass over the mesh; with
/// only >= 0, only that tile's. A triangle belongs to every grown tile its bounding box
/// (over the two tile axes) overlaps: a long triangle (a scan's coarse side wall next to a
/// fine face) can pass by a tile's vertices with none of its corners in the grown tile, and
/// its surface must still be there for them. Triangles a little beyond the grown tile do no
/// harm: every value depends only on the surface within the halo.
Buckets trianglesOfGrownTiles(const TriMesh& mesh, const TileGrid& g, double halo, int only)
{
    // The cells whose grown interval meets [lo, hi] (bounds as in inGrownCell).
    const auto overlapped = [&](double lo, double hi, double origin, double size, int& first, int& last) {
        const int c0 = std::max(0, g.cell(lo - halo, origin, size) - 1);
        const int c1 = std::min(g.n - 1, g.cell(hi + halo, origin, size) + 1);
        first = g.n, last = -1;
        for (int i = c0; i <= c1; ++i)
            if (hi >= origin + i * size - halo && lo <= origin + (i + 1) * size + halo)
                first = std::min(first, i), last = i;
    };
    return bucketize(std::size_t(g.n) * std::size_t(g.n), mesh.numTriangles(), [&](std::size_t f, const auto& add) {
        const Triangle& tri = mesh.triangles[f];
        double loA = mesh.points[tri[0]][g.axisA], hiA = loA, loB = mesh.points[tri[0]][g.axisB], hiB = loB;
        for (std::size_t k = 1; k < 3; ++k) {
            const Vec3& p = mesh.points[tri[k]];
            loA = std::min(loA, p[g.axisA]), hiA = std::max(hiA, p[g.axisA]);
            loB = std::min(loB, p[g.axisB]), hiB = std::max(hiB, p[g.axisB]);
        }
        int a0, a1, b0, b1;
        overlapped(loA, hiA, g.minA, g.sizeA, a0, a1);
        overlapped(loB, hiB, g.minB, g.sizeB, b0, b1);
        for (int a = a0; a <= a1; ++a)
            for (int b = b0; b <= b1; ++b) {
                const int t = a * g.n + b;
                if (only < 0 || t == only) add(t);
            }
    });
}

/// Vertices inside each grown tile (its size with the halo, but for the few outside vertices
/// of triangles that reach in).
std::vector<std::size_t> grownTileSizes(const TriMesh& mesh, const TileGrid& g, double halo)
{
    std::vector<std::size_t> count(std::size_t(g.n) * g.n, 0);
    for (const Vec3& p : mesh.points) {
        const std::array<int, 4> r = grownTilesOf(g, p, halo);
        for (int a = r[0]; a <= r[1]; ++a)
            for (int b = r[2]; b <= r[3]; ++b) ++count[std::size_t(a * g.n + b)];
    }
    return count;
}

/// "2.40 GB", "35.0 MB", "12 kB".
std::string readableBytes(double bytes)
{
    std::ostringstream s;
    s << std::fixed;
    if (bytes >= 1e9) s << std::setprecision(2) << bytes / 1e9 << " GB";
    else if (bytes >= 1e6) s << std::setprecision(1) << bytes / 1e6 << " MB";
    else s << std::setprecision(0) << bytes / 1e3 << " kB";
    return s.str();
}

} // namespace

double computationBytesPerVertex(const InvariantsOptions& options)
{
    const double atSixteen = options.computePatch || options.computeLine ? 1700.0 : 1200.0;
    return atSixteen * std::max(1.0, options.scales / 16.0);
}

double defaultMemoryLimit()
{
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
    return pages > 0 && pageSize > 0 ? 0.75 * double(pages) * double(pageSize) : 0.0;
}

double defaultDemMemoryBudget()
{
    const double machine = defaultMemoryLimit();
    return machine > 0 ? std::min(kDefaultDemMemoryBudget, machine) : kDefaultDemMemoryBudget;
}

double haloWidth(const ScalePlan& plan) { return plan.reach + 4.0 * plan.voxelSize; }

std::vector<int> tileOfVertices(const TriMesh& mesh, int tilesPerAxis)
{
    if (tilesPerAxis < 1 || tilesPerAxis > 1024) throw InvalidInputError("the tiles per axis must be between 1 and 1024");
    const TileGrid grid = makeGrid(computeMeshStats(mesh), tilesPerAxis);
    std::vector<int> tile(mesh.numVertices());
    for (std::size_t i = 0; i < tile.size(); ++i) tile[i] = grid.tileOf(mesh.points[i]);
    return tile;
}

namespace {

/// The tile grid for a budget: the fewest tiles per axis whose largest grown tile fits.
struct TilePlan {
    TileGrid grid;
    std::vector<std::size_t> sizes;  ///< vertices per grown tile
    double fixedBytes = 0, perVertex = 0;
    std::size_t largest() const { return *std::max_element(sizes.begin(), sizes.end()); }
};

TilePlan planTiles(const TriMesh& mesh, const InvariantsResult& whole, const InvariantsOptions& options,
                   const TilingOptions& tiling, double halo)
{
    if (tiling.memoryBudget < 0 || !std::isfinite(tiling.memoryBudget))
        throw InvalidInputError("the memory budget must be a positive number of bytes");
    if (tiling.tilesPerAxis < 0 || tiling.tilesPerAxis > 1024)
        throw InvalidInputError("the tiles per axis must be between 1 and 1024");
    // Memory: the mesh (points, triangles), the tiles' vertex and triangle lists (halos make
    // the latter about 1.2-1.5 times the triangles), local indices and what the caller
    // reserves stay whole; each tile's computation comes on top.
    TilePlan tp;
    tp.fixedBytes = double(mesh.numVertices()) * 32.0 + double(mesh.numTriangles()) * 18.0 + tiling.reservedBytes;
    tp.perVertex = computationBytesPerVertex(options);
    const std::string whatStays = tiling.reservedBytes > 0 ? " the mesh and its results alone take " : " the mesh alone takes ";
    if (tiling.tilesPerAxis > 0) {
        tp.grid = makeGrid(whole.stats, tiling.tilesPerAxis);
        tp.sizes = grownTileSizes(mesh, tp.grid, halo);
        return tp;
    }
    if (tiling.memoryBudget > 0 && tiling.memoryBudget <= tp.fixedBytes)
        throw InvalidInputError("the memory budget of " + readableBytes(tiling.memoryBudget) +
                                " is too small for even one tile:" + whatStays + readableBytes(tp.fixedBytes));
    const double allowed = tiling.memoryBudget > 0 ? (tiling.memoryBudget - tp.fixedBytes) / tp.perVertex
                                                   : std::numeric_limits<double>::max();
    const Vec3 ext = whole.stats.bboxMax - whole.stats.bboxMin;
    const double longest = std::max({ext.x, ext.y, ext.z});
    for (int n = 1;; ++n) {
        tp.grid = makeGrid(whole.stats, n);
        tp.sizes = grownTileSizes(mesh, tp.grid, halo);
        if (double(tp.largest()) <= allowed) return tp;
        // Tiles much narrower than their halo would be mostly halo: give up.
        if (longest / n < 0.5 * halo || n >= 1024) {
            std::ostringstream h;
            h << std::setprecision(3) << halo;
            throw InvalidInputError("the memory budget of " + readableBytes(tiling.memoryBudget) +
                                    " is too small for even one tile (tiles narrower than their halo of " + h.str() +
                                    " would still need about " +
                                    readableBytes(tp.fixedBytes + tp.perVertex * double(tp.largest())) +
                                    "); raise the budget or use a smaller radius");
        }
    }
}

/// Tile @p t's triangles (its grown box's, in mesh order) as a mesh of their own; @p local
/// (kNone outside the tile) and @p global map vertex numbers in and out of it.
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

TriMesh extractTile(const TriMesh& mesh, const Buckets& tileTriangles, int t, std::vector<std::uint32_t>& local,
                    std::vector<std::uint32_t>& global)
{
    TriMesh tile;
    tile.triangles.reserve(std::size_t(tileTriangles.end(t) - tileTriangles.begin(t)));
    for (const std::uint32_t* f = tileTriangles.begin(t); f != tileTriangles.end(t); ++f) {
        const Triangle& tri = mesh.triangles[*f];
        Triangle lt;
        for (std::size_t k = 0; k < 3; ++k) {
            std::uint32_t& l = local[tri[k]];
            if (l == kNone) {
                l = std::uint32_t(tile.points.size());
                tile.points.push_back(mesh.points[tri[k]]);
                global.push_back(tri[k]);
            }
            lt[k] = l;
        }
        tile.triangles.push_back(lt);
    }
    return tile;
}

/// Keeps the rows of @p own (global numbers) in every feature column, in that order.
void keepOwnRows(FeatureSet& features, const std::vector<std::uint32_t>& own, const std::vector<std::uint32_t>& local)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (FeatureColumns& columns : features.columns)
        for (std::vector<float>& column : columns) {
            std::vector<float> kept(own.size());
            for (std::size_t l = 0; l < kept.size(); ++l) {
                const std::uint32_t li = local[own[l]];
                kept[l] = li == kNone ? nan : column[li];
            }
            column.swap(kept);
        }
}

} // namespace

InvariantsResult computeTiles(const TriMesh& mesh, const InvariantsOptions& options, const TilingOptions& tiling,
                              const TileSink& sink, TiledComputeInfo* info, RunContext* progress)
{
    const Stopwatch total;
    if (options.exact) throw InvalidInputError("the exact mode is not tiled (restrict it to chosen vertices instead)");
    InvariantsOptions planning = options;
    planning.memoryLimit = 0;  // the whole is never computed at once: each tile's surface is checked
    InvariantsResult result = planInvariants(mesh, planning);
    const double halo = haloWidth(result.plan);
    const TilePlan tp = planTiles(mesh, result, options, tiling, halo);
    const int n = tp.grid.n;
    if (tiling.onlyTile >= n * n)
        throw InvalidInputError("tile " + std::to_string(tiling.onlyTile) + " does not exist (there are " +
                                std::to_string(n * n) + " tiles, 0 to " + std::to_string(n * n - 1) + ")");
    result.features.radii = result.plan.radii;

    // Each tile's own vertices and the triangles of its grown box, sorted out in one pass each.
    const std::size_t nv = mesh.numVertices(), numTiles = std::size_t(n) * std::size_t(n);
    const Buckets ownVertices = bucketize(numTiles, nv, [&](std::size_t i, const auto& add) {
        add(tp.grid.tileOf(mesh.points[i]));
    });
    const Buckets tileTriangles = trianglesOfGrownTiles(mesh, tp.grid, halo, tiling.onlyTile);
    std::size_t tilesWithVertices = 0;
    for (int t = 0; t < n * n; ++t) tilesWithVertices += ownVertices.begin(t) != ownVertices.end(t);
    InvariantsOptions tileOptions = options;
    tileOptions.plan = result.plan;  // every tile takes the whole mesh's plan
    // A tile is sized by its vertices; spikes can still give it a surface the machine cannot
    // hold: refused at once with the estimate (docs/limits.md, Memory rule).
    if (tileOptions.memoryLimit == 0) tileOptions.memoryLimit = defaultMemoryLimit();
    tileOptions.evaluatedVertices = 0;  // a tile's numbering is its own
    std::size_t computed = 0;
    std::vector<std::uint32_t> local(nv, kNone), global;  // vertex numbers in and out of the tile
    for (int t = 0; t < n * n; ++t) {
        if ((tiling.onlyTile >= 0 && t != tiling.onlyTile) || ownVertices.begin(t) == ownVertices.end(t)) continue;
        TileResult part;
        part.tile = t;
        part.vertices.assign(ownVertices.begin(t), ownVertices.end(t));
        if (progress) {
            const std::size_t tiles = tiling.onlyTile >= 0 ? 1 : tilesWithVertices;
            progress->setPrefix("tile " + std::to_string(computed + 1) + " of " + std::to_string(tiles) + ": ");
        }
        part.values = computeInvariants(extractTile(mesh, tileTriangles, t, local, global), tileOptions, progress);
        if (progress) progress->setPrefix("");
        keepOwnRows(part.values.features, part.vertices, local);
        for (std::uint32_t v : global) local[v] = kNone;
        global.clear();
        result.cost += part.values.cost;
        sink(part);
        ++computed;
    }
    if (info) {
        info->tilesPerAxis = n;
        info->tiles = computed;
        info->largestTileVertices = tp.largest();
        info->haloWidth = halo;
        info->estimatedPeakBytes = tp.fixedBytes + tp.perVertex * double(tp.largest());
    }
    result.cost.total = total.seconds();
    return result;
}

} // namespace msii
