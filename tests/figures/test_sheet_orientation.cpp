/// @file test_sheet_orientation.cpp
/// @brief Tests of figures/sheet_orientation.h: the default rule on a whole
/// tablet (the flatter obverse, the longest axis up) and on an open scan (the
/// side it faces); the same result under random rigid motions; given directions
/// taken exactly; bad directions refused.

#include <msii/core/errors.h>
#include <msii/figures/sheet_orientation.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "../support/rotation.h"

using namespace msii;
using namespace msii::samples;
using msii::test::Rotation;

namespace {

RoundedTablet tablet()
{
    RoundedTabletOptions o;
    o.spacing = 0.4;
    o.roughness = 0.005;
    return makeRoundedTablet(o);
}

/// A seeded rotation (axis and angle from a simple hash, not from std::
/// distributions).
Rotation randomRotation(std::uint64_t seed)
{
    const auto unit = [&](int k) {
        std::uint64_t z = seed * 0x9e3779b97f4a7c15ULL + std::uint64_t(k) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 31)) * 0x94d049bb133111ebULL;
        return double(z >> 11) * 0x1.0p-53;
    };
    const Vec3 axis = normalized(Vec3(unit(0) - 0.5, unit(1) - 0.5, unit(2) - 0.5));
    return Rotation(axis, 0.3 + 5.5 * unit(3));
}

TriMesh moved(const TriMesh& mesh, const Rotation& r, const Vec3& t)
{
    TriMesh out = mesh;
    for (Vec3& p : out.points) p = r(p) + t;
    return out;
}

void expectSameDirection(const Vec3& a, const Vec3& b, double tolerance)
{
    EXPECT_NEAR(norm(a - b), 0.0, tolerance)
        << "(" << a.x << ", " << a.y << ", " << a.z << ") against (" << b.x << ", " << b.y << ", " << b.z << ")";
}

}  // namespace

TEST(SheetOrientation, ATabletShowsItsFlatterSideWithTheLongestAxisUp)
{
    const RoundedTablet t = tablet();
    const SheetOrientation o = orientSheet(t.mesh);
    expectSameDirection(o.front, {0, 0, 1},
                        1e-3);  // the obverse rises 0.1 mm, the reverse 1.5 mm
    EXPECT_NEAR(std::abs(o.up.y), 1.0, 1e-6);  // 32 mm along y, 24 along x
    EXPECT_EQ(o.frontRule, "the flatter side");
    EXPECT_EQ(o.upRule, "third moment");
    EXPECT_NEAR(dot(o.front, o.up), 0.0, 1e-12);
    EXPECT_NEAR(norm(o.right()), 1.0, 1e-12);
}

TEST(SheetOrientation, PoseDoesNotMatter)
{
    const RoundedTablet t = tablet();
    const SheetOrientation still = orientSheet(t.mesh);
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
        SCOPED_TRACE(seed);
        const Rotation r = randomRotation(seed);
        const Vec3 shift(1000.0 * double(seed), -350.0,
                         5.5e5);  // also far from the origin
        const SheetOrientation posed = orientSheet(moved(t.mesh, r, shift));
        expectSameDirection(posed.front, r(still.front), 1e-6);
        expectSameDirection(posed.up, r(still.up), 1e-6);
        EXPECT_EQ(posed.frontRule, still.frontRule);
        EXPECT_EQ(posed.upRule, still.upRule);
    }
}

TEST(SheetOrientation, AnOpenScanFacesItsViewer)
{
    HeightFieldOptions h;
    h.width = 12;
    h.height = 9;
    h.spacing = 0.1;
    TriMesh scan = makeHeightField(h);  // faces +z
    SheetOrientation o = orientSheet(scan);
    expectSameDirection(o.front, {0, 0, 1}, 1e-2);
    EXPECT_EQ(o.frontRule, "the scan's side");
    EXPECT_NEAR(std::abs(o.up.x), 1.0, 1e-3);  // 12 mm along x
    for (Triangle& tri : scan.triangles) std::swap(tri[1], tri[2]);  // the same scan, facing -z
    o = orientSheet(scan);
    expectSameDirection(o.front, {0, 0, -1}, 1e-2);
}

TEST(SheetOrientation, GivenDirectionsAreTakenAsGiven)
{
    const RoundedTablet t = tablet();
    SheetOrientationOptions given;
    given.front = Vec3(0, 3, 0);
    given.up = Vec3(1, 2, 0);  // its part along front is dropped
    SheetOrientation o = orientSheet(t.mesh, given);
    EXPECT_EQ(o.front, Vec3(0, 1, 0));
    expectSameDirection(o.up, {1, 0, 0}, 1e-15);
    EXPECT_EQ(o.frontRule, "given");
    EXPECT_EQ(o.upRule, "given");

    SheetOrientationOptions frontOnly;  // up: the longest axis across it, y
    frontOnly.front = Vec3(1, 0, 0);
    o = orientSheet(t.mesh, frontOnly);
    EXPECT_NEAR(std::abs(o.up.y), 1.0, 1e-6);

    SheetOrientationOptions upOnly;  // front: the least extent across it, z, the flatter side
    upOnly.up = Vec3(0, -1, 0);
    o = orientSheet(t.mesh, upOnly);
    expectSameDirection(o.up, {0, -1, 0}, 0);
    expectSameDirection(o.front, {0, 0, 1}, 1e-3);
}

TEST(SheetOrientation, BadDirectionsAreRefused)
{
    const RoundedTablet t = tablet();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const Vec3& bad : {Vec3(0, 0, 0), Vec3(nan, 0, 1)}) {
        SheetOrientationOptions o;
        o.front = bad;
        EXPECT_THROW(orientSheet(t.mesh, o), InvalidInputError);
        o = {};
        o.up = bad;
        EXPECT_THROW(orientSheet(t.mesh, o), InvalidInputError);
    }
    SheetOrientationOptions parallel;
    parallel.front = Vec3(0, 0, 1);
    parallel.up = Vec3(0, 0, -2);
    EXPECT_THROW(orientSheet(t.mesh, parallel), InvalidInputError);
    EXPECT_THROW(orientSheet(TriMesh{}), InvalidInputError);
}
