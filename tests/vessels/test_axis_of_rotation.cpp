/// @file test_axis_of_rotation.cpp
/// @brief Tests of vessels/axis_of_rotation.h on generated vessels, sherds and seals
/// (samples/vessels.h): the axis under random poses against the true one, the shape class,
/// the rim diameter, the refusals; invariance under rigid motions; the axis frame.

#include <msii/core/errors.h>
#include <msii/samples/generators.h>
#include <msii/samples/vessels.h>
#include <msii/vessels/axis_of_rotation.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace msii;
using namespace msii::samples;

namespace {

constexpr double kPi = 3.14159265358979323846;

double degreesBetween(const Vec3& a, const Vec3& b)
{
    return std::acos(std::min(1.0, std::abs(dot(normalized(a), normalized(b))))) * 180 / kPi;
}

/// The distance of the true axis's point at mid-height from the fitted line.
double offsetAtMidHeight(const Vessel& v, const AxisOfRotation& a)
{
    const Vec3 mid = v.axisPoint + normalized(v.axisDirection) * (0.5 * v.height), d = mid - a.point;
    return norm(d - a.direction * dot(d, a.direction));
}

}  // namespace

TEST(AxisOfRotation, WholeVesselsUnderRandomPoses)
{
    for (const VesselShape shape : {VesselShape::Cylinder, VesselShape::Cone, VesselShape::Vase}) {
        SCOPED_TRACE(vesselShapeName(shape));
        VesselOptions o;
        o.shape = shape;
        o.spacing = 0.8;
        o.roughness = 0.02;
        o.poseSeed = 100 + std::uint64_t(shape);
        const Vessel v = makeVessel(o);
        const AxisOfRotation a = fitAxisOfRotation(v.mesh);
        EXPECT_LT(degreesBetween(a.direction, v.axisDirection), 0.1);
        EXPECT_GT(dot(a.direction, v.axisDirection), 0);  // from the base towards the rim
        EXPECT_LT(offsetAtMidHeight(v, a), 0.001 * a.meanRadius);
        ASSERT_TRUE(a.rimDiameter.has_value());
        EXPECT_NEAR(*a.rimDiameter, v.rimDiameter, 0.002 * v.rimDiameter);
        EXPECT_NEAR(a.height, v.height, 0.1);
        EXPECT_EQ(a.shape, shape == VesselShape::Cylinder ? RevolutionShape::Cylinder
                           : shape == VesselShape::Cone   ? RevolutionShape::Cone
                                                          : RevolutionShape::General);
        // The noise, and the profile's bins of two edges following a curved profile within a
        // tenth of an edge.
        EXPECT_LT(a.residual, o.roughness + 0.1 * o.spacing);
        EXPECT_GT(a.inlierShare, 0.5);
    }
}

TEST(AxisOfRotation, ASealIsACylinderWithoutRim)
{
    SealOptions o;
    o.spacing = 0.25;
    o.roughness = 0.005;
    o.poseSeed = 7;
    const Vessel v = makeCylinderSeal(o);
    const AxisOfRotation a = fitAxisOfRotation(v.mesh);
    EXPECT_LT(degreesBetween(a.direction, v.axisDirection), 0.1);
    EXPECT_LT(offsetAtMidHeight(v, a), 0.001 * o.radius);
    EXPECT_EQ(a.shape, RevolutionShape::Cylinder);
    EXPECT_NEAR(a.cylinderRadius, o.radius, 0.01);
    EXPECT_FALSE(a.rimDiameter.has_value());
}

TEST(AxisOfRotation, SherdsWithAndWithoutTheirRim)
{
    struct Case {
        VesselShape shape;
        double angle, from, to;
        bool rim;
    };
    const Case cases[] = {{VesselShape::Vase, 60, 40, 80, false},
                          {VesselShape::Cylinder, 90, 40, 80, false},
                          {VesselShape::Cone, 60, 30, 70, false},
                          {VesselShape::Cylinder, 60, 80, 0, true}};
    std::uint64_t pose = 200;
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(vesselShapeName(c.shape)) + " " + std::to_string(int(c.angle)));
        SherdOptions o;
        o.vessel.shape = c.shape;
        o.vessel.spacing = 0.5;
        o.vessel.roughness = 0.02;
        o.vessel.poseSeed = ++pose;
        o.angle = c.angle, o.fromHeight = c.from, o.toHeight = c.to, o.rim = c.rim;
        const Vessel v = makeSherd(o);
        const AxisOfRotation a = fitAxisOfRotation(v.mesh);
        EXPECT_LT(degreesBetween(a.direction, v.axisDirection), 1.0);
        EXPECT_LT(offsetAtMidHeight(v, a), 0.01 * a.meanRadius);
        EXPECT_EQ(a.rimDiameter.has_value(), c.rim);
        if (c.rim && a.rimDiameter) {
            EXPECT_NEAR(*a.rimDiameter, v.rimDiameter, 0.002 * v.rimDiameter);
        }
    }
}

TEST(AxisOfRotation, WhatIsNoSurfaceOfRevolutionIsRefused)
{
    HeightFieldOptions plane;
    plane.kind = HeightFieldKind::Plane;
    plane.width = 40, plane.height = 30, plane.spacing = 0.5;
    EXPECT_THROW(fitAxisOfRotation(makeHeightField(plane)), InvalidInputError);
    SphereOptions sphere;
    sphere.radius = 20, sphere.spacing = 0.5;
    try {
        fitAxisOfRotation(makeSphere(sphere));
        ADD_FAILURE() << "a sphere was given an axis";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("sphere"), std::string::npos) << e.what();
    }
    RoundedTabletOptions box;  // a rounded box: no surface of revolution
    box.spacing = 0.5;
    EXPECT_THROW(fitAxisOfRotation(makeRoundedTablet(box).mesh), InvalidInputError);
    EXPECT_THROW(fitAxisOfRotation(TriMesh{}), InvalidInputError);
}

TEST(AxisOfRotation, TheFrameIsRightHanded)
{
    const AxisFrame f(Vec3(1, 2, 3), Vec3(0, 0, 2));
    EXPECT_NEAR(norm(f.direction - Vec3(0, 0, 1)), 0, 1e-15);
    EXPECT_NEAR(norm(cross(f.e1, f.e2) - f.direction), 0, 1e-15);
    EXPECT_NEAR(f.radius(Vec3(4, 6, 10)), 5, 1e-12);
    EXPECT_NEAR(f.height(Vec3(4, 6, 10)), 7, 1e-12);
    EXPECT_NEAR(f.angle(Vec3(1, 2, 0) + f.e2), kPi / 2, 1e-12);
}
