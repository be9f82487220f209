/// Tests of io/gigamesh_files.h: GigaMesh's conventions (largest radius first, V as
/// 2x − 1), exact `.mat` text and file names, bit-exact round trips through `.mat` files,
/// every bad-input error with its line, and the PLY with a `feature_vector` list.

#include <msii/core/errors.h>
#include <msii/io/gigamesh_files.h>
#include <msii/io/write_ply.h>
#include <msii/io/read_ply.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/temp_dir.h"

using namespace msii;
using msii::test::readFile;
using msii::test::TempDir;
using msii::test::writeFile;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const double kNaNd = std::numeric_limits<double>::quiet_NaN();

/// Equal bit for bit, or both NaN.
bool sameFloat(float a, float b)
{
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    return std::memcmp(&a, &b, sizeof(float)) == 0;
}

using Columns = std::vector<std::vector<float>>;

void expectSameColumns(const Columns& actual, const Columns& expected)
{
    ASSERT_EQ(actual.size(), expected.size());
    for (std::size_t j = 0; j < expected.size(); ++j) {
        ASSERT_EQ(actual[j].size(), expected[j].size()) << j;
        for (std::size_t v = 0; v < expected[j].size(); ++v)
            EXPECT_TRUE(sameFloat(actual[j][v], expected[j][v]))
                << "column " << j << " vertex " << v << ": " << actual[j][v] << " vs " << expected[j][v];
    }
}

void expectSameValues(const std::vector<double>& actual, const std::vector<double>& expected)
{
    ASSERT_EQ(actual.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        if (std::isnan(expected[i])) EXPECT_TRUE(std::isnan(actual[i])) << i;
        else EXPECT_EQ(actual[i], expected[i]) << i;
    }
}

/// 2 vertices, 3 radii (ascending), msii normalisation; one masked value.
Columns smallColumns()
{
    return {{0.5f, 0.75f}, {0.25f, 0.625f}, {1.0f, kNaN}};
}

/// A tetrahedron (4 vertices, 4 faces).
TriMesh tetrahedron()
{
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.5, 1.5}};
    mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    return mesh;
}

/// The message of the InvalidInputError that @p read throws ("" and a failure if none).
template <class Read>
std::string invalidInputMessage(const Read& read)
{
    try {
        read();
    } catch (const InvalidInputError& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
        return "";
    }
    ADD_FAILURE() << "no exception";
    return "";
}

} // namespace

// ---------------------------------------------------------------------------------------
// Conventions

TEST(GigaMeshRows, VolumeIsTwoXMinusOneLargestRadiusFirst)
{
    const GigaMeshRows rows = toGigaMeshRows(smallColumns(), GigaMeshInvariant::Volume);
    EXPECT_EQ(rows.numVertices, 2u);
    EXPECT_EQ(rows.numValues, 3u);
    // Vertex 0: radii 3, 2, 1 → V̂ = 1, 0.25, 0.5 → 1, −0.5, 0 (flat = 0, convex < 0).
    // Vertex 1: NaN, 0.625, 0.75 → NaN, 0.25, 0.5 (concave > 0).
    expectSameValues(rows.values, {1.0, -0.5, 0.0, kNaNd, 0.25, 0.5});
    EXPECT_EQ(rows.row(1)[2], 0.5);
    expectSameColumns(fromGigaMeshRows(rows, GigaMeshInvariant::Volume), smallColumns());
}

TEST(GigaMeshRows, PatchIsUnchangedLargestRadiusFirst)
{
    const GigaMeshRows rows = toGigaMeshRows(smallColumns(), GigaMeshInvariant::Patch);
    expectSameValues(rows.values, {1.0, 0.25, 0.5, kNaNd, 0.625, 0.75});
    expectSameColumns(fromGigaMeshRows(rows, GigaMeshInvariant::Patch), smallColumns());
}

