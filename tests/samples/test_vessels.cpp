/// @file test_vessels.cpp
/// @brief Tests of msii/samples/vessels.h: the generated vessels, sherds and cylinder seals
/// against their known answers (the true profile, closed forms for the volume and area of a
/// solid of revolution, the marks, the pose), their topology (closed, outward, genus 0),
/// the spacing contract, determinism (seed, thread count) and the msii-samples command line
/// for them. Mesh properties come from tests/support/mesh_checks.h, not from the engine.

#include <msii/core/errors.h>
#include <msii/io/read_mesh.h>
#include <msii/samples/vessels.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "../support/files.h"
#include "../support/mesh_checks.h"
#include "../support/run_program.h"

using namespace msii;
using namespace msii::samples;
using msii::test::expectWatertight;
using msii::test::fingerprint;
using msii::test::identical;
using msii::test::minTriangleArea;
using msii::test::signedVolume;
using msii::test::triangleNormal;

namespace {

constexpr double kPi = 3.14159265358979323846;
using Polyline = std::vector<std::array<double, 2>>;

const VesselShape kShapes[] = {VesselShape::Cylinder, VesselShape::Cone, VesselShape::Vase};

/// A vessel of @p shape, coarse enough for fast tests.
VesselOptions vessel(VesselShape shape, double spacing = 1.5)
{
    VesselOptions o;
    o.shape = shape;
    o.spacing = spacing;
    return o;
}

/// Nearest points of a polyline in the (r, z) plane, through a grid of buckets.
class PolylineQuery {
public:
    struct Hit {
        double distance = std::numeric_limits<double>::infinity();
        std::array<double, 2> normal{};  ///< of the nearest segment, to the right of its direction
    };
    explicit PolylineQuery(const Polyline& line, double cell = 1.0) : mLine(line), mCell(cell)
    {
        for (const auto& p : line) {
            mR0 = std::min(mR0, p[0]);
            mZ0 = std::min(mZ0, p[1]);
            mR1 = std::max(mR1, p[0]);
            mZ1 = std::max(mZ1, p[1]);
        }
        mNr = int((mR1 - mR0) / cell) + 1;
        mNz = int((mZ1 - mZ0) / cell) + 1;
        mCells.resize(std::size_t(mNr) * std::size_t(mNz));
        for (std::size_t i = 0; i + 1 < line.size(); ++i) {
            const int r0 = cellR(std::min(line[i][0], line[i + 1][0])),
                      r1 = cellR(std::max(line[i][0], line[i + 1][0]));
            const int z0 = cellZ(std::min(line[i][1], line[i + 1][1])),
                      z1 = cellZ(std::max(line[i][1], line[i + 1][1]));
            for (int a = r0; a <= r1; ++a)
                for (int b = z0; b <= z1; ++b) mCells[std::size_t(b) * std::size_t(mNr) + std::size_t(a)].push_back(i);
        }
    }
    Hit nearest(double r, double z) const
    {
        Hit best;
        const int cr = cellR(r), cz = cellZ(z);
        // Rings of cells until the nearest found lies closer than the ring.
        for (int ring = 0; ring <= std::max(mNr, mNz); ++ring) {
            for (int a = cr - ring; a <= cr + ring; ++a)
                for (int b = cz - ring; b <= cz + ring; ++b) {
                    if (std::max(std::abs(a - cr), std::abs(b - cz)) != ring || a < 0 || b < 0 || a >= mNr || b >= mNz)
                        continue;
                    for (std::size_t i : mCells[std::size_t(b) * std::size_t(mNr) + std::size_t(a)])
                        consider(i, r, z, best);
                }
            if (best.distance <= ring * mCell) break;
        }
        return best;
    }

private:
    int cellR(double r) const { return std::clamp(int((r - mR0) / mCell), 0, mNr - 1); }
    int cellZ(double z) const { return std::clamp(int((z - mZ0) / mCell), 0, mNz - 1); }
    void consider(std::size_t i, double r, double z, Hit& best) const
    {
        const auto& a = mLine[i];
        const auto& b = mLine[i + 1];
        const double dr = b[0] - a[0], dz = b[1] - a[1], l2 = dr * dr + dz * dz;
        const double t = l2 > 0 ? std::clamp(((r - a[0]) * dr + (z - a[1]) * dz) / l2, 0.0, 1.0) : 0.0;
        const double d = std::hypot(a[0] + t * dr - r, a[1] + t * dz - z);
        if (d < best.distance) {
            const double l = std::sqrt(l2);
            best = {d, {dz / l, -dr / l}};
        }
    }
    const Polyline& mLine;
    double mCell, mR0 = 1e300, mZ0 = 1e300, mR1 = -1e300, mZ1 = -1e300;
    int mNr = 1, mNz = 1;
    std::vector<std::vector<std::size_t>> mCells;
};

double radial(const Vec3& p) { return std::hypot(p.x, p.y); }

/// The volume of the solid the section sweeps about the axis (closed by the axis), exactly
/// for the polyline: π Σ (r_i² + r_i r_i+1 + r_i+1²) / 3 Δz (Pappus, frustum by frustum).
double revolvedVolume(const Polyline& section)
{
    double v = 0;
    for (std::size_t i = 0; i + 1 < section.size(); ++i) {
        const double a = section[i][0], b = section[i + 1][0];
        v += (a * a + a * b + b * b) / 3.0 * (section[i + 1][1] - section[i][1]);
    }
    return kPi * v;
}

/// The area of the surface the section sweeps: π Σ (r_i + r_i+1) |segment|.
double revolvedArea(const Polyline& section)
{
    double area = 0;
    for (std::size_t i = 0; i + 1 < section.size(); ++i)
        area += kPi * (section[i][0] + section[i + 1][0]) *
                std::hypot(section[i + 1][0] - section[i][0], section[i + 1][1] - section[i][1]);
    return area;
}

double meshArea(const TriMesh& mesh)
{
    double area = 0;
    for (const Triangle& t : mesh.triangles) area += 0.5 * norm(triangleNormal(mesh, t));
    return area;
}

/// Whether (r, z) lies inside the section's loop closed by the axis (even-odd rule).
bool insideSection(const Polyline& section, double r, double z)
{
    bool inside = false;
    const std::size_t n = section.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {  // the closing edge j = n - 1 -> 0 is the axis
        const auto &a = section[i], &b = section[j];
        if ((a[1] > z) != (b[1] > z) && r < (b[0] - a[0]) * (z - a[1]) / (b[1] - a[1]) + a[0]) inside = !inside;
    }
    return inside;
}

/// Every vertex on the revolved section, and every triangle facing the way the profile's
/// outward normal does (none folded).
void expectOnTheTrueProfile(const Vessel& v, const char* what)
{
    SCOPED_TRACE(what);
    const PolylineQuery query(v.section);
    // The vertices are evaluated on the true curves, and the section's chords stray less
    // than kVesselProfileTolerance from them; 1e-9 covers the rounding of r = hypot(x, y).
    double worst = 0;
    for (const Vec3& p : v.mesh.points) worst = std::max(worst, query.nearest(radial(p), p.z).distance);
    EXPECT_LT(worst, kVesselProfileTolerance + 1e-9);
    double leastCosine = 1;
    for (const Triangle& t : v.mesh.triangles) {
        const Vec3 n = triangleNormal(v.mesh, t);
        const Vec3 m = (v.mesh.points[t[0]] + v.mesh.points[t[1]] + v.mesh.points[t[2]]) / 3.0;
        const double r = radial(m);
        const auto hit = query.nearest(r, m.z);
        const Vec3 out = r > 0 ? Vec3{hit.normal[0] * m.x / r, hit.normal[0] * m.y / r, hit.normal[1]}
                               : Vec3{0, 0, hit.normal[1]};
        leastCosine = std::min(leastCosine, dot(n, out) / norm(n));
    }
    EXPECT_GT(leastCosine, 0.5);
}

/// The rigid motion taking three points to three others (exact for a rigid motion).
struct Motion {
    std::array<Vec3, 3> from, to;  // orthonormal frames
    Vec3 origin, image;
    Vec3 rotate(const Vec3& v) const
    {
        return to[0] * dot(from[0], v) + to[1] * dot(from[1], v) + to[2] * dot(from[2], v);
    }
    Vec3 operator()(const Vec3& p) const { return image + rotate(p - origin); }
};

std::array<Vec3, 3> frame(const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 e0 = normalized(b - a);
    const Vec3 e1 = normalized((c - a) - e0 * dot(c - a, e0));
    return {e0, e1, cross(e0, e1)};
}

Motion motionBetween(const TriMesh& before, const TriMesh& after)
{
    // Three vertices far apart: the first, and the farthest from it, and the farthest from both.
    const std::size_t a = 0;
    std::size_t b = 0, c = 0;
    double best = 0;
    for (std::size_t i = 0; i < before.points.size(); ++i)
        if (norm(before.points[i] - before.points[a]) > best) best = norm(before.points[i] - before.points[a]), b = i;
    best = 0;
    for (std::size_t i = 0; i < before.points.size(); ++i) {
        const Vec3 e = normalized(before.points[b] - before.points[a]), d = before.points[i] - before.points[a];
        const double off = norm(d - e * dot(d, e));
        if (off > best) best = off, c = i;
    }
    return {frame(before.points[a], before.points[b], before.points[c]),
            frame(after.points[a], after.points[b], after.points[c]), before.points[a], after.points[a]};
}

/// The motion from @p built to @p posed, expected to carry every vertex and the truth's axis
/// (the z axis through the origin) to the posed ones.
Motion expectOneRigidMotion(const Vessel& built, const Vessel& posed)
{
    const Motion m = motionBetween(built.mesh, posed.mesh);
    double worst = 0;
    for (std::size_t i = 0; i < built.mesh.numVertices(); ++i)
        worst = std::max(worst, norm(m(built.mesh.points[i]) - posed.mesh.points[i]));
    EXPECT_LT(worst, 1e-9);
    EXPECT_LT(norm(posed.axisPoint - m(Vec3(0, 0, 0))), 1e-9);
    EXPECT_LT(norm(posed.axisDirection - m.rotate(Vec3(0, 0, 1))), 1e-12);
    return m;
}

/// A mark's deepest surface point within its radius, as the signed distance along its
/// normal from its centre (negative: below), and the distance of the vertex nearest to its
/// axis.
std::array<double, 2> deepestUnder(const TriMesh& mesh, const VesselMark& m)
{
    double deepest = 0, nearestAxis = 1e9;
    for (const Vec3& p : mesh.points) {
        const Vec3 d = p - m.centre;
        const double along = dot(d, m.normal), across = norm(d - m.normal * along);
        if (std::abs(along) > 3 * m.depth + 1) continue;
        if (across < m.radius) deepest = std::min(deepest, along);
        nearestAxis = std::min(nearestAxis, across);
    }
    return {deepest, nearestAxis};
}

/// The share of a mark's depth that the lattice may miss: its vertex nearest the axis lies
/// within a spacing of it, where the pit is still (1 − (s/r)²)² deep.
double latticeShare(double spacing, double radius) { return 1 - std::pow(1 - std::pow(spacing / radius, 2), 2); }

/// The least cosine between the normals of two triangles sharing an edge (−1: folded back).
double leastNeighbourCosine(const TriMesh& mesh)
{
    std::unordered_map<std::uint64_t, std::size_t> firstFace;
    double least = 1;
    for (std::size_t f = 0; f < mesh.numTriangles(); ++f)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = mesh.triangles[f][std::size_t(k)], b = mesh.triangles[f][std::size_t((k + 1) % 3)];
            const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
            const auto [it, first] = firstFace.emplace(key, f);
            if (first) continue;
            const Vec3 n = triangleNormal(mesh, mesh.triangles[f]),
                       m = triangleNormal(mesh, mesh.triangles[it->second]);
            least = std::min(least, dot(n, m) / (norm(n) * norm(m)));
        }
    return least;
}

