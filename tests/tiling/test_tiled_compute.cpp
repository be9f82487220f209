// Tiled computation (tiling/tiled_compute.h) against the untiled one: every feature of every
// vertex bit-identical, NaN masks equal, on an open tablet and a closed sphere, for forced
// tile counts and for tiles sized from a memory budget; a budget too small for even one
// tile is refused with the amount needed.
#include <msii/core/errors.h>
#include <msii/samples/generators.h>
#include <msii/mesh/mesh_check.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/pipeline/compute.h>
#include <msii/tiling/tiled_compute.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

using namespace msii;

namespace {

/// computeTiles with the tiles' values gathered into whole columns (NaN for vertices in no
/// tile), as one result.
InvariantsResult computeTiled(const TriMesh& mesh, const InvariantsOptions& options, const TilingOptions& tiling,
                              TiledComputeInfo* info = nullptr)
{
    FeatureSet all;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    InvariantsResult result = computeTiles(
        mesh, options, tiling,
        [&](const TileResult& part) {
            for (Invariant i : part.values.features.invariants()) {
                FeatureColumns& to = all[i];
                const FeatureColumns& from = part.values.features[i];
                if (to.empty()) to.assign(from.size(), std::vector<float>(mesh.numVertices(), nan));
                for (std::size_t j = 0; j < from.size(); ++j)
                    for (std::size_t l = 0; l < part.vertices.size(); ++l) to[j][part.vertices[l]] = from[j][l];
            }
        },
        info);
    all.radii = result.plan.radii;
    result.features = std::move(all);
    return result;
}

/// Largest |tiled − untiled| over all features; NaN must match NaN. @p compared counts the
/// pairs of numbers compared (NaN/NaN pairs are not), so that a check of nothing shows.
double maxDifference(const InvariantsResult& a, const InvariantsResult& b, std::size_t& nanMismatches,
                     std::size_t* compared = nullptr)
{
    double worst = 0;
    nanMismatches = 0;
    if (compared) *compared = 0;
    const std::vector<std::vector<float>>* as[4] = {&a.features[Invariant::Volume], &a.features[Invariant::Sphere], &a.features[Invariant::Patch],
                                                    &a.features[Invariant::Line]};
    const std::vector<std::vector<float>>* bs[4] = {&b.features[Invariant::Volume], &b.features[Invariant::Sphere], &b.features[Invariant::Patch],
                                                    &b.features[Invariant::Line]};
    for (int q = 0; q < 4; ++q) {
        EXPECT_EQ(as[q]->size(), bs[q]->size());
        for (std::size_t j = 0; j < as[q]->size() && j < bs[q]->size(); ++j)
            for (std::size_t i = 0; i < (*as[q])[j].size(); ++i) {
                const float x = (*as[q])[j][i], y = (*bs[q])[j][i];
                if (std::isnan(x) != std::isnan(y)) ++nanMismatches;
                else if (!std::isnan(x)) {
                    worst = std::max(worst, double(std::abs(x - y)));
                    if (compared) ++*compared;
                }
            }
    }
    return worst;
}

/// The same mesh computed whole and in n × n tiles, and how far they differ.
struct TiledAgainstWhole {
    InvariantsResult tiled;
    TiledComputeInfo info;
    double diff = 0;
    std::size_t nanMismatches = 0, compared = 0;
};

TiledAgainstWhole tiledAgainstWhole(const TriMesh& mesh, const InvariantsOptions& co, int n)
{
    TriMesh whole = mesh, copy = mesh;
    const InvariantsResult untiled = computeInvariants(whole, co);
    TilingOptions to;
    to.tilesPerAxis = n;
    TiledAgainstWhole t;
    t.tiled = computeTiled(copy, co, to, &t.info);
    t.diff = maxDifference(untiled, t.tiled, t.nanMismatches, &t.compared);
    return t;
}

TriMesh tablet(double width = 18, double height = 12, double spacing = 0.12, std::uint64_t seed = 3)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = width;
    ho.height = height;
    ho.spacing = spacing;
    ho.seed = seed;
    return samples::makeHeightField(ho);
}

/// Prints how @p t compares (prefixed by @p what) and expects every value bit-identical.
void expectBitIdentical(const TiledAgainstWhole& t, const std::string& what)
{
    std::printf("%s: %zu values compared, max difference %.3g, NaN mismatches %zu\n", what.c_str(), t.compared, t.diff,
                t.nanMismatches);
    EXPECT_GT(t.compared, 0u) << what;
    EXPECT_EQ(t.diff, 0.0) << what;
    EXPECT_EQ(t.nanMismatches, 0u) << what;
}