TEST(GigaMeshRows, InconsistentInputIsRefused)
{
    EXPECT_THROW(toGigaMeshRows({}, GigaMeshInvariant::Volume), InvalidInputError);
    EXPECT_THROW(toGigaMeshRows({{0.5f, 0.5f}, {0.5f}}, GigaMeshInvariant::Volume), InvalidInputError);
    GigaMeshRows rows;
    rows.numVertices = 2;
    rows.numValues = 3;
    rows.values.resize(5);
    EXPECT_THROW(fromGigaMeshRows(rows, GigaMeshInvariant::Patch), InvalidInputError);
}

// ---------------------------------------------------------------------------------------
// File names

TEST(GigaMeshFileName, FollowsGigaMesh)
{
    EXPECT_EQ(gigaMeshMatFileName("tablet", 1.0, 16, 256, GigaMeshInvariant::Volume),
              "tablet_r1.00_n4_v256.volume.mat");
    EXPECT_EQ(gigaMeshMatFileName("out/tablet", 2.5, 8, 512, GigaMeshInvariant::Patch),
              "out/tablet_r2.50_n3_v512.surface.mat");
    // "%.2f" rounds the binary value half to even, as GigaMesh's sprintf.
    EXPECT_EQ(gigaMeshMatFileName("t", 0.125, 1, 6, GigaMeshInvariant::Volume), "t_r0.12_n0_v6.volume.mat");
    EXPECT_EQ(gigaMeshMatFileName("t", 1.0, 256, 6, GigaMeshInvariant::Volume), "t_r1.00_n8_v6.volume.mat");
    // Not a power of two: the count itself, marked by a capital N.
    EXPECT_EQ(gigaMeshMatFileName("t", 1.0, 12, 6, GigaMeshInvariant::Volume), "t_r1.00_N12_v6.volume.mat");
    EXPECT_THROW(gigaMeshMatFileName("t", 0.0, 16, 6, GigaMeshInvariant::Volume), InvalidInputError);
    EXPECT_THROW(gigaMeshMatFileName("t", std::nan(""), 16, 6, GigaMeshInvariant::Volume), InvalidInputError);
    EXPECT_THROW(gigaMeshMatFileName("t", 1.0, 0, 6, GigaMeshInvariant::Volume), InvalidInputError);

    EXPECT_TRUE(gigaMeshInvariantOfFileName("a/tablet_r1.00_n4_v256.volume.mat") == GigaMeshInvariant::Volume);
    EXPECT_TRUE(gigaMeshInvariantOfFileName("tablet_r1.00_n4_v256.Surface.MAT") == GigaMeshInvariant::Patch);
    EXPECT_FALSE(gigaMeshInvariantOfFileName("tablet.vs.mat").has_value());
}

// ---------------------------------------------------------------------------------------
// .mat files

TEST(GigaMeshMat, ExactText)
{
    TempDir dir;
    const std::string path = dir.file("t_r3.00_N3_v6.volume.mat");
    const GigaMeshRows rows = toGigaMeshRows(smallColumns(), GigaMeshInvariant::Volume);
    writeGigaMeshMat(path, {"first", "", "two\nlines"}, rows);
    EXPECT_EQ(readFile(path), "# first\n#\n# two lines\n0 1 -0.5 0\n1 nan 0.25 0.5\n");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"t_r3.00_N3_v6.volume.mat"});  // no temporary left

    // Values that are not short decimals are written to read back exactly.
    GigaMeshRows awkward;
    awkward.numVertices = 1;
    awkward.numValues = 4;
    awkward.values = {0.1, -1.0 / 3.0, std::numeric_limits<double>::infinity(), -kNaNd};
    writeGigaMeshMat(path, {}, awkward);
    EXPECT_EQ(readFile(path), "0 0.1 -0.3333333333333333 inf nan\n");
}