/// The mean squared distance of @p points from their best plane: the least eigenvalue of
/// their covariance (the closed form for symmetric 3 × 3 matrices).
double leastPlaneVariance(const std::vector<Vec3>& points)
{
    Vec3 mean{};
    for (const Vec3& p : points) mean += p / double(points.size());
    double a[3][3] = {};
    for (const Vec3& p : points)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) a[i][j] += (p[i] - mean[i]) * (p[j] - mean[j]) / double(points.size());
    const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double q = (a[0][0] + a[1][1] + a[2][2]) / 3;
    const double p2 = std::pow(a[0][0] - q, 2) + std::pow(a[1][1] - q, 2) + std::pow(a[2][2] - q, 2) + 2 * p1;
    const double p = std::sqrt(p2 / 6);
    double b[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) b[i][j] = (a[i][j] - (i == j ? q : 0)) / p;
    const double det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                       b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                       b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    const double phi = std::acos(std::clamp(det / 2, -1.0, 1.0)) / 3;
    return q + 2 * p * std::cos(phi + 2 * kPi / 3);
}

} // namespace

// ---------------------------------------------------------------------------------------
// Vessels
// ---------------------------------------------------------------------------------------

TEST(Vessel, EachShapeIsClosedOutwardAndWithoutDegenerateTriangles)
{
    for (const VesselShape shape : kShapes) {
        const VesselOptions o = vessel(shape);
        const Vessel v = makeVessel(o);
        expectWatertight(v.mesh, vesselShapeName(shape));
        EXPECT_GT(signedVolume(v.mesh), 0.0) << vesselShapeName(shape);
        EXPECT_GT(leastNeighbourCosine(v.mesh), 0.3) << vesselShapeName(shape);  // a smooth surface
        EXPECT_GT(minTriangleArea(v.mesh), 0.02 * o.spacing * o.spacing) << vesselShapeName(shape);
        EXPECT_EQ(v.marks.size(), 8u);
        EXPECT_EQ(v.height, o.height);
        EXPECT_EQ(v.axisPoint, Vec3(0, 0, 0));
        EXPECT_EQ(v.axisDirection, Vec3(0, 0, 1));
        // The base's bottom at z = 0 (the pole), the rim's top at the height (to the
        // lattice's chord: the ring nearest the lip's top lies less than a spacing from it
        // along the lip, a half circle of radius wall / 2).
        double lo = 1e9, hi = -1e9;
        for (const Vec3& p : v.mesh.points) lo = std::min(lo, p.z), hi = std::max(hi, p.z);
        EXPECT_EQ(lo, 0.0);
        EXPECT_LE(hi, o.height + 1e-9);
        EXPECT_GE(hi, o.height - o.spacing * o.spacing / o.wall);
    }
}

