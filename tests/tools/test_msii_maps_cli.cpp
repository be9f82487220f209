// Drives `msii map`, `msii render`, `msii segment` and `msii outline` as a user chains them
// after `msii compute` on a small sample tablet: the EXR feature map has every channel, the
// frame and the radii, and its pixels carry the mesh's values; the PNG pictures decode, have
// the requested size plus the colour-bar margin and show the field's colours; the segment
// labels agree with the CSV table and the thresholded connectivity; the SVG outlines carry the
// requested levels. Every kind of bad input ends in one "msii: error:" line, a non-zero exit
// (2 for usage errors) and no output file; existing outputs are kept without --overwrite.
#include <msii/featuremap/feature_map.h>
#include <msii/featuremap/map_frame.h>
#include <msii/io/read_mesh.h>
#include <msii/outline/isolines.h>
#include <msii/render/colormap.h>
#include <msii/render/image.h>
#include <msii/segmentation/components.h>

#include <gtest/gtest.h>


#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/run_program.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::RunResult;
using msii::test::quoted;
using msii::test::runProgram;
using msii::test::writeFile;

namespace {

/// One folder for the whole test program, removed at exit.
const fs::path& tempDir()
{
    static const msii::test::TempDir dir;
    return dir.path();
}

RunResult run(const std::string& exe, const std::string& args) { return runProgram(exe, args, tempDir()); }

RunResult runMsii(const std::string& args) { return run(MSII_EXE, args); }

constexpr double kRadius = 0.8;
constexpr int kScales = 16;  // compute's default

/// An 8 × 6 mm tablet at spacing 0.1 (about 4900 vertices) and its features at R = 0.8
/// (x.msii.ply), made once.
const fs::path& features()
{
    static const fs::path path = [] {
        const fs::path mesh = tempDir() / "x.ply";
        const RunResult s = run(MSII_SAMPLES_EXE, "tablet --width 8 --height 6 --spacing 0.1 -q -o " + quoted(mesh));
        EXPECT_EQ(s.code, 0) << s.err;
        const RunResult c = runMsii("compute " + quoted(mesh) + " --radius 0.8 -q");
        EXPECT_EQ(c.code, 0) << c.err;
        return tempDir() / "x.msii.ply";
    }();
    return path;
}

/// `msii map x.msii.ply --pixels 300 --view +z` (the default output name), made once.
const fs::path& featureMap()
{
    static const fs::path path = [] {
        const RunResult r = runMsii("map " + quoted(features()) + " --pixels 300 --view +z -q");
        EXPECT_EQ(r.code, 0) << r.err;
        EXPECT_TRUE(r.err.empty()) << r.err;
        return tempDir() / "x.msii.map.exr";
    }();
    return path;
}

/// A flat 4 × 3 mm plane at z = 0 (seen edge-on from +x).
const fs::path& plane()
{
    static const fs::path path = [] {
        const fs::path p = tempDir() / "plane.ply";
        const RunResult s = run(MSII_SAMPLES_EXE, "plane --width 4 --height 3 --spacing 0.2 -q -o " + quoted(p));
        EXPECT_EQ(s.code, 0) << s.err;
        return p;
    }();
    return path;
}

ReadMeshResult readWithProperties(const fs::path& ply)
{
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    return readMesh(ply.string(), ro);
}

const std::vector<float>& property(const ReadMeshResult& r, const std::string& name)
{
    for (const auto& p : r.vertexProperties)
        if (p.name == name) return p.values;
    ADD_FAILURE() << "no property " << name;
    static const std::vector<float> none;
    return none;
}

/// NaN equals NaN, else bit for bit equal values.
bool sameValues(const std::vector<float>& a, const std::vector<float>& b)
{
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
    return true;
}

std::set<std::string> entriesOf(const fs::path& dir)
{
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
    return names;
}

/// `msii <command> <args> --output <fresh folder>/out<extension>`: exit code @p code, one line
/// "msii: error: ..." mentioning @p mentions, and no file left behind, neither in the output
/// folder nor next to the inputs.
void expectCleanFailureOf(const std::string& command, const std::string& args, const std::string& extension,
                          const std::string& mentions, int code = 1)
{
    SCOPED_TRACE(command + " " + args);
    const fs::path dir = tempDir() / "bad";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::set<std::string> before = entriesOf(tempDir());
    const RunResult r = runMsii(command + " " + args + " --output " + quoted(dir / ("out" + extension)));
    EXPECT_EQ(r.code, code) << r.err;
    EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_TRUE(fs::is_empty(dir)) << "output left behind";
    EXPECT_EQ(entriesOf(tempDir()), before) << "a file appeared next to the inputs";
    fs::remove_all(dir);  // e.g. a large map written by mistake
}

/// Map coordinates (u, v) of the centre of pixel (x, y).
std::array<double, 2> pixelCentre(const MapFrame& f, int x, int y)
{
    return {f.minU + (x + 0.5) * f.pixelSize, f.maxV - (y + 0.5) * f.pixelSize};
}

double longestEdge(const TriMesh& mesh)
{
    double longest = 0;
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) longest = std::max(longest, norm(mesh.points[t[k]] - mesh.points[t[(k + 1) % 3]]));
    return longest;
}

