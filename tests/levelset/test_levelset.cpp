// The level set must hold exact signed distances in its band (negative inside the solid),
// for closed meshes of either orientation and for open sheets.
#include <msii/core/errors.h>
#include <msii/levelset/levelset.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

#include "../support/rotation.h"

using namespace msii;
using msii::test::Rotation;

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

/// Reference distance from p to triangle (a, b, c): to the plane if p projects inside the
/// triangle, else to the nearest of the three edges (a formulation independent of the
/// engine's Voronoi-region one).
double triangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 n = normalized(cross(b - a, c - a));
    const Vec3 q = p - n * dot(p - a, n);
    const bool inside = dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 &&
                        dot(cross(a - c, q - c), n) >= 0;
    if (inside) return std::abs(dot(p - a, n));
    const auto segment = [&](const Vec3& u, const Vec3& v) {
        const double t = std::clamp(dot(p - u, v - u) / dot(v - u, v - u), 0.0, 1.0);
        return norm(p - (u + (v - u) * t));
    };
    return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

/// Reference distance from p to the mesh: the least over all its triangles.
double meshDistance(const TriMesh& mesh, const Vec3& p)
{
    double d = 1e9;
    for (const auto& t : mesh.triangles)
        d = std::min(d, triangleDistance(p, mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]]));
    return d;
}

} // namespace

TEST(LevelSet, BandIsExactAndSidesAreRightAroundSharpFeatures)
{
    // A rotated cube (side 2, centred at the origin): edges and corners at every angle to the grid. Voxel centres lie at
    // multiples of h in world coordinates (the index space is shifted by whole blocks).
    samples::CubeOptions co;
    co.side = 2;
    co.spacing = 0.3;
    TriMesh mesh = samples::makeCube(co);
    const Rotation rotate(normalized(Vec3(2, -1, 3)), 0.6);
    const Rotation unrotate = rotate.inverse();
    for (auto& p : mesh.points) p = rotate(p - Vec3(1, 1, 1));  // centred, then turned
    LevelSetOptions lo;
    lo.voxelSize = 0.1;
    lo.halfWidth = 2;
    const LevelSet ls = buildLevelSet(mesh, lo);
    const double h = lo.voxelSize, band = lo.halfWidth * h;
    std::size_t inBand = 0;
    for (int i = -25; i <= 25; ++i)
        for (int j = -25; j <= 25; ++j)
            for (int k = -25; k <= 25; ++k) {
                const Vec3 p(i * h, j * h, k * h);
                const double d = meshDistance(mesh, p);
                const Vec3 q = unrotate(p);  // in the cube's own frame
                const bool inside = std::max({std::abs(q.x), std::abs(q.y), std::abs(q.z)}) < 1.0;
                const double value = ls.signedDistance(p);
                if (d < 1e-9) continue;  // on the surface: either sign
                ASSERT_EQ(value < 0, inside) << "voxel " << i << " " << j << " " << k;
                if (d < band - 1e-9) {
                    ++inBand;
                    ASSERT_NEAR(std::abs(value), d, 1e-6) << "voxel " << i << " " << j << " " << k;
                }
            }
    EXPECT_GT(inBand, 5000u);
}

TEST(LevelSet, BandIsExactAtAVertexOfManyTriangles)
{
    // A closed cone whose apex joins 40 triangles, and whose base centre another 40: voxels
    // closest to either are equally close to all of them, more than the band's rasterizer
    // keeps as candidates, so those voxels take every triangle in reach instead.
    const int k = 40;
    TriMesh mesh;
    mesh.points.push_back(Vec3(0, 0, 1));  // apex
    mesh.points.push_back(Vec3(0, 0, 0));  // base centre
    for (int i = 0; i < k; ++i) {
        const double a = 2 * M_PI * i / k + 0.1;
        mesh.points.push_back(Vec3(std::cos(a), std::sin(a), 0.0));
    }
    for (int i = 0; i < k; ++i) {
        const auto u = std::uint32_t(2 + i), v = std::uint32_t(2 + (i + 1) % k);
        mesh.triangles.push_back({0, u, v});
        mesh.triangles.push_back({1, v, u});
    }
    LevelSetOptions lo;
    lo.voxelSize = 0.05;
    lo.halfWidth = 2;
    const LevelSet ls = buildLevelSet(mesh, lo);
    const double h = lo.voxelSize, band = lo.halfWidth * h;
    std::size_t inBand = 0;
    for (int i = -6; i <= 6; ++i)
        for (int j = -6; j <= 6; ++j)
            for (int l = -6; l <= 26; ++l) {
                const Vec3 p(i * h, j * h, l * h);
                const double d = meshDistance(mesh, p);
                if (d < 1e-9 || d >= band - 1e-9) continue;
                bool inside = true;  // the cone is convex: inside every face's plane
                for (const auto& t : mesh.triangles) {
                    const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
                    inside = inside && dot(p - a, cross(b - a, c - a)) < 0;
                }
                ++inBand;
                const double value = ls.signedDistance(p);
                ASSERT_EQ(value < 0, inside) << "voxel " << i << " " << j << " " << l;
                ASSERT_NEAR(std::abs(value), d, 1e-6) << "voxel " << i << " " << j << " " << l;
            }
    EXPECT_GT(inBand, 500u);
}

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

TEST(LevelSet, SidesNextToAnOpenBorderFollowTheSurface)
{
    // A tilted open square: points above and below it near its border, off the band, must
    // be outside and inside whatever the grid does beyond the border.
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Plane;
    ho.width = 4;
    ho.height = 4;
    ho.spacing = 0.1;
    ho.noise = 0;
    TriMesh mesh = samples::makeHeightField(ho);
    const Rotation rotate(normalized(Vec3(1, 2, 0.5)), 0.5);
    for (auto& p : mesh.points) p = rotate(p);
    LevelSetOptions lo;
    lo.voxelSize = 0.05;
    lo.halfWidth = 2;
    const LevelSet ls = buildLevelSet(mesh, lo);
    std::size_t checked = 0;
    for (int i = 0; i <= 80; ++i) {
        const double t = 4.0 * i / 80.0;
        // Along all four sides, 0.02 to 0.3 inside the border, 0.12 to 0.4 off the surface.
        for (const auto& [x, y] : {std::pair{t, 0.0}, std::pair{t, 4.0}, std::pair{0.0, t},
                                   std::pair{4.0, t}}) {
            for (double in : {0.02, 0.1, 0.3})
                for (double off : {0.12, 0.2, 0.4}) {
                    const double px = std::clamp(x, in, 4.0 - in), py = std::clamp(y, in, 4.0 - in);
                    EXPECT_GT(ls.signedDistance(rotate(Vec3(px, py, off))), 0) << px << " " << py;
                    EXPECT_LT(ls.signedDistance(rotate(Vec3(px, py, -off))), 0) << px << " " << py;
                    ++checked;
                }
        }
    }
    EXPECT_GT(checked, 2000u);
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