TEST(Vessel, VerticesLieOnTheTrueProfileAndNoTriangleIsFolded)
{
    for (const VesselShape shape : kShapes) {
        VesselOptions o = vessel(shape, 2.0);
        o.markDepth = 0;  // unmarked, noiseless
        const Vessel v = makeVessel(o);
        EXPECT_TRUE(v.marks.empty());
        expectOnTheTrueProfile(v, vesselShapeName(shape));
    }
}

TEST(Vessel, ProfilesRunFromTheBaseToTheRimAndMatchTheOuterRadius)
{
    for (const VesselShape shape : kShapes) {
        SCOPED_TRACE(vesselShapeName(shape));
        const VesselOptions o = vessel(shape, 2.5);
        const Vessel v = makeVessel(o);
        ASSERT_GT(v.outerProfile.size(), 10u);
        ASSERT_GT(v.innerProfile.size(), 10u);
        EXPECT_EQ(v.outerProfile.front(), (std::array<double, 2>{0, 0}));
        EXPECT_EQ(v.innerProfile.front(), (std::array<double, 2>{0, o.base}));
        EXPECT_EQ(v.section.front(), (std::array<double, 2>{0, 0}));
        EXPECT_EQ(v.section.back(), (std::array<double, 2>{0, o.base}));
        // The outer profile ends where the lip begins: at the rim diameter; the lip is a half
        // circle of diameter `wall` from there to the inner profile's end.
        EXPECT_NEAR(2 * v.outerProfile.back()[0], v.rimDiameter, 1e-12);
        const auto& a = v.outerProfile.back();
        const auto& b = v.innerProfile.back();
        EXPECT_NEAR(std::hypot(a[0] - b[0], a[1] - b[1]), o.wall, 1e-9);
        double top = 0;
        for (const auto& p : v.section) top = std::max(top, p[1]);
        EXPECT_NEAR(top, o.height, 2 * kVesselProfileTolerance);
        // vesselOuterRadius is the outer profile, up to where the lip begins.
        for (const auto& p : v.outerProfile) {
            if (p[1] > 0) {
                ASSERT_NEAR(vesselOuterRadius(o, p[1]), p[0], 1e-9) << "z " << p[1];
            }
        }
        EXPECT_TRUE(std::isnan(vesselOuterRadius(o, a[1] + 0.01)));
        EXPECT_TRUE(std::isnan(vesselOuterRadius(o, -0.01)));
        VesselOptions coarse = o;  // the mesh's options do not change the shape
        coarse.spacing = 100;
        coarse.markDepth = 10;
        EXPECT_EQ(vesselOuterRadius(coarse, 60), vesselOuterRadius(o, 60));
    }
    // Closed forms: the cylinder's radius, the cone's line, the vase's belly as its widest.
    VesselOptions o = vessel(VesselShape::Cylinder);
    EXPECT_DOUBLE_EQ(vesselOuterRadius(o, 60), o.radius);
    EXPECT_DOUBLE_EQ(makeVessel(o).rimDiameter, 2 * o.radius);
    o.shape = VesselShape::Cone;
    const Vessel cone = makeVessel(o);
    EXPECT_NEAR(cone.rimDiameter, 2 * o.topRadius, 1e-9);
    const double zTop = cone.outerProfile.back()[1];
    EXPECT_NEAR(vesselOuterRadius(o, 50), o.radius + (o.topRadius - o.radius) * 50 / zTop, 1e-9);
    o.shape = VesselShape::Vase;
    const Vessel vase = makeVessel(o);
    double widest = 0, widestZ = 0;
    for (const auto& p : vase.outerProfile)
        if (p[0] > widest) widest = p[0], widestZ = p[1];
    EXPECT_LE(widest, o.radius);
    EXPECT_NEAR(widest, o.radius, 1e-4);
    const double vaseTop = vase.outerProfile.back()[1];
    EXPECT_NEAR(widestZ / vaseTop, 0.35, 0.01);
    EXPECT_EQ(vesselOuterRadius(o, 0.35 * vaseTop), o.radius);
}

