/// Tests of outline/isolines.h: circles of a paraboloid on an irregular plane (closed, with
/// the interpolation error bound; open arcs at the border), several levels, evenLevels, NaN
/// regions, values exactly at the level (symbolic perturbation), a non-manifold edge, the
/// orientation on a hand-made square, thread-count independence, bad input, and SVG output.

#include <msii/outline/isolines.h>

#include <msii/core/errors.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "../support/flat_patch.h"
#include "../support/files.h"
#include "../support/temp_dir.h"

using namespace msii;
using msii::test::flatPatch;
using msii::test::readFile;
using msii::test::TempDir;

namespace {

constexpr double kPi = 3.14159265358979323846;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

/// The paraboloid f = z = ((x - 10)^2 + (y - 10)^2) / (2 c): the level L is the circle of
/// radius sqrt(2 c L) around (10, 10).
constexpr double kC = 5.0;
constexpr double kCx = 10.0, kCy = 10.0;

double radiusOf(const Vec3& p) { return std::hypot(p.x - kCx, p.y - kCy); }

/// The 20 x 20 mm irregular plane (spacing 0.2) lifted onto the paraboloid; f = z.
struct Paraboloid {
    TriMesh mesh;
    std::vector<float> f;
};

Paraboloid makeParaboloid(double spacing = 0.2)
{
    Paraboloid p;
    p.mesh = flatPatch(20, 20, spacing);
    p.f.resize(p.mesh.numVertices());
    for (std::size_t v = 0; v < p.f.size(); ++v) {
        Vec3& q = p.mesh.points[v];
        q.z = ((q.x - kCx) * (q.x - kCx) + (q.y - kCy) * (q.y - kCy)) / (2 * kC);
        p.f[v] = float(q.z);
    }
    return p;
}

/// The longest edge, in 3D or (@p xy) projected to the xy plane.
double maxEdgeLength(const TriMesh& mesh, bool xy = false)
{
    double e = 0;
    for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
            Vec3 d = mesh.points[t[k]] - mesh.points[t[(k + 1) % 3]];
            if (xy) d.z = 0;
            e = std::max(e, norm(d));
        }
    }
    return e;
}

/// Independent count of what the isolines of @p level must contain, with the rule "a value
/// equal to the level is above": segments = crossed triangles (all values finite), edges =
/// distinct edges crossed in those triangles.
struct Crossings {
    std::size_t segments = 0, edges = 0;
};

Crossings countCrossings(const TriMesh& mesh, const std::vector<float>& f, double level)
{
    Crossings c;
    std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
    for (const Triangle& t : mesh.triangles) {
        if (std::isnan(f[t[0]]) || std::isnan(f[t[1]]) || std::isnan(f[t[2]])) continue;
        bool crossed = false;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[k], b = t[(k + 1) % 3];
            if ((f[a] >= level) != (f[b] >= level)) {
                crossed = true;
                edges.insert({std::min(a, b), std::max(a, b)});
            }
        }
        c.segments += crossed;
    }
    c.edges = edges.size();
    return c;
}

/// Σ over the lines of their segments (points, or points − 1 when open) and of their points.
Crossings countLines(const std::vector<Polyline>& lines)
{
    Crossings c;
    for (const Polyline& line : lines) {
        c.segments += line.points.size() - (line.closed ? 0 : 1);
        c.edges += line.points.size();
    }
    return c;
}

/// Checks the shape of every line: no point twice, consecutive points (closing pair
/// included) distinct and within one triangle (at most the longest edge apart).
void expectWellFormed(const std::vector<Polyline>& lines, double emax)
{
    std::set<std::tuple<double, double, double>> all;
    std::size_t total = 0;
    for (const Polyline& line : lines) {
        ASSERT_GE(line.points.size(), line.closed ? 3u : 2u);
        const std::size_t n = line.points.size();
        for (std::size_t i = 0; i < n; ++i) {
            all.insert({line.points[i].x, line.points[i].y, line.points[i].z});
            ++total;
            if (i + 1 == n && !line.closed) break;
            const double d = norm(line.points[(i + 1) % n] - line.points[i]);
            EXPECT_GT(d, 0.0);
            EXPECT_LE(d, emax * (1 + 1e-9));
        }
    }
    EXPECT_EQ(all.size(), total);  // no point appears twice, in one line or across lines
}