TEST(GigaMeshMat, HeaderRecordsTheParameters)
{
    GigaMeshMatInfo info;
    info.inputFile = "tablet.ply";
    info.invariant = GigaMeshInvariant::Volume;
    info.largestRadius = 1.5;
    info.radii = {0.5, 1.0, 1.5};
    info.notes = {"precision: 6"};
    const std::vector<std::string> lines = gigaMeshMatHeader(info);
    ASSERT_EQ(lines.size(), 8u);
    EXPECT_EQ(lines[0].rfind("msii ", 0), 0u) << lines[0];
    EXPECT_EQ(lines[1], "input: tablet.ply");
    EXPECT_NE(lines[2].find("2*V/|B_r| - 1"), std::string::npos) << lines[2];
    EXPECT_EQ(lines[3], "largest radius R: 1.5");
    EXPECT_EQ(lines[4], "scales N: 3");
    EXPECT_EQ(lines[5], "radii, in the order of the columns (largest first): 1.5 1 0.5");
    EXPECT_EQ(lines[6], "precision: 6");
    info.invariant = GigaMeshInvariant::Patch;
    EXPECT_NE(gigaMeshMatHeader(info)[2].find("P/(pi r^2)"), std::string::npos);
}

TEST(GigaMeshMat, RoundTripIsBitExact)
{
    TempDir dir;
    const std::size_t numVertices = 1000, numRadii = 16;
    std::mt19937 random(12345);
    std::uniform_real_distribution<float> fraction(0.0f, 1.0f);
    Columns columns(numRadii, std::vector<float>(numVertices));
    for (auto& column : columns)
        for (float& value : column) value = fraction(random);
    // Special values: exact ones, tiny ones (V exact down to 2^-30), NaN.
    const float specials[] = {0.0f, 1.0f, 0.5f, 0.1f, 1e-7f, 3e-9f, std::ldexp(1.0f, -30), 0.99999994f, kNaN};
    for (std::size_t i = 0; i < std::size(specials); ++i) columns[i % numRadii][i] = specials[i];
    for (GigaMeshInvariant invariant : {GigaMeshInvariant::Volume, GigaMeshInvariant::Patch}) {
        const std::string path = dir.file(gigaMeshMatFileName("random", 1.0, 16, 6, invariant));
        const GigaMeshRows rows = toGigaMeshRows(columns, invariant);
        writeGigaMeshMat(path, {"random"}, rows);
        const GigaMeshRows read = readGigaMeshMat(path, numVertices);
        EXPECT_EQ(read.numVertices, numVertices);
        EXPECT_EQ(read.numValues, numRadii);
        expectSameValues(read.values, rows.values);
        expectSameColumns(fromGigaMeshRows(read, invariant), columns);
    }
    // P takes any float, including denormals, infinities and negative zero.
    const Columns extremes = {
        {1e-45f, -0.0f, std::numeric_limits<float>::infinity(), 3.4028235e38f, -2.5e-20f}};
    writeGigaMeshMat(dir.file("x.surface.mat"), {}, toGigaMeshRows(extremes, GigaMeshInvariant::Patch));
    expectSameColumns(fromGigaMeshRows(readGigaMeshMat(dir.file("x.surface.mat"), 5), GigaMeshInvariant::Patch),
                      extremes);
}

TEST(GigaMeshMat, ManyRowsAcrossWriteBatches)
{
    // More rows than one batch of formatting chunks (16 × 16384).
    TempDir dir;
    const std::size_t numVertices = 300000;
    Columns columns(2, std::vector<float>(numVertices));
    for (std::size_t v = 0; v < numVertices; ++v) {
        columns[0][v] = float(v % 1000) / 1000.0f;
        columns[1][v] = float(v) / float(numVertices);
    }
    const std::string path = dir.file("big.volume.mat");
    writeGigaMeshMat(path, {"big"}, toGigaMeshRows(columns, GigaMeshInvariant::Volume));
    expectSameColumns(fromGigaMeshRows(readGigaMeshMat(path, numVertices), GigaMeshInvariant::Volume), columns);
}

