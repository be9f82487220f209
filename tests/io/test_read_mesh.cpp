/// Tests of mesh/read_mesh.h and mesh/read_ply.h: every format read from files written here,
/// PLY variants (ascii, both binary byte orders, tristrips, extra properties and elements),
/// and the errors for missing, unknown, truncated and inconsistent files.

#include <msii/core/errors.h>
#include <msii/io/write_ply.h>
#include <msii/io/read_mesh.h>
#include <msii/io/read_ply.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../support/files.h"
#include "../support/temp_dir.h"

using namespace msii;
using msii::test::readFile;
using msii::test::TempDir;
using msii::test::writeFile;

namespace {

/// Appends the bytes of @p value in little- or big-endian order.
template <class T>
void appendBinary(std::string& out, T value, bool bigEndian = false)
{
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (bigEndian)
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    out.append(bytes, sizeof(T));
}

/// The unit square as two triangles, with a third triangle on top (5 vertices).
TriMesh smallMesh()
{
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1.25}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {1, 2, 4}};
    return mesh;
}

} // namespace

TEST(ReadPly, AsciiTristripsWithExtraVertexProperties)
{
    TempDir dir;
    const std::string path = dir.file("strips.ply");
    writeFile(path,
              "ply\r\n"
              "format ascii 1.0\r\n"
              "comment written by hand\r\n"
              "obj_info scanner test\r\n"
              "element vertex 6\r\n"
              "property float x\r\n"
              "property float y\r\n"
              "property float z\r\n"
              "property uchar red\r\n"
              "property uchar green\r\n"
              "property uchar blue\r\n"
              "property float confidence\r\n"
              "element tristrips 1\r\n"
              "property list int int vertex_indices\r\n"
              "end_header\r\n"
              "0 0 0 255 0 0 0.5\r\n"
              "1 0 0 0 255 0 0.25\r\n"
              "0 1 0 0 0 255 1\r\n"
              "1 1 0 10 20 30 0.125\r\n"
              "2 0 0 1 2 3 -1.5e-3\r\n"
              "2 1 0 4 5 6 +2\r\n"
              // Strip 0 1 2 3, a degenerate stitch (3 3) and a restart, then 1 4 3 5.
              "11 0 1 2 3 3 -1 1 4 3 5 5\r\n");
    ReadMeshOptions options;
    options.keepVertexProperties = true;
    const ReadMeshResult result = readMesh(path, options);
    EXPECT_EQ(result.format, "ply-ascii");
    EXPECT_EQ(result.numPolygonsRead, 1u);
    ASSERT_EQ(result.mesh.numVertices(), 6u);
    EXPECT_EQ(result.mesh.points[5], Vec3(2, 1, 0));
    // Every triangle keeps the orientation of the strip's first one (counter-clockwise, +z).
    const std::vector<Triangle> expected = {{0, 1, 2}, {2, 1, 3}, {1, 4, 3}, {3, 4, 5}};
    EXPECT_EQ(result.mesh.triangles, expected);

    ASSERT_EQ(result.vertexProperties.size(), 4u);
    EXPECT_EQ(result.vertexProperties[0].name, "red");
    EXPECT_EQ(result.vertexProperties[3].name, "confidence");
    EXPECT_EQ(result.vertexProperties[0].values, (std::vector<float>{255, 0, 0, 10, 1, 4}));
    EXPECT_EQ(result.vertexProperties[3].values, (std::vector<float>{0.5f, 0.25f, 1, 0.125f, -1.5e-3f, 2}));

    // Without the option the properties are not kept.
    EXPECT_TRUE(readMesh(path).vertexProperties.empty());
}