/// For the paraboloid (gradient pointing away from the centre), every segment must have the
/// higher values on its left: cross(direction, p - centre) > 0.
void expectHigherOnTheLeft(const Polyline& line)
{
    const std::size_t n = line.points.size();
    const std::size_t segments = line.closed ? n : n - 1;
    for (std::size_t i = 0; i < segments; ++i) {
        const Vec3& p = line.points[i];
        const Vec3& q = line.points[(i + 1) % n];
        const double dx = q.x - p.x, dy = q.y - p.y;
        const double gx = 0.5 * (p.x + q.x) - kCx, gy = 0.5 * (p.y + q.y) - kCy;
        EXPECT_GT(dx * gy - dy * gx, 0.0);
    }
}

/// Signed (shoelace) area of a closed line in the xy plane.
double signedArea(const Polyline& line)
{
    double a = 0;
    const std::size_t n = line.points.size();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3& p = line.points[i];
        const Vec3& q = line.points[(i + 1) % n];
        a += p.x * q.y - q.x * p.y;
    }
    return 0.5 * a;
}

bool onBorder(const Vec3& p) { return p.x == 0.0 || p.y == 0.0 || p.x == 20.0 || p.y == 20.0; }

std::size_t countOf(const std::string& text, const std::string& what)
{
    std::size_t count = 0;
    for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++count;
    return count;
}

} // namespace

TEST(Isolines, ParaboloidCircleIsOneClosedLine)
{
    const Paraboloid p = makeParaboloid();
    const double emax = maxEdgeLength(p.mesh);
    const double exy = maxEdgeLength(p.mesh, true);  // the edges before lifting
    const double level = 2.5, radius = std::sqrt(2 * kC * level);  // 5 mm
    const std::vector<Polyline> lines = computeIsolines(p.mesh, p.f, {level});
    ASSERT_EQ(lines.size(), 1u);
    const Polyline& line = lines[0];
    EXPECT_EQ(line.level, level);
    EXPECT_TRUE(line.closed);

    // One point per crossed edge, one segment per crossed triangle.
    const Crossings expected = countCrossings(p.mesh, p.f, level);
    EXPECT_EQ(line.points.size(), expected.edges);
    EXPECT_EQ(line.points.size(), expected.segments);
    expectWellFormed(lines, emax);

    // Along an edge whose xy length is e, f is a convex quadratic with f'' = e^2 / c, so the
    // linear interpolant lies above f by at most e^2 / (8 c). At a crossing q the
    // interpolant is L, hence L - e^2 / (8 c) <= f(q) <= L, i.e. R^2 - e^2 / 4 <=
    // |q - centre|^2 <= R^2: the points lie on or just inside the circle. 1e-5 covers the
    // float rounding of f (~1e-7 here).
    const double inner = std::sqrt(radius * radius - exy * exy / 4);
    double minRadius = 1e9, maxRadius = 0;
    for (const Vec3& q : line.points) {
        minRadius = std::min(minRadius, radiusOf(q));
        maxRadius = std::max(maxRadius, radiusOf(q));
        EXPECT_NEAR(q.z, level, 1e-6);  // z is interpolated like f: the point is at the level
    }
    EXPECT_GE(minRadius, inner - 1e-5);
    EXPECT_LE(maxRadius, radius + 1e-5);

    // Higher values on the left: clockwise around the minimum. The polygon lies inside the
    // circle, and a chord (at most exy long) between points at radius >= inner stays at
    // least sqrt(inner^2 - exy^2 / 4) = sqrt(R^2 - exy^2 / 2) from the centre.
    expectHigherOnTheLeft(line);
    const double area = -signedArea(line);
    EXPECT_GE(area, kPi * (radius * radius - exy * exy / 2));
    EXPECT_LE(area, kPi * radius * radius);
}

