// Drives `msii render --layout fat-cross` and `msii map --layout fat-cross` as a user does,
// on the generated whole tablet (msii-samples rounded-tablet: a different number of round
// marks on each of its six sides, their centres in a CSV): through each view's matrix in the
// sheet's record, every mark of a side lands in that side's view, inside its box, where a grey
// picture of V at R is brighter than the flat clay, within 2 pixels of its projected centre;
// the same tablet under random rigid motions gives the same sides in the same views (exactly
// so with --front and --up); the pixel size is 25.4 / dpi and the scale bar agrees within a
// pixel; a one-sided scan gives its one view and blank others; three scans give three sheets
// at one scale and a contact sheet; bad orientations get one error line and no file.
#include <msii/featuremap/feature_map.h>
#include <msii/io/write_ply.h>
#include <msii/io/read_mesh.h>
#include <msii/render/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/rotation.h"
#include "../support/run_program.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::Rotation;
using msii::test::quoted;
using msii::test::runProgram;
using msii::test::RunResult;

namespace {

const fs::path& tempDir()
{
    static const msii::test::TempDir dir;
    return dir.path();
}

RunResult runMsii(const std::string& args)
{
    return runProgram(MSII_EXE, args, tempDir());
}
RunResult runSamples(const std::string& args)
{
    return runProgram(MSII_SAMPLES_EXE, args, tempDir());
}

struct Mark {
    std::string side;
    Vec3 centre, normal;
    double radius = 0, depth = 0;
};

std::vector<Mark> readMarks(const fs::path& csv)
{
    std::vector<Mark> marks;
    std::istringstream in(readFile(csv.string()));
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream f(line);
        Mark m;
        f >> m.side >> m.centre.x >> m.centre.y >> m.centre.z >> m.normal.x >> m.normal.y >> m.normal.z >> m.radius >>
            m.depth;
        marks.push_back(m);
    }
    return marks;
}

/// The generated whole tablet (spacing 0.3 mm, scanner noise) and its marks, made once.
const fs::path& tablet()
{
    static const fs::path path = [] {
        const fs::path p = tempDir() / "tablet.ply";
        const RunResult r = runSamples("rounded-tablet --spacing 0.3 --roughness 0.004 -q -o " + quoted(p) +
                                       " --marks-csv " + quoted(tempDir() / "tablet.marks.csv"));
        EXPECT_EQ(r.code, 0) << r.err;
        return p;
    }();
    return path;
}

const std::vector<Mark>& marks()
{
    static const std::vector<Mark> m = (tablet(), readMarks(tempDir() / "tablet.marks.csv"));
    return m;
}

/// Its V at R = 1.5 mm (x.msii.ply), made once.
const fs::path& tabletFeatures()
{
    static const fs::path path = [] {
        const fs::path out = tempDir() / "tablet.msii.ply";
        const RunResult r = runMsii("compute " + quoted(tablet()) + " -r 1.5 --invariants V -q -o " + quoted(out));
        EXPECT_EQ(r.code, 0) << r.err;
        return out;
    }();
    return path;
}

nlohmann::json readJson(const fs::path& p)
{
    return nlohmann::json::parse(readFile(p.string()));
}

const nlohmann::json& viewNamed(const nlohmann::json& record, const std::string& name)
{
    for (const nlohmann::json& v : record["views"])
        if (v["name"] == name) return v;
    throw std::runtime_error("no view " + name);
}

/// [column, row, depth] of @p p through a view's to_pixel.
Vec3 toPixel(const nlohmann::json& view, const Vec3& p)
{
    const nlohmann::json& a = view["to_pixel"];
    Vec3 r;
    for (int i = 0; i < 3; ++i)
        r[i] = a[i][0].get<double>() * p.x + a[i][1].get<double>() * p.y + a[i][2].get<double>() * p.z +
               a[i][3].get<double>();
    return r;
}

bool inBox(const nlohmann::json& view, const Vec3& q)
{
    const nlohmann::json& b = view["box"];
    return q.x >= b[0].get<double>() && q.x < b[2].get<double>() && q.y >= b[1].get<double>() &&
           q.y < b[3].get<double>();
}

double grey(const RgbImage& image, int x, int y)
{
    return image.at(x, y)[0];
}

