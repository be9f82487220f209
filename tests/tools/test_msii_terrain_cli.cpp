// msii compute on DEM rasters (docs/terrain.md): georeferenced GeoTIFF out on the input's
// grid, the same values as the mesh path, nodata as holes, and bad rasters refused cleanly.
#include <msii/io/write_ply.h>
#include <msii/featuremap/feature_map.h>
#include <msii/io/read_mesh.h>
#include <msii/samples/generators.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/raster_output.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "../support/files.h"
#include "../support/run_program.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::RunResult;
using msii::test::runProgram;

namespace {

const fs::path& tempDir()
{
    static const msii::test::TempDir dir;
    return dir.path();
}

RunResult run(const std::string& program, const std::string& args) { return runProgram(program, args, tempDir()); }

/// The generated DEM of the tests: 160 × 120 cells of 0.5 m in EPSG:25832 (UTM-like
/// coordinates), hills of a few metres, 5 nodata patches (small ones: filled).
std::string demSample()
{
    static const std::string path = [] {
        const std::string p = (tempDir() / "dem.tif").string();
        const RunResult r = run(MSII_SAMPLES_EXE, "terrain --geotiff --width 80 --height 60 --spacing 0.5 --relief 4 "
                                                  "--holes 5 --hole-size 1.2 -q -o '" + p + "'");
        EXPECT_EQ(r.code, 0) << r.err;
        return p;
    }();
    return path;
}

/// gdalinfo -json of @p path.
std::string gdalinfo(const std::string& path)
{
    const RunResult r = run("gdalinfo", "-json '" + path + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    return r.out;
}

/// GDAL's checksum of each band of @p path (and of its overviews, if any), in order.
std::vector<std::string> bandChecksums(const std::string& path)
{
    const RunResult c = run("gdalinfo", "-checksum '" + path + "'");
    std::vector<std::string> sums;
    for (std::size_t at = c.out.find("Checksum="); at != std::string::npos; at = c.out.find("Checksum=", at + 1))
        sums.push_back(c.out.substr(at, c.out.find('\n', at) - at));
    return sums;
}

void expectCleanFailure(const std::string& input, const std::string& extra, const std::string& mentions)
{
    SCOPED_TRACE(input + " " + extra);
    const fs::path out = tempDir() / "bad.msii.tif";
    fs::remove(out);
    const RunResult r = run(MSII_EXE, "compute '" + input + "' -r 5 -n 4 " + extra + " --raster-output '" + out.string() + "'");
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(tempDir() / "bad.msii.json"));
    for (const auto& entry : fs::directory_iterator(tempDir()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

} // namespace

// The output is a GeoTIFF on the input's grid: same size, geotransform and coordinate
// system, one named band per feature, nodata as GDAL's own gdalinfo reads it (NaN in
// float32, 65535 in scaled 16-bit integers), and a Cloud-Optimized layout (with overviews
// in float32).
TEST(MsiiTerrain, GeoTiffOutIsGeoreferencedOnTheInputGrid)
{
    const fs::path out = tempDir() / "dem.msii.tif";
    const RunResult r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --bands quality,V_02,V_04,S_04 "
                                      "--raster-output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string info = gdalinfo(out.string());
    EXPECT_NE(info.find("ID[\\\"EPSG\\\",25832]]"), std::string::npos) << "EPSG:25832 is named";
    EXPECT_NE(info.find("ETRS89 / UTM zone 32N"), std::string::npos);
    for (const char* band : {"\"description\":\"quality\"", "\"description\":\"V_02\"", "\"description\":\"V_04\"",
                             "\"description\":\"S_04\""})
        EXPECT_NE(info.find(band), std::string::npos) << band;
    EXPECT_NE(info.find("\"noDataValue\":65535"), std::string::npos) << info;
    EXPECT_NE(info.find("\"scale\":0.0000152592"), std::string::npos) << info;
    EXPECT_NE(info.find("\"LAYOUT\":\"COG\""), std::string::npos);
    const fs::path floats = tempDir() / "dem_f32.msii.tif";
    const RunResult rf = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --float32 "
                                       "--raster-output '" + floats.string() + "'");
    ASSERT_EQ(rf.code, 0) << rf.err;
    EXPECT_NE(gdalinfo(floats.string()).find("\"noDataValue\":\"NaN\""), std::string::npos);
    // Overviews come with rasters larger than a tile (512 cells).
    const std::string large = (tempDir() / "large.tif").string();
    RasterGeoreference g;
    g.width = 1100, g.height = 700;
    g.crsWkt = crsWkt("EPSG:25832");
    writeRaster(large, g, {{"x", std::vector<float>(std::size_t(g.width) * std::size_t(g.height), 1.0f)}});
    EXPECT_NE(gdalinfo(large).find("\"overviews\":[\n        {\n          \"size\":[\n            550"), std::string::npos)
        << gdalinfo(large);

    const RasterImage in = readRaster(demSample()), got = readRaster(out.string());
    EXPECT_EQ(got.georeference.width, in.georeference.width);
    EXPECT_EQ(got.georeference.height, in.georeference.height);
    EXPECT_EQ(got.georeference.transform, in.georeference.transform);
    EXPECT_EQ(got.georeference.epsg, "25832");
    ASSERT_EQ(got.bands.size(), 4u);
    EXPECT_EQ(got.bands[0].name, "quality");
    // Nodata cells of the input are NaN in every band; cells with a height have a quality,
    // unless they are in no triangle (no 2 × 2 block of heights around them).
    const DemMesh dm = demToMesh(readDem(demSample()));
    std::vector<char> inTriangle(dm.mesh.numVertices(), 0);
    for (const Triangle& t : dm.mesh.triangles)
        for (std::uint32_t v : t) inTriangle[v] = 1;
    std::size_t nodata = 0;
    for (std::size_t k = 0; k < in.bands[0].values.size(); ++k) {
        const bool missing = in.bands[0].values[k] == float(in.nodata);
        nodata += missing;
        if (missing) {
            for (const RasterBand& b : got.bands) ASSERT_TRUE(std::isnan(b.values[k])) << b.name << " cell " << k;
        } else if (inTriangle[dm.vertexOfCell[k]]) {
            ASSERT_FALSE(std::isnan(got.bands[0].values[k])) << "quality at cell " << k;
        }
    }
    EXPECT_GT(nodata, 5u);
    const std::string json = readFile((tempDir() / "dem.msii.json").string());
    EXPECT_NE(json.find("\"units\": \"metre\""), std::string::npos);
    EXPECT_NE(json.find("\"holes_filled\""), std::string::npos) << "the small nodata patches are filled";
}

// The raster path computes what the mesh path computes on the same surface: the DEM's mesh
// (a vertex per cell centre, two triangles per square) written as a PLY and given to msii
// compute has the same values, bit for bit.
TEST(MsiiTerrain, EqualsTheMeshPathOnTheSameSurface)
{
    const fs::path raster = tempDir() / "same.msii.tif", ply = tempDir() / "same.ply", plyOut = tempDir() / "same.msii.ply";
    const DemMesh dm = demToMesh(readDem(demSample()));
    WritePlyOptions po;
    po.forceDoublePoints = true;  // the same coordinates exactly
    writePly(ply.string(), dm.mesh, {}, po);
    RunResult r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --bands V_01,V_04,S_04,P_04,L_04 "
                                "--raster-output '" + raster.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "compute '" + ply.string() + "' -r 5 -n 4 -q --overwrite -o '" + plyOut.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const RasterImage got = readRaster(raster.string());
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    std::map<std::string, std::vector<float>> mesh;
    for (auto& p : readMesh(plyOut.string(), ro).vertexProperties) mesh[p.name] = std::move(p.values);
    std::size_t compared = 0;
    for (const RasterBand& b : got.bands) {
        ASSERT_TRUE(mesh.count(b.name)) << b.name;
        const std::vector<float> cells = toCells(dm, mesh.at(b.name));
        ASSERT_EQ(cells.size(), b.values.size());
        for (std::size_t k = 0; k < cells.size(); ++k) {
            ASSERT_TRUE(std::memcmp(&cells[k], &b.values[k], sizeof(float)) == 0)
                << b.name << " cell " << k << ": mesh " << cells[k] << ", raster " << b.values[k];
            compared += !std::isnan(cells[k]);
        }
    }
    EXPECT_GT(compared, 5u * dm.mesh.numVertices() / 2);
}

// Rasters that cannot be computed: one error line, a non-zero exit, no output.
TEST(MsiiTerrain, BadRastersFailCleanly)
{
    const Dem good = readDem(demSample());
    const auto write = [&](const std::string& name, RasterGeoreference g, std::vector<RasterBand> bands) {
        const std::string p = (tempDir() / name).string();
        writeRaster(p, g, bands);
        return p;
    };
    RasterGeoreference noCrs = good.georeference;
    noCrs.crsWkt.clear();
    expectCleanFailure(write("nocrs.tif", noCrs, {{"height", good.heights}}), "", "no coordinate system");

    RasterGeoreference degrees = good.georeference;
    degrees.crsWkt = crsWkt("EPSG:4326");
    degrees.transform = {9.0, 1e-5, 0, 49.5, 0, -1e-5};
    const std::string inDegrees = write("degrees.tif", degrees, {{"height", good.heights}});
    expectCleanFailure(inDegrees, "", "gdalwarp -t_srs");
    // Without a radius too: the input's own problem comes first.
    const RunResult noRadius = run(MSII_EXE, "compute '" + inDegrees + "'");
    EXPECT_NE(noRadius.code, 0);
    EXPECT_EQ(std::count(noRadius.err.begin(), noRadius.err.end(), '\n'), 1) << noRadius.err;
    EXPECT_NE(noRadius.err.find("geographic coordinates (degrees)"), std::string::npos) << noRadius.err;
    // Bands the computation cannot give: refused before anything is computed, with the names.
    expectCleanFailure(demSample(), "--bands quality,V_99", "there is no feature 'V_99'");
    expectCleanFailure(demSample(), "--invariants V --bands S_04", "there is no feature 'S_04'");
    // A missing or unreadable raster is named as such, not as an unknown mesh extension.
    expectCleanFailure((tempDir() / "missing.asc").string(), "", "cannot open");
    msii::test::writeFile((tempDir() / "garbage.tif").string(), "garbage");
    expectCleanFailure((tempDir() / "garbage.tif").string(), "", "as a raster");

    const std::string twoBands = write("two.tif", good.georeference, {{"height", good.heights}, {"other", good.heights}});
    expectCleanFailure(twoBands, "", "2 bands");
    expectCleanFailure(twoBands, "--band 3", "no band 3");
    const fs::path chosen = tempDir() / "two.msii.tif";
    const RunResult r = run(MSII_EXE, "compute '" + twoBands + "' -r 5 -n 4 -q --band 2 --raster-output '" + chosen.string() + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(chosen));

    std::vector<float> none(good.heights.size(), std::numeric_limits<float>::quiet_NaN());
    expectCleanFailure(write("empty.tif", good.georeference, {{"height", none}}), "", "all nodata");

    const std::string garbage = (tempDir() / "garbage.tif").string();
    msii::test::writeFile(garbage, std::string(5000, 'x'));
    expectCleanFailure(garbage, "", "garbage.tif");
}

// A raster computed in windows (each with a halo) has the values of one piece, bit for bit:
// no seams at the windows' edges, also next to nodata patches and the raster's edge. The DEM
// has enough nodata patches that some windows need the wide halo (a gap crosses the narrow
// one's edge) and others do not, so both are compared.
TEST(MsiiTerrain, WindowsEqualOnePieceWithoutSeams)
{
    const std::string dem = (tempDir() / "patches.tif").string();
    RunResult r = run(MSII_SAMPLES_EXE, "terrain --geotiff --width 80 --height 60 --spacing 0.5 --relief 4 --holes 10 "
                                        "--hole-size 2.4 --seed 3 -q -o '" + dem + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    // Masked, some windows need the wide halo (a gap crosses the narrow one's edge) and others
    // do not; continued, every window with a border near it takes the wide one.
    for (const std::string border : {"mask", "continue"}) {
        SCOPED_TRACE("--border " + border);
        const fs::path one = tempDir() / ("one-" + border + ".msii.tif"),
                       windows = tempDir() / ("windows-" + border + ".msii.tif");
        const std::string common =
            " -r 5 -n 4 -q --overwrite --border " + border + " --bands V_02,V_04,S_04,P_04,L_04,quality,filled_share ";
        r = run(MSII_EXE, "compute '" + dem + "'" + common + "--raster-output '" + one.string() + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        r = run(MSII_EXE, "compute '" + dem + "'" + common + "--window-cells 50 --raster-output '" + windows.string() + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        const std::string json = readFile((tempDir() / ("windows-" + border + ".msii.json")).string());
        EXPECT_NE(json.find("\"per_row\": 4"), std::string::npos);
        const std::size_t at = json.find("\"windows_with_wide_halo\": ");
        ASSERT_NE(at, std::string::npos);
        const int wide = std::stoi(json.substr(at + 26));
        EXPECT_GT(wide, 0);
        if (border == "mask") {
            EXPECT_LT(wide, 12);
        }
        const RasterImage a = readRaster(one.string()), b = readRaster(windows.string());
        ASSERT_EQ(a.bands.size(), b.bands.size());
        std::size_t compared = 0, differing = 0, nan = 0;
        for (std::size_t k = 0; k < a.bands.size(); ++k) {
            ASSERT_EQ(a.bands[k].name, b.bands[k].name);
            for (std::size_t c = 0; c < a.bands[k].values.size(); ++c) {
                const float x = a.bands[k].values[c], y = b.bands[k].values[c];
                differing += std::memcmp(&x, &y, sizeof(float)) != 0;
                compared += !std::isnan(x);
                nan += std::isnan(x);
            }
        }
        EXPECT_EQ(differing, 0u);
        EXPECT_GT(compared, 6u * 12000u);
        // Continued, only cells in no triangle (nodata around them) are NaN.
        if (border == "continue") {
            EXPECT_LT(double(nan), 0.25 * double(compared)) << nan;
        }
    }
}

// A folder of adjacent DEM tiles, joined as a VRT mosaic with gdalbuildvrt, is computed as one
// surface: its values are those of the undivided DEM, bit for bit, with no seams where the
// tiles meet.
TEST(MsiiTerrain, MosaicOfTilesHasNoSeams)
{
    const fs::path folder = tempDir() / "tiles";
    fs::create_directories(folder);
    const RasterImage whole = readRaster(demSample());
    const int w = whole.georeference.width, h = whole.georeference.height;
    std::string list;
    for (int k = 0; k < 4; ++k) {  // 2 x 2 tiles of unequal sizes
        const int c0 = k % 2 ? 70 : 0, r0 = k / 2 ? 45 : 0;
        const int cols = k % 2 ? w - 70 : 70, rows = k / 2 ? h - 45 : 45;
        const std::string tile = (folder / ("tile" + std::to_string(k) + ".tif")).string();
        const RunResult r = run("gdal_translate", "-q -srcwin " + std::to_string(c0) + " " + std::to_string(r0) + " " +
                                                      std::to_string(cols) + " " + std::to_string(rows) + " '" +
                                                      demSample() + "' '" + tile + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        list += " '" + tile + "'";
    }
    const std::string vrt = (tempDir() / "mosaic.vrt").string();
    RunResult r = run("gdalbuildvrt", "-q '" + vrt + "'" + list);
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path a = tempDir() / "whole.msii.tif", b = tempDir() / "mosaic.msii.tif";
    const std::string common = " -r 5 -n 4 -q --overwrite --bands V_04,S_04,quality ";
    r = run(MSII_EXE, "compute '" + demSample() + "'" + common + "--raster-output '" + a.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "compute '" + vrt + "'" + common + "--raster-output '" + b.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const RasterImage x = readRaster(a.string()), y = readRaster(b.string());
    EXPECT_EQ(y.georeference.transform, x.georeference.transform);
    EXPECT_EQ(y.georeference.epsg, "25832");
    ASSERT_EQ(x.bands.size(), y.bands.size());
    std::size_t compared = 0;
    for (std::size_t k = 0; k < x.bands.size(); ++k) {
        ASSERT_EQ(x.bands[k].values.size(), y.bands[k].values.size());
        EXPECT_EQ(std::memcmp(x.bands[k].values.data(), y.bands[k].values.data(), x.bands[k].values.size() * sizeof(float)), 0)
            << x.bands[k].name;
        for (float v : x.bands[k].values) compared += !std::isnan(v);
    }
    EXPECT_GT(compared, 2u * 15000u);
}

// Other formats and grids: the same DEM as an ESRI ASCII grid gives the same values as the
// GeoTIFF; a DEM with rectangular cells (0.5 × 0.75 m) computes, and its result keeps them.
TEST(MsiiTerrain, AsciiGridsAndRectangularCells)
{
    const std::string asc = (tempDir() / "dem.asc").string();
    RunResult r = run("gdal_translate", "-q -of AAIGrid '" + demSample() + "' '" + asc + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path fromTif = tempDir() / "fromtif.msii.tif", fromAsc = tempDir() / "fromasc.msii.tif";
    const std::string common = " -r 5 -n 4 -q --overwrite --bands V_04,quality ";
    r = run(MSII_EXE, "compute '" + demSample() + "'" + common + "--raster-output '" + fromTif.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "compute '" + asc + "'" + common + "--raster-output '" + fromAsc.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const RasterImage a = readRaster(fromTif.string()), b = readRaster(fromAsc.string());
    ASSERT_EQ(a.bands.size(), b.bands.size());
    std::size_t finite = 0;
    double worst = 0;
    for (std::size_t k = 0; k < a.bands.size(); ++k)
        for (std::size_t c = 0; c < a.bands[k].values.size(); ++c) {
            const float x = a.bands[k].values[c], y = b.bands[k].values[c];
            ASSERT_EQ(std::isnan(x), std::isnan(y)) << c;
            if (!std::isnan(x)) worst = std::max(worst, double(std::abs(x - y))), ++finite;
        }
    EXPECT_GT(finite, 20000u);
    // The ASCII grid stores heights as decimal text: the same surface up to that rounding.
    EXPECT_LE(worst, 1e-3);

    Dem dem = readDem(demSample());
    dem.georeference.transform[5] = -0.75;  // rows 0.75 m apart, columns 0.5 m
    const std::string stretched = (tempDir() / "stretched.tif").string();
    writeRaster(stretched, dem.georeference, {{"height", dem.heights}});
    const fs::path out = tempDir() / "stretched.msii.tif";
    r = run(MSII_EXE, "compute '" + stretched + "' -r 5 -n 4 -q --overwrite --raster-output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const RasterImage s = readRaster(out.string());
    EXPECT_EQ(s.georeference.transform, dem.georeference.transform);
    std::size_t values = 0;
    for (float v : s.bands.back().values) values += !std::isnan(v) && v > 0.3f && v < 0.7f;
    EXPECT_GT(values, dem.numValid * 9 / 10);  // quality of gentle terrain: near the plane's 0.5
}

// msii render and msii map take the GeoTIFF too: a picture, and an EXR map seen from above
// with a pixel per cell, in the raster's units, the heights from the DEM it names.
TEST(MsiiTerrain, RenderAndMapTakeTheGeoTiff)
{
    const fs::path out = tempDir() / "pictured.msii.tif";
    RunResult r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --raster-output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path png = tempDir() / "pictured.png", exr = tempDir() / "pictured.map.exr";
    r = run(MSII_EXE, "render '" + out.string() + "' --shade --isolines 3 --pixels 400 --overwrite -o '" + png.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_GT(fs::file_size(png), 10000u);
    r = run(MSII_EXE, "map '" + out.string() + "' --overwrite -q -o '" + exr.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const FeatureMapImage map = readFeatureMap(exr.string(), {"height", "quality", "mask"});
    EXPECT_EQ(map.units, "m");
    EXPECT_DOUBLE_EQ(map.frame.pixelSize, 0.5);
    EXPECT_EQ(map.width, 160);  // a pixel per cell: the DEM's 160 × 120
    EXPECT_EQ(map.height, 120);
    EXPECT_EQ(map.radii.size(), 4u);
    ASSERT_TRUE(map.channels.count("quality") && map.channels.count("height"));
    std::size_t covered = 0;
    for (float m : map.channels.at("mask")) covered += m == 1.0f;
    EXPECT_GT(covered, std::size_t(map.width) * std::size_t(map.height) * 9 / 10);
}

// Only what is written is computed: the default bands (quality, then V at every radius) need
// V alone, and the record says so; V's bands are those of a run that computes P as well,
// bit for bit. quality comes first, so that a GIS opens the file on it.
TEST(MsiiTerrain, ComputesOnlyWhatTheBandsNeedAndQualityComesFirst)
{
    const fs::path onlyV = tempDir() / "only_v.msii.tif", withP = tempDir() / "with_p.msii.tif";
    // On the mesh route (P asked takes it): the same level set with P or without.
    const std::string common = "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --float32 --engine mesh ";
    RunResult r = run(MSII_EXE, common + "--raster-output '" + onlyV.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string record = readFile((tempDir() / "only_v.msii.json").string());
    EXPECT_NE(record.find("\"invariants_computed\": [\n      \"V\"\n    ]"), std::string::npos) << record;
    r = run(MSII_EXE, common + "--bands quality,V_01,V_02,V_03,V_04,P_04 --raster-output '" + withP.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string info = gdalinfo(onlyV.string());
    const std::size_t first = info.find("\"description\":\"", info.find("\"bands\":["));
    ASSERT_NE(first, std::string::npos) << info;
    EXPECT_EQ(info.compare(first, 23, "\"description\":\"quality\""), 0) << info.substr(first, 40);
    // The bands' checksums, in band order: the five of onlyV are withP's first five.
    const std::vector<std::string> a = bandChecksums(onlyV.string()), b = bandChecksums(withP.string());
    ASSERT_GE(a.size(), 5u);  // overviews may add more
    ASSERT_GE(b.size(), 6u);
    for (std::size_t band = 0; band < 5; ++band) EXPECT_EQ(a[band], b[band]) << "band " << band + 1;
}

// A DEM in degrees is refused with the command for its own UTM zone (from its centre), and
// that command gives a DEM msii computes. Here at 15° E, 46° N: zone 33 north, EPSG:32633.
TEST(MsiiTerrain, DegreesHintNamesTheUtmZoneOfTheDem)
{
    EXPECT_EQ(utmCrsFor(15.0, 46.0), "EPSG:32633");
    EXPECT_EQ(utmCrsFor(-99.0, 31.0), "EPSG:32614");   // Texas
    EXPECT_EQ(utmCrsFor(151.2, -33.9), "EPSG:32756");  // Sydney, south
    EXPECT_EQ(utmCrsFor(179.9, 10.0), "EPSG:32660");
    EXPECT_EQ(utmCrsFor(-180.0, 10.0), "EPSG:32601");
    const std::string utm = (tempDir() / "zone33.tif").string(), degrees = (tempDir() / "zone33_deg.tif").string();
    RunResult r = run(MSII_SAMPLES_EXE, "terrain --geotiff --width 60 --height 40 --spacing 1 --relief 3 --crs EPSG:32633 "
                                        "--offset 500000,5094000,300 -q -o '" + utm + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run("gdalwarp", "-q -t_srs EPSG:4326 '" + utm + "' '" + degrees + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    expectCleanFailure(degrees, "", "gdalwarp -t_srs EPSG:32633 -r bilinear zone33_deg.tif zone33_deg_utm.tif");
    // The hint, followed word for word in the DEM's folder.
    r = run("sh", "-c 'cd \"" + tempDir().string() + "\" && gdalwarp -q -t_srs EPSG:32633 -r bilinear zone33_deg.tif zone33_deg_utm.tif'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "compute '" + (tempDir() / "zone33_deg_utm.tif").string() + "' -r 5 -n 4 -q --overwrite");
    EXPECT_EQ(r.code, 0) << r.err;
}

// A raster without a coordinate system: the hint names a command that works for any format
// (an ESRI ASCII grid here, for which gdal_edit.py writes an .aux.xml that GDAL ignores),
// and names no system of its own that could mislabel the data.
TEST(MsiiTerrain, NoCrsHintWorksForAsciiGrids)
{
    const std::string asc = (tempDir() / "nocrs.asc").string();
    RunResult r = run("gdal_translate", "-q -of AAIGrid '" + demSample() + "' '" + asc + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    fs::remove(tempDir() / "nocrs.prj");
    fs::remove(tempDir() / "nocrs.asc.aux.xml");
    expectCleanFailure(asc, "", "gdal_translate -a_srs EPSG:<code> nocrs.asc nocrs_crs.tif");
    r = run("sh", "-c 'cd \"" + tempDir().string() + "\" && gdal_translate -q -a_srs EPSG:25832 nocrs.asc nocrs_crs.tif'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "compute '" + (tempDir() / "nocrs_crs.tif").string() + "' -r 5 -n 4 -q --overwrite");
    EXPECT_EQ(r.code, 0) << r.err;
}

// The default bands (fractions in [0, 1]) are written as 16-bit integers with GDAL's scale:
// within 7.7e-6 of the float32 values (--float32), NaN where they are NaN, and smaller
// (how much depends on the data: docs/terrain.md); a band that is no fraction (height)
// keeps float32.
TEST(MsiiTerrain, FractionsAreWrittenAsScaledIntegers)
{
    const fs::path scaled = tempDir() / "scaled.msii.tif", floats = tempDir() / "floats.msii.tif",
                   mixed = tempDir() / "mixed.msii.tif";
    const std::string common = "compute '" + demSample() + "' -r 5 -n 8 -q --overwrite ";
    RunResult r = run(MSII_EXE, common + "--raster-output '" + scaled.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, common + "--float32 --raster-output '" + floats.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, common + "--bands quality,height --raster-output '" + mixed.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(gdalinfo(scaled.string()).find("\"type\":\"UInt16\""), std::string::npos);
    EXPECT_NE(gdalinfo(floats.string()).find("\"type\":\"Float32\""), std::string::npos);
    EXPECT_NE(gdalinfo(mixed.string()).find("\"type\":\"Float32\""), std::string::npos);
    EXPECT_NE(readFile((tempDir() / "scaled.msii.json").string()).find("\"values\": \"uint16"), std::string::npos);
    const RasterImage a = readRaster(scaled.string()), b = readRaster(floats.string());
    ASSERT_EQ(a.bands.size(), 5u);
    const std::vector<std::string> names{"quality", "V_02", "V_04", "V_06", "V_08"};  // R/4, R/2, 3R/4, R
    for (std::size_t k = 0; k < names.size(); ++k) EXPECT_EQ(a.bands[k].name, names[k]);
    ASSERT_EQ(b.bands.size(), a.bands.size());
    std::size_t compared = 0, nan = 0;
    double largest = 0;
    for (std::size_t k = 0; k < a.bands.size(); ++k) {
        EXPECT_EQ(a.bands[k].name, b.bands[k].name);
        for (std::size_t c = 0; c < a.bands[k].values.size(); ++c) {
            const float x = a.bands[k].values[c], y = b.bands[k].values[c];
            ASSERT_EQ(std::isnan(x), std::isnan(y)) << a.bands[k].name << " cell " << c;
            if (std::isnan(x)) {
                ++nan;
                continue;
            }
            largest = std::max(largest, double(std::abs(x - y)));
            ++compared;
        }
    }
    EXPECT_GT(compared, 5u * 10000u);
    EXPECT_GT(nan, 0u);  // the sample's nodata patches
    EXPECT_LE(largest, 7.7e-6);
    EXPECT_LT(double(fs::file_size(scaled)), 0.8 * double(fs::file_size(floats)));
}

// One job per source tile of a mosaic: --tile-of-mosaic computes a tile's cells on its own
// grid, `msii merge` joins the tiles into a VRT with the band names and scale, equal to the
// mosaic computed in one piece (checksums of every band); a tile's output finds its DEM
// again relative to itself (render --shade) after the folder has moved.
TEST(MsiiTerrain, TilesOfAMosaicJoinedEqualOnePiece)
{
    const fs::path dir = tempDir() / "mosaic";
    fs::create_directories(dir / "parts");
    const std::string d = "'" + dir.string() + "/";
    struct Cut { int c0, r0, cols, rows; };
    const Cut cuts[4] = {{0, 0, 70, 50}, {70, 0, 90, 50}, {0, 50, 85, 70}, {85, 50, 75, 70}};
    std::string sources;
    for (int k = 0; k < 4; ++k) {
        const Cut& c = cuts[k];
        const RunResult r = run("gdal_translate", "-q -srcwin " + std::to_string(c.c0) + " " + std::to_string(c.r0) + " " +
                                                      std::to_string(c.cols) + " " + std::to_string(c.rows) + " '" +
                                                      demSample() + "' " + d + "t" + std::to_string(k + 1) + ".tif'");
        ASSERT_EQ(r.code, 0) << r.err;
        sources += " " + d + "t" + std::to_string(k + 1) + ".tif'";
    }
    RunResult r = run("gdalbuildvrt", "-q " + d + "mosaic.vrt'" + sources);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string common = " -r 5 -n 4 -q --overwrite ";
    r = run(MSII_EXE, "compute " + d + "mosaic.vrt'" + common + "--raster-output " + d + "whole.msii.tif'");
    ASSERT_EQ(r.code, 0) << r.err;
    std::string parts;
    for (int k = 1; k <= 4; ++k) {
        r = run(MSII_EXE, "compute " + d + "mosaic.vrt'" + common + "--tile-of-mosaic t" + std::to_string(k) +
                              " --output-dir " + d + "parts'");
        ASSERT_EQ(r.code, 0) << r.err;
        parts += " " + d + "parts/t" + std::to_string(k) + ".msii.tif'";
    }
    r = run(MSII_EXE, "merge" + parts + " -q -o " + d + "joined.msii.vrt'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::vector<std::string> whole = bandChecksums((dir / "whole.msii.tif").string()),
                                   joined = bandChecksums((dir / "joined.msii.vrt").string());
    ASSERT_EQ(whole.size(), 5u);
    EXPECT_EQ(joined, whole);
    const std::string info = gdalinfo((dir / "joined.msii.vrt").string());
    EXPECT_NE(info.find("\"description\":\"quality\""), std::string::npos);
    EXPECT_NE(info.find("\"scale\":0.0000152592"), std::string::npos);
    EXPECT_NE(readFile((dir / "parts" / "t2.msii.json").string()).find("\"tile_of_mosaic\""), std::string::npos);
    // Moved with its DEM: the part finds the mosaic's heights under its own cells.
    const fs::path moved = tempDir() / "mosaic-moved";
    fs::rename(dir, moved);
    r = run(MSII_EXE, "render '" + (moved / "parts" / "t2.msii.tif").string() + "' --shade -q -o '" +
                          (moved / "t2.png").string() + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    // A tile that is not the mosaic's is refused.
    r = run(MSII_EXE, "compute '" + (moved / "mosaic.vrt").string() + "'" + common + "--tile-of-mosaic t9");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find("none of the files"), std::string::npos) << r.err;
}

// Without --radius a DEM gets a suggestion from its cells (15 cells: 7.5 m on the sample's
// 0.5 m), and without --scales N = R / cell size, so that the smallest radius is a cell and
// the run does not warn that it is below the edge length.
TEST(MsiiTerrain, RadiusSuggestionAndRadiiOfWholeCells)
{
    RunResult r = run(MSII_EXE, "compute '" + demSample() + "'");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find("try --radius 7.5"), std::string::npos) << r.err;
    const fs::path out = tempDir() / "whole_cells.msii.tif";
    r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 --overwrite --raster-output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("smallest radius"), std::string::npos) << r.err;
    const std::string record = readFile((tempDir() / "whole_cells.msii.json").string());
    EXPECT_NE(record.find("\"scales\": 10"), std::string::npos) << record.substr(0, 2000);
    // A letter alone: that invariant at every radius.
    r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --bands quality,v --raster-output '" +
                          out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string info = gdalinfo(out.string());
    for (const char* band : {"quality", "V_01", "V_02", "V_03", "V_04"})
        EXPECT_NE(info.find("\"description\":\"" + std::string(band) + "\""), std::string::npos) << band;
    // Given, N is kept.
    r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --raster-output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(readFile((tempDir() / "whole_cells.msii.json").string()).find("\"scales\": 4"), std::string::npos);
}

// metric and smooth take msii compute's GeoTIFF and give a GeoTIFF on its grid (for a GIS,
// e.g. the QGIS plugin): the values of the same commands' PLY on the DEM's mesh, cell for
// vertex; NaN where a cell has no height; the DEM named, so that render --shade finds it. A
// GeoTIFF with V at some radii only (the default bands) is refused with the bands to write.
TEST(MsiiTerrain, MetricAndSmoothWriteGeoTiffsOnTheGrid)
{
    const fs::path features = tempDir() / "every.msii.tif";
    RunResult r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 4 -q --overwrite --bands quality,V "
                                "--raster-output '" + features.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path metricTif = tempDir() / "every.metric.tif", metricPly = tempDir() / "every.metric.ply";
    r = run(MSII_EXE, "metric '" + features.string() + "' -m mahalanobis,l2w -q --overwrite -o '" + metricTif.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "metric '" + features.string() + "' -m mahalanobis,l2w -q --overwrite -o '" + metricPly.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path smoothTif = tempDir() / "every.smooth.tif", smoothPly = tempDir() / "every.smooth.ply";
    r = run(MSII_EXE, "smooth '" + metricTif.string() + "' --properties quality,f_l2w -k 5 -q --overwrite -o '" +
                          smoothTif.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "smooth '" + metricTif.string() + "' --properties quality,f_l2w -k 5 -q --overwrite -o '" +
                          smoothPly.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;

    const RasterImage dem = readRaster(demSample());
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    for (const auto& [tif, ply, names] :
         {std::tuple{metricTif, metricPly, std::vector<std::string>{"quality", "f_mahalanobis", "f_l2w"}},
          std::tuple{smoothTif, smoothPly, std::vector<std::string>{"quality", "f_l2w"}}}) {
        SCOPED_TRACE(tif.filename().string());
        const RasterImage got = readRaster(tif.string());
        EXPECT_EQ(got.georeference.width, dem.georeference.width);
        EXPECT_EQ(got.georeference.transform, dem.georeference.transform);
        ASSERT_EQ(got.bands.size(), names.size());
        std::map<std::string, std::vector<float>> mesh;
        for (auto& p : readMesh(ply.string(), ro).vertexProperties) mesh[p.name] = std::move(p.values);
        for (std::size_t b = 0; b < names.size(); ++b) {
            EXPECT_EQ(got.bands[b].name, names[b]);
            ASSERT_TRUE(mesh.count(names[b])) << names[b];
            // The DEM's mesh has a vertex per cell with a height, in row-major order.
            std::size_t v = 0, compared = 0;
            for (std::size_t c = 0; c < got.bands[b].values.size(); ++c) {
                const float h = dem.bands[0].values[c], x = got.bands[b].values[c];
                if (std::isnan(h) || h == float(dem.nodata)) {
                    EXPECT_TRUE(std::isnan(x)) << "cell " << c;
                    continue;
                }
                ASSERT_LT(v, mesh[names[b]].size());
                const float y = mesh[names[b]][v++];
                if (std::isnan(x)) continue;  // the PLY writes quality 0 there for viewers
                EXPECT_EQ(x, y) << names[b] << " cell " << c;
                ++compared;
            }
            EXPECT_EQ(v, mesh[names[b]].size());
            EXPECT_GT(compared, got.bands[b].values.size() / 2);
        }
        const auto& md = got.metadata;
        EXPECT_NE(std::find(md.begin(), md.end(), std::pair<std::string, std::string>{"MSII_INPUT", "dem.tif"}), md.end());
    }
    const fs::path png = tempDir() / "every.metric.png";
    r = run(MSII_EXE, "render '" + smoothTif.string() + "' --shade --pixels 300 -q --overwrite -o '" + png.string() + "'");
    EXPECT_EQ(r.code, 0) << r.err;

    const fs::path defaults = tempDir() / "defaults.msii.tif";
    r = run(MSII_EXE, "compute '" + demSample() + "' -r 5 -n 8 -q --overwrite --raster-output '" + defaults.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, "metric '" + defaults.string() + "' -q --overwrite");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find("V at some radii only (V_02, V_04, V_06, V_08)"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--bands quality,V"), std::string::npos) << r.err;
}

namespace {

/// A DEM of @p n × @p n cells of 1 m in EPSG:25832: gentle hills of @p heights, whose
/// @p patch cells (a square from (50, 50)) hold @p value; declares NaN as its only nodata.
std::string demWith(const std::string& name, int n, float value, int patch, double spikes = 0)
{
    RasterGeoreference g;
    g.width = g.height = n;
    g.transform = {500000, 1, 0, 5600000, 0, -1};
    g.crsWkt = crsWkt("EPSG:25832");
    std::vector<float> z(std::size_t(n) * std::size_t(n));
    std::uint32_t state = 12345;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            float h = 300.0f + 3.0f * float(std::sin(x / 13.0)) + 2.0f * float(std::cos(y / 9.0));
            if (x >= 50 && y >= 50 && x < 50 + patch && y < 50 + patch) h = value;
            state = state * 1664525u + 1013904223u;
            if (spikes > 0 && double(state >> 8) / double(1u << 24) < spikes) h = float(state % 4800u);
            z[std::size_t(y) * std::size_t(n) + std::size_t(x)] = h;
        }
    const std::string path = (tempDir() / name).string();
    writeRaster(path, g, {{"height", z}});
    return path;
}

} // namespace

// Heights no terrain has, in a DEM that declares no nodata for them (the float minimum that
// many tools write, -9999), are nodata, with a warning that names the value, the cells and
// how to declare it; the output has no value there.
TEST(MsiiTerrain, UndeclaredNodataIsTakenAsNodataWithAWarning)
{
    for (const auto& [value, shown] : {std::pair{-3.4028235e38f, std::string("-3.40282347e+38")},
                                       std::pair{-9999.0f, std::string("-9999")}}) {
        SCOPED_TRACE(shown);
        const std::string dem = demWith("undeclared.tif", 120, value, 10);
        const fs::path out = tempDir() / "undeclared.msii.tif";
        const RunResult r = run(MSII_EXE, "compute '" + dem + "' -r 8 --overwrite --raster-output '" + out.string() + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.err.find("msii: warning: " + dem + ": 100 cells hold " + shown +
                             ", heights no terrain has, and the raster declares no nodata value for it: taken as nodata"),
                  std::string::npos)
            << r.err;
        EXPECT_NE(r.err.find("gdal_edit.py -a_nodata " + shown), std::string::npos) << r.err;
        const RasterImage got = readRaster(out.string());
        const std::vector<float>& quality = got.bands.front().values;
        EXPECT_TRUE(std::isnan(quality[55 * 120 + 55]));
        EXPECT_FALSE(std::isnan(quality[20 * 120 + 20]));
        EXPECT_GT(quality[20 * 120 + 20], 0.3f);  // a hillside's, not that of a cliff 10 km deep
        EXPECT_LT(quality[20 * 120 + 20], 0.7f);
        // The other commands read it alike.
        const fs::path png = tempDir() / "undeclared.png";
        const RunResult rr = run(MSII_EXE, "render '" + dem + "' --show relief --pixels 200 --overwrite -o '" + png.string() + "'");
        ASSERT_EQ(rr.code, 0) << rr.err;
        EXPECT_NE(rr.err.find("100 cells hold " + shown), std::string::npos) << rr.err;
    }
}

// A DEM of random heights up to 4.8 km (garbage that a broken file gives) stays within
// bounded memory: the continuation past its edge, kilometres tall, is not cut into pieces
// beyond the reach of its cells.
TEST(MsiiTerrain, NoiseDemStaysInBoundedMemory)
{
    const std::string dem = demWith("noise.tif", 60, 0, 0, 1.0);
    const fs::path out = tempDir() / "noise.msii.tif";
    const RunResult r = run(MSII_EXE, "compute '" + dem + "' -r 10 -q --overwrite --raster-output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string record = readFile((tempDir() / "noise.msii.json").string());
    const std::size_t at = record.find("\"peak_memory_bytes\": ");
    ASSERT_NE(at, std::string::npos) << record;
    EXPECT_LT(std::stod(record.substr(at + 21)), 600e6) << "before: 2.3 GB";
}

// `msii compute DEM -o NAME.ply` writes the DEM's mesh with the bands as vertex properties
// (a vertex per cell with a height, in the GeoTIFF's cell order), equal to the GeoTIFF's
// values, and no GeoTIFF; the record says which route computed them.
TEST(MsiiTerrain, PlyOutputIsTheDemMeshWithTheBands)
{
    const fs::path tif = tempDir() / "asply.msii.tif", ply = tempDir() / "asply.ply";
    const std::string common = "compute '" + demSample() + "' -r 3 -n 4 -q --overwrite --float32 --bands quality,V,S_04 ";
    RunResult r = run(MSII_EXE, common + "--raster-output '" + tif.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = run(MSII_EXE, common + "-o '" + ply.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_FALSE(fs::exists(ply.string() + ".part.tif"));
    const std::string record = readFile((tempDir() / "asply.json").string());
    EXPECT_NE(record.find("\"used\": \"heights\""), std::string::npos) << record;
    const RasterImage raster = readRaster(tif.string());
    const DemMesh dm = demToMesh(readDem(demSample()));
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    const ReadMeshResult mesh = readMesh(ply.string(), ro);
    ASSERT_EQ(mesh.mesh.numVertices(), dm.mesh.numVertices());
    EXPECT_EQ(mesh.mesh.numTriangles(), dm.mesh.numTriangles());
    std::size_t compared = 0;
    for (const RasterBand& b : raster.bands) {
        const auto p = std::find_if(mesh.vertexProperties.begin(), mesh.vertexProperties.end(),
                                    [&](const VertexProperty& q) { return q.name == b.name; });
        ASSERT_NE(p, mesh.vertexProperties.end()) << b.name;
        for (std::size_t c = 0; c < b.values.size(); ++c) {
            const std::uint32_t v = dm.vertexOfCell[c];
            if (v == DemMesh::kNoVertex || std::isnan(b.values[c])) continue;
            ASSERT_EQ(p->values[v], b.values[c]) << b.name << " cell " << c;
            ++compared;
        }
    }
    EXPECT_GT(compared, 6u * 15000u);
}
