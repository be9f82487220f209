// A DEM's V and S on the height-field route (terrain/dem_compute.h, DemEngine::HeightField,
// the default): windows give the values of one piece bit for bit, masked and continued; the
// values agree with the mesh route on the same DEM within that route's own accuracy; a DEM
// cut through has, within R of the cut, the values of the uncut one within the bounds of the
// mesh route's cut test; a tilted plane is ½ up to its edges and across a filled gap; a run
// that asks for P or L takes the mesh route and says so.
#include <msii/core/errors.h>
#include <msii/samples/generators.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/dem_compute.h>
#include <msii/terrain/grid_continuation.h>
#include <msii/terrain/raster_output.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "../support/temp_dir.h"

using namespace msii;

namespace {

/// A 60 × 45 m terrain in 0.5 m cells with nodata patches of radius @p patch m, as a GeoTIFF.
std::string demFile(const test::TempDir& dir, const std::string& name, int patches, double patch)
{
    samples::DemSampleOptions d;
    d.surface.kind = samples::HeightFieldKind::Terrain;
    d.surface.width = 60;
    d.surface.height = 45;
    d.surface.spacing = 0.5;
    d.surface.relief = 4;
    d.surface.seed = 7;
    d.nodataPatches = patches;
    d.patchRadius = patch;
    const Dem dem = samples::makeDem(d);
    const std::string path = dir.file(name);
    writeRaster(path, dem.georeference, {{"height", dem.heights}}, RasterOutputOptions());
    return path;
}

/// A DEM of @p cols × @p rows cells of @p cell m in ETRS89 / UTM 32N, heights from @p z(x, y).
template <class Height>
std::string gridFile(const test::TempDir& dir, const std::string& name, int cols, int rows, double cell, Height z)
{
    RasterGeoreference g;
    g.width = cols, g.height = rows;
    g.transform = {500000, cell, 0, 5500000 + rows * cell, 0, -cell};
    g.crsWkt = crsWkt("EPSG:25832");
    std::vector<float> heights(std::size_t(cols) * std::size_t(rows));
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) heights[std::size_t(r) * std::size_t(cols) + std::size_t(c)] = float(z(c, r));
    const std::string path = dir.file(name);
    writeRaster(path, g, {{"height", heights}}, RasterOutputOptions());
    return path;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

DemComputeOptions options(double R, int N, std::vector<std::string> bands)
{
    DemComputeOptions o;
    o.compute.invariants.radius = R;
    o.compute.invariants.scales = N;
    o.bands = std::move(bands);
    o.float32 = true;
    return o;
}

/// Rolling terrain like a 1 m lidar DEM, scaled: hills, mounds, ditches (the mesh route's cut
/// test's, tests/pipeline/test_borders.cpp).
double terrainHeight(double x, double y, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double z = 3.0 * std::sin(x / 23.0 + 6.0 * u(rng)) * std::cos(y / 31.0 + 6.0 * u(rng)) + 0.02 * x;
    for (int k = 0; k < 25; ++k) {
        const double cx = 100 * u(rng), cy = 100 * u(rng), w = 2 + 6 * u(rng), a = -1.5 + 3 * u(rng);
        z += a * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * w * w));
    }
    for (int k = 0; k < 6; ++k) {
        const double th = M_PI * u(rng), c = 100 * u(rng);
        const double d = x * std::cos(th) + y * std::sin(th) - c;
        z -= 0.8 * std::exp(-d * d / 2.0);
    }
    return z;
}

} // namespace