TEST(Vessel, VolumeConvergesToTheSolidOfRevolution)
{
    for (const VesselShape shape : kShapes) {
        SCOPED_TRACE(vesselShapeName(shape));
        VesselOptions o = vessel(shape, 2.0);
        o.markDepth = 0;
        const Vessel coarse = makeVessel(o);
        const double truth = revolvedVolume(coarse.section);
        o.spacing = 1.0;
        const double coarseError = std::abs(signedVolume(coarse.mesh) / truth - 1);
        const double fineError = std::abs(signedVolume(makeVessel(o).mesh) / truth - 1);
        // Chords fall short of the curves by ~spacing² / (8 ρ): the error shrinks ~4x.
        EXPECT_LT(coarseError, 0.01);
        EXPECT_LT(fineError, coarseError / 2.5);
    }
}

TEST(Vessel, VertexCountIsAreaOverSpacingSquared)
{
    for (const VesselShape shape : kShapes) {
        SCOPED_TRACE(vesselShapeName(shape));
        VesselOptions o = vessel(shape, 1.6);
        const Vessel coarse = makeVessel(o);
        const double area = revolvedArea(coarse.section);
        EXPECT_NEAR(double(coarse.mesh.numVertices()) * o.spacing * o.spacing / area, 1.0, 0.1);
        o.spacing = 0.8;
        EXPECT_NEAR(double(makeVessel(o).mesh.numVertices()) / double(coarse.mesh.numVertices()), 4.0, 0.2);
    }
}

TEST(Vessel, MarksAreWhereTheySay)
{
    // A cylinder: the centres and normals in closed form, each pit's depth under its centre.
    VesselOptions o = vessel(VesselShape::Cylinder, 0.5);
    o.marks = {{0.3, 30}, {2.0, 60}, {-2.5, 95}, {4.0, 20}};
    const Vessel v = makeVessel(o);
    ASSERT_EQ(v.marks.size(), o.marks.size());
    for (std::size_t k = 0; k < v.marks.size(); ++k) {
        const VesselMark& m = v.marks[k];
        SCOPED_TRACE(k);
        const double theta = o.marks[k].theta;
        EXPECT_EQ(m.theta, theta);
        EXPECT_EQ(m.height, o.marks[k].height);
        EXPECT_NEAR(norm(m.centre - Vec3(o.radius * std::cos(theta), o.radius * std::sin(theta), m.height)), 0, 1e-12);
        EXPECT_NEAR(norm(m.normal - Vec3(std::cos(theta), std::sin(theta), 0)), 0, 1e-12);
        EXPECT_EQ(m.radius, o.markRadius);
        EXPECT_EQ(m.depth, o.markDepth);
        // The deepest point lies the depth below the centre, within the lattice's share and
        // the cylinder's fall-off over the pit (radius² / 2R).
        const auto [deepest, nearestAxis] = deepestUnder(v.mesh, m);
        EXPECT_LT(nearestAxis, o.spacing);
        EXPECT_LE(deepest, -(1 - latticeShare(o.spacing, m.radius)) * m.depth);
        EXPECT_GE(deepest, -m.depth - m.radius * m.radius / (2 * o.radius));
    }
}

TEST(Vessel, MarksPressTheOuterWallAlongItsNormalAndNothingElse)
{
    // The vase's default marks, on sloping walls: the marked mesh against the unmarked one
    // (the same lattice): only vertices within a mark's radius move, inward along the
    // surface's normal, by at most the depth and at least the lattice's share of it.
    VesselOptions o = vessel(VesselShape::Vase, 0.5);
    const double depth = o.markDepth;
    const Vessel marked = makeVessel(o);
    o.markDepth = 0;
    const Vessel plain = makeVessel(o);
    ASSERT_EQ(marked.mesh.numVertices(), plain.mesh.numVertices());
    ASSERT_EQ(marked.marks.size(), 8u);
    const PolylineQuery query(plain.section);
    std::vector<double> deepest(marked.marks.size(), 0.0);
    std::size_t moved = 0;
    for (std::size_t i = 0; i < plain.mesh.numVertices(); ++i) {
        const Vec3 p = plain.mesh.points[i], d = marked.mesh.points[i] - p;
        std::size_t near = marked.marks.size();
        for (std::size_t k = 0; k < marked.marks.size(); ++k)
            if (norm(p - marked.marks[k].centre) < marked.marks[k].radius * 1.01) near = k;
        if (near == marked.marks.size()) {
            ASSERT_EQ(d, Vec3(0, 0, 0)) << "vertex " << i << " moved outside the marks";
            continue;
        }
        if (norm(d) == 0) continue;
        ++moved;
        const double r = radial(p);
        const auto hit = query.nearest(r, p.z);
        const Vec3 out{hit.normal[0] * p.x / r, hit.normal[0] * p.y / r, hit.normal[1]};
        ASSERT_GT(dot(d, out) / norm(d), -1.0 - 1e-9);
        ASSERT_LT(dot(d, out) / norm(d), -0.999) << "vertex " << i << " not moved along the normal";
        ASSERT_LE(norm(d), depth * (1 + 1e-9));
        deepest[near] = std::max(deepest[near], norm(d));
    }
    EXPECT_GT(moved, 8u * 20u);
    for (double d : deepest) EXPECT_GE(d, (1 - latticeShare(o.spacing, o.markRadius)) * depth);
    // The marks lie on the true outer wall, in different places around and along it.
    for (const VesselMark& m : marked.marks) {
        EXPECT_NEAR(radial(m.centre), vesselOuterRadius(o, m.height), 1e-9);
        EXPECT_NEAR(std::atan2(m.centre.y, m.centre.x), std::remainder(m.theta, 2 * kPi), 1e-12);
        EXPECT_NEAR(norm(m.normal), 1.0, 1e-12);
    }
    for (std::size_t a = 0; a < marked.marks.size(); ++a)
        for (std::size_t b = a + 1; b < marked.marks.size(); ++b) {
            EXPECT_GT(norm(marked.marks[a].centre - marked.marks[b].centre), 2 * o.markRadius);
            EXPECT_GT(std::abs(marked.marks[a].height - marked.marks[b].height), 1.0);
        }
}