/// A rigid motion: a seeded rotation and a shift far from the origin.
struct Motion {
    Rotation rotation;
    Vec3 shift;
    Vec3 operator()(const Vec3& p) const { return rotation(p) + shift; }
};

Motion motion(int seed)
{
    const double a = 0.7 * seed, b = 1.3 * seed;
    const Vec3 axis = normalized(Vec3(std::cos(a), std::sin(a) * std::cos(b), std::sin(b) + 0.2));
    return {Rotation(axis, 0.5 + 1.1 * seed), Vec3(4.0e5 + seed, 5.2e6 - seed, 300.0)};
}

/// The tablet moved by @p m, written in double precision.
fs::path movedTablet(const Motion& m, const std::string& name)
{
    TriMesh mesh = readMesh(tablet().string()).mesh;
    for (Vec3& p : mesh.points) p = m(p);
    const fs::path out = tempDir() / name;
    WritePlyOptions o;
    o.forceDoublePoints = true;
    writePly(out.string(), mesh, {}, o);
    return out;
}

/// For each mark, the view whose pixel at the mark's projection sees the mark's floor: the
/// sheet map's height there is the projected depth less the mark's depth. "" if none does.
std::vector<std::string> viewsSeeingTheMarks(const fs::path& sheetMap, const std::vector<Mark>& placed)
{
    const FeatureMapImage map = readFeatureMap(sheetMap.string(), {"height", "mask"});
    const nlohmann::json record = nlohmann::json::parse(map.views);
    std::vector<std::string> seen;
    for (const Mark& m : placed) {
        std::string where;
        for (const nlohmann::json& v : record["views"]) {
            const Vec3 q = toPixel(v, m.centre);
            if (!inBox(v, q)) continue;
            const std::size_t k = std::size_t(int(q.y)) * std::size_t(map.width) + std::size_t(int(q.x));
            const float h = map.channels.at("height")[k];
            if (map.channels.at("mask")[k] > 0.5f && std::abs(q.z - h - m.depth) < 0.15 * m.depth)
                where += (where.empty() ? "" : "+") + v["name"].get<std::string>();
        }
        seen.push_back(where);
    }
    return seen;
}

/// Exit code non-zero, one line "msii: error: ..." naming @p mentions, nothing in @p folder.
void expectRefused(const std::string& args, const fs::path& folder, const std::string& mentions)
{
    SCOPED_TRACE(args);
    fs::create_directories(folder);
    const RunResult r = runMsii(args);
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(folder)) << "files were left in " << folder;
}

}  // namespace

TEST(MsiiSheetsCli, EachViewShowsItsSideInPlaceBrighterWhereTheMarksAre)
{
    const fs::path png = tempDir() / "grey.png";
    const RunResult r = runMsii("render " + quoted(tabletFeatures()) +
                                " --layout fat-cross --show V_16 --colormap gray --range 0.35,0.65 --dpi 300 "
                                "--no-colorbar -q -o " +
                                quoted(png));
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json record = readJson(tempDir() / "grey.json");
    const RgbImage image = readPng(png.string());
    const double ps = record["pixel_size"].get<double>();
    ASSERT_EQ(marks().size(), 21u);
    std::map<std::string, int> perSide;
    for (const Mark& m : marks()) {
        SCOPED_TRACE(m.side);
        const nlohmann::json& view = viewNamed(record, m.side);  // the default orientation keeps the names
        EXPECT_TRUE(view["scanned"].get<bool>());
        const Vec3 q = toPixel(view, m.centre);
        ASSERT_TRUE(inBox(view, q)) << q.x << ", " << q.y;
        // The flat clay: the median grey of the view's box where it shows the tablet.
        const nlohmann::json& b = view["box"];
        std::vector<double> clay;
        for (int y = b[1].get<int>(); y < b[3].get<int>(); ++y)
            for (int x = b[0].get<int>(); x < b[2].get<int>(); ++x)
                if (image.at(x, y) != Rgb8{255, 255, 255}) clay.push_back(grey(image, x, y));
        std::nth_element(clay.begin(), clay.begin() + std::ptrdiff_t(clay.size() / 2), clay.end());
        const double flat = clay[clay.size() / 2];
        const int cx = int(q.x), cy = int(q.y);
        EXPECT_GT(grey(image, cx, cy), flat + 40) << "the mark is not brighter than the flat clay (" << flat << ")";
        // The bright blob around it (brighter than halfway to its peak) centred on the projection.
        const int reach = int(std::ceil(1.2 * m.radius / ps));
        double peak = 0;
        for (int y = cy - reach; y <= cy + reach; ++y)
            for (int x = cx - reach; x <= cx + reach; ++x) peak = std::max(peak, grey(image, x, y));
        double sx = 0, sy = 0, n = 0;
        for (int y = cy - reach; y <= cy + reach; ++y)
            for (int x = cx - reach; x <= cx + reach; ++x)
                if (std::hypot(x + 0.5 - q.x, y + 0.5 - q.y) <= reach && grey(image, x, y) > 0.5 * (flat + peak))
                    sx += x + 0.5, sy += y + 0.5, n += 1;
        ASSERT_GT(n, 0);
        EXPECT_LT(std::hypot(sx / n - q.x, sy / n - q.y), 2.0);
        ++perSide[m.side];
    }
    EXPECT_EQ(perSide, (std::map<std::string, int>{
                           {"obverse", 6}, {"reverse", 5}, {"top", 1}, {"bottom", 2}, {"left", 4}, {"right", 3}}));
}