TEST(DemHeights, WindowsEqualOnePieceMaskedAndContinued)
{
    const test::TempDir dir;
    const std::string input = demFile(dir, "dem.tif", 10, 1.2);
    for (const BorderHandling border : {BorderHandling::Mask, BorderHandling::Continue}) {
        SCOPED_TRACE(border == BorderHandling::Mask ? "mask" : "continue");
        DemComputeOptions o = options(4, 8, {"V_02", "V_08", "S_04", "S_08", "quality", "valid_radii", "filled_share", "height"});
        o.compute.border = border;
        const DemComputeResult one = computeDem(input, dir.file("one.tif"), o);
        EXPECT_EQ(one.engine, DemEngine::HeightField);
        EXPECT_TRUE(one.engineNote.empty());
        o.windowCells = 40;
        const DemComputeResult windows = computeDem(input, dir.file("windows.tif"), o);
        EXPECT_EQ(windows.windowsPerRow, 3);
        EXPECT_GT(windows.wideHaloWindows, 0);
        const RasterImage a = readRaster(dir.file("one.tif")), b = readRaster(dir.file("windows.tif"));
        ASSERT_EQ(a.bands.size(), o.bands.size());
        std::size_t compared = 0, differing = 0, nan = 0;
        for (std::size_t k = 0; k < a.bands.size(); ++k)
            for (std::size_t c = 0; c < a.bands[k].values.size(); ++c) {
                differing += !sameBits(a.bands[k].values[c], b.bands[k].values[c]);
                compared += !std::isnan(a.bands[k].values[c]);
                nan += std::isnan(a.bands[k].values[c]);
            }
        EXPECT_EQ(differing, 0u);
        EXPECT_GT(compared, 6u * 8000u);
        if (border == BorderHandling::Continue) {
            EXPECT_LT(nan, a.bands.size() * 300u);  // the nodata cells and those in no square
        } else {
            EXPECT_GT(nan, a.bands.size() * 300u);  // balls reaching the edge and the open gaps
        }
        std::remove(dir.file("one.tif").c_str());
        std::remove(dir.file("windows.tif").c_str());
    }
}

// The mesh route's V and S on terrain are within about 4e-4 to 1e-3 (mean) of exact, the
// height field's within 1e-4 (HeightField.RoughTerrainAgainstTheExactMode; docs/accuracy.md):
// the two routes agree to the mesh route's accuracy inside, and to the cut test's bounds with
// the edges and the gaps (filled and continued in each its own way).
TEST(DemHeights, AgreesWithTheMeshRoute)
{
    const test::TempDir dir;
    const std::string input = demFile(dir, "dem.tif", 8, 1.0);
    DemComputeOptions o = options(5, 8, {"V_04", "V_08", "S_08", "quality", "filled_share"});
    const DemComputeResult heights = computeDem(input, dir.file("heights.tif"), o);
    o.engine = DemEngine::Mesh;
    const DemComputeResult mesh = computeDem(input, dir.file("mesh.tif"), o);
    EXPECT_EQ(mesh.engine, DemEngine::Mesh);
    const RasterImage a = readRaster(dir.file("heights.tif")), b = readRaster(dir.file("mesh.tif"));
    const int cols = a.georeference.width, rows = a.georeference.height, edge = 12;  // R in cells, and 2
    for (std::size_t k = 0; k < a.bands.size(); ++k) {
        double inside = 0, all = 0;
        std::size_t nInside = 0, nAll = 0;
        for (int r = 0; r < rows; ++r)
            for (int c = 0; c < cols; ++c) {
                const std::size_t i = std::size_t(r) * std::size_t(cols) + std::size_t(c);
                const float x = a.bands[k].values[i], y = b.bands[k].values[i];
                ASSERT_EQ(std::isnan(x), std::isnan(y)) << a.bands[k].name << " cell " << i << ": heights " << x << ", mesh " << y;
                if (std::isnan(x)) continue;
                all += std::abs(x - y), ++nAll;
                if (c >= edge && r >= edge && c < cols - edge && r < rows - edge) inside += std::abs(x - y), ++nInside;
            }
        inside /= double(nInside), all /= double(nAll);
        std::printf("%s: mean |heights - mesh| %.2e inside, %.2e in all %zu cells\n", a.bands[k].name.c_str(), inside,
                    all, nAll);
        ASSERT_GT(nInside, 4000u);
        if (a.bands[k].name == "filled_share") {
            EXPECT_LE(all, 2e-2);
            continue;
        }
        EXPECT_LE(inside, 1e-3) << a.bands[k].name;
        EXPECT_LE(all, 3e-3) << a.bands[k].name;
    }
}

