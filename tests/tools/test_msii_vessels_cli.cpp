// Drives `msii axis`, `msii profile` and `msii unroll` as a user does, on generated vessels,
// sherds and cylinder seals with known answers (msii-samples vessel, sherd and seal, their
// truth files): irregular triangulations, scanner noise, marks at known places, random poses.
// The axis of whole objects within 0.1° and 0.1 % of the radius, their rim diameter within
// 0.2 %; of sherds of 60–90° and a third of the height within 1° and 1 %; the profile's points
// on the true profile within a tenth of the median edge, covering 99 % of it; a seal's marks
// in its rollout at r·Δθ and Δh within 0.1 mm, a cone's at their geodesic distances within
// 0.5 % + 0.3 mm; the vertex order and properties kept; a plane and a sphere refused.
#include <msii/io/read_mesh.h>
#include <msii/render/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/run_program.h"
#include "../support/temp_dir.h"

namespace fs = std::filesystem;
using namespace msii;
using msii::test::readFile;
using msii::test::quoted;
using msii::test::runProgram;
using msii::test::RunResult;

namespace {

constexpr double kPi = 3.14159265358979323846;

const fs::path& tempDir()
{
    static const msii::test::TempDir dir;
    return dir.path();
}

RunResult runMsii(const std::string& args)
{
    return runProgram(MSII_EXE, args, tempDir());
}
nlohmann::json readJson(const fs::path& p)
{
    return nlohmann::json::parse(readFile(p.string()));
}
Vec3 vec(const nlohmann::json& j)
{
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

/// `msii-samples SHAPE ARGS --truth NAME.truth.json -o NAME.ply`; returns the truth.
nlohmann::json sample(const std::string& name, const std::string& args)
{
    const fs::path ply = tempDir() / (name + ".ply"), truth = tempDir() / (name + ".truth.json");
    const RunResult r =
        runProgram(MSII_SAMPLES_EXE, args + " -q --truth " + quoted(truth) + " -o " + quoted(ply), tempDir());
    EXPECT_EQ(r.code, 0) << r.err;
    return readJson(truth);
}

/// `msii axis NAME.ply`; its record.
nlohmann::json axisOf(const std::string& name)
{
    const fs::path out = tempDir() / (name + ".axis.json");
    const RunResult r = runMsii("axis " + quoted(tempDir() / (name + ".ply")) + " -q -o " + quoted(out));
    EXPECT_EQ(r.code, 0) << r.err;
    return readJson(out);
}

/// The fitted axis against the true one: the angle between them in degrees, and the
/// distance of the true axis's point at mid-height from the fitted line.
void compareAxes(const nlohmann::json& truth, const nlohmann::json& fitted, double& degrees, double& offset)
{
    const Vec3 td = normalized(vec(truth["axis"]["direction"])), fd = normalized(vec(fitted["direction"]));
    degrees = std::acos(std::min(1.0, std::abs(dot(td, fd)))) * 180 / kPi;
    const Vec3 mid = vec(truth["axis"]["point"]) + td * (0.5 * truth["height"].get<double>());
    const Vec3 d = mid - vec(fitted["point"]);
    offset = norm(d - fd * dot(d, fd));
}

/// Distance from (r, z) to a polyline of (r, z) points.
double distanceToPolyline(const std::array<double, 2>& p, const nlohmann::json& line)
{
    double best = 1e300;
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
        const double ax = line[i][0], ay = line[i][1], bx = line[i + 1][0], by = line[i + 1][1];
        const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
        const double t = l2 > 0 ? std::clamp(((p[0] - ax) * dx + (p[1] - ay) * dy) / l2, 0.0, 1.0) : 0.0;
        best = std::min(best, std::hypot(p[0] - ax - t * dx, p[1] - ay - t * dy));
    }
    return best;
}

double polylineLength(const nlohmann::json& line)
{
    double length = 0;
    for (std::size_t i = 0; i + 1 < line.size(); ++i)
        length += std::hypot(line[i + 1][0].get<double>() - line[i][0].get<double>(),
                             line[i + 1][1].get<double>() - line[i][1].get<double>());
    return length;
}

/// Where each mark lies in a rollout: the centroid (x, y) of the rollout's vertices sunk more
/// than half the mark's depth below the surface around it, near the vertex nearest the mark's
/// centre in the input.
std::vector<std::array<double, 2>> marksInRollout(const TriMesh& input, const TriMesh& rollout,
                                                  const nlohmann::json& marks)
{
    std::vector<std::array<double, 2>> found;
    for (const nlohmann::json& m : marks) {
        const Vec3 c = vec(m["centre"]);
        const double radius = m["radius"].get<double>(), depth = m["depth"].get<double>();
        std::size_t nearest = 0;
        for (std::size_t i = 0; i < input.numVertices(); ++i)
            if (norm(input.points[i] - c) < norm(input.points[nearest] - c)) nearest = i;
        const Vec3 at = rollout.points[nearest];
        // The surface's level around the mark: the median z of the rollout's vertices in a ring
        // between 1.5 and 2.5 radii.
        std::vector<double> ring;
        for (std::size_t i = 0; i < input.numVertices(); ++i) {
            const double d = std::hypot(rollout.points[i].x - at.x, rollout.points[i].y - at.y);
            if (d > 1.5 * radius && d < 2.5 * radius) ring.push_back(rollout.points[i].z);
        }
        std::nth_element(ring.begin(), ring.begin() + std::ptrdiff_t(ring.size() / 2), ring.end());
        const double level = ring.empty() ? at.z : ring[ring.size() / 2];
        double sx = 0, sy = 0, w = 0;
        for (std::size_t i = 0; i < input.numVertices(); ++i) {
            const Vec3& p = rollout.points[i];
            const double sunk = level - p.z - 0.5 * depth;
            if (std::hypot(p.x - at.x, p.y - at.y) < 1.2 * radius && sunk > 0)
                sx += sunk * p.x, sy += sunk * p.y, w += sunk;
        }
        found.push_back({w > 0 ? sx / w : at.x, w > 0 ? sy / w : at.y});
    }
    return found;
}

}  // namespace