int colourDistance(const Rgb8& a, const Rgb8& b)
{
    return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

/// Fraction of the pixels of the top-left w × h corner that differ by more than @p tolerance.
double differingFraction(const RgbImage& a, const RgbImage& b, int w, int h, int tolerance = 3)
{
    std::size_t differ = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (colourDistance(a.at(x, y), b.at(x, y)) > tolerance) ++differ;
    return double(differ) / (double(w) * h);
}

std::vector<std::vector<std::string>> readCsv(const fs::path& path)
{
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(readFile(path.string()));
    std::string line;
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::stringstream cs(line);
        std::string cell;
        while (std::getline(cs, cell, ',')) cells.push_back(cell);
        rows.push_back(cells);
    }
    return rows;
}

/// The data-level of every <path> of an SVG, in order.
std::vector<double> pathLevels(const std::string& svg, std::size_t* paths)
{
    std::vector<double> levels;
    *paths = 0;
    for (std::size_t at = svg.find("<path"); at != std::string::npos; at = svg.find("<path", at + 1)) {
        ++*paths;
        const std::size_t end = svg.find('>', at);
        const std::string element = svg.substr(at, end - at);
        const std::size_t l = element.find("data-level=\"");
        if (l == std::string::npos) continue;
        levels.push_back(std::strtod(element.c_str() + l + 12, nullptr));
    }
    return levels;
}

} // namespace