TEST(Isolines, InconsistentOrientationStillChains)
{
    // Every other triangle flipped: the segments no longer agree on a direction, but they
    // are chained through their edges all the same. The closed circle keeps its points and
    // its start (the crossing on the smallest edge); the open arcs keep their ends.
    Paraboloid p = makeParaboloid();
    const std::vector<Polyline> reference = computeIsolines(p.mesh, p.f, {2.5, 14.4});
    for (std::size_t t = 1; t < p.mesh.triangles.size(); t += 2) {
        std::swap(p.mesh.triangles[t][1], p.mesh.triangles[t][2]);
    }
    const std::vector<Polyline> lines = computeIsolines(p.mesh, p.f, {2.5, 14.4});
    ASSERT_EQ(lines.size(), reference.size());
    ASSERT_EQ(lines.size(), 5u);
    for (std::size_t i = 0; i < lines.size(); ++i) {
        EXPECT_EQ(lines[i].closed, reference[i].closed);
        ASSERT_EQ(lines[i].points.size(), reference[i].points.size());
        std::vector<Vec3> a = lines[i].points, b = reference[i].points;
        if (lines[i].closed) {
            EXPECT_EQ(a.front(), b.front());
        } else {
            EXPECT_TRUE((a.front() == b.front() && a.back() == b.back()) ||
                        (a.front() == b.back() && a.back() == b.front()));
        }
        const auto less = [](const Vec3& u, const Vec3& v) {
            return std::tie(u.x, u.y, u.z) < std::tie(v.x, v.y, v.z);
        };
        std::sort(a.begin(), a.end(), less);
        std::sort(b.begin(), b.end(), less);
        EXPECT_TRUE(a == b);
    }

    // Where the orientation does not decide, the vertex indices do: the same mesh with its
    // triangles shuffled (each keeping its orientation) gives the same lines, point for point.
    std::mt19937 rng(5);
    std::shuffle(p.mesh.triangles.begin(), p.mesh.triangles.end(), rng);
    const std::vector<Polyline> shuffled = computeIsolines(p.mesh, p.f, {2.5, 14.4});
    ASSERT_EQ(shuffled.size(), lines.size());
    for (std::size_t i = 0; i < lines.size(); ++i) {
        EXPECT_TRUE(shuffled[i].points == lines[i].points) << "line " << i;
    }
}

TEST(Isolines, ArcsLeavingTheMeshAreOpen)
{
    // R = 12 > 10 (the distance to the sides) but < 14.1 (the corners): four arcs.
    const Paraboloid p = makeParaboloid();
    const double emax = maxEdgeLength(p.mesh);
    const double exy = maxEdgeLength(p.mesh, true);  // the edges before lifting
    const double radius = 12, level = radius * radius / (2 * kC);
    const std::vector<Polyline> lines = computeIsolines(p.mesh, p.f, {level});
    ASSERT_EQ(lines.size(), 4u);
    const Crossings expected = countCrossings(p.mesh, p.f, level);
    const Crossings got = countLines(lines);
    EXPECT_EQ(got.segments, expected.segments);
    EXPECT_EQ(got.edges, expected.edges);
    expectWellFormed(lines, emax);
    std::set<std::pair<bool, bool>> corners;  // which corner each arc cuts off
    for (const Polyline& line : lines) {
        EXPECT_FALSE(line.closed);
        EXPECT_EQ(line.level, level);
        // Both ends on the border (border edges lie exactly on it), no other point.
        EXPECT_TRUE(onBorder(line.points.front()));
        EXPECT_TRUE(onBorder(line.points.back()));
        for (std::size_t i = 1; i + 1 < line.points.size(); ++i) {
            EXPECT_FALSE(onBorder(line.points[i]));
        }
        for (const Vec3& q : line.points) {
            EXPECT_GE(radiusOf(q), std::sqrt(radius * radius - exy * exy / 4) - 1e-5);
            EXPECT_LE(radiusOf(q), radius + 1e-5);
        }
        expectHigherOnTheLeft(line);
        corners.insert({line.points[0].x > kCx, line.points[0].y > kCy});
    }
    EXPECT_EQ(corners.size(), 4u);
    // Ordered by their smallest edge (vertex (i, j) has index 101 j + i): the arcs cross the
    // bottom row at i ~ 17 and ~ 83, then the left and right columns at j ~ 83.
    EXPECT_LT(lines[0].points[0].x, kCx);
    EXPECT_LT(lines[0].points[0].y, kCy);
    EXPECT_GT(lines[1].points[0].x, kCx);
    EXPECT_LT(lines[1].points[0].y, kCy);
    EXPECT_LT(lines[2].points[0].x, kCx);
    EXPECT_GT(lines[2].points[0].y, kCy);
    EXPECT_GT(lines[3].points[0].x, kCx);
    EXPECT_GT(lines[3].points[0].y, kCy);
}