/// Where the rollout puts the point of the input's surface under @p centre: the centre
/// projected onto the nearest triangle it falls in (a mark's pit lies under its centre, along
/// the normal), mapped by that triangle's barycentric coordinates. False where no triangle
/// within 3 mm takes it, or where the triangle is cut by the seam.
bool placeInRollout(const TriMesh& input, const TriMesh& rollout, const Vec3& centre, std::array<double, 2>& at)
{
    double nearest = 3;
    bool found = false;
    for (const Triangle& t : input.triangles) {
        const Vec3 &a = input.points[t[0]], &b = input.points[t[1]], &c = input.points[t[2]];
        if (norm((a + b + c) / 3.0 - centre) > 3) continue;
        const Vec3 n = cross(b - a, c - a);
        const double area2 = dot(n, n);
        if (!(area2 > 0)) continue;
        const double off = dot(centre - a, n) / std::sqrt(area2);
        const Vec3 q = centre - n * (dot(centre - a, n) / area2);
        const double u = dot(cross(c - b, q - b), n) / area2, v = dot(cross(a - c, q - c), n) / area2, w = 1 - u - v;
        if (u < -1e-9 || v < -1e-9 || w < -1e-9 || std::abs(off) >= nearest) continue;
        const Vec3 &ra = rollout.points[t[0]], &rb = rollout.points[t[1]], &rc = rollout.points[t[2]];
        if (std::max({ra.x, rb.x, rc.x}) - std::min({ra.x, rb.x, rc.x}) > 5) continue;  // across the seam
        nearest = std::abs(off), found = true;
        at = {u * ra.x + v * rb.x + w * rc.x, u * ra.y + v * rb.y + w * rc.y};
    }
    return found;
}