TEST(ReadPly, BigEndianWithSkippedElementsAndProperties)
{
    TempDir dir;
    const std::string path = dir.file("big.ply");
    std::string bytes =
        "ply\n"
        "format binary_big_endian 1.0\n"
        "element material 2\n"
        "property list uchar int ids\n"
        "property short code\n"
        "element vertex 4\n"
        "property double x\n"
        "property double y\n"
        "property double z\n"
        "property list uchar float normal\n"
        "property ushort quality\n"
        "element face 2\n"
        "property uchar flags\n"
        "property list ushort uint vertex_index\n"
        "property list uchar float texcoord\n"
        "end_header\n";
    const bool big = true;
    // material: lists of 3 and 0 ints, each followed by a short.
    appendBinary<std::uint8_t>(bytes, 3);
    for (int i : {7, 8, 9}) appendBinary<std::int32_t>(bytes, i, big);
    appendBinary<std::int16_t>(bytes, -5, big);
    appendBinary<std::uint8_t>(bytes, 0);
    appendBinary<std::int16_t>(bytes, 6, big);
    const double coords[4][3] = {{0.1, 0, 0}, {1, 0, 0}, {1, 1, -2.5}, {0, 1, 1e-300}};
    for (const auto& p : coords) {
        for (double c : p) appendBinary(bytes, c, big);
        appendBinary<std::uint8_t>(bytes, 1);
        appendBinary(bytes, 3.5f, big);
        appendBinary<std::uint16_t>(bytes, 513, big);
    }
    // A quad, then a triangle.
    appendBinary<std::uint8_t>(bytes, 1);
    appendBinary<std::uint16_t>(bytes, 4, big);
    for (std::uint32_t v : {0u, 1u, 2u, 3u}) appendBinary(bytes, v, big);
    appendBinary<std::uint8_t>(bytes, 2);
    appendBinary(bytes, 0.25f, big);
    appendBinary(bytes, 0.75f, big);
    appendBinary<std::uint8_t>(bytes, 0);
    appendBinary<std::uint16_t>(bytes, 3, big);
    for (std::uint32_t v : {3u, 2u, 1u}) appendBinary(bytes, v, big);
    appendBinary<std::uint8_t>(bytes, 0);
    writeFile(path, bytes);

    ReadMeshOptions options;
    options.keepVertexProperties = true;
    const ReadMeshResult result = readPly(path, options);
    EXPECT_EQ(result.format, "ply-binary");
    EXPECT_EQ(result.numPolygonsRead, 2u);
    ASSERT_EQ(result.mesh.numVertices(), 4u);
    for (int v = 0; v < 4; ++v)
        EXPECT_EQ(result.mesh.points[std::size_t(v)], Vec3(coords[v][0], coords[v][1], coords[v][2]));
    const std::vector<Triangle> expected = {{0, 1, 2}, {0, 2, 3}, {3, 2, 1}};
    EXPECT_EQ(result.mesh.triangles, expected);
    ASSERT_EQ(result.vertexProperties.size(), 1u);  // the list `normal` is skipped
    EXPECT_EQ(result.vertexProperties[0].name, "quality");
    EXPECT_EQ(result.vertexProperties[0].values, std::vector<float>(4, 513.0f));
}