TEST(Isolines, SeveralLevelsAndEvenLevels)
{
    EXPECT_EQ(evenLevels(0, 8, 3), (std::vector<double>{2, 4, 6}));
    const std::vector<double> quarter = evenLevels(1, 2, 4);
    ASSERT_EQ(quarter.size(), 4u);
    for (int k = 0; k < 4; ++k) {
        EXPECT_DOUBLE_EQ(quarter[k], 1 + 0.2 * (k + 1));
    }
    EXPECT_TRUE(evenLevels(0, 1, 0).empty());
    EXPECT_TRUE(evenLevels(0, 1, -2).empty());

    const Paraboloid p = makeParaboloid();
    const double exy = maxEdgeLength(p.mesh, true);  // the edges before lifting
    // Unsorted, with a duplicate: the result is by level, each level once.
    const std::vector<Polyline> lines = computeIsolines(p.mesh, p.f, {6, 2, 4, 2});
    ASSERT_EQ(lines.size(), 3u);
    const double levels[3] = {2, 4, 6};
    for (int k = 0; k < 3; ++k) {
        const Polyline& line = lines[k];
        EXPECT_EQ(line.level, levels[k]);
        EXPECT_TRUE(line.closed);
        const double radius = std::sqrt(2 * kC * levels[k]);
        for (const Vec3& q : line.points) {
            EXPECT_GE(radiusOf(q), std::sqrt(radius * radius - exy * exy / 4) - 1e-5);
            EXPECT_LE(radiusOf(q), radius + 1e-5);
        }
        EXPECT_EQ(line.points.size(), countCrossings(p.mesh, p.f, levels[k]).segments);
    }
    EXPECT_EQ(computeIsolines(p.mesh, p.f, evenLevels(0, 8, 3)).size(), 3u);
    // Levels outside the range of f, and no levels: nothing.
    EXPECT_TRUE(computeIsolines(p.mesh, p.f, {-1, 100}).empty());
    EXPECT_TRUE(computeIsolines(p.mesh, p.f, {}).empty());
}