/// A closed slab as scanners and meshers make them: the fine irregular tablet on top, and
/// side walls and a bottom of a few long triangles (bottom outline vertices @p bottomStep
/// apart, the bottom a fan).
TriMesh slabWithLongWalls(double width, double height, double spacing, double thickness, double bottomStep)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = width;
    ho.height = height;
    ho.spacing = spacing;
    ho.seed = 9;
    ho.closed = true;
    ho.thickness = thickness;
    ho.wallStep = bottomStep;
    return samples::makeHeightField(ho);
}

} // namespace

TEST(TiledCompute, SlabWithLongWallTrianglesEqualsUntiled)
{
    // A fine irregular top next to thin walls and a bottom of long triangles: the tiles hold
    // more or less surface per vertex than the whole mesh, so a route for P and L chosen per
    // level from a tile's own counts (samples against vertices) could differ from the whole
    // mesh's; it is chosen from the whole mesh's vertex spacing (docs/method.md, Where P and
    // L are evaluated).
    const TriMesh mesh = slabWithLongWalls(10, 8, 0.04, 1.0, 1.5);
    const MeshCheckResult check = checkMesh(mesh);
    ASSERT_TRUE(check.closed);
    ASSERT_EQ(check.numInconsistentEdges, 0u);
    ASSERT_EQ(check.firstProblem(), "");
    const MeshStats stats = computeMeshStats(mesh);
    std::printf("slab with long walls: %zu vertices, median edge %.3f, longest %.2f\n", mesh.numVertices(),
                stats.medianEdge, stats.maxEdge);
    ASSERT_GT(stats.maxEdge, 30 * stats.medianEdge);
    InvariantsOptions co;
    co.radius = 0.5;
    for (int n : {2, 3, 4}) {
        const TiledAgainstWhole t = tiledAgainstWhole(mesh, co, n);
        expectBitIdentical(t, "slab with long walls, " + std::to_string(n) + " x " + std::to_string(n) + " tiles");
    }
}

TEST(TiledCompute, OpenTabletEqualsUntiled)
{
    TriMesh mesh = tablet();
    InvariantsOptions co;
    co.radius = 1.0;
    TriMesh whole = mesh;
    const InvariantsResult untiled = computeInvariants(whole, co);
    for (int n : {2, 3}) {
        TilingOptions to;
        to.tilesPerAxis = n;
        TiledComputeInfo info;
        TriMesh copy = mesh;
        const InvariantsResult tiled = computeTiled(copy, co, to, &info);
        std::size_t nanMismatches = 0, compared = 0;
        const double diff = maxDifference(untiled, tiled, nanMismatches, &compared);
        std::printf("tablet %zu vertices, %d x %d tiles (%zu computed, largest %zu vertices, halo %.2f): "
                    "max difference %.3g, NaN mismatches %zu\n",
                    mesh.numVertices(), n, n, info.tiles, info.largestTileVertices, info.haloWidth, diff,
                    nanMismatches);
        EXPECT_EQ(info.tilesPerAxis, n);
        EXPECT_EQ(info.tiles, std::size_t(n * n));
        EXPECT_LT(info.largestTileVertices, mesh.numVertices());
        EXPECT_GT(compared, 0u);
        EXPECT_EQ(diff, 0.0);
        EXPECT_EQ(nanMismatches, 0u);
        EXPECT_DOUBLE_EQ(tiled.plan.voxelSize, untiled.plan.voxelSize);
    }
}

// A dense mesh (more vertices than samples on the coarse levels), so that P and L are
// evaluated at the samples and fitted to the vertices there: the longest chain of
// dependence (dependenceReach), which the halo must cover for identical values.
TEST(TiledCompute, DenseTabletEqualsUntiledBitForBit)
{
    const TriMesh mesh = tablet(7, 6, 0.03, 4);
    InvariantsOptions co;
    co.radius = 1.0;
    const TiledAgainstWhole t = tiledAgainstWhole(mesh, co, 2);
    expectBitIdentical(t, "dense tablet " + std::to_string(mesh.numVertices()) + " vertices, 2 x 2 tiles (halo " +
                              std::to_string(t.info.haloWidth) + ")");
}

// Every vertex moved onto a voxel face or centre plane: x and y multiples of 1/32 mm, which
// are exact binary numbers and multiples of h/2 for h = 1/48 mm, which is not. There a
// vertex's cell is a tie between two, decided by rounding: the tiles' grids are shifted by
// other whole blocks than the whole mesh's, and the tie must still be broken the same way:
// positions come from the global index, with the shift kept as a whole number of voxels
// (docs/method.md, Level set).
TEST(TiledCompute, VerticesOnVoxelPlanesEqualUntiledBitForBit)
{
    TriMesh mesh = tablet();
    InvariantsOptions co;
    co.radius = 1.0;
    co.voxelSize = 1.0 / 48.0;
    co.computePatch = co.computeLine = false;  // the tie is in V and S's cell choice
    const double step = 1.0 / 32.0;
    // Moved by 12 mm, where an index shifted in floating point would round ties both ways.
    for (Vec3& p : mesh.points)
        p.x = 12.0 + std::round(p.x / step) * step, p.y = 12.0 + std::round(p.y / step) * step;
    const TiledAgainstWhole t = tiledAgainstWhole(mesh, co, 3);
    expectBitIdentical(t, "tablet on voxel planes, " + std::to_string(mesh.numVertices()) + " vertices, 3 x 3 tiles");
}