TEST(ReadPly, VertexListsKeptAsNumberedProperties)
{
    TempDir dir;
    const std::string path = dir.file("lists.ply");
    // Big endian, two lists of different types around a scalar (GigaMesh's feature_vector
    // is `list uint8 float`); kept lists come after the scalars, in header order.
    std::string bytes =
        "ply\n"
        "format binary_big_endian 1.0\n"
        "element vertex 3\n"
        "property float x\n"
        "property float y\n"
        "property float z\n"
        "property list ushort double normal\n"
        "property float quality\n"
        "property list uint8 float feature_vector\n"
        "element face 1\n"
        "property list uchar int vertex_indices\n"
        "end_header\n";
    const bool big = true;
    for (int v = 0; v < 3; ++v) {
        for (float c : {float(v), float(v * v), 0.5f}) appendBinary(bytes, c, big);
        appendBinary<std::uint16_t>(bytes, 1, big);
        appendBinary(bytes, 0.25 * v, big);
        appendBinary(bytes, -1.5f * float(v), big);
        appendBinary<std::uint8_t>(bytes, 12);
        for (int k = 0; k < 12; ++k) appendBinary(bytes, float(10 * v + k), big);
    }
    appendBinary<std::uint8_t>(bytes, 3);
    for (std::int32_t v : {0, 1, 2}) appendBinary(bytes, v, big);
    writeFile(path, bytes);

    ReadMeshOptions options;
    options.keepVertexLists = true;
    ReadMeshResult result = readPly(path, options);
    ASSERT_EQ(result.vertexProperties.size(), 1u + 12u);  // scalars need keepVertexProperties
    EXPECT_EQ(result.vertexProperties[0].name, "normal_00");
    EXPECT_EQ(result.vertexProperties[0].values, (std::vector<float>{0.0f, 0.25f, 0.5f}));
    EXPECT_EQ(result.vertexProperties[1].name, "feature_vector_00");
    EXPECT_EQ(result.vertexProperties[12].name, "feature_vector_11");
    EXPECT_EQ(result.vertexProperties[12].values, (std::vector<float>{11.0f, 21.0f, 31.0f}));
    EXPECT_EQ(result.mesh.points[2], Vec3(2, 4, 0.5));
    EXPECT_EQ(result.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}}));

    options.keepVertexProperties = true;
    result = readPly(path, options);
    ASSERT_EQ(result.vertexProperties.size(), 2u + 12u);
    EXPECT_EQ(result.vertexProperties[0].name, "quality");
    EXPECT_EQ(result.vertexProperties[0].values, (std::vector<float>{0.0f, -1.5f, -3.0f}));
    EXPECT_EQ(result.vertexProperties[1].name, "normal_00");
    EXPECT_EQ(result.vertexProperties[7].name, "feature_vector_05");
    EXPECT_EQ(result.vertexProperties[7].values, (std::vector<float>{5.0f, 15.0f, 25.0f}));

    // Ascii; lists of different lengths are refused with the vertex named.
    writeFile(path,
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
              "property list uchar float feature_vector\nelement face 1\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 0 2 0.5 nan\n1 0 0 2 -0.5 inf\n0 1 0 2 1e-3 0\n3 0 1 2\n");
    result = readPly(path, options);
    ASSERT_EQ(result.vertexProperties.size(), 2u);
    EXPECT_EQ(result.vertexProperties[0].values, (std::vector<float>{0.5f, -0.5f, 1e-3f}));
    EXPECT_TRUE(std::isnan(result.vertexProperties[1].values[0]));
    EXPECT_TRUE(std::isinf(result.vertexProperties[1].values[1]));
    writeFile(path,
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
              "property list uchar float feature_vector\nelement face 1\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 0 2 0.5 0.5\n1 0 0 2 0.5 0.5\n0 1 0 3 0.5 0.5 0.5\n3 0 1 2\n");
    try {
        readPly(path, options);
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("different lengths (2 values at vertex 1, 3 at vertex 3)"),
                  std::string::npos)
            << e.what();
    }
    options.keepVertexLists = false;  // the default: lists are skipped
    EXPECT_TRUE(readPly(path, options).vertexProperties.empty());
}

TEST(ReadPly, LittleEndianSignedCountsAndSmallTypes)
{
    TempDir dir;
    const std::string path = dir.file("little.ply");
    std::string bytes =
        "ply\n"
        "format binary_little_endian 1.0\n"
        "element vertex 3\n"
        "property int16 x\n"
        "property int8 y\n"
        "property uint8 z\n"
        "property float64 value\n"
        "element face 1\n"
        "property list int32 int32 vertex_indices\n"
        "end_header\n";
    appendBinary<std::int16_t>(bytes, -300);
    appendBinary<std::int8_t>(bytes, -7);
    appendBinary<std::uint8_t>(bytes, 200);
    appendBinary(bytes, 1.0 / 3.0);
    appendBinary<std::int16_t>(bytes, 1);
    appendBinary<std::int8_t>(bytes, 2);
    appendBinary<std::uint8_t>(bytes, 3);
    appendBinary(bytes, 2.0);
    appendBinary<std::int16_t>(bytes, 4);
    appendBinary<std::int8_t>(bytes, 5);
    appendBinary<std::uint8_t>(bytes, 6);
    appendBinary(bytes, 3.0);
    appendBinary<std::int32_t>(bytes, 3);
    for (std::int32_t v : {2, 0, 1}) appendBinary(bytes, v);
    writeFile(path, bytes);

    ReadMeshOptions options;
    options.keepVertexProperties = true;
    const ReadMeshResult result = readMesh(path, options);
    ASSERT_EQ(result.mesh.numVertices(), 3u);
    EXPECT_EQ(result.mesh.points[0], Vec3(-300, -7, 200));
    EXPECT_EQ(result.mesh.points[2], Vec3(4, 5, 6));
    EXPECT_EQ(result.mesh.triangles, (std::vector<Triangle>{{2, 0, 1}}));
    ASSERT_EQ(result.vertexProperties.size(), 1u);
    EXPECT_EQ(result.vertexProperties[0].values[0], float(1.0 / 3.0));
}