// The mesh route's cut test (Borders.CutTerrainMatchesTheUncut) on the raster: the DEM and its
// part past a cut along two sides; at the cells within R of the cut, V at every radius
// within mean 3e-3 and 95th percentile 1e-2 over all radii, and per radius mean 3e-3 and
// 95th percentile 1.5e-2.
TEST(DemHeights, CutDemMatchesTheUncut)
{
    const test::TempDir dir;
    for (const std::uint64_t seed : {3u, 11u}) {
        const int n = 160, c0 = n / 4, N = 8;
        const double h = 0.5, R = 8.0;
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> rough(-0.05, 0.05);
        std::vector<double> z(std::size_t(n) * n);
        for (int r = 0; r < n; ++r)
            for (int c = 0; c < n; ++c) z[std::size_t(r) * n + c] = terrainHeight(c * h, (n - 1 - r) * h, seed) + rough(rng);
        const std::string whole = gridFile(dir, "whole.tif", n, n, h, [&](int c, int r) { return z[std::size_t(r) * n + c]; });
        // The part right of and above the cut: columns and rows [c0, n) of the bottom-left
        // origin, that is columns [c0, n) and rows [0, n − c0) of the raster.
        const std::string cut = gridFile(dir, "cut.tif", n - c0, n - c0, h,
                                         [&](int c, int r) { return z[std::size_t(r) * n + c + c0]; });
        std::vector<std::string> bands;
        for (int j = 1; j <= N; ++j) bands.push_back(j < 10 ? "V_0" + std::to_string(j) : "V_" + std::to_string(j));
        computeDem(whole, dir.file("whole.msii.tif"), options(R, N, bands));
        computeDem(cut, dir.file("cut.msii.tif"), options(R, N, bands));
        const RasterImage a = readRaster(dir.file("whole.msii.tif")), b = readRaster(dir.file("cut.msii.tif"));
        std::vector<std::vector<double>> d(static_cast<std::size_t>(N));
        for (int r = 0; r < n - c0; ++r)
            for (int c = c0; c < n; ++c) {
                const double toCut = std::min(c - c0, n - c0 - 1 - r) * h, toFar = std::min((n - 1 - c) * h, r * h);
                if (toCut > R || toFar <= 2.5 * R) continue;
                for (int j = 0; j < N; ++j) {
                    const float x = a.bands[std::size_t(j)].values[std::size_t(r) * n + c],
                                y = b.bands[std::size_t(j)].values[std::size_t(r) * (n - c0) + (c - c0)];
                    ASSERT_FALSE(std::isnan(x) || std::isnan(y));
                    d[std::size_t(j)].push_back(std::abs(double(x) - double(y)));
                }
            }
        ASSERT_GT(d[0].size(), 200u);
        std::vector<double> all;
        for (int j = 0; j < N; ++j) {
            std::vector<double>& v = d[std::size_t(j)];
            all.insert(all.end(), v.begin(), v.end());
            double mean = 0;
            for (const double x : v) mean += x / double(v.size());
            std::sort(v.begin(), v.end());
            const double p95 = v[std::size_t(0.95 * double(v.size() - 1))];
            std::printf("cut, seed %d, V at r_%d: mean |d| %.2e, 95th percentile %.2e (%zu cells)\n", int(seed), j + 1,
                        mean, p95, v.size());
            EXPECT_LE(mean, 3e-3) << j;
            EXPECT_LE(p95, 1.5e-2) << j;
        }
        double mean = 0;
        for (const double x : all) mean += x / double(all.size());
        std::sort(all.begin(), all.end());
        EXPECT_LE(mean, 3e-3);
        EXPECT_LE(all[std::size_t(0.95 * double(all.size() - 1))], 1e-2);
        for (const char* f : {"whole.msii.tif", "cut.msii.tif", "whole.tif", "cut.tif"}) std::remove(dir.file(f).c_str());
    }
}

