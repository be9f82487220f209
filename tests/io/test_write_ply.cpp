/// Tests of io/write_ply.h (round trips through the PLY reader, exact values) and of
/// io/atomic_file.h (no partial or temporary files left behind).

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>
#include <msii/io/write_ply.h>
#include <msii/io/read_ply.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <csignal>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../support/files.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::TempDir;

namespace {

/// A tetrahedron with float-exact but "awkward" coordinates, and 3 properties.
struct Sample {
    TriMesh mesh;
    std::vector<VertexProperty> properties;
};

Sample sample()
{
    Sample s;
    s.mesh.points = {{0.1f, -2.75, 1e-5f}, {1.0f / 3.0f, 7, -0.0}, {123456.78f, 0.2f, 3}, {-1, -1, 1e30f}};
    s.mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    s.properties = {{"V_01", {0.5f, 1.0f / 7.0f, -3e-20f, 1e20f}},
                    {"quality", {std::numeric_limits<float>::quiet_NaN(), 0, 1, 2}},
                    {"curvature", {-1.5f, std::numeric_limits<float>::infinity(), 3.25f, 0.1f}}};
    return s;
}

void expectSameFloats(const std::vector<float>& a, const std::vector<float>& b)
{
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (std::isnan(b[i])) EXPECT_TRUE(std::isnan(a[i])) << i;
        else EXPECT_EQ(a[i], b[i]) << i;
    }
}

void expectRoundTrip(const std::string& path, const Sample& s)
{
    ReadMeshOptions options;
    options.keepVertexProperties = true;
    const ReadMeshResult result = readPly(path, options);
    EXPECT_EQ(result.mesh.points, s.mesh.points);
    EXPECT_EQ(result.mesh.triangles, s.mesh.triangles);
    ASSERT_EQ(result.vertexProperties.size(), s.properties.size());
    for (std::size_t i = 0; i < s.properties.size(); ++i) {
        EXPECT_EQ(result.vertexProperties[i].name, s.properties[i].name);
        expectSameFloats(result.vertexProperties[i].values, s.properties[i].values);
    }
}

} // namespace

TEST(WritePly, BinaryRoundTripIsExact)
{
    TempDir dir;
    const Sample s = sample();
    WritePlyOptions options;
    options.comments = {"msii test", "two\nlines"};
    writePly(dir.file("out.ply"), s.mesh, s.properties, options);
    const std::string bytes = readFile(dir.file("out.ply"));
    const std::string header = bytes.substr(0, bytes.find("end_header\n") + 11);
    EXPECT_EQ(header,
              "ply\nformat binary_little_endian 1.0\ncomment msii test\ncomment two lines\n"
              "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
              "property float V_01\nproperty float quality\nproperty float curvature\n"
              "element face 4\nproperty list uchar int vertex_indices\nend_header\n");
    EXPECT_EQ(bytes.size(), header.size() + 4 * 6 * 4 + 4 * 13);
    expectRoundTrip(dir.file("out.ply"), s);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.ply"});
}

// Integer properties (labels, counts) are written as int, NaN as 0, and read back as
// integers; a name prefix (CloudCompare's scalar_) is written to the header and taken off
// again by the reader, so msii reads what it wrote either way.
TEST(WritePly, IntegerPropertiesAndNamePrefix)
{
    TempDir dir;
    Sample s = sample();
    s.properties.push_back({"label", {3, 0, std::numeric_limits<float>::quiet_NaN(), 16777216}, true});
    for (const bool binary : {true, false}) {
        SCOPED_TRACE(binary ? "binary" : "ascii");
        WritePlyOptions options;
        options.binary = binary;
        options.propertyPrefix = "scalar_";
        const std::string path = dir.file(binary ? "int.ply" : "int-ascii.ply");
        writePly(path, s.mesh, s.properties, options);
        const std::string bytes = readFile(path);
        const std::string header = bytes.substr(0, bytes.find("end_header\n"));
        EXPECT_NE(header.find("property float scalar_V_01\nproperty float scalar_quality\n"
                              "property float scalar_curvature\nproperty int scalar_label\n"),
                  std::string::npos) << header;
        ReadMeshOptions ro;
        ro.keepVertexProperties = true;
        const ReadMeshResult back = readPly(path, ro);
        ASSERT_EQ(back.vertexProperties.size(), 4u);
        EXPECT_EQ(back.vertexProperties[1].name, "quality");
        EXPECT_FALSE(back.vertexProperties[1].integer);
        EXPECT_EQ(back.vertexProperties[3].name, "label");
        EXPECT_TRUE(back.vertexProperties[3].integer);
        EXPECT_EQ(back.vertexProperties[3].values, (std::vector<float>{3, 0, 0, 16777216}));
    }
}