TEST(MsiiVesselsCli, AxisOfWholeObjects)
{
    struct Case {
        const char* name;
        const char* args;
        const char* shape;
        double roughness, spacing;
    };
    const Case cases[] = {
        {"cylinder", "vessel --profile cylinder --spacing 0.7 --roughness 0.02 --pose-seed 11", "cylinder", 0.02, 0.7},
        {"cone", "vessel --profile cone --spacing 0.7 --roughness 0.02 --pose-seed 12", "cone", 0.02, 0.7},
        {"vase", "vessel --profile vase --spacing 0.7 --roughness 0.02 --pose-seed 13", "surface of revolution", 0.02,
         0.7},
        {"seal", "seal --spacing 0.2 --roughness 0.005 --pose-seed 14", "cylinder", 0.005, 0.2},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const nlohmann::json truth = sample(c.name, c.args), fitted = axisOf(c.name);
        double degrees, offset;
        compareAxes(truth, fitted, degrees, offset);
        const double radius = fitted["mean_radius"].get<double>();
        EXPECT_LT(degrees, 0.1);
        EXPECT_LT(offset, 0.001 * radius);
        EXPECT_EQ(fitted["shape"], c.shape);
        // The noise, and the profile's bins of two edges following a curved profile within a
        // tenth of an edge.
        EXPECT_LT(fitted["residual"].get<double>(), c.roughness + 0.1 * c.spacing);
        if (truth["rim_diameter"].is_null()) {
            EXPECT_TRUE(fitted["rim_diameter"].is_null());
        } else {
            ASSERT_TRUE(fitted["rim_diameter"].is_number());
            const double rim = truth["rim_diameter"].get<double>();
            EXPECT_NEAR(fitted["rim_diameter"].get<double>(), rim, 0.002 * rim);
        }
        // From the base towards the rim, and at the object's lowest point.
        if (std::string(c.name) != "seal") {
            EXPECT_GT(dot(vec(truth["axis"]["direction"]), vec(fitted["direction"])), 0);
            EXPECT_LT(norm(vec(truth["axis"]["point"]) - vec(fitted["point"])), 0.05);
        }
    }
}

TEST(MsiiVesselsCli, AxisOfSherds)
{
    const char* cases[] = {
        "sherd --profile vase --angle 60 --from 40 --to 80 --pose-seed 21",
        "sherd --profile vase --angle 90 --from 10 --to 50 --pose-seed 22",
        "sherd --profile cylinder --angle 60 --from 40 --to 80 --pose-seed 23",
        "sherd --profile cone --angle 75 --from 30 --to 70 --pose-seed 24",
        "sherd --profile vase --angle 60 --from 70 --to 110 --pose-seed 25",
        "sherd --profile cylinder --angle 60 --rim --from 80 --pose-seed 26",
    };
    int k = 0;
    for (const char* args : cases) {
        SCOPED_TRACE(args);
        const std::string name = "sherd" + std::to_string(k++);
        const nlohmann::json truth = sample(name, std::string(args) + " --spacing 0.45 --roughness 0.02");
        const nlohmann::json fitted = axisOf(name);
        double degrees, offset;
        compareAxes(truth, fitted, degrees, offset);
        EXPECT_LT(degrees, 1.0);
        EXPECT_LT(offset, 0.01 * fitted["mean_radius"].get<double>());
        // A rim where the piece has one, else none.
        EXPECT_EQ(fitted["rim_diameter"].is_null(), truth["rim_diameter"].is_null()) << fitted["rim_diameter"];
        if (!truth["rim_diameter"].is_null() && fitted["rim_diameter"].is_number()) {
            EXPECT_NEAR(fitted["rim_diameter"].get<double>(), truth["rim_diameter"].get<double>(),
                        0.002 * truth["rim_diameter"].get<double>());
        }
    }
}