TEST(Vessel, RoughnessMovesVerticesAlongTheNormalUpToIt)
{
    VesselOptions o = vessel(VesselShape::Cone, 2.0);
    o.markDepth = 0;
    o.roughness = 0.05;
    const Vessel rough = makeVessel(o);
    const PolylineQuery query(rough.section);
    double worst = 0, mean = 0;
    for (const Vec3& p : rough.mesh.points) {
        const double d = query.nearest(radial(p), p.z).distance;
        worst = std::max(worst, d);
        mean += d;
    }
    mean /= double(rough.mesh.numVertices());
    EXPECT_LE(worst, o.roughness + kVesselProfileTolerance);
    EXPECT_NEAR(mean, o.roughness / 2, 0.1 * o.roughness);  // uniform in [-E, E]: |d| averages E / 2
}

TEST(Vessel, PoseIsOneRigidMotionAndTheTruthFollowsIt)
{
    VesselOptions o = vessel(VesselShape::Vase, 2.0);
    o.roughness = 0.02;
    const Vessel built = makeVessel(o);
    o.poseSeed = 7;
    const Vessel posed = makeVessel(o);
    ASSERT_EQ(posed.mesh.numVertices(), built.mesh.numVertices());
    EXPECT_TRUE(posed.mesh.triangles == built.mesh.triangles);
    // The truth's axis is the posed z axis through the posed origin; the marks moved along.
    const Motion m = expectOneRigidMotion(built, posed);
    EXPECT_NEAR(norm(posed.axisDirection), 1.0, 1e-12);
    EXPECT_LE(norm(posed.axisPoint), 1000.0);
    EXPECT_GT(norm(posed.axisPoint), 1.0);
    EXPECT_LT(std::abs(posed.axisDirection.z), 0.999);
    ASSERT_EQ(posed.marks.size(), built.marks.size());
    for (std::size_t k = 0; k < built.marks.size(); ++k) {
        EXPECT_LT(norm(posed.marks[k].centre - m(built.marks[k].centre)), 1e-9);
        EXPECT_LT(norm(posed.marks[k].normal - m.rotate(built.marks[k].normal)), 1e-12);
        EXPECT_EQ(posed.marks[k].theta, built.marks[k].theta);
        EXPECT_EQ(posed.marks[k].height, built.marks[k].height);
    }
    EXPECT_EQ(posed.section, built.section);  // the profiles stay in the object's frame
    EXPECT_EQ(posed.rimDiameter, built.rimDiameter);
}

TEST(Vessel, PosesAreSpreadOverAllRotationsAndTheBall)
{
    // Uniform rotations send +z uniformly over the sphere (mean ~0, z² averaging 1/3);
    // uniform points in the ball have |t|³ uniform in [0, 1000³].
    SealOptions o;
    o.spacing = 5;
    o.markDepth = 0;
    Vec3 mean{};
    double zz = 0, cube = 0;
    const int n = 300;
    for (int k = 1; k <= n; ++k) {
        o.poseSeed = std::uint64_t(k);
        const Vessel v = makeCylinderSeal(o);
        mean += v.axisDirection / double(n);
        zz += v.axisDirection.z * v.axisDirection.z / n;
        ASSERT_LE(norm(v.axisPoint), 1000.0);
        cube += std::pow(norm(v.axisPoint) / 1000, 3) / n;
    }
    EXPECT_LT(norm(mean), 0.15);
    EXPECT_NEAR(zz, 1.0 / 3.0, 0.06);
    EXPECT_NEAR(cube, 0.5, 0.06);
}

// ---------------------------------------------------------------------------------------
// Sherds
// ---------------------------------------------------------------------------------------

namespace {

SherdOptions sherd(bool rim, double angle, double spacing = 0.8)
{
    SherdOptions o;
    o.vessel.spacing = spacing;
    o.rim = rim;
    o.angle = angle;
    o.theta0 = 0.4;
    return o;
}

} // namespace