TEST(ReadPly, LargeBinaryRoundTrip)
{
    // A 300 x 300 grid: exercises the buffered fast paths well beyond one write chunk.
    TempDir dir;
    const std::string path = dir.file("grid.ply");
    const std::uint32_t n = 300;
    TriMesh mesh;
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) mesh.points.push_back({i * 0.5, j * 0.25, float((i * j) % 7) * 0.125});
    for (std::uint32_t j = 0; j + 1 < n; ++j) {
        for (std::uint32_t i = 0; i + 1 < n; ++i) {
            const std::uint32_t v = j * n + i;
            mesh.triangles.push_back({v, v + 1, v + n + 1});
            mesh.triangles.push_back({v, v + n + 1, v + n});
        }
    }
    writePly(path, mesh, {});
    const ReadMeshResult result = readMesh(path);
    EXPECT_EQ(result.mesh.points, mesh.points);
    EXPECT_EQ(result.mesh.triangles, mesh.triangles);
    EXPECT_EQ(result.numPolygonsRead, mesh.numTriangles());
}

TEST(ReadMesh, ObjWithQuad)
{
    TempDir dir;
    const std::string path = dir.file("quad.OBJ");  // extensions are case-insensitive
    writeFile(path,
              "# a quad and a triangle\n"
              "v 0 0 0\n"
              "v 1 0 0\n"
              "v 1 1 0\n"
              "v 0 1 0\n"
              "v 0.5 0.5 1.5\n"
              "vn 0 0 1\n"
              "f 1//1 2//1 3//1 4//1\n"
              "f 2 3 5\n");
    const ReadMeshResult result = readMesh(path);
    EXPECT_EQ(result.format, "obj");
    EXPECT_EQ(result.numPolygonsRead, 2u);
    ASSERT_EQ(result.mesh.numVertices(), 5u);
    EXPECT_EQ(result.mesh.points[4], Vec3(0.5, 0.5, 1.5));
    EXPECT_EQ(result.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {1, 2, 4}}));
}

TEST(ReadMesh, ObjKeepsDuplicateAndNonManifoldFaces)
{
    // OpenMesh's own mesh kernel would refuse these faces; the raw importer must keep them.
    TempDir dir;
    const std::string path = dir.file("bad.obj");
    writeFile(path,
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
              "f 1 2 3\nf 1 2 3\nf 1 2 4\nf 1 2 5\n");
    const ReadMeshResult result = readMesh(path);
    EXPECT_EQ(result.mesh.numTriangles(), 4u);
}

TEST(ReadMesh, Off)
{
    TempDir dir;
    const std::string path = dir.file("mesh.off");
    writeFile(path,
              "OFF\n"
              "5 2 0\n"
              "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 2\n"
              "4 0 1 2 3\n"
              "3 1 2 4\n");
    const ReadMeshResult result = readMesh(path);
    EXPECT_EQ(result.format, "off");
    ASSERT_EQ(result.mesh.numVertices(), 5u);
    EXPECT_EQ(result.mesh.points[4], Vec3(0.5, 0.5, 2));
    EXPECT_EQ(result.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {1, 2, 4}}));
}