TEST(MsiiVesselsCli, ProfileLiesOnTheTrueProfile)
{
    // Unmarked and without noise, so that the surface is the true profile revolved.
    const nlohmann::json truth =
        sample("plainvase", "vessel --profile vase --spacing 0.6 --mark-depth 0 --pose-seed 31");
    const fs::path svg = tempDir() / "plainvase.profile.svg", csv = tempDir() / "plainvase.profile.csv";
    const RunResult r = runMsii("profile " + quoted(tempDir() / "plainvase.ply") + " -q -o " + quoted(svg));
    ASSERT_EQ(r.code, 0) << r.err;
    const TriMesh mesh = readMesh((tempDir() / "plainvase.ply").string()).mesh;
    std::vector<double> edges;
    for (const Triangle& t : mesh.triangles) edges.push_back(norm(mesh.points[t[0]] - mesh.points[t[1]]));
    std::nth_element(edges.begin(), edges.begin() + std::ptrdiff_t(edges.size() / 2), edges.end());
    const double edge = edges[edges.size() / 2];
    // Every point within a tenth of the median edge of the true profile (x is the distance
    // from the axis, y the height from the base's bottom).
    std::istringstream in(readFile(csv.string()));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "line,x,y");
    double worst = 0, length = 0;
    std::array<double, 2> last{};
    int lastLine = -1, points = 0;
    while (std::getline(in, line)) {
        int id;
        double x, y;
        char comma;
        std::istringstream fields(line);
        fields >> id >> comma >> x >> comma >> y;
        worst = std::max(worst, distanceToPolyline({std::abs(x), y}, truth["section"]));
        if (id == lastLine) length += std::hypot(x - last[0], y - last[1]);
        last = {x, y}, lastLine = id, ++points;
    }
    EXPECT_GT(points, 1000);
    EXPECT_LT(worst, 0.1 * edge) << "median edge " << edge;
    // Both halves of the profile: twice the true section, less what the axis closes.
    EXPECT_GE(length, 0.99 * 2 * polylineLength(truth["section"]));
    const std::string drawing = readFile(svg.string());
    EXPECT_NE(drawing.find("class=\"axis\""), std::string::npos);
    EXPECT_NE(drawing.find("stroke-dasharray"), std::string::npos);
    EXPECT_NE(drawing.find("class=\"rim\""), std::string::npos);
    EXPECT_NE(drawing.find("class=\"scale\""), std::string::npos);
#ifdef MSII_TEST_PICTURES
    fs::create_directories(MSII_TEST_PICTURES);
    fs::copy_file(svg, fs::path(MSII_TEST_PICTURES) / "vase-profile.svg", fs::copy_options::overwrite_existing);
#endif
}

TEST(MsiiVesselsCli, RolloutKeepsTheMarksPlaces)
{
    // A 25 mm seal: its marks at r·Δθ and Δh of each other, within 0.1 mm (up to a mirror).
    const nlohmann::json truth = sample("seal", "seal --spacing 0.12 --roughness 0.003 --pose-seed 41");
    const fs::path roll = tempDir() / "seal.roll.ply";
    RunResult r = runMsii("unroll " + quoted(tempDir() / "seal.ply") + " --shape cylinder -q -o " + quoted(roll));
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json record = readJson(tempDir() / "seal.roll.json");
    EXPECT_EQ(record["shape"], "cylinder");
    const double R = record["radius"].get<double>();
    EXPECT_NEAR(R, 12.5, 0.01);
    const TriMesh input = readMesh((tempDir() / "seal.ply").string()).mesh, rollout = readMesh(roll.string()).mesh;
    const std::vector<std::array<double, 2>> at = marksInRollout(input, rollout, truth["marks"]);
    ASSERT_GE(at.size(), 8u);
    // The rollout may run either way round, and a seal has no base to tell up from down.
    double mirror = 0, upside = 0;
    for (std::size_t i = 0; i < at.size(); ++i)
        for (std::size_t j = i + 1; j < at.size(); ++j) {
            const nlohmann::json &a = truth["marks"][i], &b = truth["marks"][j];
            mirror += (at[j][0] - at[i][0]) * std::sin(b["theta"].get<double>() - a["theta"].get<double>());
            upside += (at[j][1] - at[i][1]) * (b["height"].get<double>() - a["height"].get<double>());
        }
    const double sign = mirror >= 0 ? 1 : -1, up = upside >= 0 ? 1 : -1;
    for (std::size_t i = 0; i < at.size(); ++i)
        for (std::size_t j = i + 1; j < at.size(); ++j) {
            SCOPED_TRACE(std::to_string(i) + "-" + std::to_string(j));
            const nlohmann::json &a = truth["marks"][i], &b = truth["marks"][j];
            const double dx = sign * (at[j][0] - at[i][0]),
                         arc = R * (b["theta"].get<double>() - a["theta"].get<double>());
            const double turn = 2 * kPi * R;  // across the seam, a whole turn apart
            const double off = std::remainder(dx - arc, turn);
            EXPECT_LT(std::abs(off), 0.1);
            EXPECT_NEAR(up * (at[j][1] - at[i][1]), b["height"].get<double>() - a["height"].get<double>(), 0.1);
        }
#ifdef MSII_TEST_PICTURES
    r = runMsii("render " + quoted(roll) + " --show relief --view +z --pixels 1200 -q -o " +
                quoted(fs::path(MSII_TEST_PICTURES) / "seal-rollout.png") + " --overwrite");
    EXPECT_EQ(r.code, 0) << r.err;
#endif
}

