// The level set must hold exact signed distances in its band (negative inside the solid),
// for closed meshes of either orientation and for open sheets.
#include <msii/core/errors.h>
#include <msii/levelset/levelset.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace msii;

namespace {

/// Max |distance − expected| over points on rays through the sphere, within 1 voxel.
double sphereError(const LevelSet& ls, double radius, double sign)
{
    double worst = 0;
    for (int i = 0; i < 2000; ++i) {
        // deterministic directions on a spiral
        const double z = 1.0 - 2.0 * (i + 0.5) / 2000.0, phi = i * 2.399963229728653;
        const Vec3 u(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
        for (double d : {-0.08, -0.03, 0.0, 0.04, 0.08}) {  // within 1 voxel: the trilinear cell stays in the band
            const double expected = sign * d;
            worst = std::max(worst, std::abs(ls.signedDistance(u * (radius + d)) - expected));
        }
    }
    return worst;
}

} // namespace

TEST(LevelSet, SphereDistancesAreExactInTheBand)
{
    samples::SphereOptions o;
    o.radius = 5;
    o.spacing = 0.1;
    const TriMesh mesh = samples::makeSphere(o);
    LevelSetOptions lo;
    lo.voxelSize = 0.08;
    const LevelSet ls = buildLevelSet(mesh, lo);
    // The mesh lies inside the sphere by at most its sagitta, ~edge^2 / (8 R) < 5e-4, plus
    // trilinear interpolation of the distance (h^2 / (8 R) ~ 2e-4).
    EXPECT_LE(sphereError(ls, 5.0, +1.0), 1.5e-3);
    EXPECT_LT(ls.signedDistance(Vec3(0, 0, 4.9)), 0);   // inside
    EXPECT_GT(ls.signedDistance(Vec3(0, 0, 5.1)), 0);   // outside
    EXPECT_LT(ls.signedDistance(Vec3(0, 0, 0)), 0);     // deep inside (flood-filled)
    EXPECT_GT(ls.info().activeVoxels, 1000u);
}

TEST(LevelSet, CavityIsTheComplement)
{
    samples::SphereOptions o;
    o.radius = 5;
    o.spacing = 0.1;
    o.cavity = true;
    const TriMesh mesh = samples::makeSphere(o);
    LevelSetOptions lo;
    lo.voxelSize = 0.08;
    const LevelSet ls = buildLevelSet(mesh, lo);
    EXPECT_LE(sphereError(ls, 5.0, -1.0), 1.5e-3);
    EXPECT_GT(ls.signedDistance(Vec3(0, 0, 0)), 0);     // the hollow is outside the solid
}

TEST(LevelSet, OpenSheetInsideIsBehindTheSurface)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Plane;
    ho.width = 6;
    ho.height = 6;
    ho.spacing = 0.1;
    ho.noise = 0;
    const TriMesh mesh = samples::makeHeightField(ho);
    LevelSetOptions lo;
    lo.voxelSize = 0.05;
    const LevelSet ls = buildLevelSet(mesh, lo);
    for (double z : {-0.12, -0.03, 0.02, 0.11})
        EXPECT_NEAR(ls.signedDistance(Vec3(3.01, 2.97, z)), z, 1e-4) << z;
    EXPECT_LT(ls.signedDistance(Vec3(3, 3, -2.0)), 0);  // far behind: still inside
    EXPECT_GT(ls.signedDistance(Vec3(3, 3, 2.0)), 0);
}

TEST(LevelSet, RejectsBadVoxelSize)
{
    samples::CubeOptions co;
    const TriMesh mesh = samples::makeCube(co);
    LevelSetOptions lo;
    lo.voxelSize = 0;
    EXPECT_THROW(buildLevelSet(mesh, lo), InvalidInputError);
    lo.voxelSize = -1;
    EXPECT_THROW(buildLevelSet(mesh, lo), InvalidInputError);
    lo.voxelSize = 1e-9;
    EXPECT_THROW(buildLevelSet(mesh, lo), InvalidInputError);
}