// 1. The map after compute: every channel of the PLY plus height, mask and normal, the size
// asked for, the radii from compute's comment, and pixels that carry the vertices' values.
TEST(MsiiMapsCli, MapAfterComputeHasEveryChannelFrameAndValues)
{
    const ReadMeshResult mesh = readWithProperties(features());
    const FeatureMapImage map = readFeatureMap(featureMap().string());

    // 8 × 6 mm seen from +z: 300 pixels along x, 225 along y.
    EXPECT_EQ(map.width, 300);
    EXPECT_NEAR(map.height, 225, 1);
    ASSERT_TRUE(map.hasFrame);
    EXPECT_EQ(map.frame.width, map.width);
    EXPECT_EQ(map.frame.height, map.height);
    EXPECT_NEAR(map.frame.pixelSize * map.width, 8.0, 0.1);
    EXPECT_NEAR(map.frame.normal.z, 1.0, 1e-12);  // +z: seen from above
    EXPECT_NEAR(map.frame.axisU.x, 1.0, 1e-12);   // u = +x, v = +y
    EXPECT_NEAR(map.frame.axisV.y, 1.0, 1e-12);
    EXPECT_EQ(map.units, "mm");

    std::set<std::string> expected{"height", "mask", "normal.x", "normal.y", "normal.z"};
    std::size_t featureCount = 0;
    for (const auto& p : mesh.vertexProperties) {
        expected.insert(p.name);
        featureCount += p.name[1] == '_';
    }
    EXPECT_EQ(featureCount, 4u * kScales);  // V_, S_, P_, L_ at 16 radii
    EXPECT_TRUE(expected.count("quality"));
    std::set<std::string> channels;
    for (const auto& [name, values] : map.channels) {
        channels.insert(name);
        EXPECT_EQ(values.size(), std::size_t(map.width) * std::size_t(map.height)) << name;
    }
    EXPECT_EQ(channels, expected);

    // msii:radii: r_j = j·R/N from "R=0.8 N=16" in compute's comment, which the
    // parameters carry on.
    EXPECT_EQ(map.radii.size(), std::size_t(kScales));
    for (std::size_t j = 1; j <= std::min(map.radii.size(), std::size_t(kScales)); ++j)
        EXPECT_NEAR(map.radii[j - 1], double(j) * kRadius / kScales, 1e-6) << j;
    EXPECT_NE(map.parameters.find("map --view +z"), std::string::npos) << map.parameters;
    EXPECT_NE(map.parameters.find("compute R=0.8 N=16"), std::string::npos) << map.parameters;
    EXPECT_EQ(fs::path(map.source), fs::absolute(features())) << map.source;

    const auto& mask = map.channels.at("mask");
    const auto& quality = map.channels.at("quality");
    const auto& height = map.channels.at("height");
    const auto& nx = map.channels.at("normal.x");
    const auto& ny = map.channels.at("normal.y");
    const auto& nz = map.channels.at("normal.z");
    // The tablet fills its own bounding rectangle: every pixel sees it; normals are unit and
    // mostly towards the viewer.
    std::size_t covered = 0, upwards = 0;
    for (std::size_t i = 0; i < mask.size(); ++i) {
        EXPECT_TRUE(mask[i] == 0.0f || mask[i] == 1.0f) << i;
        if (mask[i] != 1.0f) continue;
        ++covered;
        const double len = std::sqrt(double(nx[i]) * nx[i] + double(ny[i]) * ny[i] + double(nz[i]) * nz[i]);
        EXPECT_NEAR(len, 1.0, 1e-3) << i;
        upwards += nz[i] > 0.7f;
    }
    EXPECT_GT(double(covered), 0.98 * double(mask.size()));
    EXPECT_GT(double(upwards), 0.9 * double(covered));

    // The middle pixel: mask 1, quality close to that of the nearest vertex.
    std::vector<Vec3> onMap;
    for (const Vec3& p : mesh.mesh.points) onMap.push_back(map.frame.toMap(p));
    const auto& q = property(mesh, "quality");
    ASSERT_EQ(q.size(), onMap.size());
    const int mx = map.width / 2, my = map.height / 2;
    const std::size_t mi = std::size_t(my) * std::size_t(map.width) + std::size_t(mx);
    EXPECT_EQ(mask[mi], 1.0f);
    {
        const auto c = pixelCentre(map.frame, mx, my);
        std::size_t nearest = 0;
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t v = 0; v < onMap.size(); ++v) {
            const double d = std::hypot(onMap[v].x - c[0], onMap[v].y - c[1]);
            if (d < best) best = d, nearest = v;
        }
        EXPECT_LT(best, 0.2);
        ASSERT_TRUE(std::isfinite(q[nearest]));
        EXPECT_NEAR(quality[mi], q[nearest], 0.05);
        EXPECT_NEAR(height[mi], onMap[nearest].z, 0.05);
    }
    // Every 7th pixel: the interpolated quality and height lie within the values of the
    // vertices around it (those of its triangle are no farther than the longest edge).
    const double reach = longestEdge(mesh.mesh) + map.frame.pixelSize;
    std::size_t checked = 0, nan = 0;
    for (int y = 3; y < map.height; y += 7)
        for (int x = 3; x < map.width; x += 7) {
            const std::size_t i = std::size_t(y) * std::size_t(map.width) + std::size_t(x);
            if (mask[i] != 1.0f) continue;
            const auto c = pixelCentre(map.frame, x, y);
            double qlo = INFINITY, qhi = -INFINITY, hlo = INFINITY, hhi = -INFINITY;
            bool anyNan = false;
            for (std::size_t v = 0; v < onMap.size(); ++v) {
                if (std::hypot(onMap[v].x - c[0], onMap[v].y - c[1]) > reach) continue;
                hlo = std::min(hlo, onMap[v].z), hhi = std::max(hhi, onMap[v].z);
                if (std::isnan(q[v])) anyNan = true;
                else qlo = std::min(qlo, double(q[v])), qhi = std::max(qhi, double(q[v]));
            }
            SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
            EXPECT_GE(height[i], hlo - 1e-5);
            EXPECT_LE(height[i], hhi + 1e-5);
            if (std::isnan(quality[i])) {  // quality is never NaN at a vertex, so neither here
                ++nan;
                continue;
            }
            EXPECT_FALSE(anyNan);
            EXPECT_GE(quality[i], qlo - 1e-5);
            EXPECT_LE(quality[i], qhi + 1e-5);
            ++checked;
        }
    EXPECT_GT(checked, 300u);
    EXPECT_EQ(nan, 0u);
}