// A tilted plane is ½ at every cell, up to the edges (the continuation carries the plane on)
// and around a filled gap (the biharmonic fill of a plane is the plane).
TEST(DemHeights, PlaneIsOneHalfUpToTheEdgesAndAcrossGaps)
{
    const test::TempDir dir;
    const int n = 60;
    const std::string input = gridFile(dir, "plane.tif", n, n, 1.0, [&](int c, int r) {
        if ((c - 30) * (c - 30) + (r - 25) * (r - 25) <= 1) return std::numeric_limits<double>::quiet_NaN();
        return 200 + 0.4 * c - 0.7 * r;
    });
    const DemComputeResult result = computeDem(input, dir.file("plane.msii.tif"), options(6, 6, {"V_03", "V_06", "S_06", "filled_share"}));
    const RasterImage a = readRaster(dir.file("plane.msii.tif"));
    double worst = 0;
    std::size_t compared = 0;
    for (std::size_t k = 0; k < 3; ++k)
        for (const float v : a.bands[k].values)
            if (!std::isnan(v)) worst = std::max(worst, std::abs(double(v) - 0.5)), ++compared;
    std::printf("plane: largest |value - 1/2| %.1e over %zu values\n", worst, compared);
    EXPECT_GT(compared, 3u * 3500u);
    EXPECT_LE(worst, 2e-5);
    bool filled = false;
    for (const Diagnostic& d : result.diagnostics) filled = filled || d.kind == "holes_filled";
    EXPECT_TRUE(filled);
    // filled_share: about ½ along an edge, ¾ in a corner, 0 far from everything.
    const std::vector<float>& share = a.bands[3].values;
    EXPECT_NEAR(share[std::size_t(30) * n], 0.5, 0.05);
    EXPECT_NEAR(share[0], 0.75, 0.05);
    EXPECT_EQ(share[std::size_t(45) * n + 15], 0.0f);
}

// Radii far below a cell: the disc's quadrature covers the disc, not whole cells cut as
// finely as the disc needs (a radius of a thousandth of a cell once took minutes), the values
// of a tilted plane are ½, and the run says that such radii see only the cell's plane.
TEST(DemHeights, RadiiFarBelowACellAreComputedAndSaidSo)
{
    const test::TempDir dir;
    const int n = 20;
    const std::string input = gridFile(dir, "plane.tif", n, n, 1.0, [](int c, int r) { return 200 + 0.4 * c - 0.7 * r; });
    const auto belowCell = [](const DemComputeResult& r) {
        for (const Diagnostic& d : r.diagnostics)
            if (d.kind == "smallest_radius_below_cell") return true;
        return false;
    };
    const DemComputeResult tiny = computeDem(input, dir.file("tiny.tif"), options(0.004, 4, {"V_01", "V_04", "S_04"}));
    EXPECT_TRUE(belowCell(tiny));
    const RasterImage a = readRaster(dir.file("tiny.tif"));
    double worst = 0;
    std::size_t compared = 0;
    for (const RasterBand& band : a.bands)
        for (const float v : band.values)
            if (!std::isnan(v)) worst = std::max(worst, std::abs(double(v) - 0.5)), ++compared;
    std::printf("plane, R = 0.004 cells: largest |value - 1/2| %.1e over %zu values\n", worst, compared);
    EXPECT_EQ(compared, 3u * n * n);
    EXPECT_LE(worst, 1e-3);
    // Radii of whole cells: not said.
    EXPECT_FALSE(belowCell(computeDem(input, dir.file("cells.tif"), options(4, 4, {"V_04"}))));
}

// A radius larger than the whole DEM (R in other units than the DEM's, most likely) is
// refused before anything is computed: its balls would hold all of it, at a cost growing
// with R²; R as large as the DEM is computed.
TEST(DemHeights, RadiusBeyondTheWholeDemIsRefused)
{
    const test::TempDir dir;
    const std::string input = gridFile(dir, "plane.tif", 20, 10, 1.0, [](int c, int r) { return 200 + 0.4 * c - 0.7 * r; });
    try {
        computeDem(input, dir.file("wide.tif"), options(21, 4, {"V_04"}));
        ADD_FAILURE() << "R = 21 on a DEM 20 m across was computed";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("larger than the whole DEM (20"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("wide.tif")));
    EXPECT_EQ(computeDem(input, dir.file("whole.tif"), options(20, 4, {"V_04"})).input.numValid, 200u);
}