TEST(Isolines, NaNRegionBreaksLines)
{
    const double level = 2.5;  // the circle of radius 5
    Paraboloid p = makeParaboloid();
    const double emax = maxEdgeLength(p.mesh);
    const double exy = maxEdgeLength(p.mesh, true);  // the edges before lifting
    ASSERT_LT(exy, 0.5);  // no edge spans the strip
    // A NaN strip |x - 10| < 0.5 across the whole mesh cuts the circle twice.
    std::vector<float> f = p.f;
    for (std::size_t v = 0; v < f.size(); ++v) {
        if (std::abs(p.mesh.points[v].x - kCx) < 0.5) f[v] = kNaN;
    }
    std::vector<Polyline> lines = computeIsolines(p.mesh, f, {level});
    ASSERT_EQ(lines.size(), 2u);
    Crossings expected = countCrossings(p.mesh, f, level);
    EXPECT_EQ(countLines(lines).segments, expected.segments);
    EXPECT_EQ(countLines(lines).edges, expected.edges);
    expectWellFormed(lines, emax);
    for (const Polyline& line : lines) {
        EXPECT_FALSE(line.closed);
        const bool right = line.points[0].x > kCx;
        for (const Vec3& q : line.points) {
            EXPECT_EQ(q.x > kCx, right);
            EXPECT_GE(std::abs(q.x - kCx), 0.5);
        }
        // The ends are on edges of triangles next to the strip.
        EXPECT_LT(std::abs(line.points.front().x - kCx), 0.5 + exy);
        EXPECT_LT(std::abs(line.points.back().x - kCx), 0.5 + exy);
        expectHigherOnTheLeft(line);
    }

    // Only the lower half of the strip: the circle is cut once, one open line.
    f = p.f;
    for (std::size_t v = 0; v < f.size(); ++v) {
        const Vec3& q = p.mesh.points[v];
        if (std::abs(q.x - kCx) < 0.5 && q.y < kCy) f[v] = kNaN;
    }
    lines = computeIsolines(p.mesh, f, {level});
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_FALSE(lines[0].closed);
    expected = countCrossings(p.mesh, f, level);
    EXPECT_EQ(lines[0].points.size(), expected.segments + 1);
    EXPECT_EQ(lines[0].points.size(), expected.edges);
    EXPECT_LT(lines[0].points.front().y, kCy);
    EXPECT_LT(lines[0].points.back().y, kCy);
}

TEST(Isolines, ValuesExactlyAtTheLevel)
{
    // f = round(z): integer values, many vertices exactly at the level 3. They count as
    // above, so the line separates {round(z) <= 2} = {z < 2.5} from the rest.
    Paraboloid p = makeParaboloid();
    const double emax = maxEdgeLength(p.mesh);
    const double exy = maxEdgeLength(p.mesh, true);  // the edges before lifting
    std::vector<float> f = p.f;
    std::size_t atLevel = 0;
    for (float& v : f) {
        v = std::round(v);
        atLevel += v == 3.0f;
    }
    ASSERT_GT(atLevel, 100u);
    std::vector<Polyline> lines = computeIsolines(p.mesh, f, {3.0});
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_TRUE(lines[0].closed);
    Crossings expected = countCrossings(p.mesh, f, 3.0);
    EXPECT_EQ(lines[0].points.size(), expected.segments);
    EXPECT_EQ(lines[0].points.size(), expected.edges);
    expectWellFormed(lines, emax);
    for (const Vec3& q : lines[0].points) {  // crossings between the disc's last vertices and the next
        EXPECT_GT(radiusOf(q), 5.0 - exy);
        EXPECT_LT(radiusOf(q), 5.0 + exy);
    }

    // f = round(x): the level 5 is reached exactly along a band of vertices; the line is
    // the open line between round(x) = 4 and 5, from the bottom border to the top one.
    for (std::size_t v = 0; v < f.size(); ++v) f[v] = float(std::round(p.mesh.points[v].x));
    lines = computeIsolines(p.mesh, f, {5.0});
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_FALSE(lines[0].closed);
    expected = countCrossings(p.mesh, f, 5.0);
    EXPECT_EQ(lines[0].points.size(), expected.segments + 1);
    EXPECT_EQ(lines[0].points.size(), expected.edges);
    expectWellFormed(lines, emax);
    EXPECT_EQ(std::min(lines[0].points.front().y, lines[0].points.back().y), 0.0);
    EXPECT_EQ(std::max(lines[0].points.front().y, lines[0].points.back().y), 20.0);
    for (const Vec3& q : lines[0].points) {
        EXPECT_NEAR(q.x, 4.5, exy);
    }

    // One interior vertex exactly at the level, all others below: a tiny closed loop around
    // it, one distinct point per incident edge, each within 1e-6 of an edge length of it.
    const TriMesh& mesh = p.mesh;
    const std::uint32_t center = std::uint32_t(50 * 101 + 50);  // lattice vertex (50, 50)
    std::fill(f.begin(), f.end(), 0.0f);
    f[center] = 1.0f;
    std::set<std::uint32_t> ring;
    for (const Triangle& t : mesh.triangles) {
        if (std::find(t.begin(), t.end(), center) == t.end()) continue;
        for (const std::uint32_t v : t) {
            if (v != center) ring.insert(v);
        }
    }
    lines = computeIsolines(mesh, f, {1.0});
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_TRUE(lines[0].closed);
    EXPECT_EQ(lines[0].points.size(), ring.size());
    expectWellFormed(lines, emax);
    for (const Vec3& q : lines[0].points) {
        EXPECT_LE(norm(q - mesh.points[center]), 1e-6 * emax * (1 + 1e-6));
    }
    // The same vertex at the level with all others above: nothing crosses.
    std::fill(f.begin(), f.end(), 2.0f);
    f[center] = 1.0f;
    EXPECT_TRUE(computeIsolines(mesh, f, {1.0}).empty());
    // A constant field equal to the level: everything is above, no line.
    std::fill(f.begin(), f.end(), 1.0f);
    EXPECT_TRUE(computeIsolines(mesh, f, {1.0}).empty());
}