TEST(VesselSherd, WithAndWithoutRimClosedOutwardAndInTheWall)
{
    for (const bool rim : {false, true})
        for (const double angle : {60.0, 90.0}) {
            const std::string what = std::string(rim ? "rim " : "") + std::to_string(int(angle));
            SCOPED_TRACE(what);
            SherdOptions o = sherd(rim, angle);
            o.vessel.markDepth = 0;
            const Vessel s = makeSherd(o);
            expectWatertight(s.mesh, what.c_str());
            EXPECT_GT(signedVolume(s.mesh), 0.0);
            // No triangle folded back on its neighbour: the sharpest edges are the breaks'
            // meeting the walls, at most ~50° off a right angle where a break leans most.
            EXPECT_GT(leastNeighbourCosine(s.mesh), -0.9);
            EXPECT_GT(minTriangleArea(s.mesh), 0.02 * o.vessel.spacing * o.vessel.spacing);
            // A piece of the wall: about angle/360 of the wall's volume between the heights.
            const double r = vesselOuterRadius(o.vessel, 60);
            double narrowest = 1e9;
            for (double z = o.fromHeight - 3; z < (rim ? 110.0 : o.toHeight + 3); z += 0.5)
                narrowest = std::min(narrowest, vesselOuterRadius(o.vessel, z));
            EXPECT_NEAR(signedVolume(s.mesh) / (angle / 360 * 2 * kPi * r * o.vessel.wall * ((rim ? 120 : 80) - 40)), 1,
                        0.35);
            // Every vertex lies in the wall (inside the section or on it); the outer and
            // inner faces' vertices on it.
            const PolylineQuery query(s.section);
            std::size_t onProfile = 0;
            double lo = 1e9, hi = -1e9, first = 1e9, last = -1e9;
            for (const Vec3& p : s.mesh.points) {
                const double d = query.nearest(radial(p), p.z).distance;
                ASSERT_TRUE(d < kVesselProfileTolerance + 1e-9 || insideSection(s.section, radial(p), p.z))
                    << p.x << ' ' << p.y << ' ' << p.z;
                onProfile += d < kVesselProfileTolerance + 1e-9;
                lo = std::min(lo, p.z), hi = std::max(hi, p.z);
                const double theta = std::atan2(p.y, p.x);
                first = std::min(first, theta), last = std::max(last, theta);
            }
            EXPECT_GT(double(onProfile), 0.75 * double(s.mesh.numVertices()));
            // Its extent: around from θ0 to θ0 + angle, up from 40 to 80 (or the rim), each
            // break wandering by less than 1.5 mm and a quarter of the wall.
            const double wander = (1.5 + 0.25 * o.vessel.wall) / narrowest;
            EXPECT_GT(first, o.theta0 - wander);
            EXPECT_LT(first, o.theta0 + wander);
            EXPECT_GT(last, o.theta0 + angle * kPi / 180 - wander);
            EXPECT_LT(last, o.theta0 + angle * kPi / 180 + wander);
            EXPECT_NEAR(lo, o.fromHeight, 4.0);
            EXPECT_NEAR(s.height, hi - lo, o.vessel.spacing);
            if (rim) {
                EXPECT_NEAR(hi, o.vessel.height, 0.05);
                EXPECT_EQ(s.rimDiameter, makeVessel(o.vessel).rimDiameter);
            } else {
                EXPECT_NEAR(hi, o.toHeight, 4.0);
                EXPECT_EQ(s.rimDiameter, 0.0);
            }
        }
}

TEST(VesselSherd, BreaksAreJaggedAndNotPlanar)
{
    // The start break: the vertices of the triangles facing back around the axis (−θ) stray
    // from their best plane by a root mean square of several tenths of a millimetre.
    SherdOptions o = sherd(false, 75);
    o.vessel.shape = VesselShape::Cylinder;
    const Vessel s = makeSherd(o);
    std::vector<Vec3> breakPoints;
    for (const Triangle& t : s.mesh.triangles) {
        const Vec3 m = (s.mesh.points[t[0]] + s.mesh.points[t[1]] + s.mesh.points[t[2]]) / 3.0;
        const Vec3 back = normalized(Vec3(m.y, -m.x, 0));
        const Vec3 n = triangleNormal(s.mesh, t);
        if (dot(n, back) > 0.7 * norm(n))
            for (std::uint32_t v : t) breakPoints.push_back(s.mesh.points[v]);
    }
    ASSERT_GT(breakPoints.size(), 100u);
    EXPECT_GT(std::sqrt(leastPlaneVariance(breakPoints)), 0.2);
    // The cube's a faces are those breaks: every one of those points near θ0.
    for (const Vec3& p : breakPoints) EXPECT_NEAR(std::atan2(p.y, p.x), o.theta0, 0.12);
    // The bottom and top breaks (the cylinder's wall stands upright, so they face down and
    // up) wander in height by millimetres, not along a level circle.
    for (const double side : {-1.0, 1.0}) {
        double lo = 1e9, hi = -1e9;
        for (const Triangle& t : s.mesh.triangles) {
            const Vec3 n = triangleNormal(s.mesh, t);
            if (side * n.z > 0.7 * norm(n))
                for (std::uint32_t v : t) lo = std::min(lo, s.mesh.points[v].z), hi = std::max(hi, s.mesh.points[v].z);
        }
        EXPECT_GT(hi - lo, 1.0) << side;
        EXPECT_LT(hi - lo, 2 * (1.5 + 0.25 * o.vessel.wall)) << side;
    }
}

TEST(VesselSherd, VertexCountIsAreaOverSpacingSquared)
{
    for (const bool rim : {false, true}) {
        SherdOptions o = sherd(rim, 90, 0.8);
        const Vessel coarse = makeSherd(o);
        EXPECT_NEAR(double(coarse.mesh.numVertices()) * 0.8 * 0.8 / meshArea(coarse.mesh), 1.0, 0.15) << rim;
        o.vessel.spacing = 0.4;
        EXPECT_NEAR(double(makeSherd(o).mesh.numVertices()) / double(coarse.mesh.numVertices()), 4.0, 0.3) << rim;
    }
}

TEST(VesselSherd, HasTheMarksInsideThePieceWhereTheySay)
{
    SherdOptions o = sherd(false, 75, 0.5);
    const double middle = o.theta0 + 37.5 * kPi / 180;
    o.vessel.marks = {{middle, 60}, {middle + 0.3, 50}, {middle + 2.0, 60}, {middle, 20}};
    const Vessel s = makeSherd(o);
    ASSERT_EQ(s.marks.size(), 2u);  // the two inside the piece
    EXPECT_EQ(s.marks[0].theta, middle);
    EXPECT_EQ(s.marks[1].height, 50);
    for (const VesselMark& m : s.marks) {
        EXPECT_NEAR(radial(m.centre), vesselOuterRadius(o.vessel, m.height), 1e-9);
        const auto [deepest, nearestAxis] = deepestUnder(s.mesh, m);
        EXPECT_LT(nearestAxis, o.vessel.spacing);
        EXPECT_LE(deepest, -(1 - latticeShare(o.vessel.spacing, m.radius)) * m.depth);
        EXPECT_GE(deepest, -m.depth - m.radius * m.radius / vesselOuterRadius(o.vessel, m.height));
    }
    // The marks outside leave the piece alone: only two pits' worth of vertices moved.
    SherdOptions plain = o;
    plain.vessel.marks = {{middle, 60}, {middle + 0.3, 50}};
    EXPECT_TRUE(identical(makeSherd(plain).mesh, s.mesh));
}

