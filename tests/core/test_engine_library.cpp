// The libraries libmsii loads on first use (src/core/engine_library.h): a run loads only the
// large dependencies it needs. Each case runs in a process of its own (a death test that
// re-executes this program), so that what another case loaded does not count.
#include <msii/invariants/invariants.h>
#include <msii/samples/generators.h>
#include <msii/terrain/dem_compute.h>
#include <msii/terrain/raster_output.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "../support/temp_dir.h"

using namespace msii;

namespace {

/// Whether a library whose file name contains @p name is mapped into this process.
bool loaded(const std::string& name)
{
    std::ifstream maps("/proc/self/maps");
    for (std::string line; std::getline(maps, line);)
        if (line.find(name) != std::string::npos) return true;
    return false;
}

/// 1 + the first of @p names (whose entry in @p expected says whether it should be loaded) that
/// is not as expected; 0 if all are.
int firstUnexpected(const std::vector<std::pair<std::string, bool>>& expected)
{
    for (std::size_t k = 0; k < expected.size(); ++k)
        if (loaded(expected[k].first) != expected[k].second) return int(k) + 1;
    return 0;
}

} // namespace

// V, S, P and L on a mesh load the level set's library (OpenVDB), but neither GDAL nor the
// raster library: exit code k names the k-th library of the list that was not as expected.
TEST(EngineLibrary, MeshRunLoadsNoGdal)
{
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    const auto run = [] {
        samples::SphereOptions so;
        so.radius = 1, so.spacing = 0.1;
        InvariantsOptions o;
        o.radius = 0.3, o.scales = 4;
        computeInvariants(samples::makeSphere(so), o);
        return firstUnexpected({{"libmsii_levelset", true}, {"libopenvdb", true}, {"libmsii_raster", false},
                                {"libgdal", false}});
    };
    EXPECT_EXIT(std::exit(run()), ::testing::ExitedWithCode(0), "");
}

// A DEM on the height field loads GDAL (through the raster library) but not OpenVDB.
TEST(EngineLibrary, HeightFieldRunLoadsNoOpenVdb)
{
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    const auto run = [] {
        const test::TempDir dir;
        samples::DemSampleOptions d;
        d.surface.kind = samples::HeightFieldKind::Terrain;
        d.surface.width = d.surface.height = 30, d.surface.spacing = 1;
        const Dem dem = samples::makeDem(d);
        const std::string input = dir.file("dem.tif");
        writeRaster(input, dem.georeference, {{"height", dem.heights}});
        DemComputeOptions o;
        o.compute.invariants.radius = 4, o.compute.invariants.scales = 4;
        computeDem(input, dir.file("dem.msii.tif"), o);
        return firstUnexpected({{"libmsii_raster", true}, {"libgdal", true}, {"libmsii_levelset", false},
                                {"libopenvdb", false}});
    };
    EXPECT_EXIT(std::exit(run()), ::testing::ExitedWithCode(0), "");
}
