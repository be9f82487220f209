/// Tests of tools/msii/view_folder.h: the 16-bit codes and their stated precision, the
/// sections of data.bin (planes, differences, deflate) read back exactly, and the folder
/// written whole or not at all.

#include "../../tools/msii/view_folder.h"

#include "../support/temp_dir.h"

#include <msii/core/errors.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <vector>

using namespace msii;
using namespace msii::tools;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

double decoded(const QuantizedColumn& q, std::size_t i) { return q.lo + q.codes[i] * q.step; }

/// A folder with the page's files (empty ones: the writer copies, it does not read them).
void makeAssets(const std::filesystem::path& dir)
{
    for (const std::string& f : viewAssetFiles()) {
        std::filesystem::create_directories((dir / f).parent_path());
        std::ofstream(dir / f) << "// " << f << "\n";
    }
}

/// A mesh of two triangles and one column.
struct SmallInput {
    std::vector<float> values{0.25f, 0.5f, 0.75f, kNaN};
    ViewInput input;
    SmallInput()
    {
        ViewMesh m;
        m.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
        m.normals = {0, 0, 127, 0, 0, 127, 0, 0, 127, 0, 0, 127};
        m.triangles = {0, 1, 2, 0, 2, 3};
        input.mesh = m;
        input.source = "small.msii.ply";
        input.radii = {0.5, 1};
        input.columns.push_back({"V_01", &values, false});
    }
};

} // namespace

TEST(QuantizeColumn, ValuesAreWithinHalfAStepAndNaNIsMarked)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.2f, 0.8f);
    std::vector<float> v(10000);
    for (float& x : v) x = u(rng);
    v[17] = kNaN;
    v[18] = std::numeric_limits<float>::infinity();
    const QuantizedColumn q = quantizeColumn(v);
    EXPECT_EQ(q.missing, 2u);
    EXPECT_EQ(q.codes[17], kViewMissingCode);
    EXPECT_EQ(q.codes[18], kViewMissingCode);
    // A power of two, just large enough; lo on its grid, at or below the minimum.
    EXPECT_EQ(q.step, std::exp2(std::round(std::log2(q.step))));
    EXPECT_GE(q.step, (q.max - q.min) / 65532);
    EXPECT_LT(q.step, 2 * (q.max - q.min) / 65532);
    EXPECT_EQ(q.lo, std::floor(q.lo / q.step) * q.step);
    EXPECT_LE(q.lo, q.min);
    EXPECT_LE(q.maxError(), (q.max - q.min) / 65532);  // the stated precision
    double worst = 0;
    std::size_t compared = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (!std::isfinite(v[i])) continue;
        EXPECT_LT(q.codes[i], kViewMissingCode);
        worst = std::max(worst, std::abs(decoded(q, i) - double(v[i])));
        ++compared;
    }
    EXPECT_EQ(compared, v.size() - 2);
    EXPECT_LE(worst, q.maxError() * (1 + 1e-9));
    EXPECT_GT(worst, 0.5 * q.maxError());  // the bound is the real one, not a loose one
    for (std::uint16_t c : q.codes) EXPECT_TRUE(c <= 65534 || c == kViewMissingCode);
}

TEST(QuantizeColumn, EqualValuesStayEqualAcrossColumnsAndFlatValuesAreExact)
{
    // Two columns of different ranges hold the same values (a feature vector constant over
    // the radii): their decoded values must be equal too, as msii metric's constancy tests
    // need, and the flat surface's 0.5 must decode to 0.5 exactly.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.45f, 0.55f);
    std::vector<float> a(1000), b(1000);
    for (std::size_t i = 0; i < a.size(); ++i) a[i] = b[i] = u(rng);
    a[0] = 0.1f, b[0] = 0.9f;  // different ranges, so different lo
    a[1] = b[1] = 0.5f;
    const QuantizedColumn qa = quantizeColumn(a), qb = quantizeColumn(b);
    EXPECT_NE(qa.lo, qb.lo);
    std::size_t compared = 0;
    for (std::size_t i = 1; i < a.size(); ++i, ++compared) EXPECT_EQ(decoded(qa, i), decoded(qb, i)) << i;
    EXPECT_EQ(compared, a.size() - 1);
    EXPECT_EQ(decoded(qa, 1), 0.5);
    EXPECT_EQ(decoded(qb, 1), 0.5);
}