// 1b. --half, every --compression and --properties give readable maps with the same values.
TEST(MsiiMapsCli, MapHalfCompressionAndPropertySubset)
{
    const FeatureMapImage full = readFeatureMap(featureMap().string());
    const auto& q = full.channels.at("quality");
    const auto& v1 = full.channels.at("V_01");
    const fs::path dir = tempDir() / "maps";
    fs::create_directories(dir);
    const std::string common = "map " + quoted(features()) + " --pixels 300 --view +z -q --properties quality,V_01 ";

    for (const char* compression : {"none", "rle", "zips", "zip", "piz"}) {
        SCOPED_TRACE(compression);
        const fs::path out = dir / (std::string(compression) + ".exr");
        const RunResult r = runMsii(common + "--compression " + compression + " -o " + quoted(out));
        ASSERT_EQ(r.code, 0) << r.err;
        const FeatureMapImage m = readFeatureMap(out.string());
        EXPECT_EQ(m.width, full.width);
        EXPECT_EQ(m.height, full.height);
        std::set<std::string> names;
        for (const auto& kv : m.channels) names.insert(kv.first);
        EXPECT_EQ(names, (std::set<std::string>{"height", "mask", "normal.x", "normal.y", "normal.z", "quality", "V_01"}));
        // Lossless: the same floats as the full piz map.
        EXPECT_TRUE(sameValues(m.channels.at("quality"), q));
        EXPECT_TRUE(sameValues(m.channels.at("V_01"), v1));
        EXPECT_TRUE(sameValues(m.channels.at("height"), full.channels.at("height")));
        EXPECT_EQ(m.radii.size(), std::size_t(kScales));
    }
    // Uncompressed is larger than every compressed map.
    for (const char* compression : {"rle", "zips", "zip", "piz"})
        EXPECT_LT(fs::file_size(dir / (std::string(compression) + ".exr")), fs::file_size(dir / "none.exr")) << compression;

    const fs::path half = dir / "half.exr";
    const RunResult r = runMsii(common + "--half -o " + quoted(half));
    ASSERT_EQ(r.code, 0) << r.err;
    const FeatureMapImage h = readFeatureMap(half.string());
    ASSERT_EQ(h.width, full.width);
    ASSERT_EQ(h.height, full.height);
    const auto& hq = h.channels.at("quality");
    ASSERT_EQ(hq.size(), q.size());
    std::size_t finite = 0;
    for (std::size_t i = 0; i < q.size(); ++i) {
        if (std::isnan(q[i])) {
            EXPECT_TRUE(std::isnan(hq[i])) << i;
            continue;
        }
        ++finite;
        EXPECT_NEAR(hq[i], q[i], 1e-3 * std::abs(q[i]) + 1e-6) << i;  // half: 11 significant bits
    }
    EXPECT_GT(finite, 1000u);
    // Half of the bytes per value: the half map is smaller than the float one.
    EXPECT_LT(fs::file_size(half), fs::file_size(dir / "piz.exr"));
}