namespace {

/// Two triangles of the unit square, as STL lists them (vertices repeated per facet).
const float kStlTriangles[2][3][3] = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}}};

void expectStlSquare(const ReadMeshResult& result)
{
    EXPECT_EQ(result.format, "stl");
    ASSERT_EQ(result.mesh.numTriangles(), 2u);
    // Coordinates survive (whether or not shared corners are merged into one vertex).
    for (int f = 0; f < 2; ++f)
        for (int k = 0; k < 3; ++k) {
            const Vec3& p = result.mesh.points[result.mesh.triangles[std::size_t(f)][std::size_t(k)]];
            EXPECT_EQ(p, Vec3(kStlTriangles[f][k][0], kStlTriangles[f][k][1], kStlTriangles[f][k][2]));
        }
}

} // namespace

TEST(ReadMesh, AsciiStl)
{
    TempDir dir;
    const std::string path = dir.file("square.stl");
    std::string text = "solid square\n";
    for (const auto& triangle : kStlTriangles) {
        text += "  facet normal 0 0 1\n    outer loop\n";
        for (const auto& p : triangle)
            text += "      vertex " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
        text += "    endloop\n  endfacet\n";
    }
    text += "endsolid square\n";
    writeFile(path, text);
    expectStlSquare(readMesh(path));
}

TEST(ReadMesh, BinaryStlWhoseHeaderStartsWithSolid)
{
    // Many exporters start the 80-byte header of a binary STL with "solid": the reader must
    // still recognise it as binary (by its size).
    TempDir dir;
    const std::string path = dir.file("square.stl");
    std::string bytes = "solid exported by a careless tool";
    bytes.resize(80, ' ');
    appendBinary<std::uint32_t>(bytes, 2);
    for (const auto& triangle : kStlTriangles) {
        for (float n : {0.0f, 0.0f, 1.0f}) appendBinary(bytes, n);
        for (const auto& p : triangle)
            for (float c : p) appendBinary(bytes, c);
        appendBinary<std::uint16_t>(bytes, 0);
    }
    writeFile(path, bytes);
    expectStlSquare(readMesh(path));
}

TEST(ReadMesh, MissingFileIsIOError)
{
    TempDir dir;
    for (const char* name : {"missing.ply", "missing.obj", "missing.stl"}) {
        const std::string path = dir.file(name);
        try {
            readMesh(path);
            ADD_FAILURE() << "no exception for " << path;
        } catch (const IOError& e) {
            EXPECT_NE(std::string(e.what()).find("cannot open '" + path + "': No such file"), std::string::npos)
                << e.what();
        }
    }
}

TEST(ReadMesh, UnknownExtensionIsInvalidInput)
{
    TempDir dir;
    const std::string path = dir.file("mesh.xyz");
    writeFile(path, "0 0 0\n");
    try {
        readMesh(path);
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find(".ply, .obj, .off, .stl"), std::string::npos) << e.what();
    }
    writeFile(dir.file("mesh"), "0 0 0\n");
    EXPECT_THROW(readMesh(dir.file("mesh")), InvalidInputError);
}

TEST(ReadMesh, TruncatedBinaryPly)
{
    TempDir dir;
    const std::string full = dir.file("full.ply");
    writePly(full, smallMesh(), {});
    const std::string bytes = readFile(full);
    const std::size_t header = bytes.find("end_header\n") + 11;
    // Cut inside the vertices, inside the faces, and one byte short.
    for (std::size_t keep : {header + 5, header + 5 * 12 + 7, bytes.size() - 1}) {
        const std::string path = dir.file("cut.ply");
        writeFile(path, bytes.substr(0, keep));
        try {
            readMesh(path);
            ADD_FAILURE() << "no exception when keeping " << keep << " bytes";
        } catch (const InvalidInputError& e) {
            EXPECT_NE(std::string(e.what()).find("unexpected end of file in '" + path + "'"), std::string::npos)
                << e.what();
        }
    }
    // A list length that the file cannot hold is refused before allocating for it.
    std::string huge = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\n"
                       "property list uint int vertex_indices\nend_header\n";
    for (int i = 0; i < 3; ++i) appendBinary(huge, 0.0f);
    appendBinary<std::uint32_t>(huge, 4000000000u);
    appendBinary<std::int32_t>(huge, 0);
    writeFile(dir.file("huge.ply"), huge);
    EXPECT_THROW(readMesh(dir.file("huge.ply")), InvalidInputError);

    // The header itself cut short.
    writeFile(dir.file("cut.ply"), bytes.substr(0, header - 5));
    EXPECT_THROW(readMesh(dir.file("cut.ply")), InvalidInputError);
}