TEST(QuantizeColumn, WholeNumbersAreExactConstantsAndEmptyColumnsAreValid)
{
    const std::vector<float> labels{0, 3, 16, 16, 2};
    const QuantizedColumn q = quantizeColumn(labels, true);
    EXPECT_EQ(q.step, 1);
    for (std::size_t i = 0; i < labels.size(); ++i) EXPECT_EQ(decoded(q, i), labels[i]);
    EXPECT_EQ(q.maxError(), 0);

    const QuantizedColumn c = quantizeColumn({0.5f, 0.5f, kNaN});
    EXPECT_EQ(c.step, 0);
    EXPECT_EQ(decoded(c, 0), 0.5);
    EXPECT_EQ(c.codes[2], kViewMissingCode);

    const QuantizedColumn none = quantizeColumn({kNaN, kNaN});
    EXPECT_EQ(none.missing, 2u);
    EXPECT_TRUE(std::isnan(none.min));
}

TEST(EncodeSection, EveryEncodingReadsBackExactly)
{
    std::mt19937 rng(3);
    std::vector<std::uint16_t> codes(5000);
    std::uint16_t walk = 30000;
    for (auto& c : codes) c = walk = std::uint16_t(walk + int(rng() % 41) - 20);  // wraps at 0 and 65535
    codes[10] = kViewMissingCode;
    std::vector<std::uint32_t> indices(3000);
    for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = std::uint32_t(i / 3 + (i % 3) * 170) ^ (i % 7 == 0 ? 0xffff0000u : 0u);
    std::vector<float> floats(4000);
    for (std::size_t i = 0; i < floats.size(); ++i) floats[i] = float(std::sin(double(i)) * 1e3);
    int cases = 0;
    for (bool planes : {false, true})
        for (bool delta : {false, true}) {
            const SectionEncoding e{planes, delta, 6};
            const auto check = [&](const auto& values) {
                using T = typename std::decay_t<decltype(values)>::value_type;
                const std::string z = encodeSection(values.data(), values.size(), sizeof(T), e);
                const std::vector<unsigned char> back = decodeSection(z, values.size(), sizeof(T), e);
                ASSERT_EQ(back.size(), values.size() * sizeof(T));
                EXPECT_EQ(std::memcmp(back.data(), values.data(), back.size()), 0) << "planes " << planes << " delta " << delta;
                ++cases;
            };
            check(codes);
            check(indices);
            if (!delta) check(floats);
        }
    EXPECT_EQ(cases, 10);
    // Differences of a slow walk and split bytes are what make the codes small.
    const std::string plain = encodeSection(codes.data(), codes.size(), 2, {false, false, 6});
    const std::string coded = encodeSection(codes.data(), codes.size(), 2, {true, true, 6});
    EXPECT_LT(coded.size(), plain.size());
    EXPECT_THROW(decodeSection("not zlib", 4, 2, {}), InvalidInputError);
}