// Cells many times longer one way than the other are a broken pixel size (a GeoTIFF's
// ModelPixelScale of 1 × 9999): refused before anything is computed, with the command that
// makes them square; cells of 1 × 2 are computed.
TEST(DemHeights, CellsFarLongerOneWayAreRefused)
{
    const test::TempDir dir;
    const auto write = [&](const std::string& name, double cellHeight) {
        RasterGeoreference g;
        g.width = 30, g.height = 20;
        g.transform = {500000, 1.0, 0, 5500000, 0, -cellHeight};
        g.crsWkt = crsWkt("EPSG:25832");
        std::vector<float> heights(std::size_t(g.width) * std::size_t(g.height));
        for (std::size_t k = 0; k < heights.size(); ++k) heights[k] = float(100 + 0.01 * double(k % 30));
        writeRaster(dir.file(name), g, {{"height", heights}}, RasterOutputOptions());
        return dir.file(name);
    };
    const std::string needles = write("needles.tif", 9999), oblong = write("oblong.tif", 2);
    try {
        computeDem(needles, dir.file("needles.msii.tif"), options(4, 4, {"V_04"}));
        ADD_FAILURE() << "cells of 1 x 9999 were computed";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("far longer one way"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("gdalwarp -tr 1 1"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("needles.msii.tif")));
    const DemComputeResult r = computeDem(oblong, dir.file("oblong.msii.tif"), options(8, 4, {"V_04"}));
    EXPECT_EQ(r.input.numValid, 600u);
}

TEST(DemHeights, PAndLTakeTheMeshRouteAndSaySo)
{
    const test::TempDir dir;
    const std::string input = demFile(dir, "dem.tif", 0, 1.0);
    const DemComputeResult r = computeDem(input, dir.file("pl.tif"), options(3, 4, {"V_04", "P_04"}));
    EXPECT_EQ(r.engine, DemEngine::Mesh);
    EXPECT_NE(r.engineNote.find("P and L"), std::string::npos) << r.engineNote;
}

// The grid's continuation alone: heights and filled gaps are kept apart from continued cells,
// and a gap longer than the fill limit stays open (and is continued).
TEST(GridContinuation, FillsSmallGapsAndContinuesTheRest)
{
    HeightGrid g;
    g.cols = 30, g.rows = 20;
    g.z.assign(600, 5.0f);
    const auto set = [&](int c, int r) { g.z[std::size_t(r) * 30 + std::size_t(c)] = std::numeric_limits<float>::quiet_NaN(); };
    set(5, 5), set(6, 5);                          // small: 6 cell edges around, 9 long
    for (int c = 15; c < 25; ++c)
        for (int r = 8; r < 14; ++r) set(c, r);    // large: 32 edges, 48 long
    GridContinuationOptions o;
    o.maxHolePerimeter = 20;
    o.margin = 3;
    o.fitRadius = 2;
    const GridContinuationResult r = continueGrid(g, o);
    EXPECT_EQ(r.gapsFilled, 1u);
    EXPECT_EQ(r.cellsFilled, 2u);
    EXPECT_EQ(r.grid.cols, 36);
    const auto kind = [&](int c, int row) { return r.kind[std::size_t(row + 3) * 36 + std::size_t(c + 3)]; };
    const auto z = [&](int c, int row) { return r.grid.z[std::size_t(row + 3) * 36 + std::size_t(c + 3)]; };
    EXPECT_EQ(kind(5, 5), GridCell::Filled);
    EXPECT_FLOAT_EQ(z(5, 5), 5.0f);
    EXPECT_EQ(kind(20, 10), GridCell::Continued);
    EXPECT_FLOAT_EQ(z(20, 10), 5.0f);
    EXPECT_EQ(kind(-3, -3), GridCell::Continued);
    EXPECT_EQ(kind(10, 10), GridCell::Height);
    EXPECT_EQ(r.cellsContinued, 36u * 26u - 600u + 60u);
}