TEST(ReadMesh, TruncatedAsciiPly)
{
    TempDir dir;
    const std::string path = dir.file("cut.ply");
    writeFile(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
    EXPECT_THROW(readMesh(path), InvalidInputError);
}

TEST(ReadMesh, FaceIndexOutOfRange)
{
    TempDir dir;
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                               "end_header\n0 0 0\n1 0 0\n0 1 0\n";
    writeFile(dir.file("high.ply"), header + "3 0 1 3\n");
    writeFile(dir.file("negative.ply"), header + "3 0 -1 2\n");
    writeFile(dir.file("high.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    writeFile(dir.file("high.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    for (const char* name : {"high.ply", "negative.ply", "high.obj", "high.off"})
        EXPECT_THROW(readMesh(dir.file(name)), InvalidInputError) << name;

    // The binary fast path checks too.
    writePly(dir.file("ok.ply"), smallMesh(), {});
    const std::string bytes = readFile(dir.file("ok.ply"));
    const std::size_t lastIndex = bytes.size() - 4;  // last index of the last face
    std::string bad = bytes;
    const std::int32_t five = 5;
    std::memcpy(&bad[lastIndex], &five, 4);
    writeFile(dir.file("bad.ply"), bad);
    EXPECT_THROW(readMesh(dir.file("bad.ply")), InvalidInputError);
}

TEST(ReadMesh, EmptyAndGarbageFilesAreInvalidInputAndQuiet)
{
    TempDir dir;
    std::string garbage;
    for (int i = 0; i < 3000; ++i) garbage += char((i * 7919) % 251);
    for (const char* extension : {".ply", ".obj", ".off", ".stl"}) {
        const std::string empty = dir.file(std::string("empty") + extension);
        const std::string junk = dir.file(std::string("junk") + extension);
        writeFile(empty, "");
        writeFile(junk, garbage);
        testing::internal::CaptureStderr();
        testing::internal::CaptureStdout();
        EXPECT_THROW(readMesh(empty), InvalidInputError) << empty;
        EXPECT_THROW(readMesh(junk), InvalidInputError) << junk;
        // OpenMesh's own warnings must not reach the user.
        EXPECT_EQ(testing::internal::GetCapturedStdout(), "") << extension;
        EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << extension;
    }
}

TEST(ReadMesh, OpenMeshWarningsAreSilenced)
{
    TempDir dir;
    const std::string path = dir.file("material.obj");
    writeFile(path, "mtllib missing.mtl\nusemtl stone\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    testing::internal::CaptureStderr();
    testing::internal::CaptureStdout();
    EXPECT_EQ(readMesh(path).mesh.numTriangles(), 1u);
    EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(ReadMesh, TruncatedOff)
{
    // OpenMesh's OFF reader would silently repeat values for the missing ones.
    TempDir dir;
    const std::string complete = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    writeFile(dir.file("ok.off"), complete);
    EXPECT_EQ(readMesh(dir.file("ok.off")).mesh.numTriangles(), 2u);
    for (std::size_t cut : {complete.size() - 3, complete.size() - 9, complete.size() - 20}) {
        writeFile(dir.file("cut.off"), complete.substr(0, cut));
        EXPECT_THROW(readMesh(dir.file("cut.off")), InvalidInputError) << cut;
    }
}

TEST(ReadMesh, PlyHeaderErrors)
{
    TempDir dir;
    const std::string path = dir.file("bad.ply");
    const std::vector<std::string> headers = {
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
        "ply\nformat weird 1.0\nelement vertex 0\nend_header\n",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
        "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n3 0 1 2\n",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0 1\n",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 zero 0 0 1 0 3 0 1 2\n",
        "ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n",
    };
    for (const std::string& header : headers) {
        writeFile(path, header);
        EXPECT_THROW(readMesh(path), InvalidInputError) << header;
    }
}

// Real OFF files: a comment right after the keyword, comments at line ends, blank lines,
// colours after the indices, polygons; and OBJ files with v/vt/vn, negative indices,
// polygons, groups and objects.
TEST(ReadMesh, OffAndObjAsRealFilesHaveThem)
{
    TempDir dir;
    writeFile(dir.file("commented.off"), "OFF\n# made by a scanner\n\n4 2 0\n0 0 0\n1 0 0 # corner\n1 1 0\n\n0 1 0\n"
                                         "4 0 1 2 3 255 0 0\n3 0 2 1 0.5 0.5 0.5\n");
    const ReadMeshResult off = readMesh(dir.file("commented.off"));
    EXPECT_EQ(off.mesh.points.size(), 4u);
    EXPECT_EQ(off.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {0, 2, 1}}));
    EXPECT_EQ(off.numPolygonsRead, 2u);
    EXPECT_EQ(off.mesh.points[1], Vec3(1, 0, 0));
    writeFile(dir.file("counts-on-keyword-line.off"), "COFF 3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n");
    EXPECT_EQ(readMesh(dir.file("counts-on-keyword-line.off")).mesh.triangles, (std::vector<Triangle>{{0, 1, 2}}));

    writeFile(dir.file("textured.obj"), "# exported\nmtllib t.mtl\no tablet\ng front\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                        "vt 0 0\nvt 1 0\nvn 0 0 1\nusemtl clay\ns 1\nf 1/1/1 2/2/1 3/2/1 4/1/1\n"
                                        "g back\nf -4//1 -2//1 -1//1\n");
    const ReadMeshResult obj = readMesh(dir.file("textured.obj"));
    EXPECT_EQ(obj.mesh.points.size(), 4u);
    EXPECT_EQ(obj.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {0, 2, 3}}));
}

// An OBJ vertex whose coordinates OpenMesh cannot read (nan, inf, beyond float) is named by
// its line and number, not reported later as a face pointing past the last vertex.
TEST(ReadMesh, ObjVertexThatIsNotFiniteIsNamedByItsLine)
{
    TempDir dir;
    const std::string head = "# a scan\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (const auto& [name, bad, mentions] :
         {std::tuple{"nan.obj", "v nan 0 0", "'nan', which is not a finite number"},
          std::tuple{"inf.obj", "v 0 -inf 0", "'-inf', which is not a finite number"},
          std::tuple{"huge.obj", "v 0 0 1e308", "'1e308', beyond the range"}}) {
        writeFile(dir.file(name), head + bad + "\nv 1 1 0\nf 1 2 3\nf 2 5 3\n");
        try {
            readMesh(dir.file(name));
            ADD_FAILURE() << name << " was read";
        } catch (const InvalidInputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("line 5: vertex 4 has the coordinate " + std::string(mentions)), std::string::npos) << what;
        }
    }
    // Vertex normals and texture coordinates are not vertices; ordinary numbers pass.
    writeFile(dir.file("fine.obj"), head + "vn 0 0 1\nvt 0.5 0.5\nv 1 1 -2.5e-3\nf 1 2 3\nf 2 4 3\n");
    EXPECT_EQ(readMesh(dir.file("fine.obj")).mesh.numVertices(), 4u);
}