TEST(WriteViewFolder, WritesThePageTheHeaderAndTheData)
{
    test::TempDir dir;
    makeAssets(dir.path() / "assets");
    SmallInput small;
    ViewFolderOptions options;
    options.assets = (dir.path() / "assets").string();
    const std::string folder = dir.file("small.msii.view");
    const ViewFolderResult r = writeViewFolder(small.input, folder, options);
    EXPECT_EQ(r.columns, 1u);
    for (const std::string& f : viewAssetFiles()) EXPECT_TRUE(std::filesystem::is_regular_file(folder + "/" + f)) << f;
    std::ifstream in(folder + "/data.json");
    const nlohmann::json h = nlohmann::json::parse(in);
    EXPECT_EQ(h["format"], "msii-view 1");
    EXPECT_EQ(h["kind"], "mesh");
    EXPECT_EQ(h["items"], 4);
    EXPECT_EQ(h["mesh"]["triangles"], 2);
    EXPECT_EQ(h["radius"], 1.0);
    EXPECT_EQ(h["scales"], 2);
    EXPECT_EQ(h["colormaps"]["viridis"].get<std::string>().size(), 256u * 6);
    EXPECT_EQ(h["colormaps"]["viridis"].get<std::string>().substr(0, 6), "440154");  // matplotlib's first entry
    const nlohmann::json& c = h["columns"][0];
    EXPECT_EQ(c["name"], "V_01");
    EXPECT_EQ(c["missing"], 1);
    EXPECT_EQ(c["step"].get<double>(), std::exp2(-16));  // the power of two above 0.5/65532
    EXPECT_EQ(c["max_error"].get<double>(), std::exp2(-17));
    EXPECT_NEAR(r.largestError, c["max_error"].get<double>(), 1e-15);
    // The sections tile data.bin, and each reads back.
    std::ifstream binFile(folder + "/data.bin", std::ios::binary);
    const std::string bin((std::istreambuf_iterator<char>(binFile)), {});
    EXPECT_EQ(bin.size(), r.dataBytes);
    std::uint64_t end = 0;
    int sections = 0;
    for (const auto& [name, s] : h["sections"].items()) {
        end = std::max<std::uint64_t>(end, s["offset"].get<std::uint64_t>() + s["bytes"].get<std::uint64_t>());
        const std::size_t size = s["type"] == "float32" || s["type"] == "uint32" ? 4 : s["type"] == "uint16" ? 2 : 1;
        const auto back = decodeSection(bin.substr(s["offset"], s["bytes"]), s["count"], size, {s["planes"], s["delta"], 6});
        if (name == "indices") {
            std::vector<std::uint32_t> t(6);
            std::memcpy(t.data(), back.data(), 24);
            EXPECT_EQ(t, small.input.mesh->triangles);
        }
        if (name == "column:V_01") {
            std::vector<std::uint16_t> q(4);
            std::memcpy(q.data(), back.data(), 8);
            EXPECT_EQ(q, (std::vector<std::uint16_t>{0, 16384, 32768, kViewMissingCode}));
        }
        ++sections;
    }
    EXPECT_EQ(sections, 4);  // positions, normals, indices, one column
    EXPECT_EQ(end, bin.size());
    // Only the folder is left: no temporary one.
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"assets", "small.msii.view"}));
}

TEST(WriteViewFolder, RefusesAnExistingFolderAndReplacesItWithOverwrite)
{
    test::TempDir dir;
    makeAssets(dir.path() / "assets");
    SmallInput small;
    ViewFolderOptions options;
    options.assets = (dir.path() / "assets").string();
    const std::string folder = dir.file("small.msii.view");
    std::filesystem::create_directory(folder);
    std::ofstream(folder + "/mine.txt") << "keep";
    EXPECT_THROW(writeViewFolder(small.input, folder, options), IOError);
    EXPECT_TRUE(std::filesystem::exists(folder + "/mine.txt"));
    options.overwrite = true;
    writeViewFolder(small.input, folder, options);
    EXPECT_FALSE(std::filesystem::exists(folder + "/mine.txt"));
    EXPECT_TRUE(std::filesystem::exists(folder + "/data.bin"));
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"assets", "small.msii.view"}));
}

TEST(WriteViewFolder, LeavesNothingWhenItFailsOrIsInterrupted)
{
    test::TempDir dir;
    SmallInput small;
    ViewFolderOptions options;
    options.assets = (dir.path() / "no-such-assets").string();
    EXPECT_ANY_THROW(writeViewFolder(small.input, dir.file("a.view"), options));
    makeAssets(dir.path() / "assets");
    options.assets = (dir.path() / "assets").string();
    std::atomic<bool> cancel{true};
    options.cancel = &cancel;
    EXPECT_THROW(writeViewFolder(small.input, dir.file("b.view"), options), Interrupted);
    // A temporary folder of a process that is gone (killed with -9) is removed by the next run.
    std::filesystem::create_directory(dir.path() / ".c.view.tmp-999999999-0");
    cancel = false;
    writeViewFolder(small.input, dir.file("c.view"), options);
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"assets", "c.view"}));
}

TEST(WriteViewFolder, RefusesAnInputWithoutColumns)
{
    test::TempDir dir;
    SmallInput small;
    small.input.columns.clear();
    EXPECT_THROW(writeViewFolder(small.input, dir.file("a.view"), {}), InvalidInputError);
}