TEST(GigaMeshMat, ReadsGigaMeshStyleFilesInAnyOrder)
{
    TempDir dir;
    const std::string path = dir.file("gm_r1.00_n1_v256.volume.mat");
    // As GigaMesh writes them (boxed `#` header, fixed 10 decimals, `nan`/`-nan`), plus what
    // hand-edited files bring: blank lines, tabs, CR-LF, rows out of order, other spellings.
    writeFile(path,
              "# +------------------------------------------+\n"
              "# | Mesh:       tablet.ply\n"
              "#\n"
              "\n"
              "2 -0.0000000000 0.1250000000\r\n"
              "  0\t0.5000000000   NaN\n"
              "   # a comment between rows\n"
              "1 -nan +0.25\n"
              "3 inf 1e-3\n"
              "\n");
    const GigaMeshRows rows = readGigaMeshMat(path, 4);
    EXPECT_EQ(rows.numVertices, 4u);
    EXPECT_EQ(rows.numValues, 2u);
    expectSameValues(rows.values, {0.5, kNaNd, kNaNd, 0.25, -0.0, 0.125,
                                   std::numeric_limits<double>::infinity(), 0.001});
    // Radius ascending: column 0 is the second value of each row; V = (g + 1)/2.
    const Columns columns = fromGigaMeshRows(rows, GigaMeshInvariant::Volume);
    const float inf = std::numeric_limits<float>::infinity();
    expectSameColumns(columns, {{kNaN, 0.625f, 0.5625f, 0.5005f}, {0.75f, kNaN, 0.5f, inf}});
}

TEST(GigaMeshMat, BadInputNamesFileAndLine)
{
    TempDir dir;
    const std::string path = dir.file("bad.volume.mat");
    struct Case {
        const char* text;
        std::vector<const char*> expected;  // substrings of the message
    };
    const Case cases[] = {
        {"# header\n0 0.1 0.2\n1 0.1 0.2\n", {"ends at line 3", "2 rows", "3 vertices", "none for vertex 2"}},
        {"", {"no rows of values in its 0 lines", "3 vertices"}},
        {"# only\n# comments\n\n", {"no rows of values in its 3 lines", "3 vertices"}},
        {"0 1\n1 1\n2 1\n3 1\n", {"line 4:", "vertex index 3 is out of range", "3 vertices"}},
        {"0 0.1 0.2\n\n1 0.3\n2 0.1 0.2\n", {"line 3:", "has 1 value after", "first row (line 1) has 2"}},
        {"0 0.1 0.2\n1 0.3 0.4 0.5\n", {"line 2:", "has 3 values after", "has 2"}},
        {"0 0.1 0.2\n1 0.3 abc\n", {"line 2:", "value 2 'abc' is not a number"}},
        {"0 0.1 0.2\n1 0.3 0,4\n", {"line 2:", "'0,4' is not a number"}},
        {"#\n0 0.1\n2 0.1\n0 0.2\n", {"line 4:", "vertex index 0 appears a second time (first on line 2)"}},
        {"7 0.5\n", {"line 1:", "vertex index 7 is out of range"}},
        {"-1 0.5\n", {"line 1:", "vertex index '-1' is not a whole number"}},
        {"0.0 0.5\n", {"line 1:", "vertex index '0.0' is not a whole number"}},
        {"0 0.5\n1\n", {"line 2:", "vertex index 1 has no values"}},
    };
    for (const Case& c : cases) {
        writeFile(path, c.text);
        const std::string message = invalidInputMessage([&] { readGigaMeshMat(path, 3); });
        EXPECT_NE(message.find("'" + path + "'"), std::string::npos) << message;
        for (const char* expected : c.expected)
            EXPECT_NE(message.find(expected), std::string::npos) << "'" << expected << "' not in: " << message;
    }
    EXPECT_THROW(readGigaMeshMat(dir.file("missing.volume.mat"), 3), IOError);
    std::filesystem::create_directory(dir.file("folder.mat"));
    EXPECT_THROW(readGigaMeshMat(dir.file("folder.mat"), 3), IOError);
}

