// The DEM engine's mesh route in process (terrain/dem_compute.h, DemEngine::Mesh, or P and
// L asked; the height-field route: test_dem_heights.cpp): a generated GeoTIFF with nodata
// patches, computed in one window and in windows with halos, has the values of the
// pipeline (pipeline/compute.h) run on the DEM's whole mesh, bit for bit, cell by cell; a
// band that the options cannot give is refused before any computation, naming those that
// can; masked values are counted over the own cells. A window whose spikes make its surface
// exceed the memory limit is computed in smaller windows, with the values of one piece; one
// that stays too large when split is refused before anything is computed.
#include <msii/core/errors.h>
#include <msii/invariants/invariants.h>
#include <msii/io/feature_properties.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/pipeline/compute.h>
#include <msii/samples/generators.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/dem_compute.h>
#include <msii/terrain/raster_output.h>
#include <msii/tiling/tiled_compute.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "../support/temp_dir.h"

using namespace msii;

namespace {

/// A 60 × 45 m terrain in 0.5 m cells with 8 nodata patches, as a GeoTIFF.
std::string demFile(const test::TempDir& dir)
{
    samples::DemSampleOptions d;
    d.surface.kind = samples::HeightFieldKind::Terrain;
    d.surface.width = 60;
    d.surface.height = 45;
    d.surface.spacing = 0.5;
    d.surface.relief = 4;
    d.surface.seed = 7;
    d.nodataPatches = 8;
    d.patchRadius = 2.0;
    const Dem dem = samples::makeDem(d);
    const std::string path = dir.file("dem.tif");
    RasterOutputOptions ro;
    ro.nodata = -9999.0;
    writeRaster(path, dem.georeference, {{"height", dem.heights}}, ro);
    return path;
}

/// A 120 × 120 m terrain in 1 m cells with @p spikes cells raised 5 km, or (@p spikes < 0) a fifth of all cells raised by up to 5 km.
std::string spikyDemFile(const test::TempDir& dir, int spikes)
{
    samples::DemSampleOptions d;
    d.surface.kind = samples::HeightFieldKind::Terrain;
    d.surface.width = 120;
    d.surface.height = 120;
    d.surface.spacing = 1.0;
    d.surface.relief = 3;
    d.surface.seed = 11;
    Dem dem = samples::makeDem(d);
    std::uint32_t state = 12345;
    const auto next = [&] { return state = state * 1664525u + 1013904223u; };
    if (spikes < 0)
        for (float& z : dem.heights)
            if (next() % 5u == 0) z += float(next() % 5000u);
    for (int k = 0; k < spikes; ++k)
        dem.heights[next() % dem.heights.size()] += 5000.0f;
    const std::string path = dir.file(spikes < 0 ? "noise.tif" : "spikes.tif");
    writeRaster(path, dem.georeference, {{"height", dem.heights}}, RasterOutputOptions());
    return path;
}

DemComputeOptions demOptions()
{
    DemComputeOptions o;
    o.compute.invariants.radius = 4;
    o.compute.invariants.scales = 4;
    o.bands = {"V_02", "V_04", "S_04", "P_04", "L_04", "quality", "filled_share", "height"};
    return o;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

} // namespace

TEST(DemCompute, WindowsEqualThePipelineOnTheWholeMesh)
{
    const test::TempDir dir;
    const std::string input = demFile(dir);
    DemComputeOptions o = demOptions();
    const DemComputeResult one = computeDem(input, dir.file("one.tif"), o);
    EXPECT_EQ(one.windowsPerRow * one.windowsPerColumn, 1);
    o.windowCells = 40;
    const DemComputeResult windows = computeDem(input, dir.file("windows.tif"), o);
    EXPECT_EQ(windows.windowsPerRow, 3);
    EXPECT_EQ(windows.windowsPerColumn, 3);
    EXPECT_GT(windows.narrowHaloCells, 0);
    EXPECT_EQ(windows.masked.total(), one.masked.total());
    EXPECT_EQ(windows.masked.vertices, one.masked.vertices);

    // The same surface through the pipeline, as a mesh: the DEM's cells are its vertices.
    const DemMesh dm = demToMesh(readDem(input));
    const ComputeResult mesh = compute(dm.mesh, o.compute);
    const std::vector<VertexProperty> props = outputProperties(mesh.features, mesh.filledShare);
    const RasterImage a = readRaster(dir.file("one.tif")), b = readRaster(dir.file("windows.tif"));
    ASSERT_EQ(a.bands.size(), o.bands.size());
    ASSERT_EQ(b.bands.size(), o.bands.size());
    const std::vector<float> share = toCells(dm, mesh.filledShare);
    std::size_t compared = 0, differing = 0;
    for (std::size_t k = 0; k + 1 < o.bands.size(); ++k) {  // all but height
        const auto p = std::find_if(props.begin(), props.end(), [&](const VertexProperty& q) { return q.name == o.bands[k]; });
        ASSERT_NE(p, props.end()) << o.bands[k];
        const std::vector<float> cells = toCells(dm, p->values);
        ASSERT_EQ(a.bands[k].name, o.bands[k]);
        for (std::size_t c = 0; c < cells.size(); ++c) {
            // A cell in no triangle (no filled share) is nodata in every band.
            const float want = std::isnan(share[c]) ? std::numeric_limits<float>::quiet_NaN() : cells[c];
            differing += !sameBits(a.bands[k].values[c], want) + !sameBits(b.bands[k].values[c], want);
            compared += !std::isnan(want);
        }
    }
    EXPECT_EQ(differing, 0u);
    EXPECT_GT(compared, 5u * 8000u);
    EXPECT_EQ(one.masked.total(), mesh.masked.total());
}

TEST(DemCompute, BandsThatCannotBeGivenAreRefusedFirst)
{
    const test::TempDir dir;
    const std::string input = demFile(dir);
    DemComputeOptions o = demOptions();
    o.compute.invariants.select({Invariant::Volume});
    o.bands = {"quality", "S_04"};  // S is not computed
    try {
        computeDem(input, dir.file("out.tif"), o);
        FAIL() << "S_04 was accepted without S";
    } catch (const InvalidInputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("no feature 'S_04'"), std::string::npos) << what;
        EXPECT_NE(what.find("V_01 ... V_04, quality"), std::string::npos) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.tif")));
    o.bands = {"quality"};
    o.compute.tiling.tilesPerAxis = 2;
    EXPECT_THROW(computeDem(input, dir.file("out.tif"), o), InvalidInputError);
}

TEST(DemCompute, SpikyWindowsAreSplitAndKeepTheValuesOfOnePiece)
{
    const test::TempDir dir;
    const std::string input = spikyDemFile(dir, 20);
    DemComputeOptions o;
    o.compute.invariants.radius = 3;
    o.compute.invariants.scales = 4;
    o.compute.invariants.select({Invariant::Volume});
    o.bands = {"V_01", "V_04", "quality", "filled_share"};
    o.engine = DemEngine::Mesh;  // the mesh route's windows (the height field has no surface to split)
    const DemComputeResult one = computeDem(input, dir.file("one.tif"), o);
    ASSERT_EQ(one.windowsPerRow * one.windowsPerColumn, 1);
    EXPECT_EQ(one.splitWindows, 0);
    // A budget of half the whole surface's estimate: the raster fits one window by its cells
    // (1.2 kB each for V), not by its surface; it is split until each part's spikes fit.
    const double whole = surfaceBytesEstimate(computeMeshStats(demToMesh(readDem(input)).mesh).area, one.plan.voxelSize,
                                              o.compute.invariants);
    o.compute.tiling.memoryBudget = 0.5 * whole;
    ASSERT_GT(o.compute.tiling.memoryBudget, 120.0 * 120.0 * computationBytesPerVertex(o.compute.invariants));
    const DemComputeResult split = computeDem(input, dir.file("split.tif"), o);
    EXPECT_GT(split.splitWindows, 1);
    EXPECT_EQ(split.plan.voxelSize, one.plan.voxelSize);
    const RasterImage a = readRaster(dir.file("one.tif")), b = readRaster(dir.file("split.tif"));
    ASSERT_EQ(a.bands.size(), o.bands.size());
    ASSERT_EQ(b.bands.size(), o.bands.size());
    std::size_t compared = 0, differing = 0;
    for (std::size_t k = 0; k < o.bands.size(); ++k)
        for (std::size_t c = 0; c < a.bands[k].values.size(); ++c) {
            differing += !sameBits(a.bands[k].values[c], b.bands[k].values[c]);
            compared += !std::isnan(a.bands[k].values[c]);
        }
    EXPECT_EQ(differing, 0u);
    EXPECT_GT(compared, 4u * 14000u);
}

TEST(DemCompute, SpikesTooDenseForTheBudgetWhenSplitAreRefusedAtOnce)
{
    const test::TempDir dir;
    const std::string input = spikyDemFile(dir, -1);
    DemComputeOptions o;
    o.compute.invariants.radius = 3;
    o.compute.invariants.scales = 4;
    o.compute.tiling.memoryBudget = 50e6;
    o.engine = DemEngine::Mesh;
    try {
        computeDem(input, dir.file("out.tif"), o);
        FAIL() << "a surface of spikes 5 km high was computed in 50 MB";
    } catch (const MemoryLimitError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("the surface would take about"), std::string::npos) << what;
        EXPECT_NE(what.find("the smallest the raster is split into"), std::string::npos) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.tif")));
}