// 2. Pictures: every kind decodes, with the colour-bar margin; the colours follow the field.
TEST(MsiiMapsCli, RenderPicturesFromFeaturesAndFromMap)
{
    const fs::path dir = tempDir() / "render";
    fs::create_directories(dir);
    const std::string in = quoted(features()) + " --pixels 300 --view +z ";
    const auto render = [&](const std::string& name, const std::string& args, std::string* summary = nullptr) {
        SCOPED_TRACE(name);
        const fs::path out = dir / (name + ".png");
        const RunResult r = runMsii("render " + args + " -o " + quoted(out) + (summary ? "" : " -q"));
        EXPECT_EQ(r.code, 0) << r.err;
        if (summary) *summary = r.err;
        RgbImage image;
        try {
            image = readPng(out.string());
        } catch (const std::exception& e) {
            ADD_FAILURE() << e.what();
        }
        EXPECT_GE(image.width, 300);
        return image;
    };
    const RgbImage quality = render("quality", in);
    const RgbImage relief = render("relief", in + "--show relief");
    const RgbImage height = render("height", in + "--show height");
    std::string summary;
    const RgbImage v01 = render("v01", in + "--show V_01 --colormap coolwarm --center 0.5 --isolines 5", &summary);
    const RgbImage contrast = render("contrast", in + "--show relief --high-contrast");

    const FeatureMapImage map = readFeatureMap(featureMap().string());
    const int w = map.width, h = map.height;
    // Same frame as the map: the picture is the top-left w × h corner; the colour bar makes
    // the figure wider, the scale bar taller.
    for (const RgbImage* image : {&quality, &height, &v01}) {
        EXPECT_GT(image->width, w);
        EXPECT_GT(image->height, h);
    }
    EXPECT_GE(relief.height, h);
    ASSERT_GE(quality.width, w);
    ASSERT_GE(quality.height, h);
    ASSERT_GE(relief.width, w);
    ASSERT_GE(relief.height, h);
    ASSERT_GE(height.width, w);
    ASSERT_GE(contrast.width, w);
    ASSERT_GE(contrast.height, h);
    ASSERT_GE(v01.width, w);
    ASSERT_GE(v01.height, h);
    EXPECT_GT(differingFraction(quality, relief, w, h), 0.5);
    EXPECT_GT(differingFraction(quality, height, w, h), 0.3);
    EXPECT_GT(differingFraction(relief, contrast, w, h), 0.3);
    // Relief is grey.
    std::size_t grey = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Rgb8 c = relief.at(x, y);
            grey += c[0] == c[1] && c[1] == c[2];
        }
    EXPECT_GT(double(grey), 0.99 * w * h);

    // --center 0.5: the range in the summary is symmetric about 0.5; 5 isolines are drawn in black.
    std::smatch m;
    ASSERT_TRUE(std::regex_search(summary, m, std::regex(R"(V_01 in \[([-0-9.e+]+), ([-0-9.e+]+)\])"))) << summary;
    const double lo = std::stod(m[1].str()), hi = std::stod(m[2].str());
    EXPECT_LT(lo, 0.5);
    EXPECT_NEAR(lo + hi, 1.0, 1e-5);
    std::size_t dark = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Rgb8 c = v01.at(x, y);
            dark += c[0] < 60 && c[1] < 60 && c[2] < 60;
        }
    EXPECT_GT(dark, 100u);

    // Default colours: viridis over the 1st to 99th percentile of the pixels' quality.
    const auto& q = map.channels.at("quality");
    const ValueRange range = percentileRange(q, 1, 99);
    std::size_t exact = 0, finite = 0;
    int lowest = -1, highest = -1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
            if (std::isnan(q[i])) {
                EXPECT_EQ(colourDistance(quality.at(x, y), colorAt(ColorMapKind::Viridis, NAN)), 0);  // no data: grey
                continue;
            }
            ++finite;
            const Rgb8 want = colorAt(ColorMapKind::Viridis, (q[i] - range.lo) / (range.hi - range.lo));
            exact += colourDistance(quality.at(x, y), want) <= 3;
            if (lowest < 0 || q[i] < q[std::size_t(lowest)]) lowest = int(i);
            if (highest < 0 || q[i] > q[std::size_t(highest)]) highest = int(i);
        }
    EXPECT_GT(finite, 10000u);
    EXPECT_GT(double(exact), 0.999 * double(finite));
    // Strongly different quality: strongly different colours; equal quality: equal colours.
    ASSERT_GE(lowest, 0);
    const Rgb8 cLow = quality.at(lowest % w, lowest / w), cHigh = quality.at(highest % w, highest / w);
    EXPECT_GT(q[std::size_t(highest)] - q[std::size_t(lowest)], 0.2);
    EXPECT_GT(colourDistance(cLow, cHigh), 150);
    std::size_t pairs = 0;
    for (int i = 0; i < w * h && pairs < 20; i += 97) {
        if (std::isnan(q[std::size_t(i)])) continue;
        for (int j = i + 5 * w; j < w * h; j += 13)
            if (std::abs(q[std::size_t(j)] - q[std::size_t(i)]) < 1e-5f) {
                EXPECT_LE(colourDistance(quality.at(i % w, i / w), quality.at(j % w, j / w)), 2) << i << " " << j;
                ++pairs;
                break;
            }
    }
    EXPECT_GE(pairs, 5u);

    // From the EXR map: the same picture size (the map plus the margins) and the same pixels.
    const fs::path fromMap = dir / "frommap.png";
    const RunResult r = runMsii("render " + quoted(featureMap()) + " --show quality -q -o " + quoted(fromMap));
    ASSERT_EQ(r.code, 0) << r.err;
    const RgbImage mapPicture = readPng(fromMap.string());
    EXPECT_EQ(mapPicture.width, quality.width);
    EXPECT_EQ(mapPicture.height, quality.height);
    ASSERT_GE(mapPicture.width, w);
    ASSERT_GE(mapPicture.height, h);
    EXPECT_LT(differingFraction(mapPicture, quality, w, h), 0.001);
    // The default name: <stem>.<what>.png next to the input.
    const RunResult d = runMsii("render " + quoted(featureMap()) + " -q");
    ASSERT_EQ(d.code, 0) << d.err;
    EXPECT_TRUE(fs::exists(tempDir() / "x.msii.map.quality.png"));
}