TEST(MsiiVesselsCli, ConeRolloutKeepsGeodesicDistances)
{
    const nlohmann::json truth = sample("cone", "vessel --profile cone --spacing 0.5 --roughness 0.01 --pose-seed 51");
    const fs::path roll = tempDir() / "cone.roll.ply";
    const RunResult r = runMsii("unroll " + quoted(tempDir() / "cone.ply") + " --shape cone -q -o " + quoted(roll));
    ASSERT_EQ(r.code, 0) << r.err;
    // The true cone from its outer wall's profile, r = r0 + k z, between a fifth and four fifths
    // of the height (clear of the foot's and the lip's roundings).
    std::vector<std::array<double, 2>> wall;
    const double height = truth["height"].get<double>();
    for (const auto& p : truth["outer_profile"])
        if (p[1].get<double>() > 0.2 * height && p[1].get<double>() < 0.8 * height)
            wall.push_back({p[0].get<double>(), p[1].get<double>()});
    ASSERT_GE(wall.size(), 10u);
    const std::array<double, 2>&p0 = wall.front(), &p1 = wall.back();
    const double k = (p1[0] - p0[0]) / (p1[1] - p0[1]);
    const double r0 = p0[0] - k * p0[1], apex = -r0 / k;
    const double sinA = std::abs(k) / std::sqrt(1 + k * k);
    const auto along = [&](double z) { return std::abs(z - apex) * std::sqrt(1 + k * k); };  // from the apex
    const TriMesh input = readMesh((tempDir() / "cone.ply").string()).mesh, rollout = readMesh(roll.string()).mesh;
    // Vertices on the true outer wall (off the marks, clear of foot and lip), each at its
    // distance s from the apex and its angle θ about the true axis.
    const Vec3 axisPoint = vec(truth["axis"]["point"]), axis = normalized(vec(truth["axis"]["direction"]));
    const Vec3 e1 = normalized(cross(axis, std::abs(axis.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0))),
               e2 = cross(axis, e1);
    struct OnWall {
        std::size_t vertex;
        double s, theta;
    };
    std::vector<OnWall> onWall;
    for (std::size_t i = 0; i < input.numVertices(); i += 37) {
        const Vec3 d = input.points[i] - axisPoint;
        const double z = dot(d, axis), x = dot(d, e1), y = dot(d, e2);
        if (z < 0.2 * height || z > 0.8 * height || std::abs(std::hypot(x, y) - (r0 + k * z)) > 0.05) continue;
        onWall.push_back({i, along(z), std::atan2(y, x)});
    }
    ASSERT_GE(onWall.size(), 500u);
    // Every pair's distance in the development against the geodesic on the true cone: the short
    // way round, or across the seam, within 0.05 % + 0.02 mm (the fitted cone's error, the roughness).
    int compared = 0;
    double worst = 0;
    for (std::size_t i = 0; i < onWall.size(); i += 7)
        for (std::size_t j = i + 1; j < onWall.size(); j += 5) {
            const OnWall &a = onWall[i], &b = onWall[j];
            const double dTheta = std::abs(std::remainder(b.theta - a.theta, 2 * kPi));
            const auto geodesic = [&](double turn) {
                return std::sqrt(a.s * a.s + b.s * b.s - 2 * a.s * b.s * std::cos(turn * sinA));
            };
            const double shortWay = geodesic(dTheta), longWay = geodesic(2 * kPi - dTheta);
            const Vec3 &p = rollout.points[a.vertex], &q = rollout.points[b.vertex];
            const double d = std::hypot(q.x - p.x, q.y - p.y);
            worst = std::max(worst, std::min(std::abs(d - shortWay) / (0.0005 * shortWay + 0.02),
                                             std::abs(d - longWay) / (0.0005 * longWay + 0.02)));
            ++compared;
        }
    EXPECT_LE(worst, 1.0);
    EXPECT_GE(compared, 1000);
    // The marks, at known (θ, height): their centres' places in the rollout, pair by pair,
    // against their geodesic distances within 0.5 % + 0.3 mm (the target).
    std::vector<std::array<double, 3>> marks;  // x, y in the rollout; s from the apex
    std::vector<double> thetas;
    for (const auto& m : truth["marks"]) {
        std::array<double, 2> at;
        if (!placeInRollout(input, rollout, vec(m["centre"]), at)) continue;
        marks.push_back({at[0], at[1], along(m["height"].get<double>())});
        thetas.push_back(m["theta"].get<double>());
    }
    ASSERT_GE(marks.size(), 6u);
    for (std::size_t i = 0; i < marks.size(); ++i)
        for (std::size_t j = i + 1; j < marks.size(); ++j) {
            SCOPED_TRACE(std::to_string(i) + "-" + std::to_string(j));
            const double s1 = marks[i][2], s2 = marks[j][2];
            const double dTheta = std::abs(std::remainder(thetas[j] - thetas[i], 2 * kPi));
            const auto geodesic = [&](double turn) {
                return std::sqrt(s1 * s1 + s2 * s2 - 2 * s1 * s2 * std::cos(turn * sinA));
            };
            const double shortWay = geodesic(dTheta), longWay = geodesic(2 * kPi - dTheta);
            const double d = std::hypot(marks[j][0] - marks[i][0], marks[j][1] - marks[i][1]);
            EXPECT_LE(std::min(std::abs(d - shortWay) / (0.005 * shortWay + 0.3),
                               std::abs(d - longWay) / (0.005 * longWay + 0.3)),
                      1.0)
                << d << " against " << shortWay << " or " << longWay;
        }
}

