/// @file test_unroll.cpp
/// @brief Tests of vessels/unroll.h: a cylinder's development keeps lengths on it (its
/// points at x = R θ, y = h, z = 0), a cone's keeps every distance measured on the cone; the
/// seam's copies, the triangles at the axis left out, the impression mirrored; the vertex
/// order kept.

#include <msii/core/errors.h>
#include <msii/samples/vessels.h>
#include <msii/vessels/unroll.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace msii;
using namespace msii::samples;

namespace {

constexpr double kPi = 3.14159265358979323846;

AxisOfRotation axisAlongZ(double cylinderRadius, double coneRadius0 = 0, double coneSlope = 0)
{
    AxisOfRotation a;
    a.point = Vec3(0, 0, 0), a.direction = Vec3(0, 0, 1);
    a.cylinderRadius = a.meanRadius = cylinderRadius, a.coneRadius0 = coneRadius0, a.coneSlope = coneSlope;
    a.height = 35;
    return a;
}

}  // namespace

TEST(Unroll, ACylinderLiesFlatAtItsRadius)
{
    SealOptions o;
    o.spacing = 0.3;
    o.markDepth = 0;
    const Vessel seal = makeCylinderSeal(o);
    const Unrolled u = unrollSurface(seal.mesh, axisAlongZ(o.radius));
    ASSERT_GE(u.mesh.numVertices(), seal.mesh.numVertices());
    EXPECT_EQ(u.mesh.numVertices(), seal.mesh.numVertices() + u.copyOf.size());
    EXPECT_GT(u.copyOf.size(), 0u);
    EXPECT_GT(u.trianglesLeftOut, 0u);  // the ends' triangles at the axis
    const AxisFrame f(Vec3(0, 0, 0), Vec3(0, 0, 1));
    for (std::size_t i = 0; i < seal.mesh.numVertices(); ++i) {
        const Vec3& p = seal.mesh.points[i];
        if (std::abs(f.radius(p) - o.radius) > 1e-9) continue;  // the side
        double theta = f.angle(p);
        if (theta < 0) theta += 2 * kPi;
        ASSERT_NEAR(u.mesh.points[i].x, o.radius * theta, 1e-9);
        ASSERT_NEAR(u.mesh.points[i].y, p.z, 1e-12);
        ASSERT_NEAR(u.mesh.points[i].z, 0, 1e-9);
    }
    // Lengths kept on the cylinder itself: only the chords' sagitta.
    EXPECT_LT(u.maxDistortion, 0.01);
    // The impression is the mirror image with the relief inverted.
    UnrollOptions mirrored;
    mirrored.impression = true;
    const Unrolled m = unrollSurface(seal.mesh, axisAlongZ(o.radius), mirrored);
    for (std::size_t i = 0; i < 100; ++i) {
        EXPECT_EQ(m.mesh.points[i].x, -u.mesh.points[i].x);
        EXPECT_EQ(m.mesh.points[i].z, -u.mesh.points[i].z);
    }
}

TEST(Unroll, AConesDevelopmentKeepsDistancesOnIt)
{
    // Points on the cone r = 40 − 0.2 z: the distance between two of them along the cone (the
    // geodesic, a straight line in the development) equals their distance in the rollout.
    VesselOptions o;
    o.shape = VesselShape::Cone;
    o.spacing = 1.0;
    const Vessel v = makeVessel(o);
    const AxisOfRotation axis = axisAlongZ(45, 50, -0.15);
    UnrollOptions cone;
    cone.shape = UnrollShape::Cone;
    const Unrolled u = unrollSurface(v.mesh, axis, cone);
    EXPECT_NEAR(u.apexHeight, 50 / 0.15, 1e-9);
    EXPECT_NEAR(std::tan(u.halfAngle), 0.15, 1e-12);
    TriMesh points;
    const auto onCone = [](double z, double theta) {
        const double r = 50 - 0.15 * z;
        return Vec3(r * std::cos(theta), r * std::sin(theta), z);
    };
    // Four far-apart points (every vertex is placed, in a triangle or not) and one small
    // triangle, which a rollout needs.
    points.points = {onCone(20, 0.5), onCone(80, 1.2), onCone(50, 2.0),
                     onCone(30, 0.9), onCone(21, 0.5), onCone(20, 0.52)};
    points.triangles = {{0, 4, 5}};
    const Unrolled d = unrollSurface(points, axis, cone);
    const double sinA = std::sin(u.halfAngle), apex = 50 / 0.15;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
            const double zi = points.points[i].z, zj = points.points[j].z;
            const double si = (apex - zi) / std::cos(u.halfAngle), sj = (apex - zj) / std::cos(u.halfAngle);
            const double ti = std::atan2(points.points[i].y, points.points[i].x),
                         tj = std::atan2(points.points[j].y, points.points[j].x);
            const double geodesic = std::sqrt(si * si + sj * sj - 2 * si * sj * std::cos((tj - ti) * sinA));
            EXPECT_NEAR(norm(d.mesh.points[i] - d.mesh.points[j]), geodesic, 1e-9 * geodesic);
            EXPECT_NEAR(d.mesh.points[i].z, 0, 1e-9);
        }
    EXPECT_THROW(unrollSurface(points, axisAlongZ(45), cone), InvalidInputError);  // no slope
    points.triangles = {{0, 1, 2}};  // only a triangle spanning 86° about the axis: nothing to unroll
    EXPECT_THROW(unrollSurface(points, axis, cone), InvalidInputError);
}

TEST(Unroll, TheSeamRunsThroughAPiecesOpenSide)
{
    // A sherd of 80° straddling the axis frame's angle 0: the default seam goes round to the
    // open side and cuts nothing; a seam through the piece cuts it.
    const AxisOfRotation axis = axisAlongZ(50);
    const AxisFrame f(axis.point, axis.direction);
    SherdOptions o;
    o.vessel.shape = VesselShape::Cylinder;
    o.vessel.spacing = 0.6;
    o.angle = 80, o.fromHeight = 40, o.toHeight = 80;
    o.theta0 = std::atan2(f.e1.y, f.e1.x) - 40 * kPi / 180;
    const Vessel sherd = makeSherd(o);
    const Unrolled u = unrollSurface(sherd.mesh, axis);
    EXPECT_TRUE(u.copyOf.empty());
    EXPECT_LT(std::cos(u.seamAngle), -0.5);  // across the axis from the piece
    UnrollOptions through;
    through.cutThrough = f.point + f.e1 * 50 + f.direction * 60;
    EXPECT_FALSE(unrollSurface(sherd.mesh, axis, through).copyOf.empty());
}
