// Drives the msii program as a user would: a good run writes a PLY with the promised
// properties and a JSON record; every kind of bad input ends in one "msii: error:" line, a
// non-zero exit and no output file.
#include <msii/io/write_ply.h>
#include <msii/featuremap/feature_map.h>
#include <msii/io/read_mesh.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>


#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include <unistd.h>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/run_program.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::RunResult;
using msii::test::runProgram;
using msii::test::writeFile;

namespace {

/// One folder for the whole test program, removed at exit.
const fs::path& tempDir()
{
    static const msii::test::TempDir dir;
    return dir.path();
}

RunResult runMsii(const std::string& args) { return runProgram(MSII_EXE, args, tempDir()); }

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

/// One clear line, non-zero exit, and no output left behind (`msii <command> <args>`).
void expectCleanFailureOf(const std::string& command, const std::string& args, const std::string& mentions)
{
    SCOPED_TRACE(command + " " + args);
    const fs::path out = tempDir() / "bad_out.ply";
    fs::remove(out);
    const RunResult r = runMsii(command + " " + args + " --output '" + out.string() + "'");
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    for (const auto& entry : fs::directory_iterator(tempDir()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

void expectCleanFailure(const std::string& args, const std::string& mentions)
{
    expectCleanFailureOf("compute", args, mentions);
}

/// Bit for bit (NaN equals NaN).
bool sameFloats(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// The vertex properties of a PLY, by name.
std::map<std::string, std::vector<float>> propertiesOf(const fs::path& ply)
{
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    std::map<std::string, std::vector<float>> out;
    for (auto& p : readMesh(ply.string(), ro).vertexProperties) out[p.name] = std::move(p.values);
    return out;
}

} // namespace

TEST(MsiiCli, ComputeWritesFeaturesAndSidecar)
{
    const fs::path out = tempDir() / "good.ply";
    // --border mask: NaN where a ball reaches the patch's border, and quality's fallback.
    const RunResult r = runMsii("compute '" + smallPatch() + "' --radius 0.8 --scales 4 --border mask --quiet --overwrite --output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;  // --quiet
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    const ReadMeshResult res = readMesh(out.string(), ro);
    std::vector<std::string> names;
    for (const auto& p : res.vertexProperties) names.push_back(p.name);
    const std::vector<std::string> expected{"V_01", "V_02", "V_03", "V_04", "S_01", "S_02",
                                            "S_03", "S_04", "P_01", "P_02", "P_03", "P_04",
                                            "L_01", "L_02", "L_03", "L_04", "quality", "valid_radii",
                                            "filled_share"};
    ASSERT_EQ(names, expected);
    // Middle of a gently curved tablet: values near one half; near the border: NaN.
    std::size_t finite = 0, masked = 0;
    for (float v : res.vertexProperties[0].values) (std::isnan(v) ? masked : finite)++;
    EXPECT_GT(finite, 0u);
    EXPECT_GT(masked, 0u);
    // quality is never NaN (MeshLab aborts on it): V at the largest radius with a value, a
    // plane's 1/2 where none has one; valid_radii, an int property, counts those radii.
    EXPECT_FALSE(res.vertexProperties[16].integer);
    EXPECT_TRUE(res.vertexProperties[17].integer);
    EXPECT_NE(readFile(out.string()).find("property int valid_radii\n"), std::string::npos);
    std::size_t partial = 0, none = 0, checked = 0;
    for (std::size_t i = 0; i < res.mesh.numVertices(); ++i) {
        const float quality = res.vertexProperties[16].values[i];
        const float count = res.vertexProperties[17].values[i];
        ASSERT_FALSE(std::isnan(quality)) << "vertex " << i;
        int valid = 0;
        float largest = 0.5f;
        for (std::size_t j = 0; j < 4; ++j)
            if (!std::isnan(res.vertexProperties[j].values[i])) ++valid, largest = res.vertexProperties[j].values[i];
        EXPECT_EQ(count, float(valid)) << "vertex " << i;
        EXPECT_EQ(quality, largest) << "vertex " << i;
        partial += valid > 0 && valid < 4;
        none += valid == 0;
        ++checked;
    }
    EXPECT_EQ(checked, res.mesh.numVertices());
    EXPECT_GT(partial, 0u);  // the rule was exercised: border vertices with some radii
    EXPECT_GT(none, 0u);
    {  // by default the border is continued: every value is there, and the record counts the
       // vertices whose ball rests partly on the continuation
        const fs::path cont = tempDir() / "continued.ply";
        const RunResult rc = runMsii("compute '" + smallPatch() + "' --radius 0.8 --scales 4 --quiet --overwrite --output '" + cont.string() + "'");
        ASSERT_EQ(rc.code, 0) << rc.err;
        const ReadMeshResult c = readMesh(cont.string(), ro);
        std::size_t nan = 0, withShare = 0;
        for (std::size_t k = 0; k < 16; ++k)
            for (float v : c.vertexProperties[k].values) nan += std::isnan(v);
        for (float s : c.vertexProperties[18].values) withShare += s > 0;
        EXPECT_EQ(nan, 0u);
        EXPECT_GT(withShare, 0u);
        const std::string cjson = readFile((tempDir() / "continued.json").string());
        EXPECT_NE(cjson.find("\"vertices_with_filled_share\": " + std::to_string(withShare)), std::string::npos) << cjson;
        EXPECT_NE(cjson.find("\"border\": \"continue\""), std::string::npos);
        const RunResult bad = runMsii("compute '" + smallPatch() + "' --radius 0.8 --border clip --quiet --overwrite --output '" + cont.string() + "'");
        EXPECT_EQ(bad.code, 2) << bad.err;
        EXPECT_NE(bad.err.find("--border"), std::string::npos) << bad.err;
    }
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
    // Repairable meshes are refused only with --strict (by default they are repaired).
    expectCleanFailure("'" + writeText("degenerate.obj",
                                       "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n") + "' -r 1 --strict",
                       "degenerate");
    expectCleanFailure("'" + writeText("duplicate.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\n") + "' -r 1 --strict",
                       "duplicate");
    expectCleanFailure("'" + writeText("nonmanifold.obj",
                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
                                       "f 1 2 3\nf 2 1 4\nf 1 2 5\n") + "' -r 1 --strict",
                       "non-manifold");
    // Nothing left after repair: refused all the same.
    expectCleanFailure("'" + writeText("only-degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n") + "' -r 1",
                       "no faces with an area");
    expectCleanFailure("'" + writeText("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n") + "' -r 1",
                       "unexpected end of file");
    expectCleanFailure(patch, "--radius is required");
    expectCleanFailure(patch + " -r 0", "radius");
    expectCleanFailure(patch + " -r -2", "radius");
    expectCleanFailure(patch + " -r 1 -n 0", "scales");
    expectCleanFailure(patch + " -r 1 -n 100000", "scales");
    expectCleanFailure(patch + " -r 1e9", "radius");
    expectCleanFailure(patch + " -r 1 --invariants V,Q", "unknown invariant 'Q'");
    expectCleanFailure(patch + " -r 1 --fill-holes -3", "the hole size must be 0 (fill none) or a positive length");
    expectCleanFailure(patch + " -r 1 --pl-precision 0.5", "P and L precision");
    expectCleanFailure(patch + " -r 1 --pl-precision 0", "P and L precision");
    expectCleanFailure(patch + " -r 1 --pl-precision 100", "P and L precision");
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
    {
        // Next to the input by default: where that place cannot take the output (a folder
        // of its name here; a read-only data folder for most users), the line says where
        // else it can go. With --output the user chose the place, and is not told.
        SCOPED_TRACE("default output place unwritable");
        const fs::path folder = tempDir() / "readonly-place";
        fs::create_directories(folder / "patch.msii.ply");
        fs::copy_file(smallPatch(), folder / "patch.ply", fs::copy_options::overwrite_existing);
        const RunResult r = runMsii("compute '" + (folder / "patch.ply").string() + "' -r 1 -n 4");
        EXPECT_NE(r.code, 0);
        EXPECT_EQ(r.err.rfind("msii: error: ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find("it is a folder. Write it elsewhere with -o FILE or --output-dir FOLDER."), std::string::npos)
            << r.err;
        const RunResult chosen = runMsii("compute '" + (folder / "patch.ply").string() + "' -r 1 -n 4 --output '" +
                                         (folder / "patch.msii.ply").string() + "'");
        EXPECT_NE(chosen.code, 0);
        EXPECT_EQ(chosen.err.find("Write it elsewhere"), std::string::npos) << chosen.err;
    }
}

// --random-vertices draws among the vertices in a face: a scan's stray points (here more
// than half of the vertices) have no values, so drawing one would refuse the whole run.
TEST(MsiiCli, RandomVerticesAreDrawnAmongThoseInAFace)
{
    const fs::path dir = tempDir() / "random_vertices";
    fs::create_directories(dir);
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Plane;
    o.width = 3;
    o.height = 3;
    o.spacing = 0.1;
    TriMesh mesh = samples::makeHeightField(o);
    const std::size_t inFaces = mesh.numVertices();
    for (std::size_t k = 0; k < 2 * inFaces; ++k) mesh.points.push_back({0.01 * double(k), -1.0, 0.0});  // stray points
    const fs::path in = dir / "strays.ply", out = dir / "strays.msii.ply";
    writePly(in.string(), mesh, {});
    const RunResult r = runMsii("compute '" + in.string() + "' --radius 0.5 --scales 2 --invariants P --exact "
                                "--random-vertices 30 --quiet --overwrite --output '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    const ReadMeshResult e = readMesh(out.string(), ro);
    std::size_t computed = 0;
    for (std::size_t i = 0; i < e.mesh.numVertices(); ++i)
        if (!std::isnan(e.vertexProperties[0].values[i])) {
            EXPECT_LT(i, inFaces) << "a stray point got a value";
            ++computed;
        }
    EXPECT_EQ(computed, 30u);
    const RunResult tooMany = runMsii("compute '" + in.string() + "' --radius 0.5 --scales 2 --exact --random-vertices " +
                                      std::to_string(inFaces + 1) + " --quiet --overwrite --output '" + out.string() + "'");
    EXPECT_NE(tooMany.code, 0);
    EXPECT_NE(tooMany.err.find("in a face"), std::string::npos) << tooMany.err;
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
    ASSERT_EQ(names, (std::vector<std::string>{"V_01", "V_02", "V_03", "V_04", "P_01", "P_02", "P_03", "P_04", "quality",
                                               "valid_radii", "filled_share"}));
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

// metric and smooth after compute, as a user chains them: f as the formulas give it from the
// file's own features, references by vertex and by vector agree, GigaMesh .mat input gives
// the same f, smoothing changes what it is asked to and nothing else.
TEST(MsiiCli, MetricAndSmoothAfterCompute)
{
    const fs::path dir = tempDir() / "metric";
    fs::create_directories(dir);
    const fs::path features = dir / "patch.msii.ply";
    const RunResult rc = runMsii("compute '" + smallPatch() + "' --radius 0.8 --scales 4 --invariants V,P "
                                 "--border mask --gigamesh --quiet --output '" + features.string() + "'");
    ASSERT_EQ(rc.code, 0) << rc.err;
    const auto in = propertiesOf(features);
    const std::size_t nv = in.at("V_01").size();

    const fs::path m = dir / "m.ply";
    const RunResult rm = runMsii("metric '" + features.string() + "' --invariants V --metric l2,mahalanobis,l1w "
                                 "--quiet --output '" + m.string() + "'");
    ASSERT_EQ(rm.code, 0) << rm.err;
    EXPECT_TRUE(rm.err.empty()) << rm.err;
    auto out = propertiesOf(m);
    for (const auto& [name, values] : in)
        if (name != "quality") {
            EXPECT_TRUE(sameFloats(out.at(name), values)) << name << " kept as it was";
        }
    ASSERT_TRUE(out.count("f_l2") && out.count("f_mahalanobis") && out.count("f_l1w"));
    {  // quality = f_l2, and 0 where that is undefined (never NaN)
        std::vector<float> expected = out.at("f_l2");
        std::size_t undefined = 0;
        for (float& v : expected)
            if (std::isnan(v)) v = 0.0f, ++undefined;
        EXPECT_GT(undefined, 0u);
        EXPECT_TRUE(sameFloats(out.at("quality"), expected));
    }
    std::size_t checked = 0, masked = 0;
    for (std::size_t i = 0; i < nv; ++i) {
        double l2 = 0, l1w = 0;
        for (int j = 1; j <= 4; ++j) {
            const double d = in.at("V_0" + std::to_string(j))[i] - 0.5;  // flat: V/|B| = 1/2
            l2 += d * d;
            l1w += (3.0 * j * j - 3.0 * j + 1.0) / 64.0 * std::abs(d);  // Eq. 6, n = 4
        }
        if (std::isnan(l2)) {
            EXPECT_TRUE(std::isnan(out.at("f_l2")[i]));
            ++masked;
            continue;
        }
        EXPECT_NEAR(out.at("f_l2")[i], std::sqrt(l2), 1e-6);
        EXPECT_NEAR(out.at("f_l1w")[i], l1w, 1e-6);
        ++checked;
    }
    EXPECT_GT(checked, 100u);
    EXPECT_GT(masked, 0u);

    // Reference by vertex == reference by its vector (printed to 9 digits: float exact).
    std::size_t ref = 0;
    while (std::isnan(in.at("V_01")[ref]) || std::isnan(in.at("V_04")[ref])) ++ref;
    std::ostringstream vec;
    vec << std::setprecision(9);
    for (int j = 1; j <= 4; ++j) vec << (j > 1 ? "," : "") << in.at("V_0" + std::to_string(j))[ref];
    const fs::path byVertex = dir / "byvertex.ply", byVector = dir / "byvector.ply";
    ASSERT_EQ(runMsii("metric '" + features.string() + "' --metric cosine --reference vertex:" +
                      std::to_string(ref) + " --quiet -o '" + byVertex.string() + "'").code, 0);
    ASSERT_EQ(runMsii("metric '" + features.string() + "' --metric cosine --reference vector:" + vec.str() +
                      " --quiet -o '" + byVector.string() + "'").code, 0);
    const auto a = propertiesOf(byVertex).at("quality"), b = propertiesOf(byVector).at("quality");
    EXPECT_NEAR(a[ref], 1.0, 1e-6);  // a vector is parallel to itself
    for (std::size_t i = 0; i < nv; ++i)
        if (!std::isnan(a[i])) {
            EXPECT_NEAR(a[i], b[i], 1e-6);
        }

    // The GigaMesh .mat of the same run on the bare mesh gives the same f.
    const fs::path fromMat = dir / "frommat.ply";
    const RunResult rg = runMsii("metric '" + smallPatch() + "' --mat '" + (dir / "patch_r0.80_n2_v6.volume.mat").string() +
                                 "' --metric l2 --quiet -o '" + fromMat.string() + "'");
    ASSERT_EQ(rg.code, 0) << rg.err;
    const auto g = propertiesOf(fromMat).at("quality");
    for (std::size_t i = 0; i < nv; ++i)
        if (!std::isnan(out.at("f_l2")[i])) {
            EXPECT_NEAR(g[i], out.at("f_l2")[i], 1e-6);
        }

    // smooth: quality changes, the rest stays; --all-features smooths V and P as well.
    const fs::path s1 = dir / "s1.ply", s2 = dir / "s2.ply";
    const RunResult rs = runMsii("smooth '" + m.string() + "' --filter median -k 3 --quiet -o '" + s1.string() + "'");
    ASSERT_EQ(rs.code, 0) << rs.err;
    const auto smoothed = propertiesOf(s1);
    EXPECT_FALSE(sameFloats(smoothed.at("quality"), out.at("quality")));
    EXPECT_TRUE(sameFloats(smoothed.at("V_02"), out.at("V_02")));
    EXPECT_TRUE(sameFloats(smoothed.at("f_mahalanobis"), out.at("f_mahalanobis")));
    ASSERT_EQ(runMsii("smooth '" + m.string() + "' --all-features --delta ring -k 2 --quiet -o '" + s2.string() + "'").code, 0);
    const auto all = propertiesOf(s2);
    EXPECT_FALSE(sameFloats(all.at("V_02"), out.at("V_02")));
    EXPECT_FALSE(sameFloats(all.at("P_04"), out.at("P_04")));
    EXPECT_TRUE(sameFloats(all.at("f_l1w"), out.at("f_l1w")));
}

TEST(MsiiCli, MetricAndSmoothBadInputFailCleanly)
{
    const fs::path features = tempDir() / "bad_features.msii.ply";
    ASSERT_EQ(runMsii("compute '" + smallPatch() + "' --radius 0.8 --scales 4 --invariants V,P --quiet "
                      "--output '" + features.string() + "'").code, 0);
    const std::string f = "'" + features.string() + "'";
    expectCleanFailureOf("metric", f + " --metric l7", "unknown metric 'l7'");
    expectCleanFailureOf("metric", f + " --invariants V,Q", "unknown invariant 'Q'");
    expectCleanFailureOf("metric", f + " --invariants S", "no S features");
    expectCleanFailureOf("metric", "'" + smallPatch() + "'", "no V features");
    expectCleanFailureOf("metric", f + " --reference vertex:99999999", "the mesh has");
    expectCleanFailureOf("metric", f + " --reference vertex:x", "not a vertex index");
    expectCleanFailureOf("metric", f + " --reference vector:1,2", "has 2 values");
    expectCleanFailureOf("metric", f + " --reference sideways", "--reference 'sideways'");
    expectCleanFailureOf("metric", f + " --metric lp --p 0", "--p must be a positive number");
    expectCleanFailureOf("metric", f + " --metric lp --p -1", "--p must be a positive number");
    expectCleanFailureOf("metric", f + " --metric cosine", "flat");
    expectCleanFailureOf("metric", f + " --mat '" + writeText("x.volume.mat", "0 1 2\n") + "'", "x.volume.mat");
    expectCleanFailureOf("metric", f + " --mat '" + writeText("x.txt", "0 1\n") + "'", "not named like");
    expectCleanFailureOf("metric", "'" + (tempDir() / "missing.ply").string() + "'", "cannot open");
    expectCleanFailureOf("smooth", f + " --iterations -1", "--iterations must be 0 or more");
    expectCleanFailureOf("smooth", f + " --filter gauss", "unknown --filter 'gauss'");
    expectCleanFailureOf("smooth", f + " --delta tiny", "unknown --delta");
    expectCleanFailureOf("smooth", f + " --properties height", "no vertex property 'height'");
    expectCleanFailureOf("smooth", "'" + smallPatch() + "' --all-features", "no features");
}

namespace {
/// The "status" of each line of a JSON-lines manifest, in order.
std::vector<std::string> manifestStatuses(const fs::path& path)
{
    std::vector<std::string> out;
    std::stringstream in(readFile(path.string()));
    for (std::string line; std::getline(in, line);) {
        const auto at = line.find("\"status\":\"");
        out.push_back(at == std::string::npos ? "?" : line.substr(at + 10, line.find('"', at + 10) - at - 10));
    }
    return out;
}
} // namespace

// A folder that also holds msii's own outputs (computed into it, then metric, smooth and
// segment on them): only the scan is an input, not what msii made of it.
TEST(MsiiCli, ComputeFolderLeavesMsiisOwnOutputsOut)
{
    const fs::path in = tempDir() / "own-outputs";
    fs::create_directories(in);
    fs::copy_file(smallPatch(), in / "a.ply", fs::copy_options::overwrite_existing);
    for (const char* made : {"a.msii.ply", "a.gigamesh.ply", "a.msii.metric.ply", "a.msii.metric.smooth.ply",
                             "a.msii.segments.ply", "a.msii.smooth.ply"})
        fs::copy_file(smallPatch(), in / made, fs::copy_options::overwrite_existing);
    const RunResult r = runMsii("compute '" + in.string() + "' -r 0.8 -n 4 -q --overwrite --output-dir '" +
                                (tempDir() / "own-outputs-out").string() + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(manifestStatuses(tempDir() / "own-outputs-out" / "msii-manifest.jsonl").size(), 1u);
}

// A folder as a collection: good and broken files, the rest goes on after a
// failure, finished outputs are skipped on a rerun, an interrupted output (no JSON record)
// is redone, the manifest records each input, and the exit status says whether any failed.
TEST(MsiiCli, ComputeCollectionSkipsResumesAndReports)
{
    const fs::path in = tempDir() / "collection", out = tempDir() / "collection-out";
    fs::create_directories(in);
    fs::copy_file(smallPatch(), in / "a.ply", fs::copy_options::overwrite_existing);
    fs::copy_file(smallPatch(), in / "b.ply", fs::copy_options::overwrite_existing);
    writeFile((in / "c.off").string(), "OFF\n0 0 0\n");         // broken
    writeFile((in / "notes.txt").string(), "not a mesh\n");      // ignored
    const std::string run = "compute '" + in.string() + "' -r 0.8 -n 4 -q --output-dir '" + out.string() + "'";
    const fs::path manifest = out / "msii-manifest.jsonl";

    RunResult r = runMsii(run);
    EXPECT_EQ(r.code, 1) << r.err;  // c.off failed
    EXPECT_NE(r.err.find("c.off"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("2 done, 0 skipped (outputs exist), 1 failed"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(out / "a.msii.ply") && fs::exists(out / "b.msii.json"));
    EXPECT_FALSE(fs::exists(out / "c.msii.ply"));
    EXPECT_EQ(manifestStatuses(manifest), (std::vector<std::string>{"done", "done", "failed"}));

    // Rerun: both finished outputs are skipped (and kept as they were).
    const auto written = fs::last_write_time(out / "a.msii.ply");
    r = runMsii(run);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("0 done, 2 skipped"), std::string::npos) << r.err;
    EXPECT_EQ(fs::last_write_time(out / "a.msii.ply"), written);

    // An interrupted run left b's PLY without its JSON record: it is redone; without the
    // broken file the collection succeeds.
    fs::remove(out / "b.msii.json");
    fs::remove(in / "c.off");
    r = runMsii(run);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(out / "b.msii.json"));
    const auto statuses = manifestStatuses(manifest);
    ASSERT_EQ(statuses.size(), 8u);
    EXPECT_EQ(std::vector<std::string>(statuses.end() - 2, statuses.end()),
              (std::vector<std::string>{"skipped", "done"}));
    EXPECT_NE(readFile(manifest.string()).find("\"radius\":0.8"), std::string::npos);

    // Other parameters than the existing outputs': not skipped but refused (per input).
    r = runMsii("compute '" + in.string() + "' -r 0.9 -n 4 -q --output-dir '" + out.string() + "'");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("exists with other parameters (radius"), std::string::npos) << r.err;
    // Two inputs that would write one output: refused before anything is computed.
    fs::create_directories(tempDir() / "collection2");
    fs::copy_file(smallPatch(), tempDir() / "collection2" / "a.ply", fs::copy_options::overwrite_existing);
    r = runMsii("compute '" + in.string() + "' '" + (tempDir() / "collection2").string() + "' -r 0.8 -n 4 -q --output-dir '" +
                (tempDir() / "collection-out2").string() + "'");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("would both write"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(tempDir() / "collection-out2" / "b.msii.ply"));

    // A folder without meshes: one clear error, nothing written.
    fs::create_directories(tempDir() / "no-meshes");
    writeFile((tempDir() / "no-meshes" / "readme.txt").string(), "x\n");
    r = runMsii("compute '" + (tempDir() / "no-meshes").string() + "' -r 1");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("has no mesh files"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

// Repair is the default: the faces around a non-manifold edge (a fin glued onto a scan)
// are dropped, the hole filled, and the run says so; --strict refuses the mesh instead, with
// one line and no output.
TEST(MsiiCli, RepairsByDefaultAndStrictRefuses)
{
    TriMesh mesh = readMesh(smallPatch()).mesh;
    // The fin on the triangle nearest the middle of the 4 x 4 mm patch, away from its border.
    Triangle t = mesh.triangles.front();
    double nearest = 1e9;
    for (const Triangle& c : mesh.triangles) {
        const Vec3 m = (mesh.points[c[0]] + mesh.points[c[1]] + mesh.points[c[2]]) / 3.0;
        const double d = std::hypot(m.x - 2.0, m.y - 2.0);
        if (d < nearest) nearest = d, t = c;
    }
    mesh.points.push_back((mesh.points[t[0]] + mesh.points[t[1]]) * 0.5 + Vec3(0, 0, 0.3));
    mesh.triangles.push_back({t[0], t[1], std::uint32_t(mesh.numVertices() - 1)});
    const std::string fin = (tempDir() / "fin.ply").string();
    writePly(fin, mesh, {});
    const fs::path out = tempDir() / "fin.msii.ply";
    RunResult r = runMsii("compute '" + fin + "' -r 0.8 -n 4 --strict --output '" + out.string() + "'");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("1 non-manifold edge"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("without it msii repairs this"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out));
    r = runMsii("compute '" + fin + "' -r 0.8 -n 4 --output '" + out.string() + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("removed the 3 faces around 1 non-manifold edge"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("filled 1 hole"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(out));
    const std::string json = readFile((tempDir() / "fin.msii.json").string());
    EXPECT_NE(json.find("\"non_manifold_faces_removed\""), std::string::npos);
    EXPECT_NE(json.find("\"filled\": 1"), std::string::npos) << json;
    // The output keeps the input's vertices and faces; filled_share is written.
    const ReadMeshResult written = readMesh(out.string(), {true});
    EXPECT_EQ(written.mesh.points.size(), mesh.points.size());
    EXPECT_EQ(written.mesh.triangles, mesh.triangles);
    bool hasShare = false;
    for (const VertexProperty& p : written.vertexProperties) hasShare |= p.name == "filled_share";
    EXPECT_TRUE(hasShare);
}

// An STL file (a triangle soup: three vertices of its own per triangle, as floats) gives
// the values of the same surface written as a PLY with shared vertices, vertex by vertex at
// the same positions.
TEST(MsiiCli, StlSoupGivesTheValuesOfTheSharedMesh)
{
    samples::SphereOptions so;
    so.radius = 3;
    so.spacing = 0.25;
    TriMesh mesh = samples::makeSphere(so);
    for (Vec3& p : mesh.points) p = {double(float(p.x)), double(float(p.y)), double(float(p.z))};
    const std::string ply = (tempDir() / "soup-shared.ply").string(), stl = (tempDir() / "soup.stl").string();
    writePly(ply, mesh, {});
    {
        std::string bytes(80, ' ');
        const auto put = [&](const void* data, std::size_t n) { bytes.append(static_cast<const char*>(data), n); };
        const std::uint32_t count = std::uint32_t(mesh.numTriangles());
        put(&count, 4);
        for (const Triangle& t : mesh.triangles) {
            const float zero[3] = {0, 0, 0};
            put(zero, 12);
            for (std::uint32_t v : t) {
                const float p[3] = {float(mesh.points[v].x), float(mesh.points[v].y), float(mesh.points[v].z)};
                put(p, 12);
            }
            const std::uint16_t attributes = 0;
            put(&attributes, 2);
        }
        writeFile(stl, bytes);
    }
    const fs::path outPly = tempDir() / "soup-shared.msii.ply", outStl = tempDir() / "soup.msii.ply";
    RunResult r = runMsii("compute '" + ply + "' -r 1 -n 4 -q --overwrite --output '" + outPly.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("compute '" + stl + "' -r 1 -n 4 -q --overwrite --output '" + outStl.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    ReadMeshOptions ro;
    ro.keepVertexProperties = true;
    const ReadMeshResult a = readMesh(outPly.string(), ro), b = readMesh(outStl.string(), ro);
    ASSERT_EQ(b.mesh.numVertices(), a.mesh.numVertices());  // merged to shared vertices
    std::map<std::array<double, 3>, std::size_t> at;
    for (std::size_t i = 0; i < a.mesh.numVertices(); ++i) at[{a.mesh.points[i].x, a.mesh.points[i].y, a.mesh.points[i].z}] = i;
    ASSERT_EQ(a.vertexProperties.size(), b.vertexProperties.size());
    std::size_t compared = 0;
    double largest = 0;
    for (std::size_t i = 0; i < b.mesh.numVertices(); ++i) {
        const auto it = at.find({b.mesh.points[i].x, b.mesh.points[i].y, b.mesh.points[i].z});
        ASSERT_NE(it, at.end()) << i;
        for (std::size_t k = 0; k < a.vertexProperties.size(); ++k) {
            const float x = a.vertexProperties[k].values[it->second], y = b.vertexProperties[k].values[i];
            ASSERT_EQ(std::isnan(x), std::isnan(y));
            if (std::isnan(x)) continue;
            largest = std::max(largest, double(std::abs(x - y)));
            ++compared;
        }
    }
    std::printf("STL soup against the shared PLY: %zu values compared, largest difference %.3g\n", compared, largest);
    EXPECT_EQ(compared, a.mesh.numVertices() * a.vertexProperties.size());
    EXPECT_LE(largest, 1e-6);
}

// --tiles and --memory-budget: the tiled run writes the same file as the
// untiled one, records its tiling in the JSON, and a budget too small for one tile is refused.
TEST(MsiiCli, TiledComputeWritesTheSameFeatures)
{
    const fs::path untiled = tempDir() / "untiled.msii.ply", tiled = tempDir() / "tiled.msii.ply";
    RunResult r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --output '" + untiled.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --tiles 2 --output '" + tiled.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto a = propertiesOf(untiled), b = propertiesOf(tiled);
    ASSERT_EQ(a.size(), b.size());
    for (const auto& [name, values] : a) {
        ASSERT_TRUE(b.count(name)) << name;
        EXPECT_TRUE(sameFloats(values, b.at(name))) << name;
    }
    // Written tile by tile straight into the file, yet byte for byte the untiled file.
    EXPECT_TRUE(readFile(untiled.string()) == readFile(tiled.string()));
    // The invariants spelled as Python spells them, or in lower case with spaces: the same file.
    for (const char* spelled : {"VSPL", "'v, s, p, l'"}) {
        const fs::path other = tempDir() / "spelled.msii.ply";
        r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --invariants " + spelled + " --output '" +
                    other.string() + "'");
        ASSERT_EQ(r.code, 0) << spelled << ": " << r.err;
        EXPECT_TRUE(readFile(untiled.string()) == readFile(other.string())) << spelled;
    }
    EXPECT_NE(readFile((tempDir() / "tiled.msii.json").string()).find("\"tiles_per_axis\": 2"), std::string::npos);
    expectCleanFailure("'" + smallPatch() + "' -r 0.6 --memory-budget 10K", "too small for even one tile");
    expectCleanFailure("'" + smallPatch() + "' -r 0.6 --memory-budget lots", "is not a size");
}

// --property-names cloudcompare: every vertex property named scalar_<name> (CloudCompare's
// command line loads only those as scalar fields), the same values, tiled or not; msii's own
// commands read such files by their plain names.
TEST(MsiiCli, CloudCompareNames)
{
    const fs::path plain = tempDir() / "cc-plain.ply", cc = tempDir() / "cc.ply", ccTiled = tempDir() / "cc-tiled.ply";
    RunResult r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --output '" + plain.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --property-names cloudcompare --output '" +
                cc.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string bytes = readFile(cc.string());
    const std::string header = bytes.substr(0, bytes.find("end_header"));
    std::size_t named = 0;
    for (const char* line : {"property float scalar_V_01\n", "property float scalar_L_04\n",
                             "property float scalar_quality\n", "property int scalar_valid_radii\n",
                             "property float scalar_filled_share\n", "property float x\n"}) {
        EXPECT_NE(header.find(line), std::string::npos) << line << header;
        ++named;
    }
    EXPECT_EQ(named, 6u);
    EXPECT_EQ(header.find("property float V_01"), std::string::npos) << header;
    const auto a = propertiesOf(plain), b = propertiesOf(cc);
    ASSERT_EQ(a.size(), 19u);
    ASSERT_EQ(a.size(), b.size());
    for (const auto& [name, values] : a) {
        ASSERT_TRUE(b.count(name)) << name;
        EXPECT_TRUE(sameFloats(values, b.at(name))) << name;
    }
    r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --tiles 2 --property-names cloudcompare "
                "--output '" + ccTiled.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(readFile(cc.string()) == readFile(ccTiled.string()));
    const fs::path m = tempDir() / "cc-metric.ply";
    r = runMsii("metric '" + cc.string() + "' --invariants V --metric l2 -q --overwrite --property-names cloudcompare "
                "--output '" + m.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(readFile(m.string()).find("property float scalar_f_l2\n"), std::string::npos);
    expectCleanFailure("'" + smallPatch() + "' -r 0.6 --property-names meshlab", "--property-names");
}

// Tiles computed separately (one job each: --tiles K --tile I) and joined by msii merge give
// the untiled result byte for byte; a missing or repeated tile is refused.
TEST(MsiiCli, MergeJoinsSeparateTiles)
{
    const fs::path whole = tempDir() / "merge-whole.ply", merged = tempDir() / "merge-merged.ply";
    RunResult r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --output '" + whole.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    std::string parts;
    for (int t = 3; t >= 0; --t) {  // any order
        const fs::path part = tempDir() / ("merge-part" + std::to_string(t) + ".ply");
        r = runMsii("compute '" + smallPatch() + "' -r 0.6 -n 4 -q --overwrite --tiles 2 --tile " + std::to_string(t) +
                    " --output '" + part.string() + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        parts += " '" + part.string() + "'";
    }
    r = runMsii("merge" + parts + " -q --overwrite --output '" + merged.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(readFile(whole.string()), readFile(merged.string()));
    const std::string p0 = "'" + (tempDir() / "merge-part0.ply").string() + "'";
    const std::string p1 = "'" + (tempDir() / "merge-part1.ply").string() + "'";
    expectCleanFailureOf("merge", p0 + " " + p1, "is missing");
    expectCleanFailureOf("merge", p0 + " " + p0, "given twice");
    expectCleanFailureOf("merge", "'" + smallPatch() + "'", "is not a tile");
    expectCleanFailure("'" + smallPatch() + "' -r 0.6 --tiles 2 --tile 4", "does not exist");
    expectCleanFailure("'" + smallPatch() + "' -r 0.6 --tile 1", "goes with --tiles");

    // A vertex in no face, far from the surface, widens the file's box but not the prepared
    // mesh's, on which the tiles are cut: the parts still join to the whole result.
    TriMesh stray = readMesh(smallPatch()).mesh;
    stray.points.push_back({40, -30, 5});
    const std::string strayPly = (tempDir() / "stray.ply").string();
    writePly(strayPly, stray, {});
    const fs::path strayWhole = tempDir() / "stray-whole.ply", strayMerged = tempDir() / "stray-merged.ply";
    r = runMsii("compute '" + strayPly + "' -r 0.6 -n 4 -q --overwrite --output '" + strayWhole.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    parts.clear();
    for (int t = 0; t < 4; ++t) {
        const fs::path part = tempDir() / ("stray-part" + std::to_string(t) + ".ply");
        r = runMsii("compute '" + strayPly + "' -r 0.6 -n 4 -q --overwrite --tiles 2 --tile " + std::to_string(t) +
                    " --output '" + part.string() + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        parts += " '" + part.string() + "'";
    }
    r = runMsii("merge" + parts + " -q --overwrite --output '" + strayMerged.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(readFile(strayWhole.string()) == readFile(strayMerged.string()));
}

// A scan in georeferenced coordinates (UTM-like: x ≈ 500 km, y ≈ 5,500 km) computes like the
// same scan at the origin (docs/method.md, Local frame), and its output keeps the input's
// coordinates in double precision.
TEST(MsiiCli, GeoreferencedCoordinatesWork)
{
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Terrain;
    o.width = 30;
    o.height = 20;
    o.spacing = 0.25;
    o.relief = 2;
    TriMesh mesh = samples::makeHeightField(o);
    const fs::path local = tempDir() / "terrain-local.ply", utm = tempDir() / "terrain-utm.ply";
    writePly(local.string(), mesh, {});
    for (Vec3& p : mesh.points) p += Vec3{512000.0, 5498000.0, 310.0};
    writePly(utm.string(), mesh, {});
    const fs::path a = tempDir() / "terrain-local.msii.ply", b = tempDir() / "terrain-utm.msii.ply";
    RunResult r = runMsii("compute '" + local.string() + "' -r 3 -n 4 -q --overwrite -o '" + a.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("compute '" + utm.string() + "' -r 3 -n 4 -q --overwrite --units m -o '" + b.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    // The units given are stated in the outputs, and the map takes them from there.
    EXPECT_NE(readFile(b.string()).find("comment units m\n"), std::string::npos);
    EXPECT_NE(readFile((tempDir() / "terrain-utm.msii.json").string()).find("\"units\": \"m\""), std::string::npos);
    const fs::path map = tempDir() / "terrain-utm.map.exr";
    r = runMsii("map '" + b.string() + "' --view +z --pixels 200 -q --overwrite -o '" + map.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(readFeatureMap(map.string(), {"mask"}).units, "m");
    const ReadMeshResult out = readMesh(b.string());
    ASSERT_EQ(out.mesh.numVertices(), mesh.numVertices());
    for (std::size_t i = 0; i < mesh.numVertices(); ++i) ASSERT_EQ(out.mesh.points[i], mesh.points[i]) << i;
    // The values: as close as a sub-voxel move makes them (the tests of compute.h hold the
    // bounds); here, that nothing is lost or masked by the move.
    const auto va = propertiesOf(a), vb = propertiesOf(b);
    double sum = 0;
    std::size_t n = 0, nanMismatches = 0;
    for (const std::string name : {"V_04", "S_04", "P_04", "L_04"})
        for (std::size_t i = 0; i < va.at(name).size(); ++i) {
            const float x = va.at(name)[i], y = vb.at(name)[i];
            if (std::isnan(x) != std::isnan(y)) ++nanMismatches;
            if (std::isnan(x) || std::isnan(y)) continue;
            sum += std::abs(x - y);
            ++n;
        }
    EXPECT_EQ(nanMismatches, 0u);
    ASSERT_GT(n, mesh.numVertices());
    EXPECT_LE(sum / double(n), 1e-3);
}

// --progress-lines: for a program that runs msii (the QGIS plugin), progress as lines
// "msii: progress PERCENT STAGE" on stderr though it is a pipe, each stage ending at 100.0;
// without it a pipe gets none. The output is the same either way.
TEST(MsiiCli, ProgressLinesForProgramsThatRunMsii)
{
    const fs::path a = tempDir() / "progress_a.ply", b = tempDir() / "progress_b.ply";
    RunResult r = runMsii("compute '" + smallPatch() + "' -r 0.5 -n 4 --overwrite --progress-lines -o '" + a.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    std::istringstream lines(r.err);
    std::string line, stage;
    std::size_t reports = 0, stagesEnded = 0;
    while (std::getline(lines, line)) {
        if (line.rfind("msii: progress ", 0) != 0) continue;
        ++reports;
        char* end = nullptr;
        const double percent = std::strtod(line.c_str() + 15, &end);
        EXPECT_GE(percent, 0.0) << line;
        EXPECT_LE(percent, 100.0) << line;
        ASSERT_EQ(*end, ' ') << line;
        stage = end + 1;
        EXPECT_FALSE(stage.empty()) << line;
        stagesEnded += percent == 100.0;
    }
    EXPECT_GE(stagesEnded, 3u) << r.err;  // level set, V and S, P and L at least
    EXPECT_GT(reports, stagesEnded) << r.err;
    r = runMsii("compute '" + smallPatch() + "' -r 0.5 -n 4 --overwrite -o '" + b.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("msii: progress "), std::string::npos) << r.err;
    EXPECT_EQ(readFile(a.string()).size(), readFile(b.string()).size());
    EXPECT_TRUE(sameFloats(propertiesOf(a)["V_04"], propertiesOf(b)["V_04"]));
}

// A temporary file that a killed run left (kill -9) is removed by the next run that writes
// the same output, if its process no longer runs; another output's, or a running process's,
// is kept.
TEST(MsiiCli, StaleTemporaryFilesOfAKilledRunAreRemoved)
{
    const fs::path folder = tempDir() / "stale";
    fs::create_directories(folder);
    const fs::path out = folder / "out.ply";
    const fs::path stale = folder / ".out.ply.tmp-999999-0";
    const fs::path running = folder / (".out.ply.tmp-" + std::to_string(::getpid()) + "-3");
    const fs::path other = folder / ".other.ply.tmp-999999-0";
    for (const fs::path& p : {stale, running, other}) writeFile(p.string(), "partial");
    const RunResult r = runMsii("compute '" + smallPatch() + "' -r 0.5 -n 4 -q -o '" + out.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(out));
    EXPECT_FALSE(fs::exists(stale));
    EXPECT_TRUE(fs::exists(running));  // this test's own process runs
    EXPECT_TRUE(fs::exists(other));
}