TEST(TiledCompute, ClosedSphereEqualsUntiled)
{
    samples::SphereOptions so;
    so.radius = 4;
    so.spacing = 0.15;
    const TriMesh mesh = samples::makeSphere(so);
    InvariantsOptions co;
    co.radius = 1.0;
    const TiledAgainstWhole t = tiledAgainstWhole(mesh, co, 2);
    expectBitIdentical(t, "sphere " + std::to_string(mesh.numVertices()) + " vertices, 2 x 2 tiles");
    // A closed mesh: nothing is masked, tiled or not.
    ComputeOptions tiled;
    tiled.invariants = co;
    tiled.tiling.tilesPerAxis = 2;
    EXPECT_EQ(compute(mesh, tiled).masked.total(), 0u);
}

// The one entry point: the pipeline (pipeline/compute.h) with tilesPerAxis or a memory
// budget computes in tiles, with the values of one piece, and counts the masked values alike.
TEST(TiledCompute, FrontDoorTilesEqualOnePiece)
{
    const TriMesh mesh = tablet(10, 8, 0.12);
    ComputeOptions co;
    co.invariants.radius = 1.0;
    co.invariants.scales = 8;
    const ComputeResult whole = compute(mesh, co);
    EXPECT_EQ(whole.masked.total(), 0u);  // an open tablet: continued past its rim
    EXPECT_GT(whole.masked.withFilledShare, 0u);
    EXPECT_LT(whole.masked.withFilledShare, mesh.numVertices());
    for (const bool byBudget : {false, true}) {
        for (const bool streamed : {false, true}) {
            ComputeOptions tiled = co;
            if (byBudget) tiled.tiling.memoryBudget = 1e9;  // room for one tile: the budget route
            else tiled.tiling.tilesPerAxis = 3;
            InvariantsResult parts;
            ComputeResult r;
            if (streamed) {  // the pieces scattered back into whole columns
                const float nan = std::numeric_limits<float>::quiet_NaN();
                r = computeStreamed(mesh, tiled, [&](const ComputedPiece& piece) {
                    for (Invariant i : piece.features.invariants()) {
                        FeatureColumns& to = parts.features[i];
                        if (to.empty()) to.assign(piece.features[i].size(), std::vector<float>(mesh.numVertices(), nan));
                        for (std::size_t j = 0; j < to.size(); ++j)
                            for (std::size_t k = 0; k < piece.vertices.size(); ++k)
                                to[j][piece.vertices[k]] = piece.features[i][j][k];
                    }
                });
                EXPECT_TRUE(r.features[Invariant::Volume].empty());
            } else {
                r = compute(mesh, tiled);
                parts.features = r.features;
            }
            EXPECT_TRUE(r.tiled);
            EXPECT_EQ(r.masked.total(), whole.masked.total());
            InvariantsResult one;
            one.features = whole.features;
            TiledAgainstWhole t;
            t.diff = maxDifference(one, parts, t.nanMismatches, &t.compared);
            expectBitIdentical(t, std::string(byBudget ? "front door, memory budget 1 GB" : "front door, 3 x 3 tiles") +
                                      (streamed ? ", streamed" : ""));
        }
    }
    ComputeOptions exact = co;
    exact.invariants.exact = true;
    exact.tiling.tilesPerAxis = 2;
    EXPECT_THROW(compute(mesh, exact), InvalidInputError);
}

TEST(TiledCompute, TilesFromMemoryBudget)
{
    TriMesh mesh = tablet();
    InvariantsOptions co;
    co.radius = 1.0;
    co.computePatch = co.computeLine = false;  // quicker; V and S carry the tiling logic too
    TriMesh whole = mesh;
    const InvariantsResult untiled = computeInvariants(whole, co);
    const double budget = 0.5 * computationBytesPerVertex(co) * double(mesh.numVertices());
    TilingOptions to;
    to.memoryBudget = budget;
    TiledComputeInfo info;
    TriMesh copy = mesh;
    const InvariantsResult tiled = computeTiled(copy, co, to, &info);
    EXPECT_GE(info.tilesPerAxis, 2);
    EXPECT_LE(info.estimatedPeakBytes, budget);
    std::size_t nanMismatches = 0, compared = 0;
    EXPECT_EQ(maxDifference(untiled, tiled, nanMismatches, &compared), 0.0);
    EXPECT_EQ(nanMismatches, 0u);
    EXPECT_GT(compared, 0u);
}