TEST(Isolines, OrientationAndPointsOnASquare)
{
    // Unit square split along (0,0)-(1,1), counter-clockwise; f = x, level 0.25: the line
    // runs down (higher x on its left) through the three crossed edges.
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    const std::vector<float> f = {0, 1, 1, 0};
    std::vector<Polyline> lines = computeIsolines(mesh, f, {0.25});
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_FALSE(lines[0].closed);
    ASSERT_EQ(lines[0].points.size(), 3u);
    EXPECT_EQ(lines[0].points[0], Vec3(0.25, 1, 0));
    EXPECT_EQ(lines[0].points[1], Vec3(0.25, 0.25, 0));
    EXPECT_EQ(lines[0].points[2], Vec3(0.25, 0, 0));

    // Clockwise triangles (normal down): seen from their front the line runs the other way.
    mesh.triangles = {{0, 2, 1}, {0, 3, 2}};
    lines = computeIsolines(mesh, f, {0.25});
    ASSERT_EQ(lines.size(), 1u);
    ASSERT_EQ(lines[0].points.size(), 3u);
    EXPECT_EQ(lines[0].points[0], Vec3(0.25, 0, 0));
    EXPECT_EQ(lines[0].points[2], Vec3(0.25, 1, 0));
}

TEST(Isolines, NonManifoldEdgeEndsLines)
{
    // Three triangles share the edge (0, 1); f goes from 0 to 1 along it. Each triangle's
    // segment runs from that edge to its own border edge: three open two-point lines.
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}};
    mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    const std::vector<float> f = {0, 1, 0, 0, 0};
    std::vector<Polyline> lines = computeIsolines(mesh, f, {0.5});
    ASSERT_EQ(lines.size(), 3u);
    for (const Polyline& line : lines) {
        EXPECT_FALSE(line.closed);
        ASSERT_EQ(line.points.size(), 2u);
        const bool startsOnShared = line.points[0] == Vec3(0.5, 0, 0);
        const bool endsOnShared = line.points[1] == Vec3(0.5, 0, 0);
        EXPECT_NE(startsOnShared, endsOnShared);
    }
    // Two of them (a manifold edge): one line through it.
    mesh.triangles.pop_back();
    lines = computeIsolines(mesh, f, {0.5});
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_EQ(lines[0].points.size(), 3u);
    EXPECT_EQ(lines[0].points[1], Vec3(0.5, 0, 0));
}

