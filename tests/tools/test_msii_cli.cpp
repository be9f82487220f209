// Drives the msii program as a user would: a good run writes a PLY with the promised
// properties and a JSON record; every kind of bad input ends in one "msii: error:" line, a
// non-zero exit and no output file.
#include <msii/io/write_ply.h>
#include <msii/mesh/read_mesh.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::writeFile;

namespace {

struct RunResult {
    int code = -1;
    std::string err;
};

/// One folder for the whole test program, removed at exit.
const fs::path& tempDir()
{
    static const msii::test::TempDir dir;
    return dir.path();
}

RunResult runMsii(const std::string& args)
{
    const fs::path err = tempDir() / "stderr.txt";
    const std::string cmd = std::string("'") + MSII_EXE + "' " + args + " >/dev/null 2>'" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = readFile(err.string());
    return r;
}

std::string writeText(const std::string& name, const std::string& text)
{
    const std::string path = (tempDir() / name).string();
    writeFile(path, text);
    return path;
}

std::string smallPatch()
{
    static const std::string path = [] {
        samples::HeightFieldOptions o;
        o.kind = samples::HeightFieldKind::Tablet;
        o.width = 4;
        o.height = 4;
        o.spacing = 0.1;
        const std::string p = (tempDir() / "patch.ply").string();
        writePly(p, samples::makeHeightField(o), {});
        return p;
    }();
    return path;
}

/// One clear line, non-zero exit, and no output left behind.
void expectCleanFailure(const std::string& args, const std::string& mentions)
{
    SCOPED_TRACE(args);
    const fs::path out = tempDir() / "bad_out.ply";
    fs::remove(out);
    const RunResult r = runMsii("compute " + args + " --output '" + out.string() + "'");
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    for (const auto& entry : fs::directory_iterator(tempDir()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

} // namespace

TEST(MsiiCli, ComputeWritesFeaturesAndSidecar)
{
    const fs::path out = tempDir() / "good.ply";
    const RunResult r = runMsii("compute '" + smallPatch() + "' --radius 0.8 --scales 4 --quiet --overwrite --output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;  // --quiet
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    const ReadMeshResult res = readMesh(out.string(), ro);
    std::vector<std::string> names;
    for (const auto& p : res.vertexProperties) names.push_back(p.name);
    const std::vector<std::string> expected{"V_01", "V_02", "V_03", "V_04", "S_01", "S_02", "S_03", "S_04", "quality"};
    EXPECT_EQ(names, expected);
    // Middle of a gently curved tablet: values near one half; near the border: NaN.
    std::size_t finite = 0, masked = 0;
    for (float v : res.vertexProperties[0].values) (std::isnan(v) ? masked : finite)++;
    EXPECT_GT(finite, 0u);
    EXPECT_GT(masked, 0u);
    const std::string json = readFile((tempDir() / "good.json").string());
    for (const char* key : {"\"radii\"", "\"voxel_size\"", "\"timings_seconds\"", "\"version\"", "\"median\""})
        EXPECT_NE(json.find(key), std::string::npos) << key;
    // Existing output without --overwrite: refused.
    const RunResult again = runMsii("compute '" + smallPatch() + "' --radius 0.8 --scales 4 --output '" + out.string() + "'");
    EXPECT_NE(again.code, 0);
    EXPECT_NE(again.err.find("--overwrite"), std::string::npos);
}

TEST(MsiiCli, BadInputFailsCleanly)
{
    const std::string patch = "'" + smallPatch() + "'";
    expectCleanFailure("'" + (tempDir() / "missing.ply").string() + "' -r 1", "cannot open");
    expectCleanFailure("'" + writeText("mesh.xyz", "1 2 3\n") + "' -r 1", "xyz");
    expectCleanFailure("'" + writeText("empty.off", "OFF\n0 0 0\n") + "' -r 1", "empty.off");
    expectCleanFailure("'" + writeText("verts.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n") + "' -r 1", "faces");
    expectCleanFailure("'" + writeText("nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n") + "' -r 1", "NaN");
    expectCleanFailure("'" + writeText("inf.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n") + "' -r 1", "infinite");
    expectCleanFailure("'" + writeText("degenerate.obj",
                                       "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n") + "' -r 1",
                       "degenerate");
    expectCleanFailure("'" + writeText("duplicate.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\n") + "' -r 1",
                       "duplicate");
    expectCleanFailure("'" + writeText("nonmanifold.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
                                       "f 1 2 3\nf 2 1 4\nf 1 2 5\n") + "' -r 1",
                       "non-manifold");
    expectCleanFailure(patch, "--radius is required");
    expectCleanFailure(patch + " -r 0", "radius");
    expectCleanFailure(patch + " -r -2", "radius");
    expectCleanFailure(patch + " -r 1 -n 0", "scales");
    expectCleanFailure(patch + " -r 1 -n 100000", "scales");
    expectCleanFailure(patch + " -r 1e9", "radius");
    {
        SCOPED_TRACE("unwritable output");
        const RunResult r = runMsii("compute " + patch + " -r 1 --output /nonexistent-folder/x.ply");
        EXPECT_NE(r.code, 0);
        EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    }
}