// An OFF vertex with a coordinate that is not a finite number (out of range, nan, inf) is
// named as such, with its number; one with too few numbers keeps its own message.
TEST(ReadMesh, OffVertexThatIsNotFiniteIsNamed)
{
    TempDir dir;
    for (const auto& [name, bad, mentions] :
         {std::tuple{"huge.off", "1e400 0 0", "vertex 1 has the coordinate '1e400', which is not a finite number"},
          std::tuple{"nan.off", "0 nan 0", "vertex 1 has the coordinate 'nan', which is not a finite number"},
          std::tuple{"inf.off", "0 0 -inf", "vertex 1 has the coordinate '-inf', which is not a finite number"},
          std::tuple{"short.off", "0 0", "vertex 1 is not 3 numbers ('0 0')"}}) {
        writeFile(dir.file(name), std::string("OFF\n3 1 0\n0 0 0\n") + bad + "\n0 1 0\n3 0 1 2\n");
        try {
            readMesh(dir.file(name));
            ADD_FAILURE() << name << " was read";
        } catch (const InvalidInputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(mentions), std::string::npos) << what;
        }
    }
}

// Messages that quote a file's bytes stay one printable line.
TEST(Errors, PrintableLineEscapesControlsAndBrokenUtf8)
{
    EXPECT_EQ(printableLine("plain text, π·R and ×"), "plain text, π·R and ×");
    EXPECT_EQ(printableLine("a\nb\rc\td\x01"), "a\\x0Ab\\x0Dc\\x09d\\x01");
    EXPECT_EQ(printableLine(std::string("bad \xFF byte \xC3")), "bad \\xFF byte \\xC3");
    EXPECT_EQ(printableLine("\xC2\x85 next line, \xE2\x80\xA8 separator"), "\\xC2\\x85 next line, \\xE2\\x80\\xA8 separator");
    EXPECT_EQ(printableLine("\x7F"), "\\x7F");
    // Format characters (U+0603, U+200B) escaped; letters of names kept.
    EXPECT_EQ(printableLine("Tafel_Zürich_ΑΩ_Москва ≥ 2 m²"), "Tafel_Zürich_ΑΩ_Москва ≥ 2 m²");
    EXPECT_EQ(printableLine("a\xD8\x83" "b\xE2\x80\x8B" "c"), "a\\xD8\\x83b\\xE2\\x80\\x8Bc");
}