TEST(VesselSherd, PoseIsOneRigidMotion)
{
    SherdOptions o = sherd(true, 60, 1.0);
    o.vessel.roughness = 0.02;
    const Vessel built = makeSherd(o);
    o.vessel.poseSeed = 11;
    const Vessel posed = makeSherd(o);
    expectOneRigidMotion(built, posed);
    EXPECT_EQ(posed.height, built.height);
}

// ---------------------------------------------------------------------------------------
// Cylinder seals
// ---------------------------------------------------------------------------------------

TEST(VesselSeal, ClosedWithTheVolumeOfItsOutlineAndItsMarks)
{
    SealOptions o;
    o.spacing = 0.4;
    const Vessel seal = makeCylinderSeal(o);
    expectWatertight(seal.mesh, "seal");
    EXPECT_GT(minTriangleArea(seal.mesh), 0.02 * o.spacing * o.spacing);
    EXPECT_EQ(seal.rimDiameter, 0.0);
    EXPECT_EQ(seal.height, o.height);
    EXPECT_TRUE(seal.innerProfile.empty());
    EXPECT_EQ(seal.outerProfile, seal.section);
    EXPECT_EQ(seal.section.back(), (std::array<double, 2>{0, o.height}));
    // The volume: the cylinder less its rounded edges (exact for the outline), less the marks
    // (each less than π r² depth).
    // A rounded edge of radius e takes the corner e² (1 − π/4) whose centroid lies
    // e (10 − 3π) / (3 (4 − π)) inside the corner, about the axis (Pappus).
    const double outline = revolvedVolume(seal.section);
    const double edge = 0.05 * o.radius;
    const double corner = edge * edge * (1 - kPi / 4) * 2 * kPi * (o.radius - edge * (10 - 3 * kPi) / (3 * (4 - kPi)));
    EXPECT_NEAR(outline, kPi * o.radius * o.radius * o.height - 2 * corner, 0.05);
    const double marks = 10 * kPi * o.markRadius * o.markRadius * o.markDepth;
    EXPECT_LT(signedVolume(seal.mesh), outline);
    EXPECT_GT(signedVolume(seal.mesh), outline * (1 - 0.002) - marks);
    ASSERT_EQ(seal.marks.size(), 10u);
    for (const VesselMark& m : seal.marks) {
        EXPECT_NEAR(radial(m.centre), o.radius, 1e-12);
        EXPECT_GT(m.height, edge + m.radius);
        EXPECT_LT(m.height, o.height - edge - m.radius);
        const auto [deepest, nearestAxis] = deepestUnder(seal.mesh, m);
        EXPECT_LT(nearestAxis, o.spacing);
        EXPECT_LE(deepest, -(1 - latticeShare(o.spacing, m.radius)) * m.depth);
        EXPECT_GE(deepest, -m.depth - m.radius * m.radius / (2 * o.radius));
    }
    SealOptions plain = o;
    plain.markDepth = 0;
    const Vessel unmarked = makeCylinderSeal(plain);
    EXPECT_TRUE(unmarked.marks.empty());
    expectOnTheTrueProfile(unmarked, "seal");
}

// ---------------------------------------------------------------------------------------
// Invalid options
// ---------------------------------------------------------------------------------------

TEST(VesselOptions, InvalidValuesThrowInvalidInputError)
{
    const auto refused = [](VesselOptions o) { EXPECT_THROW(makeVessel(o), InvalidInputError); };
    VesselOptions o = vessel(VesselShape::Vase, 2.0);
    EXPECT_NO_THROW(makeVessel(o));
    o.wall = 9;  // more than a third of the neck's radius (22.5)
    refused(o);
    o = vessel(VesselShape::Cylinder, 2.0);
    o.base = 50;
    refused(o);
    o = vessel(VesselShape::Vase, 2.0);
    o.marks = {{0.0, 119}};  // on the lip
    refused(o);
    o.marks = {{0.0, 0.5}};  // on the foot
    refused(o);
    o = vessel(VesselShape::Cone, 2.0);
    o.topRadius = -1;
    refused(o);
    o = vessel(VesselShape::Cylinder, 3.0);  // coarser than half the wall: the lip gets no rings
    refused(o);
    o = vessel(VesselShape::Vase, 0.0);
    refused(o);
    o = vessel(VesselShape::Vase, 1e-4);  // billions of vertices
    refused(o);
    SherdOptions s = sherd(false, 200);
    EXPECT_THROW(makeSherd(s), InvalidInputError);
    s = sherd(false, 75);
    s.fromHeight = 2;  // in the base
    EXPECT_THROW(makeSherd(s), InvalidInputError);
    s = sherd(false, 75);
    s.toHeight = 119;  // in the lip
    EXPECT_THROW(makeSherd(s), InvalidInputError);
    s = sherd(false, 75);
    s.toHeight = 41;  // too little for its breaks
    EXPECT_THROW(makeSherd(s), InvalidInputError);
    s = sherd(false, 2);
    EXPECT_THROW(makeSherd(s), InvalidInputError);
    SealOptions seal;
    seal.markRadius = 20;
    EXPECT_THROW(makeCylinderSeal(seal), InvalidInputError);
}

// ---------------------------------------------------------------------------------------
// Determinism
// ---------------------------------------------------------------------------------------

namespace {

std::vector<TriMesh> allObjects(std::uint64_t seed)
{
    std::vector<TriMesh> out;
    for (const VesselShape shape : kShapes) {
        VesselOptions o = vessel(shape, 1.5);
        o.roughness = 0.02;
        o.seed = seed;
        o.poseSeed = seed + 100;
        out.push_back(makeVessel(o).mesh);
    }
    for (const bool rim : {false, true}) {
        SherdOptions o = sherd(rim, 75, 0.8);
        o.vessel.roughness = 0.02;
        o.vessel.seed = seed;
        out.push_back(makeSherd(o).mesh);
    }
    SealOptions o;
    o.spacing = 0.5;
    o.roughness = 0.01;
    o.seed = seed;
    out.push_back(makeCylinderSeal(o).mesh);
    return out;
}

} // namespace