TEST(GigaMeshMat, WriteErrorsLeaveNoFile)
{
    TempDir dir;
    GigaMeshRows rows = toGigaMeshRows(smallColumns(), GigaMeshInvariant::Volume);
    rows.values.pop_back();
    EXPECT_THROW(writeGigaMeshMat(dir.file("a.volume.mat"), {}, rows), InvalidInputError);
    EXPECT_THROW(writeGigaMeshMat(dir.file("no/folder/a.volume.mat"), {},
                                  toGigaMeshRows(smallColumns(), GigaMeshInvariant::Volume)),
                 IOError);
    EXPECT_TRUE(dir.entries().empty());
}

// ---------------------------------------------------------------------------------------
// PLY with feature_vector

TEST(GigaMeshPly, QualityIsTheLargestElementOrTheLargestRadius)
{
    GigaMeshRows rows;
    rows.numVertices = 3;
    rows.numValues = 3;
    rows.values = {-0.5, 0.25, 0.125,  kNaNd, -0.75, -0.25,  kNaNd, kNaNd, kNaNd};
    const std::vector<float> largest = gigaMeshQuality(rows, GigaMeshQuality::MaxElement);
    EXPECT_EQ(largest[0], 0.25f);
    EXPECT_EQ(largest[1], -0.25f);  // NaN ignored
    EXPECT_TRUE(std::isnan(largest[2]));
    const std::vector<float> first = gigaMeshQuality(rows, GigaMeshQuality::LargestRadius);
    EXPECT_EQ(first[0], -0.5f);
    EXPECT_TRUE(std::isnan(first[1]));
}