// 3. Components: labels in the PLY, one CSV row per label, areas positive and decreasing.
// Without any font (fontconfig configured with none), pictures still come, with the built-in
// pixel font and one warning that says how to get a real one.
TEST(MsiiMapsCli, RenderWithoutFontsFallsBackWithAWarning)
{
    const fs::path conf = tempDir() / "no-fonts.conf", out = tempDir() / "no-fonts.png";
    writeFile(conf.string(), "<?xml version=\"1.0\"?>\n<fontconfig></fontconfig>\n");
    ::setenv("FONTCONFIG_FILE", conf.c_str(), 1);
    const RunResult r = runMsii("render " + quoted(features()) + " --pixels 200 --overwrite -o " + quoted(out));
    ::unsetenv("FONTCONFIG_FILE");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("msii: warning: no font found (install fonts-dejavu-core"), std::string::npos) << r.err;
    const RgbImage picture = readPng(out.string());
    EXPECT_GT(picture.width, 200);
    // The built-in font has no grey: every pixel of the bottom margin's label is black or white.
    std::size_t ink = 0, grey = 0;
    for (int y = picture.height - 20; y < picture.height; ++y)
        for (int x = 0; x < picture.width / 2; ++x) {
            const Rgb8 c = picture.at(x, y);
            if (c[0] == 255 && c[1] == 255 && c[2] == 255) continue;
            ++ink;
            grey += c[0] != 0;
        }
    EXPECT_GT(ink, 10u);
    EXPECT_EQ(grey, 0u);
}

TEST(MsiiMapsCli, SegmentLabelsAgreeWithTable)
{
    const ReadMeshResult in = readWithProperties(features());
    const auto& q = property(in, "quality");
    const double threshold = 0.55;
    const fs::path dir = tempDir() / "segment";
    fs::create_directories(dir);
    const fs::path out = dir / "seg.ply";
    const RunResult r = runMsii("segment " + quoted(features()) + " --threshold 0.55 --min-vertices 10 -o " + quoted(out));
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path csv = dir / "seg.csv";
    ASSERT_TRUE(fs::exists(csv));
    const ReadMeshResult seg = readWithProperties(out);
    ASSERT_EQ(seg.mesh.numVertices(), in.mesh.numVertices());
    ASSERT_EQ(seg.mesh.numTriangles(), in.mesh.numTriangles());
    EXPECT_TRUE(sameValues(property(seg, "quality"), q));  // carried over
    const auto& label = property(seg, "label");
    ASSERT_EQ(label.size(), q.size());
    {  // an integer property, for viewers and scripts that group by it
        std::ifstream file(out, std::ios::binary);
        std::string header, line;
        while (std::getline(file, line) && line != "end_header") header += line + "\n";
        EXPECT_NE(header.find("property int label\n"), std::string::npos) << header;
    }

    std::map<int, std::size_t> count;
    for (std::size_t i = 0; i < label.size(); ++i) {
        const int l = int(label[i]);
        ASSERT_EQ(float(l), label[i]) << i;
        if (l == 0) continue;
        ++count[l];
        EXPECT_GE(q[i], threshold) << i;  // only selected vertices are labelled
    }
    // Connected through edges: two selected neighbours have the same label.
    for (const Triangle& t : seg.mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[k], b = t[(k + 1) % 3];
            if (q[a] >= threshold && q[b] >= threshold) {
                EXPECT_EQ(label[a], label[b]) << a << "-" << b;
            }
        }

    const auto rows = readCsv(csv);
    ASSERT_GE(rows.size(), 2u);
    EXPECT_EQ(rows[0][0], "label");
    EXPECT_EQ(rows[0][2], "area");
    EXPECT_EQ(rows.size() - 1, count.size());  // one row per distinct nonzero label
    ASSERT_FALSE(count.empty());
    EXPECT_EQ(count.rbegin()->first, int(count.size()));  // labels 1 .. K
    double previous = INFINITY;
    for (std::size_t k = 1; k < rows.size(); ++k) {
        ASSERT_EQ(rows[k].size(), 12u);
        const int l = std::stoi(rows[k][0]);
        EXPECT_EQ(l, int(k));
        EXPECT_EQ(std::stoul(rows[k][1]), count[l]) << "label " << l;
        EXPECT_GE(count[l], 10u);  // --min-vertices 10
        const double area = std::stod(rows[k][2]);
        EXPECT_GT(area, 0.0);
        EXPECT_LE(area, previous);  // largest first
        previous = area;
        // Area: a third of every triangle at each labelled vertex.
        double cells = 0;
        for (const Triangle& t : seg.mesh.triangles) {
            const double a = 0.5 * norm(cross(seg.mesh.points[t[1]] - seg.mesh.points[t[0]],
                                              seg.mesh.points[t[2]] - seg.mesh.points[t[0]]));
            for (std::uint32_t v : t)
                if (int(label[v]) == l) cells += a / 3;
        }
        EXPECT_NEAR(area, cells, 1e-6 + 1e-5 * cells) << "label " << l;
    }
}