TEST(VesselDeterminism, SameSeedSameMeshOtherSeedOtherMesh)
{
    const auto a = allObjects(42), b = allObjects(42), c = allObjects(43);
    ASSERT_EQ(a.size(), c.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_TRUE(identical(a[i], b[i])) << "object " << i;
        EXPECT_NE(fingerprint(a[i]), fingerprint(c[i])) << "object " << i;
    }
}

TEST(VesselDeterminism, IndependentOfTheThreadCount)
{
    const auto parallel = allObjects(5);
    std::vector<TriMesh> serial;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial = allObjects(5);
    }
    for (std::size_t i = 0; i < parallel.size(); ++i) EXPECT_TRUE(identical(parallel[i], serial[i])) << "object " << i;
}

// ---------------------------------------------------------------------------------------
// msii-samples vessel, sherd, seal
// ---------------------------------------------------------------------------------------

namespace {

msii::test::RunResult runSamples(const std::string& args)
{
    return msii::test::runProgram(MSII_SAMPLES_EXE, args, ::testing::TempDir());
}

Vec3 jsonVec3(const nlohmann::json& j) { return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()}; }

} // namespace

TEST(VesselCli, WritesTheShapesAndTheirTruth)
{
    const std::string dir = ::testing::TempDir();
    struct Case {
        std::string args;
        Vessel expected;
    };
    VesselOptions v = vessel(VesselShape::Cone, 2.0);
    v.poseSeed = 3;
    v.seed = 9;
    SherdOptions s = sherd(true, 80, 1.0);
    s.theta0 = 0;
    SealOptions seal;
    seal.spacing = 0.5;
    seal.markDepth = 0.3;
    const Case cases[] = {
        {"vessel --profile cone --spacing 2 --seed 9 --pose-seed 3", makeVessel(v)},
        {"sherd --rim --angle 80 --spacing 1", makeSherd(s)},
        {"seal --spacing 0.5 --mark-depth 0.3", makeCylinderSeal(seal)},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args);
        const std::string ply = dir + "cli_object.ply", truth = dir + "cli_object.json";
        const auto r = runSamples(c.args + " -q --double --output '" + ply + "' --truth '" + truth + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        const TriMesh mesh = readMesh(ply).mesh;
        EXPECT_EQ(mesh.numVertices(), c.expected.mesh.numVertices());
        EXPECT_EQ(mesh.numTriangles(), c.expected.mesh.numTriangles());
        EXPECT_EQ(mesh.points.at(17), c.expected.mesh.points.at(17));
        const nlohmann::json j = nlohmann::json::parse(msii::test::readFile(truth));
        EXPECT_EQ(jsonVec3(j.at("axis").at("point")), c.expected.axisPoint);
        EXPECT_EQ(jsonVec3(j.at("axis").at("direction")), c.expected.axisDirection);
        if (c.expected.rimDiameter > 0) {
            EXPECT_EQ(j.at("rim_diameter").get<double>(), c.expected.rimDiameter);
        } else {
            EXPECT_TRUE(j.at("rim_diameter").is_null());
        }
        EXPECT_EQ(j.at("height").get<double>(), c.expected.height);
        ASSERT_EQ(j.at("marks").size(), c.expected.marks.size());
        for (std::size_t k = 0; k < c.expected.marks.size(); ++k) {
            const nlohmann::json& m = j.at("marks").at(k);
            EXPECT_EQ(jsonVec3(m.at("centre")), c.expected.marks[k].centre);
            EXPECT_EQ(jsonVec3(m.at("normal")), c.expected.marks[k].normal);
            EXPECT_EQ(m.at("theta").get<double>(), c.expected.marks[k].theta);
            EXPECT_EQ(m.at("height").get<double>(), c.expected.marks[k].height);
            EXPECT_EQ(m.at("radius").get<double>(), c.expected.marks[k].radius);
            EXPECT_EQ(m.at("depth").get<double>(), c.expected.marks[k].depth);
        }
        EXPECT_EQ(j.at("section").get<Polyline>(), c.expected.section);
        EXPECT_EQ(j.at("outer_profile").get<Polyline>(), c.expected.outerProfile);
        EXPECT_EQ(j.at("inner_profile").get<Polyline>(), c.expected.innerProfile);
    }
}

TEST(VesselCli, RefusesOptionsThatDoNotApplyWithOneLine)
{
    const std::string out = " --output '" + ::testing::TempDir() + "never_written_vessel.ply'";
    const std::string truth = " --truth '" + ::testing::TempDir() + "never_written_vessel.json'";
    const std::pair<std::string, std::string> cases[] = {
        {"seal --wall 3", "--wall"},
        {"seal --profile cone", "--profile"},
        {"vessel --angle 60", "--angle"},
        {"vessel --rim", "--rim"},
        {"sphere --pose-seed 2", "--pose-seed"},
        {"cube", "--truth"},
        {"vessel --top-radius 20", "--profile cone"},
        {"sherd --rim --to 90", "--rim"},
        {"vessel --profile bowl", "bowl"},
        {"vessel --pose-seed -1", "--pose-seed"},
        {"vessel --wall 40", "wall"},
        {"sherd --from 1", "sherd"},
    };
    for (const auto& [args, mentions] : cases) {
        SCOPED_TRACE(args);
        const auto r = runSamples(args + out + truth);
        EXPECT_EQ(r.code, 2);
        EXPECT_EQ(r.err.rfind("msii-samples: error: ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    }
    EXPECT_FALSE(std::ifstream(::testing::TempDir() + "never_written_vessel.ply").good());
    EXPECT_FALSE(std::ifstream(::testing::TempDir() + "never_written_vessel.json").good());
}