TEST(TiledCompute, BudgetTooSmallForOneTile)
{
    TriMesh mesh = tablet();
    InvariantsOptions co;
    co.radius = 1.0;
    TilingOptions to;
    to.memoryBudget = 1e5;  // less than the mesh itself
    try {
        computeTiled(mesh, co, to);
        FAIL() << "a 100 kB budget was accepted";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("too small for even one tile"), std::string::npos) << e.what();
    }
    to.memoryBudget = 6e6;  // the mesh fits (4 MB), but tiles narrower than the halo would not
    try {
        computeTiled(mesh, co, to);
        FAIL() << "a 6 MB budget was accepted";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("too small for even one tile"), std::string::npos) << e.what();
    }
    to.memoryBudget = -1;
    EXPECT_THROW(computeTiled(mesh, co, to), InvalidInputError);
    to.memoryBudget = 0;
    to.tilesPerAxis = -2;
    EXPECT_THROW(computeTiled(mesh, co, to), InvalidInputError);
    co.exact = true;
    to.tilesPerAxis = 2;
    EXPECT_THROW(computeTiled(mesh, co, to), InvalidInputError);
}

// computeTiles (results handed over tile by tile, never held whole): every vertex arrives
// exactly once, in ascending order within its tile, with the values of the untiled run; the
// tiles' vertices are those of tileOfVertices; onlyTile hands over that tile alone; the
// returned result has no feature columns.
TEST(TiledCompute, TilesHandedToASinkCoverEveryVertexOnce)
{
    TriMesh mesh = tablet();
    InvariantsOptions co;
    co.radius = 1.0;
    co.computePatch = false;  // quicker; L still exercises the P/L columns
    TriMesh whole = mesh;
    const InvariantsResult untiled = computeInvariants(whole, co);
    TilingOptions to;
    to.tilesPerAxis = 3;
    const std::vector<int> owner = tileOfVertices(mesh, 3);
    std::vector<int> seen(mesh.numVertices(), 0);
    std::size_t parts = 0, mismatches = 0, outOfOrder = 0, wrongTile = 0;
    const auto sink = [&](const TileResult& part) {
        ++parts;
        ASSERT_EQ(part.values.features[Invariant::Volume].size(), untiled.features[Invariant::Volume].size());
        ASSERT_EQ(part.values.features[Invariant::Line].size(), untiled.features[Invariant::Line].size());
        EXPECT_TRUE(part.values.features[Invariant::Patch].empty());
        for (std::size_t l = 0; l < part.vertices.size(); ++l) {
            const std::uint32_t v = part.vertices[l];
            ++seen[v];
            if (l > 0 && v <= part.vertices[l - 1]) ++outOfOrder;
            if (owner[v] != part.tile) ++wrongTile;
            const auto check = [&](const std::vector<std::vector<float>>& got, const std::vector<std::vector<float>>& want) {
                for (std::size_t j = 0; j < want.size(); ++j) {
                    const float a = got[j][l], b = want[j][v];
                    if (std::isnan(a) != std::isnan(b) || (!std::isnan(a) && a != b)) ++mismatches;
                }
            };
            check(part.values.features[Invariant::Volume], untiled.features[Invariant::Volume]);
            check(part.values.features[Invariant::Sphere], untiled.features[Invariant::Sphere]);
            check(part.values.features[Invariant::Line], untiled.features[Invariant::Line]);
        }
    };
    TriMesh copy = mesh;
    const InvariantsResult tiled = computeTiles(copy, co, to, sink);
    EXPECT_EQ(parts, 9u);
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(mesh.numVertices()));
    EXPECT_EQ(outOfOrder, 0u);
    EXPECT_EQ(wrongTile, 0u);
    EXPECT_EQ(mismatches, 0u);  // bit-identical
    EXPECT_TRUE(tiled.features[Invariant::Volume].empty());

    to.onlyTile = 4;
    parts = 0;
    std::fill(seen.begin(), seen.end(), 0);
    TriMesh again = mesh;
    computeTiles(again, co, to, sink);
    EXPECT_EQ(parts, 1u);
    std::size_t inTile4 = 0, seenOutside = 0;
    for (std::size_t v = 0; v < seen.size(); ++v) {
        inTile4 += owner[v] == 4;
        seenOutside += owner[v] != 4 && seen[v] != 0;
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(inTile4));
    EXPECT_EQ(seenOutside, 0u);
    EXPECT_EQ(mismatches, 0u);
}