TEST(GigaMeshPly, LayoutValuesAndQualityReadBack)
{
    TempDir dir;
    const std::string path = dir.file("tetra_r1.00_n2_v6.ply");
    const TriMesh mesh = tetrahedron();
    // V columns (radius ascending) of 4 vertices; 0.1 gives a value 2x − 1 that is not a float.
    const Columns columns = {
        {0.5f, 0.75f, 0.25f, 0.5f}, {0.625f, 0.5f, 0.375f, kNaN}, {0.5f, 0.875f, 0.125f, 0.1f}};
    const float g3 = float(2.0 * double(0.1f) - 1.0);
    const GigaMeshRows rows = toGigaMeshRows(columns, GigaMeshInvariant::Volume);
    GigaMeshPlyOptions options;
    options.comments = {"msii test"};
    writeGigaMeshPly(path, mesh, rows, options);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"tetra_r1.00_n2_v6.ply"});

    // The header and body, byte by byte.
    const std::string bytes = readFile(path);
    const std::string header =
        "ply\nformat binary_little_endian 1.0\ncomment msii test\nelement vertex 4\n"
        "property float x\nproperty float y\nproperty float z\nproperty float quality\n"
        "property list uchar float feature_vector\nelement face 4\n"
        "property list uchar int vertex_indices\nend_header\n";
    ASSERT_EQ(bytes.substr(0, header.size()), header);
    const std::size_t vertexBytes = 4 * 4 + 1 + 3 * 4;
    ASSERT_EQ(bytes.size(), header.size() + 4 * vertexBytes + 4 * 13);
    const auto floatAt = [&](std::size_t offset) {
        float value;
        std::memcpy(&value, bytes.data() + offset, sizeof(float));
        return value;
    };
    // quality = max element; feature_vector = largest radius first, V as 2x − 1.
    const float expectedQuality[4] = {0.25f, 0.75f, -0.25f, 0.0f};
    const float expectedVector[4][3] = {{0.0f, 0.25f, 0.0f},
                                        {0.75f, 0.0f, 0.5f},
                                        {-0.75f, -0.25f, -0.5f},
                                        {g3, kNaN, 0.0f}};
    for (std::size_t v = 0; v < 4; ++v) {
        const std::size_t offset = header.size() + v * vertexBytes;
        EXPECT_EQ(floatAt(offset), float(mesh.points[v].x));
        EXPECT_EQ(floatAt(offset + 12), expectedQuality[v]) << v;
        EXPECT_EQ(std::uint8_t(bytes[offset + 16]), 3u);
        for (std::size_t k = 0; k < 3; ++k)
            EXPECT_TRUE(sameFloat(floatAt(offset + 17 + 4 * k), expectedVector[v][k])) << v << " " << k;
    }

    // msii's reader with keepVertexLists: `quality`, then feature_vector_00 … _02.
    ReadMeshOptions readOptions;
    readOptions.keepVertexProperties = true;
    readOptions.keepVertexLists = true;
    const ReadMeshResult read = readPly(path, readOptions);
    EXPECT_EQ(read.mesh.points, mesh.points);
    EXPECT_EQ(read.mesh.triangles, mesh.triangles);
    ASSERT_EQ(read.vertexProperties.size(), 4u);
    EXPECT_EQ(read.vertexProperties[0].name, "quality");
    EXPECT_EQ(read.vertexProperties[1].name, "feature_vector_00");
    EXPECT_EQ(read.vertexProperties[3].name, "feature_vector_02");
    EXPECT_EQ(read.vertexProperties[2].values[1], 0.0f);
    // Without keepVertexLists the list is skipped, as before.
    ReadMeshOptions scalarsOnly;
    scalarsOnly.keepVertexProperties = true;
    EXPECT_EQ(readPly(path, scalarsOnly).vertexProperties.size(), 1u);

    // readGigaMeshPly: rows and quality; back to msii columns exactly except where
    // 2x − 1 was rounded to float (vertex 3, largest radius: within 3e-8).
    const GigaMeshPlyContents contents = readGigaMeshPly(path);
    EXPECT_EQ(contents.mesh.triangles, mesh.triangles);
    EXPECT_EQ(contents.rows.numVertices, 4u);
    EXPECT_EQ(contents.rows.numValues, 3u);
    ASSERT_EQ(contents.quality.size(), 4u);
    for (std::size_t v = 0; v < 4; ++v) {
        EXPECT_EQ(contents.quality[v], expectedQuality[v]);
        for (std::size_t k = 0; k < 3; ++k)
            EXPECT_TRUE(sameFloat(float(contents.rows.row(v)[k]), expectedVector[v][k]));
    }
    Columns back = fromGigaMeshRows(contents.rows, GigaMeshInvariant::Volume);
    EXPECT_NEAR(back[2][3], 0.1f, 3e-8);
    EXPECT_NE(back[2][3], 0.1f);  // the float rounding of the PLY is visible here ...
    back[2][3] = 0.1f;
    expectSameColumns(back, columns);  // ... and nowhere else

    // The element of the largest radius instead of the largest element.
    options.quality = GigaMeshQuality::LargestRadius;
    writeGigaMeshPly(path, mesh, rows, options);
    EXPECT_EQ(readGigaMeshPly(path).quality, (std::vector<float>{0.0f, 0.75f, -0.75f, g3}));
}

TEST(GigaMeshPly, ErrorsLeaveNoFile)
{
    TempDir dir;
    const TriMesh mesh = tetrahedron();
    // Rows for 2 vertices, mesh of 4.
    const GigaMeshRows twoVertices = toGigaMeshRows(smallColumns(), GigaMeshInvariant::Volume);
    EXPECT_THROW(writeGigaMeshPly(dir.file("a.ply"), mesh, twoVertices), InvalidInputError);
    // 256 values do not fit the uchar count.
    const GigaMeshRows tooLong = toGigaMeshRows(Columns(256, std::vector<float>(4, 0.5f)), GigaMeshInvariant::Volume);
    EXPECT_THROW(writeGigaMeshPly(dir.file("a.ply"), mesh, tooLong), InvalidInputError);
    EXPECT_TRUE(dir.entries().empty());
    // A PLY without feature_vector.
    writePly(dir.file("plain.ply"), mesh, {});
    const std::string message = invalidInputMessage([&] { readGigaMeshPly(dir.file("plain.ply")); });
    EXPECT_NE(message.find("no per-vertex feature_vector"), std::string::npos) << message;
}