TEST(MsiiSheetsCli, PoseDoesNotMatter)
{
    // Unmoved, each mark is seen in the view of its own side, and in no other.
    const fs::path still = tempDir() / "still.sheet.exr";
    RunResult r = runMsii("map " + quoted(tablet()) + " --layout fat-cross --dpi 200 -q -o " + quoted(still));
    ASSERT_EQ(r.code, 0) << r.err;
    const std::vector<std::string> reference = viewsSeeingTheMarks(still, marks());
    for (std::size_t k = 0; k < marks().size(); ++k) EXPECT_EQ(reference[k], marks()[k].side) << k;
    for (int seed = 1; seed <= 3; ++seed) {
        SCOPED_TRACE(seed);
        const Motion m = motion(seed);
        std::vector<Mark> placed = marks();
        for (Mark& mark : placed) mark.centre = m(mark.centre);
        const fs::path moved = movedTablet(m, "moved" + std::to_string(seed) + ".ply");
        // By the default rule: the same sides in the same views.
        const fs::path sheet = tempDir() / ("moved" + std::to_string(seed) + ".sheet.exr");
        r = runMsii("map " + quoted(moved) + " --layout fat-cross --dpi 200 -q -o " + quoted(sheet));
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_EQ(viewsSeeingTheMarks(sheet, placed), reference);
        // Told the front and up: exactly the named sides.
        const Vec3 front = m.rotation(Vec3(0, 0, 1)), up = m.rotation(Vec3(0, 1, 0));
        std::ostringstream given;
        given.precision(17);
        given << " --front " << front.x << "," << front.y << "," << front.z << " --up " << up.x << "," << up.y << ","
              << up.z;
        const fs::path told = tempDir() / ("told" + std::to_string(seed) + ".sheet.exr");
        r = runMsii("map " + quoted(moved) + " --layout fat-cross --dpi 200 -q" + given.str() + " -o " + quoted(told));
        ASSERT_EQ(r.code, 0) << r.err;
        const std::vector<std::string> seen = viewsSeeingTheMarks(told, placed);
        for (std::size_t k = 0; k < placed.size(); ++k) EXPECT_EQ(seen[k], placed[k].side) << k;
        const nlohmann::json views = nlohmann::json::parse(readFeatureMap(told.string(), {"mask"}).views);
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(views["front"][i].get<double>(), front[i], 1e-15);
            EXPECT_NEAR(views["up"][i].get<double>(), up[i], 1e-12);
        }
    }
}

TEST(MsiiSheetsCli, PixelSizeFollowsTheDpiAndTheScaleBarAgrees)
{
    const fs::path png = tempDir() / "scale.png";
    const RunResult r = runMsii("render " + quoted(tablet()) + " --layout fat-cross --dpi 600 -q -o " + quoted(png));
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json record = readJson(tempDir() / "scale.json");
    const double ps = record["pixel_size"].get<double>();
    EXPECT_DOUBLE_EQ(ps, 25.4 / 600);
    EXPECT_DOUBLE_EQ(record["dpi"].get<double>(), 600);
    // The scale bar: the longest black run in a row below the views.
    const RgbImage image = readPng(png.string());
    int below = 0;
    for (const nlohmann::json& v : record["views"]) below = std::max(below, v["box"][3].get<int>());
    int longest = 0;
    for (int y = below; y < image.height; ++y)
        for (int x = 0, run = 0; x < image.width; ++x) {
            run = image.at(x, y) == Rgb8{0, 0, 0} ? run + 1 : 0;
            longest = std::max(longest, run);
        }
    const double length = record["scale_bar"]["length"].get<double>();
    EXPECT_EQ(record["scale_bar"]["units"], "mm");
    EXPECT_LE(std::abs(longest - length / ps), 1.0) << longest << " pixels for " << length << " mm";
}