// 4. Outlines: one <path> per line, each at one of the levels asked for.
TEST(MsiiMapsCli, OutlineWritesPathsAtTheLevels)
{
    const ReadMeshResult in = readWithProperties(features());
    const auto& q = property(in, "quality");
    double qmin = INFINITY, qmax = -INFINITY;
    for (float v : q)
        if (!std::isnan(v)) qmin = std::min(qmin, double(v)), qmax = std::max(qmax, double(v));
    const fs::path dir = tempDir() / "outline";
    fs::create_directories(dir);

    const fs::path two = dir / "two.svg";
    const RunResult r = runMsii("outline " + quoted(features()) + " --levels 0.5,0.55 -q -o " + quoted(two));
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string svg = readFile(two.string());
    EXPECT_EQ(svg.find("<svg"), svg.find('<', svg.find("?>")));
    std::size_t paths = 0;
    const std::vector<double> levels = pathLevels(svg, &paths);
    EXPECT_GT(paths, 1u);
    EXPECT_EQ(levels.size(), paths);  // every path carries its level
    std::map<double, std::size_t> perLevel;
    for (double l : levels) {
        EXPECT_TRUE(l == 0.5 || l == 0.55) << l;
        ++perLevel[l];
    }
    EXPECT_EQ(perLevel.size(), 2u);  // quality crosses both levels
    // The same lines as the engine computes on the mesh.
    const std::vector<Polyline> lines = computeIsolines(in.mesh, q, {0.5, 0.55});
    EXPECT_EQ(paths, lines.size());

    const fs::path three = dir / "three.svg";
    const RunResult c = runMsii("outline " + quoted(features()) + " --count 3 -q -o " + quoted(three));
    ASSERT_EQ(c.code, 0) << c.err;
    const std::vector<double> counted = pathLevels(readFile(three.string()), &paths);
    EXPECT_EQ(counted.size(), paths);
    const std::set<double> distinct(counted.begin(), counted.end());
    ASSERT_EQ(distinct.size(), 3u);
    const std::vector<double> l3(distinct.begin(), distinct.end());
    for (double l : l3) {
        EXPECT_GT(l, qmin);
        EXPECT_LT(l, qmax);
    }
    EXPECT_NEAR(l3[1] - l3[0], l3[2] - l3[1], 1e-6 * (qmax - qmin));  // evenly spaced
}