TEST(WritePly, AsciiRoundTripIsExact)
{
    TempDir dir;
    const Sample s = sample();
    WritePlyOptions options;
    options.binary = false;
    writePly(dir.file("out.ply"), s.mesh, s.properties, options);
    const std::string text = readFile(dir.file("out.ply"));
    EXPECT_EQ(text.rfind("ply\nformat ascii 1.0\n", 0), 0u);
    EXPECT_NE(text.find("\n3 0 2 1\n"), std::string::npos);
    expectRoundTrip(dir.file("out.ply"), s);
}

TEST(WritePly, ListPropertyIsWrittenAndSkippedByTheReader)
{
    TempDir dir;
    const Sample s = sample();
    for (bool binary : {true, false}) {
        WritePlyOptions options;
        options.binary = binary;
        options.listName = "features";
        options.listLength = 3;
        for (int i = 0; i < 12; ++i) options.listValues.push_back(float(i) * 0.5f);
        writePly(dir.file("list.ply"), s.mesh, s.properties, options);
        const std::string bytes = readFile(dir.file("list.ply"));
        EXPECT_NE(bytes.find("property float curvature\nproperty list uchar float features\nelement face 4\n"),
                  std::string::npos);
        if (binary) EXPECT_EQ(bytes.size(), bytes.find("end_header\n") + 11 + 4 * (24 + 1 + 12) + 4 * 13);
        else EXPECT_NE(bytes.find(" 3 0 0.5 1\n"), std::string::npos);
        expectRoundTrip(dir.file("list.ply"), s);
    }
}

TEST(WritePly, DoublePointsWhenFloatWouldLoseDetail)
{
    TempDir dir;
    TriMesh mesh;
    // Map coordinates: a 1 m triangle 5000 km from the origin, with mm detail.
    mesh.points = {{5e6 + 0.001, 1e6, 10}, {5e6 + 1.002, 1e6, 10}, {5e6, 1e6 + 1.003, 10.5}};
    mesh.triangles = {{0, 1, 2}};
    writePly(dir.file("map.ply"), mesh, {});
    EXPECT_NE(readFile(dir.file("map.ply")).find("property double x\n"), std::string::npos);
    EXPECT_EQ(readPly(dir.file("map.ply")).mesh.points, mesh.points);

    // Float-exact points stay float unless double is forced.
    const Sample s = sample();
    writePly(dir.file("float.ply"), s.mesh, {});
    EXPECT_NE(readFile(dir.file("float.ply")).find("property float x\n"), std::string::npos);
    WritePlyOptions options;
    options.forceDoublePoints = true;
    options.binary = false;
    mesh.points[0].x = 0.1;
    writePly(dir.file("forced.ply"), mesh, {}, options);
    EXPECT_NE(readFile(dir.file("forced.ply")).find("property double z\n"), std::string::npos);
    EXPECT_EQ(readPly(dir.file("forced.ply")).mesh.points, mesh.points);
}