// Indices as the file has them: OBJ's 0 (it counts from 1), an OFF index written inf.
TEST(ReadMesh, BadFaceIndicesAreNamedAsWritten)
{
    TempDir dir;
    writeFile(dir.file("zero.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0/1 2/2 3/3\n");
    writeFile(dir.file("inf.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 inf\n");
    for (const auto& [name, mentions] : {std::pair{"zero.obj", "line 4: the face corner '0/1' has the vertex index 0"},
                                         std::pair{"inf.off", "vertex index inf in face 1"}}) {
        try {
            readMesh(dir.file(name));
            ADD_FAILURE() << name << " was read";
        } catch (const InvalidInputError& e) {
            EXPECT_NE(std::string(e.what()).find(mentions), std::string::npos) << e.what();
        }
    }
}

// A binary STL cut short, or with a damaged count, is said to be so (OpenMesh would read it
// as text and find no vertices).
TEST(ReadMesh, BinaryStlOfTheWrongSizeIsNamedAsSuch)
{
    TempDir dir;
    std::string bytes(84 + 2 * 50, '\0');
    bytes[80] = 2;  // two triangles
    for (int t = 0; t < 2; ++t) {
        const float corners[9] = {0, 0, 0, 1, 0, 0, 0, 1, float(t)};
        std::memcpy(&bytes[std::size_t(84 + 50 * t + 12)], corners, sizeof corners);
    }
    writeFile(dir.file("whole.stl"), bytes);
    EXPECT_EQ(readMesh(dir.file("whole.stl")).mesh.numTriangles(), 2u);
    writeFile(dir.file("short.stl"), bytes.substr(0, bytes.size() - 7));
    try {
        readMesh(dir.file("short.stl"));
        ADD_FAILURE() << "read";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("is a binary STL that declares 2 triangles (184 bytes) but is 177 bytes long"),
                  std::string::npos)
            << e.what();
    }
}