// 5. Bad input: one error line, the right exit code, no output.
TEST(MsiiMapsCli, BadInputFailsCleanly)
{
    const std::string f = quoted(features());
    const std::string map = quoted(featureMap());
    const std::string missing = quoted(tempDir() / "missing.ply");
    const fs::path junk = tempDir() / "junk.ply";
    writeFile(junk.string(), "hello\n");

    // map. (--properties quality --half keeps a map written by mistake small.)
    const std::string small = " --properties quality --half --compression rle";
    expectCleanFailureOf("map", f + " --pixels 0" + small, ".exr", "--pixels");
    expectCleanFailureOf("map", f + " --pixels -5" + small, ".exr", "--pixels");
    expectCleanFailureOf("map", f + " --pixels 100000" + small, ".exr", "largest allowed side");
    expectCleanFailureOf("map", f + " --pixel-size 0" + small, ".exr", "--pixel-size");
    expectCleanFailureOf("map", f + " --dpi 0" + small, ".exr", "--dpi");
    expectCleanFailureOf("map", f + " --view 0,0,0", ".exr", "zero length");
    expectCleanFailureOf("map", f + " --view sideways", ".exr", "unknown view 'sideways'");
    expectCleanFailureOf("map", quoted(plane()) + " --view +x --pixels 100", ".exr", "edge-on");
    expectCleanFailureOf("map", f + " --properties nosuch", ".exr", "no vertex property 'nosuch'");
    expectCleanFailureOf("map", f + " --compression lzma", ".exr", "'lzma'");
    expectCleanFailureOf("map", missing, ".exr", "cannot open");
    expectCleanFailureOf("map", quoted(junk), ".exr", "not a PLY file");
    expectCleanFailureOf("map", "", ".exr", "input is required", 2);

    // render
    const std::string r = f + " --pixels 200";
    expectCleanFailureOf("render", r + " --show nosuch", ".png", "no vertex property 'nosuch'");
    expectCleanFailureOf("render", r + " --range 2,1", ".png", "--range");
    expectCleanFailureOf("render", r + " --font " + quoted(junk), ".png", "not a font");
    expectCleanFailureOf("render", r + " --percentiles 50", ".png", "--percentiles");
    expectCleanFailureOf("render", r + " --isolines -1", ".png", "--isolines");
    expectCleanFailureOf("render", r + " --light 1", ".png", "--light");
    expectCleanFailureOf("render", r + " --colormap jet", ".png", "jet");
    expectCleanFailureOf("render", f + " --pixels 0", ".png", "--pixels");
    expectCleanFailureOf("render", map + " --show V_99", ".png", "no channel 'V_99'");
    expectCleanFailureOf("render", missing, ".png", "cannot open");

    // segment
    expectCleanFailureOf("segment", f, ".ply", "--threshold is required", 2);
    expectCleanFailureOf("segment", f + " --threshold nan", ".ply", "--threshold must be a finite number");
    expectCleanFailureOf("segment", f + " --threshold 0.5 --property nosuch", ".ply", "no vertex property 'nosuch'");
    expectCleanFailureOf("segment", f + " --threshold 0.5 --min-vertices 0", ".ply", "--min-vertices");
    expectCleanFailureOf("segment", f + " --threshold 0.5 --min-area -1", ".ply", "--min-area");
    expectCleanFailureOf("segment", missing + " --threshold 0.5", ".ply", "cannot open");

    // outline
    expectCleanFailureOf("outline", f, ".svg", "give --levels or --count");
    expectCleanFailureOf("outline", f + " --levels a,b", ".svg", "'a' is not a number");
    expectCleanFailureOf("outline", f + " --count -1", ".svg", "--count");
    expectCleanFailureOf("outline", f + " --levels 0.5 --property nosuch", ".svg", "no vertex property 'nosuch'");
}

// 5b. An existing output is kept, byte for byte, unless --overwrite is given.
TEST(MsiiMapsCli, ExistingOutputsAreNotOverwritten)
{
    const fs::path dir = tempDir() / "keep";
    fs::create_directories(dir);
    const std::string f = quoted(features());
    struct Case {
        std::string command, args, output;
    };
    const std::vector<Case> cases{
        {"map", f + " --pixels 64 --properties quality", "m.exr"},
        {"render", f + " --pixels 64", "r.png"},
        {"segment", f + " --threshold 0.55", "s.ply"},
        {"outline", f + " --levels 0.5", "o.svg"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.command);
        const fs::path out = dir / c.output;
        writeFile(out.string(), "keep me\n");
        const RunResult r = runMsii(c.command + " " + c.args + " -q -o " + quoted(out));
        EXPECT_EQ(r.code, 1);
        EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
        EXPECT_EQ(readFile(out.string()), "keep me\n");
        const RunResult o = runMsii(c.command + " " + c.args + " -q --overwrite -o " + quoted(out));
        EXPECT_EQ(o.code, 0) << o.err;
        EXPECT_NE(readFile(out.string()), "keep me\n");
    }
    // segment's table is protected as well.
    const fs::path table = dir / "t.csv";
    writeFile(table.string(), "keep me\n");
    const RunResult r = runMsii("segment " + f + " --threshold 0.55 -q -o " + quoted(dir / "t.ply"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
    EXPECT_EQ(readFile(table.string()), "keep me\n");
    EXPECT_FALSE(fs::exists(dir / "t.ply"));
}