TEST(Isolines, TerrainIsWellFormedAndIndependentOfThreads)
{
    // Hills and valleys: many open and closed lines per level.
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Terrain;
    o.width = 30;
    o.height = 20;
    o.spacing = 0.1;
    o.hillWidth = 2;
    const TriMesh mesh = samples::makeHeightField(o);
    std::vector<float> f(mesh.numVertices());
    double lo = 1e9, hi = -1e9;
    for (std::size_t v = 0; v < f.size(); ++v) {
        f[v] = float(mesh.points[v].z);
        lo = std::min(lo, mesh.points[v].z);
        hi = std::max(hi, mesh.points[v].z);
    }
    const std::vector<double> levels = evenLevels(lo, hi, 9);
    const std::vector<Polyline> lines = computeIsolines(mesh, f, levels);
    const double emax = maxEdgeLength(mesh);
    std::size_t open = 0, closed = 0;
    for (std::size_t k = 0; k < levels.size(); ++k) {
        std::vector<Polyline> atLevel;
        for (const Polyline& line : lines) {
            if (line.level == levels[k]) atLevel.push_back(line);
        }
        const Crossings expected = countCrossings(mesh, f, levels[k]);
        const Crossings got = countLines(atLevel);
        EXPECT_EQ(got.segments, expected.segments);
        EXPECT_EQ(got.edges, expected.edges);
        expectWellFormed(atLevel, emax);
        for (const Polyline& line : atLevel) {
            (line.closed ? closed : open) += 1;
            if (!line.closed) {  // open lines end only at the border here
                EXPECT_TRUE(onBorder(line.points.front()) || line.points.front().x == 30.0);
                EXPECT_TRUE(onBorder(line.points.back()) || line.points.back().x == 30.0);
            }
        }
    }
    EXPECT_GT(open, 5u);
    EXPECT_GT(closed, 5u);
    for (std::size_t i = 1; i < lines.size(); ++i) {
        EXPECT_LE(lines[i - 1].level, lines[i].level);
    }

    const auto expectSame = [&](const std::vector<Polyline>& other) {
        ASSERT_EQ(other.size(), lines.size());
        for (std::size_t i = 0; i < lines.size(); ++i) {
            EXPECT_EQ(other[i].level, lines[i].level);
            EXPECT_EQ(other[i].closed, lines[i].closed);
            EXPECT_TRUE(other[i].points == lines[i].points) << "line " << i;
        }
    };
    {
        SCOPED_TRACE("one thread");
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        expectSame(computeIsolines(mesh, f, levels));
    }
    {
        // The canonical form (start, direction, order) depends on the vertices only: the
        // triangles shuffled and their corners rotated give the same lines.
        SCOPED_TRACE("triangles shuffled");
        TriMesh shuffled = mesh;
        std::mt19937 rng(3);
        std::shuffle(shuffled.triangles.begin(), shuffled.triangles.end(), rng);
        for (std::size_t t = 0; t < shuffled.triangles.size(); ++t) {
            Triangle& tri = shuffled.triangles[t];
            std::rotate(tri.begin(), tri.begin() + t % 3, tri.end());
        }
        expectSame(computeIsolines(shuffled, f, levels));
    }
}

TEST(Isolines, BadInputThrows)
{
    const Paraboloid p = makeParaboloid(1.0);
    EXPECT_THROW(computeIsolines(p.mesh, std::vector<float>(p.f.size() + 1), {1.0}), InvalidInputError);
    EXPECT_THROW(computeIsolines(p.mesh, p.f, {1.0, std::numeric_limits<double>::quiet_NaN()}),
                 InvalidInputError);
    EXPECT_THROW(computeIsolines(p.mesh, p.f, {std::numeric_limits<double>::infinity()}), InvalidInputError);
    TriMesh broken = p.mesh;
    broken.triangles[3][1] = std::uint32_t(broken.numVertices() + 7);
    EXPECT_THROW(computeIsolines(broken, p.f, {1.0}), InvalidInputError);
    EXPECT_TRUE(computeIsolines(TriMesh{}, {}, {1.0}).empty());
}