TEST(MsiiVesselsCli, AGivenAxisUnrollsAsTheFittedOne)
{
    // The axis from its record, or as a bare line: the same cylinder as the fit's (the outer
    // wall's, not pulled by the inner wall or the base), hence the same rollout.
    sample("jar", "vessel --profile cylinder --spacing 0.8 --roughness 0.01 --pose-seed 71");
    const nlohmann::json fitted = axisOf("jar");
    const fs::path jar = tempDir() / "jar.ply";
    const auto radiusOf = [&](const std::string& axisOption, const std::string& name) {
        const fs::path out = tempDir() / (name + ".roll.ply");
        const RunResult r =
            runMsii("unroll " + quoted(jar) + " " + axisOption + " --shape cylinder -q -o " + quoted(out));
        EXPECT_EQ(r.code, 0) << r.err;
        return readJson(tempDir() / (name + ".roll.json"))["radius"].get<double>();
    };
    const double own = radiusOf("", "jar-own");
    EXPECT_NEAR(own, 50, 0.01);
    EXPECT_EQ(radiusOf("--axis " + quoted(tempDir() / "jar.axis.json"), "jar-record"), own);
    const Vec3 p = vec(fitted["point"]), d = vec(fitted["direction"]);
    char line[256];
    std::snprintf(line, sizeof line, "--axis %.12g,%.12g,%.12g:%.12g,%.12g,%.12g", p.x, p.y, p.z, d.x, d.y, d.z);
    EXPECT_NEAR(radiusOf(line, "jar-line"), 50, 0.05);
}

TEST(MsiiVesselsCli, ASherdIsNotCutByTheSeam)
{
    // By default the seam runs through the open side of a piece: no seam copies, and the
    // rollout as wide as the piece's arc.
    const nlohmann::json truth =
        sample("piece", "sherd --profile cylinder --angle 80 --from 40 --to 80 --spacing 0.5 --pose-seed 81");
    const fs::path roll = tempDir() / "piece.roll.ply";
    RunResult r = runMsii("unroll " + quoted(tempDir() / "piece.ply") + " --shape cylinder -q -o " + quoted(roll));
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json record = readJson(tempDir() / "piece.roll.json");
    EXPECT_EQ(record["vertices"]["seam_copies"].get<std::size_t>(), 0u);
    const TriMesh rollout = readMesh(roll.string()).mesh;
    double lo = 1e300, hi = -1e300;
    for (const Vec3& q : rollout.points) lo = std::min(lo, q.x), hi = std::max(hi, q.x);
    EXPECT_LT(hi - lo, 2 * kPi * 50 * 100 / 360);  // within the 80° piece and its breaks' wander
    // A rim sherd's profile: its rim diameter drawn across the axis, inside the drawing.
    sample("rimpiece", "sherd --profile cylinder --angle 70 --rim --from 80 --spacing 0.5 --pose-seed 82");
    const fs::path svg = tempDir() / "rimpiece.profile.svg";
    r = runMsii("profile " + quoted(tempDir() / "rimpiece.ply") + " -q -o " + quoted(svg));
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string drawing = readFile(svg.string());
    const std::size_t rim = drawing.find("class=\"rim\"");
    ASSERT_NE(rim, std::string::npos);
    const std::size_t x1 = drawing.find("x1=\"", rim);
    ASSERT_NE(x1, std::string::npos);
    EXPECT_GT(std::stod(drawing.substr(x1 + 4)), 0);  // the dimension line's left end on the paper
}