TEST(MsiiSheetsCli, AOneSidedScanGivesItsViewAndBlankOthers)
{
    const fs::path scan = tempDir() / "open.ply", png = tempDir() / "open.png";
    ASSERT_EQ(runSamples("tablet --width 12 --height 9 --spacing 0.08 --roughness 0.003 -q -o " + quoted(scan)).code,
              0);
    const RunResult r =
        runMsii("render " + quoted(scan) + " --layout fat-cross --labels --pixels 600 -q -o " + quoted(png));
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json record = readJson(tempDir() / "open.json");
    const RgbImage image = readPng(png.string());
    for (const nlohmann::json& v : record["views"]) {
        SCOPED_TRACE(v["name"].get<std::string>());
        EXPECT_EQ(v["scanned"].get<bool>(), v["name"] == "obverse");
        // Inside its frame, a blank view is white; the obverse shows the scan.
        const nlohmann::json& b = v["box"];
        int drawn = 0;
        for (int y = b[1].get<int>() + 1; y + 1 < b[3].get<int>(); ++y)
            for (int x = b[0].get<int>() + 1; x + 1 < b[2].get<int>(); ++x)
                drawn += image.at(x, y) != Rgb8{255, 255, 255};
        if (v["scanned"].get<bool>())
            EXPECT_GT(drawn, 0.9 * (b[2].get<int>() - b[0].get<int>()) * (b[3].get<int>() - b[1].get<int>()));
        else
            EXPECT_EQ(drawn, 0);
    }
}

TEST(MsiiSheetsCli, ACollectionGivesSheetsAtOneScaleAndAContactSheet)
{
    const fs::path scans = tempDir() / "collection", out = tempDir() / "sheets";
    fs::create_directories(scans);
    std::string inputs;
    const char* sizes[] = {"--width 20 --height 28", "--width 24 --height 32", "--width 14 --height 20 --thickness 8"};
    for (int k = 0; k < 3; ++k) {
        const fs::path p = scans / ("tablet" + std::to_string(k) + ".ply");
        ASSERT_EQ(runSamples(std::string("rounded-tablet --spacing 0.5 --marks 2,2,1,1,1,1 ") + sizes[k] + " -q -o " +
                             quoted(p))
                      .code,
                  0);
        inputs += " " + quoted(p);
    }
    const RunResult r = runMsii("render" + inputs + " --layout fat-cross --pixels 500 -q --output-dir " + quoted(out));
    ASSERT_EQ(r.code, 0) << r.err;
    double pixelSize = 0;
    int longest = 0;
    const std::string index = readFile((out / "index.html").string());
    for (int k = 0; k < 3; ++k) {
        const std::string stem = "tablet" + std::to_string(k) + ".relief.sheet";
        const nlohmann::json record = readJson(out / (stem + ".json"));
        const RgbImage image = readPng((out / (stem + ".png")).string());
        if (k == 0) pixelSize = record["pixel_size"].get<double>();
        EXPECT_EQ(record["pixel_size"].get<double>(), pixelSize);  // one scale
        longest = std::max({longest, image.width, image.height});
        EXPECT_NE(index.find("tablet" + std::to_string(k) + ".ply"), std::string::npos);
        EXPECT_NE(index.find("href=\"" + stem + ".png\""), std::string::npos);
        EXPECT_TRUE(fs::exists(out / "thumbs" / (stem + ".png")));
    }
    EXPECT_LE(longest, 500 + 200);  // the largest sheet's views fill 500 pixels; the scale bar adds below
}