TEST(WritePly, InvalidPropertiesLeaveNoFile)
{
    TempDir dir;
    const Sample s = sample();
    std::vector<VertexProperty> shortProperty = s.properties;
    shortProperty[1].values.pop_back();
    EXPECT_THROW(writePly(dir.file("a.ply"), s.mesh, shortProperty), InvalidInputError);
    std::vector<VertexProperty> badName = s.properties;
    badName[0].name = "two words";
    EXPECT_THROW(writePly(dir.file("a.ply"), s.mesh, badName), InvalidInputError);
    WritePlyOptions options;
    options.listName = "features";
    options.listLength = 2;
    options.listValues.resize(7);
    EXPECT_THROW(writePly(dir.file("a.ply"), s.mesh, s.properties, options), InvalidInputError);
    TriMesh badMesh = s.mesh;
    badMesh.triangles[2][1] = 4;
    EXPECT_THROW(writePly(dir.file("a.ply"), badMesh, {}), InvalidInputError);
    EXPECT_TRUE(dir.entries().empty());
}

TEST(WritePly, MissingFolderIsIOError)
{
    TempDir dir;
    const Sample s = sample();
    try {
        writePly(dir.file("no/such/folder/out.ply"), s.mesh, s.properties);
        ADD_FAILURE() << "no exception";
    } catch (const IOError& e) {
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
}

// More than two batches of records (8 chunks of 32768 per batch) for vertices and faces, so
// that the next batch is formatted while one is written.
TEST(WritePly, LargeMeshWithManyPropertiesRoundTrips)
{
    TempDir dir;
    TriMesh mesh;
    const std::uint32_t n = 600000;
    for (std::uint32_t i = 0; i < n; ++i) mesh.points.push_back({float(i) * 0.25f, float(i % 97), -float(i % 13)});
    for (std::uint32_t i = 0; i + 2 < n; ++i) mesh.triangles.push_back({i, i + 1, i + 2});
    std::vector<VertexProperty> properties;
    for (int p = 0; p < 8; ++p) {
        properties.push_back({"V_" + std::to_string(p), std::vector<float>(n)});
        for (std::uint32_t i = 0; i < n; ++i) properties.back().values[i] = float(i) / float(p + 1);
    }
    writePly(dir.file("big.ply"), mesh, properties);
    ReadMeshOptions options;
    options.keepVertexProperties = true;
    const ReadMeshResult result = readPly(dir.file("big.ply"), options);
    EXPECT_EQ(result.mesh.points, mesh.points);
    EXPECT_EQ(result.mesh.triangles, mesh.triangles);
    ASSERT_EQ(result.vertexProperties.size(), properties.size());
    for (std::size_t p = 0; p < properties.size(); ++p)
        EXPECT_EQ(result.vertexProperties[p].values, properties[p].values);
}

// ---------------------------------------------------------------------------------------
// AtomicFile

// PlyPieceWriter (results larger than memory are written tile by tile): pieces in
// any order give the bytes of writePly; vertices never given are NaN; nothing appears before
// commit(), and an abandoned writer leaves no file.
TEST(PlyPieceWriter, PiecesInAnyOrderGiveTheBytesOfWritePly)
{
    TempDir dir;
    // A strip of 300 vertices (runs of consecutive vertices and single ones), 2 properties.
    TriMesh mesh;
    std::vector<VertexProperty> properties = {{"V_01", {}}, {"quality", {}}};
    for (int i = 0; i < 300; ++i) {
        mesh.points.push_back({0.1 * i, (i % 2) * 0.7, std::sin(0.05 * i)});
        properties[0].values.push_back(float(i) / 7.0f);
        properties[1].values.push_back(i % 11 == 0 ? std::numeric_limits<float>::quiet_NaN() : -float(i));
    }
    for (std::uint32_t i = 0; i + 2 < 300; ++i) mesh.triangles.push_back({i, i + 1 + (i % 2), i + 2 - (i % 2)});
    for (bool doublePoints : {false, true}) {
        WritePlyOptions options;
        options.forceDoublePoints = doublePoints;
        options.comments = {"msii test"};
        writePly(dir.file("whole.ply"), mesh, properties, options);
        fs::remove(dir.file("pieces.ply"));
        {
            PlyPieceWriter pieces(dir.file("pieces.ply"), mesh, {{"V_01"}, {"quality"}}, options);
            // Three pieces, last vertices first; vertex 0 is part of the second piece.
            const std::vector<std::vector<std::uint32_t>> parts = {
                {200, 201, 202, 250, 251, 299}, {0, 1, 2, 3, 150}, {}};
            std::vector<bool> given(300, false);
            for (const auto& part : parts)
                for (std::uint32_t v : part) given[v] = true;
            std::vector<std::uint32_t> rest;
            for (std::uint32_t v = 0; v < 300; ++v)
                if (!given[v]) rest.push_back(v);
            std::vector<std::vector<std::uint32_t>> all = parts;
            all.push_back(rest);
            for (const auto& part : all) {
                std::vector<float> a, b;
                for (std::uint32_t v : part) a.push_back(properties[0].values[v]), b.push_back(properties[1].values[v]);
                pieces.write(part, {a.data(), b.data()});
            }
            EXPECT_FALSE(fs::exists(dir.file("pieces.ply")));
            pieces.commit();
        }
        EXPECT_EQ(readFile(dir.file("pieces.ply")), readFile(dir.file("whole.ply"))) << "double points " << doublePoints;
    }

    // Vertices never given are NaN; the rest as given.
    {
        PlyPieceWriter pieces(dir.file("partial.ply"), mesh, {{"V_01"}});
        const float value[2] = {0.25f, 0.5f};
        pieces.write({7, 8}, {value});
        pieces.commit();
    }
    ReadMeshOptions keep;
    keep.keepVertexProperties = true;
    const ReadMeshResult partial = readPly(dir.file("partial.ply"), keep);
    ASSERT_EQ(partial.vertexProperties.size(), 1u);
    EXPECT_EQ(partial.mesh.points.size(), 300u);
    EXPECT_EQ(partial.mesh.triangles, mesh.triangles);
    const std::vector<float>& v = partial.vertexProperties[0].values;
    EXPECT_EQ(v[7], 0.25f);
    EXPECT_EQ(v[8], 0.5f);
    std::size_t nans = 0;
    for (float x : v) nans += std::isnan(x);
    EXPECT_EQ(nans, 298u);

    // Abandoned (e.g. a tile failed): no file, no temporary.
    {
        PlyPieceWriter pieces(dir.file("abandoned.ply"), mesh, {{"V_01"}});
        const float value = 1;
        pieces.write({3}, {&value});
    }
    EXPECT_FALSE(fs::exists(dir.file("abandoned.ply")));
    for (const auto& entry : fs::directory_iterator(dir.path()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();

    // Misuse is refused.
    PlyPieceWriter pieces(dir.file("misuse.ply"), mesh, {{"V_01"}});
    const float value = 1;
    EXPECT_THROW(pieces.write({300}, {&value}), InvalidInputError);
    EXPECT_THROW(pieces.write({3}, {}), InvalidInputError);
    WritePlyOptions ascii;
    ascii.binary = false;
    EXPECT_THROW(PlyPieceWriter(dir.file("ascii.ply"), mesh, {{"V_01"}}, ascii), InvalidInputError);
    EXPECT_THROW(PlyPieceWriter(dir.file("bad.ply"), mesh, {{"two words"}}), InvalidInputError);
}

TEST(AtomicFile, CommitReplacesTargetAndLeavesNoTemporary)
{
    TempDir dir;
    const std::string target = dir.file("out.txt");
    writeTextFileAtomic(target, "old");
    {
        AtomicFile file(target);
        file.write(std::string("new "));
        file.write("content", 7);
        EXPECT_EQ(readFile(target), "old");  // untouched until commit
        file.commit();
    }
    EXPECT_EQ(readFile(target), "new content");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

// Mode::Large (O_DIRECT blocks of 16 MB written in the background): appends of odd sizes,
// patches in the part already written, across its end, in the block being filled and
// beyond the end, and a tail that is not a whole 4 KB give the bytes of an in-memory model,
// as in Mode::Buffered.
TEST(AtomicFile, LargeModeGivesTheBytesWritten)
{
    TempDir dir;
    const std::size_t mb = std::size_t(1) << 20;
    std::vector<char> data(36 * mb + 12345);
    std::uint32_t state = 12345;
    for (char& c : data) c = char((state = state * 1664525u + 1013904223u) >> 24);
    for (const auto mode : {AtomicFile::Mode::Large, AtomicFile::Mode::Buffered}) {
        const std::string target = dir.file(mode == AtomicFile::Mode::Large ? "large.bin" : "buffered.bin");
        std::vector<char> model;
        AtomicFile file(target, mode);
        if (mode == AtomicFile::Mode::Large)
            std::printf("Mode::Large in %s: %s\n", dir.path().c_str(),
                        file.writesDirect() ? "direct writes" : "the file system refuses O_DIRECT: buffered");
        const auto append = [&](std::size_t from, std::size_t to) {
            // In uneven pieces, as OpenEXR writes: 4-byte fields and large chunks.
            for (std::size_t at = from; at < to;) {
                const std::size_t n = std::min(to - at, at % 3 == 0 ? std::size_t(4) : std::size_t(3 * mb + 7));
                file.write(data.data() + at, n);
                model.insert(model.end(), data.begin() + std::ptrdiff_t(at), data.begin() + std::ptrdiff_t(at + n));
                at += n;
            }
            EXPECT_EQ(file.position(), model.size());
        };
        const auto patch = [&](std::size_t offset, std::size_t bytes, char value) {
            const std::vector<char> p(bytes, value);
            file.writeAt(offset, p.data(), bytes);
            if (model.size() < offset + bytes) model.resize(offset + bytes);
            std::fill(model.begin() + std::ptrdiff_t(offset), model.begin() + std::ptrdiff_t(offset + bytes), value);
        };
        append(0, 20 * mb);              // the first block is written, 4 MB fill the second
        patch(100, 1000, 'a');           // written part
        patch(16 * mb - 500, 1000, 'b');  // across its end
        patch(18 * mb, 1000, 'c');        // in the block being filled
        patch(20 * mb + 10, 20, 'd');     // beyond the end: a hole, then overwritten
        const std::size_t before = model.size();
        model.resize(20 * mb);
        append(20 * mb, data.size());
        ASSERT_GT(model.size(), before);
        patch(data.size() - 3, 3, 'e');   // in the tail
        file.commit();
        EXPECT_TRUE(readFile(target) == std::string(model.begin(), model.end()));
    }
}

TEST(AtomicFile, ExceptionBeforeCommitLeavesTargetUntouched)
{
    TempDir dir;
    const std::string target = dir.file("out.txt");
    writeTextFileAtomic(target, "original");
    try {
        AtomicFile file(target);
        file.write(std::string(100000, 'x'));
        EXPECT_EQ(dir.entries().size(), 2u);  // target and the temporary file
        throw std::runtime_error("interrupted");
    } catch (const std::runtime_error&) {
    }
    EXPECT_EQ(readFile(target), "original");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});

    // Without a previous target, nothing appears at all.
    { AtomicFile file(dir.file("new.txt")); file.write(std::string("data")); }
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, ClearErrors)
{
    TempDir dir;
    const std::string missing = dir.file("missing/out.txt");
    try {
        AtomicFile file(missing);
        ADD_FAILURE() << "no exception";
    } catch (const IOError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("cannot write '" + missing + "': ", 0), 0u) << e.what();
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
    EXPECT_THROW(checkWritable(missing), IOError);

    fs::create_directory(dir.file("folder"));
    EXPECT_THROW(AtomicFile(dir.file("folder")), IOError);
    EXPECT_THROW(checkWritable(dir.file("folder")), IOError);
    EXPECT_THROW(writeTextFileAtomic(dir.file("folder"), "x"), IOError);
    EXPECT_TRUE(fs::is_directory(dir.file("folder")));

    EXPECT_NO_THROW(checkWritable(dir.file("fine.txt")));
    EXPECT_FALSE(fs::exists(dir.file("fine.txt")));  // checking creates nothing

    // A folder without write permission (root ignores permissions, so only check then).
    if (::geteuid() != 0) {
        fs::create_directory(dir.file("readonly"));
        fs::permissions(dir.file("readonly"), fs::perms::owner_read | fs::perms::owner_exec);
        EXPECT_THROW(checkWritable(dir.file("readonly/out.txt")), IOError);
        EXPECT_THROW(AtomicFile(dir.file("readonly/out.txt")), IOError);
        fs::permissions(dir.file("readonly"), fs::perms::owner_all);
    }
}

// An interrupted process (Ctrl-C, kill, a closed terminal) leaves neither the target nor its
// temporary file: a child opens two AtomicFiles, writes, and is killed by each signal.
// A write error in Mode::Large's background thread (here: the file size limit at 20 MB, in
// a child process) fails the next writes and commit(), a second commit() too, and leaves
// neither the target nor a temporary file.
TEST(AtomicFile, LargeModeWriteErrorFailsEveryCommit)
{
    for (const auto mode : {AtomicFile::Mode::Large, AtomicFile::Mode::Buffered}) {
        TempDir dir;
        const pid_t child = ::fork();
        ASSERT_GE(child, 0);
        if (child == 0) {
            std::signal(SIGXFSZ, SIG_IGN);
            const rlimit limit{20u << 20, 20u << 20};
            if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(10);
            const std::vector<char> chunk(std::size_t(1) << 20, 'x');
            int code = 0;
            {
                AtomicFile file(dir.file("out.bin"), mode);
                int failed = -1;
                for (int i = 0; i < 40 && failed < 0; ++i) {
                    try {
                        file.write(chunk.data(), chunk.size());
                    } catch (const IOError&) {
                        failed = i;
                    }
                }
                // Buffered: fails at 20 MB or at commit; Large: by the block after 32 MB.
                if (failed >= 0 && failed < 19) code = 11;
                for (int attempt = 0; attempt < 2; ++attempt) {
                    try {
                        file.commit();
                        code = 12 + attempt;  // must not succeed
                    } catch (const IOError&) {
                    }
                }
            }
            ::_exit(code);
        }
        int status = 0;
        ASSERT_EQ(::waitpid(child, &status, 0), child);
        ASSERT_TRUE(WIFEXITED(status));
        EXPECT_EQ(WEXITSTATUS(status), 0) << (mode == AtomicFile::Mode::Large ? "large" : "buffered");
        EXPECT_TRUE(dir.entries().empty());
    }
}

TEST(AtomicFile, InterruptionRemovesTheTemporaryFiles)
{
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        TempDir dir;
        writeTextFileAtomic(dir.file("old.txt"), "original");
        const pid_t child = ::fork();
        ASSERT_GE(child, 0);
        if (child == 0) {
            AtomicFile a(dir.file("a.ply")), b(dir.file("old.txt"));
            a.write(std::string(100000, 'x'));
            b.write(std::string("new"));
            ::raise(sig);
            ::_exit(0);  // not reached
        }
        int status = 0;
        ASSERT_EQ(::waitpid(child, &status, 0), child);
        EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "signal " << sig;
        EXPECT_EQ(dir.entries(), std::vector<std::string>{"old.txt"}) << "signal " << sig;
        EXPECT_EQ(readFile(dir.file("old.txt")), "original");
    }
}