TEST(MsiiVesselsCli, RolloutKeepsTheVerticesAndTheirProperties)
{
    sample("small", "seal --spacing 0.3 --radius 6 --height 12 --mark-radius 0.8 --pose-seed 61");
    const fs::path features = tempDir() / "small.msii.ply", roll = tempDir() / "small.roll.ply";
    RunResult r =
        runMsii("compute " + quoted(tempDir() / "small.ply") + " -r 1.2 --invariants V -q -o " + quoted(features));
    ASSERT_EQ(r.code, 0) << r.err;
    r = runMsii("unroll " + quoted(features) + " -q -o " + quoted(roll));
    ASSERT_EQ(r.code, 0) << r.err;
    ReadMeshOptions o;
    o.keepVertexProperties = true;
    const ReadMeshResult in = readMesh(features.string(), o), out = readMesh(roll.string(), o);
    const nlohmann::json record = readJson(tempDir() / "small.roll.json");
    const std::size_t n = in.mesh.numVertices(), copies = record["vertices"]["seam_copies"].get<std::size_t>();
    EXPECT_GT(copies, 0u);
    ASSERT_EQ(out.mesh.numVertices(), n + copies);
    ASSERT_EQ(out.vertexProperties.size(), in.vertexProperties.size());
    for (std::size_t p = 0; p < in.vertexProperties.size(); ++p) {
        EXPECT_EQ(out.vertexProperties[p].name, in.vertexProperties[p].name);
        const std::vector<float>&a = in.vertexProperties[p].values, &b = out.vertexProperties[p].values;
        for (std::size_t i = 0; i < n; ++i) ASSERT_TRUE(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i]))) << i;
    }
    // Each seam copy lies a whole turn (2πR) from its original, at the same height.
    const double turn = 2 * kPi * record["radius"].get<double>();
    for (std::size_t c = 0; c < copies; ++c) {
        const Vec3& copy = out.mesh.points[n + c];
        double best = 1e300;
        for (std::size_t i = 0; i < n; ++i)
            if (std::abs(out.mesh.points[i].y - copy.y) < 1e-4 && std::abs(out.mesh.points[i].z - copy.z) < 1e-4)
                best = std::min(best, std::abs(std::abs(copy.x - out.mesh.points[i].x) - turn));
        EXPECT_LT(best, 1e-3) << c;
    }
}

TEST(MsiiVesselsCli, PlaneAndSphereAreRefused)
{
    const fs::path folder = tempDir() / "refused";
    fs::create_directories(folder);
    for (const char* shape : {"plane --width 30 --height 20 --spacing 0.5", "sphere --radius 20 --spacing 0.5"}) {
        SCOPED_TRACE(shape);
        const fs::path ply = folder / "in.ply";
        ASSERT_EQ(runProgram(MSII_SAMPLES_EXE, std::string(shape) + " -q -o " + quoted(ply), tempDir()).code, 0);
        const RunResult r = runMsii("axis " + quoted(ply) + " -o " + quoted(folder / "out.json"));
        EXPECT_EQ(r.code, 1);
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(std::string(shape).rfind("plane", 0) == 0 ? "plane" : "sphere"), std::string::npos)
            << r.err;
        EXPECT_FALSE(fs::exists(folder / "out.json"));
        fs::remove(ply);
    }
}
