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
#include <sstream>
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
    const std::vector<std::string> expected{"V_01", "V_02", "V_03", "V_04", "S_01", "S_02",
                                            "S_03", "S_04", "P_01", "P_02", "P_03", "P_04",
                                            "L_01", "L_02", "L_03", "L_04", "quality"};
    ASSERT_EQ(names, expected);
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
    expectCleanFailure(patch + " -r 1 --invariants V,Q", "unknown invariant 'Q'");
    expectCleanFailure(patch + " -r 1 --invariants ,", "selects nothing");
    expectCleanFailure(patch + " -r 1 --exact --vertices 0,99999999", "vertex 99999999 does not exist");
    expectCleanFailure(patch + " -r 1 --exact --vertices 0,x7", "'x7' is not a vertex index");
    expectCleanFailure(patch + " -r 1 --exact --vertices -3", "'-3' is not a vertex index");
    expectCleanFailure(patch + " -r 1 --exact --random-vertices 99999999", "more than the mesh");
    expectCleanFailure(patch + " -r 1 --vertices 3", "go with --exact");
    expectCleanFailure(patch + " -r 1 --invariants S,L --gigamesh", "--gigamesh writes V and P");
    {
        SCOPED_TRACE("unwritable output");
        const RunResult r = runMsii("compute " + patch + " -r 1 --output /nonexistent-folder/x.ply");
        EXPECT_NE(r.code, 0);
        EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    }
}

// Selection, exact mode and GigaMesh files from the command line: the exact values at the
// chosen vertices agree with the fast ones, the rest are NaN, and the GigaMesh files hold
// V as 2x - 1 and P, radii largest first.
TEST(MsiiCli, ExactModeSelectionAndGigaMeshFiles)
{
    const fs::path dir = tempDir() / "exact";
    fs::create_directories(dir);
    const fs::path fast = dir / "fast.msii.ply", exact = dir / "exact.msii.ply";
    const std::string common = "compute '" + smallPatch() + "' --radius 0.8 --scales 4 --quiet --overwrite ";
    const RunResult rf = runMsii(common + "--invariants V,P --gigamesh --output '" + fast.string() + "'");
    ASSERT_EQ(rf.code, 0) << rf.err;
    const RunResult re = runMsii(common + "--invariants P,V --exact --random-vertices 40 --seed 3 --output '" + exact.string() + "'");
    ASSERT_EQ(re.code, 0) << re.err;
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    const ReadMeshResult f = readMesh(fast.string(), ro), e = readMesh(exact.string(), ro);
    std::vector<std::string> names;
    for (const auto& p : e.vertexProperties) names.push_back(p.name);
    ASSERT_EQ(names, (std::vector<std::string>{"V_01", "V_02", "V_03", "V_04", "P_01", "P_02", "P_03", "P_04", "quality"}));
    std::size_t computed = 0, compared = 0;
    for (std::size_t i = 0; i < e.mesh.numVertices(); ++i) {
        if (std::isnan(e.vertexProperties[0].values[i])) continue;
        ++computed;
        for (std::size_t k = 0; k < 8; ++k) {
            const float x = e.vertexProperties[k].values[i], y = f.vertexProperties[k].values[i];
            if (std::isnan(x) || std::isnan(y)) continue;
            EXPECT_NEAR(x, y, k < 4 ? 5e-3 : 5e-2) << names[k] << " vertex " << i;
            ++compared;
        }
    }
    EXPECT_LE(computed, 40u);
    EXPECT_GT(compared, 20u);
    // GigaMesh files next to the output: the .mat rows are the PLY's columns, reversed, V as 2x - 1.
    const fs::path volume = dir / "patch_r0.80_n2_v6.volume.mat", surface = dir / "patch_r0.80_n2_v6.surface.mat";
    ASSERT_TRUE(fs::exists(volume));
    ASSERT_TRUE(fs::exists(surface));
    ASSERT_TRUE(fs::exists(dir / "patch.gigamesh.ply"));
    const std::string text = readFile(volume.string());
    std::size_t line = text.find("\n0 ");
    ASSERT_NE(line, std::string::npos);
    std::istringstream row(text.substr(line + 1));
    std::string token;
    row >> token;
    ASSERT_EQ(token, "0");
    double values[4];
    for (double& v : values) {
        row >> token;
        v = std::strtod(token.c_str(), nullptr);  // reads "nan" too
    }
    for (int k = 0; k < 4; ++k) {
        const float v = f.vertexProperties[std::size_t(3 - k)].values[0];
        if (std::isnan(v)) EXPECT_TRUE(std::isnan(values[k]));
        else EXPECT_NEAR(values[k], 2.0 * v - 1.0, 1e-6);
    }
}