TEST(Isolines, SvgFile)
{
    TempDir dir;
    // Exact text of a small drawing: y flipped inside the area [1, 11] x [2, 12].
    Polyline2 small;
    small.level = 1.5;
    small.points = {{{1, 2}}, {{3, 4}}, {{1.25, 11.5}}};
    SvgOptions options;
    options.minX = 1;
    options.minY = 2;
    options.width = 10;
    options.height = 10;
    writeSvg(dir.file("small.svg"), {small}, options);
    std::string text = readFile(dir.file("small.svg"));
    EXPECT_EQ(text.rfind("<?xml", 0), 0u);
    EXPECT_NE(text.find("xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
    EXPECT_NE(text.find("width=\"10mm\" height=\"10mm\" viewBox=\"0 0 10 10\""), std::string::npos);
    EXPECT_NE(text.find("stroke-width=\"0.01\""), std::string::npos);  // width / 1000
    EXPECT_NE(text.find("fill=\"none\" stroke=\"black\""), std::string::npos);
    EXPECT_NE(text.find("<path data-level=\"1.5\" d=\"M0 10 L2 8 L0.25 0.5\"/>"), std::string::npos);
    EXPECT_EQ(text.substr(text.size() - 7), "</svg>\n");

    // Unknown units: unitless sizes; explicit stroke width; a closed path ends with Z.
    small.closed = true;
    options.units = "furlong";
    options.strokeWidth = 0.125;
    writeSvg(dir.file("small.svg"), {small}, options);
    text = readFile(dir.file("small.svg"));
    EXPECT_NE(text.find("width=\"10\" height=\"10\" viewBox"), std::string::npos);
    EXPECT_NE(text.find("stroke-width=\"0.125\""), std::string::npos);
    EXPECT_NE(text.find("L0.25 0.5 Z\"/>"), std::string::npos);

    // The paraboloid's lines (closed circles and open arcs) projected to the map.
    const Paraboloid p = makeParaboloid();
    const std::vector<Polyline> lines = computeIsolines(p.mesh, p.f, {2.5, 6.4, 14.4});
    ASSERT_EQ(lines.size(), 6u);  // two circles, four arcs
    std::vector<Polyline2> map;
    for (const Polyline& line : lines) {
        Polyline2 l;
        l.level = line.level;
        l.closed = line.closed;
        for (const Vec3& q : line.points) l.points.push_back({q.x, q.y});
        map.push_back(l);
    }
    SvgOptions area;
    area.width = 20;
    area.height = 20;
    writeSvg(dir.file("lines.svg"), map, area);
    text = readFile(dir.file("lines.svg"));
    EXPECT_EQ(text.rfind("<?xml", 0), 0u);
    EXPECT_EQ(countOf(text, "<svg "), 1u);
    EXPECT_EQ(countOf(text, "<path "), map.size());
    EXPECT_EQ(countOf(text, "data-level=\"2.5\""), 1u);
    EXPECT_EQ(countOf(text, "data-level=\"14.4\""), 4u);
    EXPECT_EQ(countOf(text, " Z\""), 2u);
    std::size_t points = 0;
    for (const Polyline2& l : map) points += l.points.size();
    EXPECT_EQ(countOf(text, "d=\"M") + countOf(text, " L"), points);
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"lines.svg", "small.svg"}));  // no temporaries

    EXPECT_THROW(writeSvg(dir.file("missing/out.svg"), map, area), IOError);
    area.height = 0;
    EXPECT_THROW(writeSvg(dir.file("flat.svg"), map, area), InvalidInputError);
    EXPECT_EQ(dir.entries().size(), 2u);
}