TEST(MsiiSheetsCli, TheRecordRedoesTheSheetAndViewsComeSeparately)
{
    const fs::path first = tempDir() / "first.png", again = tempDir() / "again.png";
    RunResult r = runMsii("render " + quoted(tabletFeatures()) +
                          " --layout fat-cross --labels --shade --isolines 4 --dpi 250 --views-separately -q -o " + quoted(first));
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("render " + quoted(tabletFeatures()) + " --layout fat-cross --labels --shade --isolines 4 -q --orientation " +
                quoted(tempDir() / "first.json") + " -o " + quoted(again));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(readFile(first.string()), readFile(again.string()));
    const nlohmann::json record = readJson(tempDir() / "first.json");
    for (const nlohmann::json& v : record["views"]) {
        const RgbImage view = readPng((tempDir() / ("first." + v["name"].get<std::string>() + ".png")).string());
        EXPECT_EQ(view.width, v["box"][2].get<int>() - v["box"][0].get<int>());
        EXPECT_EQ(view.height, v["box"][3].get<int>() - v["box"][1].get<int>());
    }
#ifdef MSII_TEST_PICTURES
    // The README's picture and docs/figures.md's: this sheet, as the test made it.
    fs::create_directories(MSII_TEST_PICTURES);
    fs::copy_file(first, fs::path(MSII_TEST_PICTURES) / "rounded-tablet.sheet.png",
                  fs::copy_options::overwrite_existing);
#endif
}

TEST(MsiiSheetsCli, TheSheetMapHasEveryChannelAndTheViewsFrames)
{
    const fs::path exr = tempDir() / "features.sheet.exr", png = tempDir() / "features.png";
    RunResult r = runMsii("map " + quoted(tabletFeatures()) + " --layout fat-cross --dpi 150 -q -o " + quoted(exr));
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("render " + quoted(tabletFeatures()) + " --layout fat-cross --dpi 150 -q -o " + quoted(png));
    ASSERT_EQ(r.code, 0) << r.err;
    const FeatureMapImage map = readFeatureMap(exr.string());
    for (const char* c : {"height", "normal.x", "normal.y", "normal.z", "mask", "V_01", "V_16", "quality"})
        EXPECT_TRUE(map.channels.count(c)) << c;
    EXPECT_DOUBLE_EQ(map.frame.pixelSize, 25.4 / 150);
    const nlohmann::json views = nlohmann::json::parse(map.views), record = readJson(tempDir() / "features.json");
    EXPECT_EQ(views["layout"], "fat-cross");
    EXPECT_EQ(views["views"], record["views"]);  // the same layout as the picture's
    EXPECT_EQ(map.width, record["sheet"][0].get<int>());  // the views' part of the picture
    EXPECT_EQ(map.height, record["sheet"][1].get<int>());
    // At each mark's pixel the map holds V at R above the flat clay's 0.5, and faces its viewer.
    for (const Mark& m : marks()) {
        const Vec3 q = toPixel(viewNamed(views, m.side), m.centre);
        const std::size_t k = std::size_t(int(q.y)) * std::size_t(map.width) + std::size_t(int(q.x));
        EXPECT_GT(map.channels.at("V_16")[k], 0.52f) << m.side;
        EXPECT_GT(map.channels.at("normal.z")[k], 0.9f) << m.side;
    }
}

TEST(MsiiSheetsCli, BadOrientationsAreRefusedWithOneLineAndNoFile)
{
    const fs::path folder = tempDir() / "refused";
    const std::string in = quoted(tablet()), out = " -o " + quoted(folder / "x.png");
    expectRefused("render " + in + " --layout fat-cross --front 0,0,0" + out, folder, "--front");
    expectRefused("render " + in + " --layout fat-cross --up 0,0,0" + out, folder, "--up");
    expectRefused("render " + in + " --layout fat-cross --front 1,2" + out, folder, "--front");
    expectRefused("render " + in + " --layout fat-cross --front 0,0,1 --up 0,0,-3" + out, folder, "parallel");
    expectRefused("render " + in + " --layout fat-cross --front nan,0,1" + out, folder, "--front");
    expectRefused("render " + in + " --layout fat-cross --orientation " + quoted(folder / "none.json") + out, folder,
                  "--orientation");
    expectRefused("render " + in + " --front 0,0,1" + out, folder, "--layout");
    expectRefused("map " + in + " --layout fat-cross --front 0,1,0 --up 0,2,0 -o " + quoted(folder / "x.exr"), folder,
                  "parallel");
    expectRefused("render " + in + " " + in + " --layout fat-cross" + out, folder, "--output-dir");
}
