/// @file test_principal_axes.cpp
/// @brief Tests of mesh/principal_axes.h against closed forms: a box's surface
/// (area, centroid, covariance, axes along its sides), an open square's vector
/// area, and the covariance-free moments.

#include <msii/mesh/principal_axes.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace msii;

TEST(PrincipalAxes, ACubesSurfaceHasItsClosedForms)
{
    samples::CubeOptions o;
    o.side = 2.0;
    o.spacing = 0.25;
    const TriMesh cube = samples::makeCube(o);
    const SurfaceMoments m = surfaceMoments(cube);
    EXPECT_NEAR(m.area, 24.0, 1e-9);
    EXPECT_NEAR(norm(m.centroid - Vec3(1, 1, 1)), 0.0, 1e-12);
    EXPECT_NEAR(norm(m.vectorArea), 0.0, 1e-12);  // closed
    // Per axis, over the six faces of side a: ∫ (x − a/2)² dA = 2 a² (a/2)² + 4
    // a² a²/12, divided by the area 6 a²: a²/4 · (1/3 + 2/9) = 5 a²/36... for a =
    // 2: 5/9.
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(m.covariance[i][j], i == j ? 5.0 / 9.0 : 0.0, 1e-12) << i << j;
    const SurfaceMoments plain = surfaceMoments(cube, false);
    EXPECT_EQ(plain.area, m.area);
    EXPECT_EQ(plain.centroid, m.centroid);
    EXPECT_EQ(plain.covariance[0][0], 0.0);
}

TEST(PrincipalAxes, AxesOfABoxAreAlongItsSides)
{
    samples::RoundedTabletOptions o;  // 24 × 32 × 10
    o.spacing = 0.5;
    o.marks = {0, 0, 0, 0, 0, 0};
    o.obverseBulge = o.reverseBulge = 0;
    const PrincipalAxes p = principalAxes(surfaceMoments(samples::makeRoundedTablet(o).mesh).covariance);
    EXPECT_LT(p.variances[0], p.variances[1]);
    EXPECT_LT(p.variances[1], p.variances[2]);
    EXPECT_NEAR(std::abs(p.axes[0].z), 1.0, 1e-9);
    EXPECT_NEAR(std::abs(p.axes[1].x), 1.0, 1e-9);
    EXPECT_NEAR(std::abs(p.axes[2].y), 1.0, 1e-9);
    EXPECT_EQ(canonicalSign(Vec3(-0.1, -0.9, 0.2)), Vec3(0.1, 0.9, -0.2));
    EXPECT_EQ(canonicalSign(Vec3(0.1, 0.9, -0.2)), Vec3(0.1, 0.9, -0.2));
}

TEST(PrincipalAxes, AnOpenSquaresVectorAreaIsItsArea)
{
    samples::HeightFieldOptions h;
    h.kind = samples::HeightFieldKind::Plane;
    h.width = 3;
    h.height = 2;
    h.spacing = 0.1;
    const SurfaceMoments m = surfaceMoments(samples::makeHeightField(h));
    EXPECT_NEAR(m.area, 6.0, 1e-9);
    EXPECT_NEAR(m.vectorArea.z, 6.0, 1e-9);
    EXPECT_NEAR(norm(m.centroid - Vec3(1.5, 1.0, 0)), 0.0, 1e-9);
    EXPECT_NEAR(m.covariance[0][0], 9.0 / 12.0, 1e-9);
    EXPECT_NEAR(m.covariance[1][1], 4.0 / 12.0, 1e-9);
    EXPECT_NEAR(m.covariance[2][2], 0.0, 1e-12);
}
