/// @file test_generators.cpp
/// @brief Tests of msii/samples/generators.h: closed forms (volumes, the sphere), topology
/// (watertight / bordered manifolds, orientation), the spacing contract, determinism
/// (seed, thread count, golden fingerprints) and the msii-samples command line.
/// The mesh properties are checked by code local to this file, so these tests do not rely
/// on the engine's own mesh checks.

#include <msii/core/errors.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <ios>
#include <iterator>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../support/files.h"
#include "../support/mesh_checks.h"
#include "../support/run_program.h"

using namespace msii;
using namespace msii::samples;
using msii::test::analyzeEdges;
using msii::test::EdgeReport;
using msii::test::expectWatertight;
using msii::test::fingerprint;
using msii::test::identical;
using msii::test::minTriangleArea;
using msii::test::readFile;
using msii::test::RunResult;
using msii::test::runProgram;
using msii::test::signedVolume;
using msii::test::triangleNormal;

namespace {

constexpr double kPi = 3.14159265358979323846;

HeightFieldOptions heightField(HeightFieldKind kind, bool closed = false)
{
    HeightFieldOptions o;
    o.kind = kind;
    o.closed = closed;
    return o;
}

const HeightFieldKind kAllKinds[] = {HeightFieldKind::Plane, HeightFieldKind::Terrain, HeightFieldKind::Tablet};

const char* kindName(HeightFieldKind k)
{
    return k == HeightFieldKind::Plane ? "plane" : k == HeightFieldKind::Terrain ? "terrain" : "tablet";
}

} // namespace

// ---------------------------------------------------------------------------------------
// Sphere
// ---------------------------------------------------------------------------------------

TEST(SampleSphere, VertexCountAndPointsExactlyOnTheSphere)
{
    SphereOptions o;
    o.radius = 10.0;
    o.spacing = 0.15;
    o.center = {1.5, -2.25, 3.0};
    const TriMesh mesh = makeSphere(o);
    // k = round(sqrt(0.4 pi) * 10 / 0.15) = 75 -> 10 k^2 + 2 vertices, 20 k^2 triangles.
    EXPECT_GE(mesh.numVertices(), 40000u);
    EXPECT_EQ(mesh.numVertices(), 10u * 75u * 75u + 2u);
    EXPECT_EQ(mesh.numTriangles(), 20u * 75u * 75u);
    double worst = 0;
    for (const Vec3& p : mesh.points) worst = std::max(worst, std::abs(norm(p - o.center) - o.radius));
    EXPECT_LE(worst, 1e-12 * o.radius);
}

TEST(SampleSphere, WatertightOutwardAndVolumeBelowTheBall)
{
    for (const double spacing : {0.5, 0.2}) {
        SphereOptions o;
        o.radius = 10.0;
        o.spacing = spacing;
        const TriMesh mesh = makeSphere(o);
        expectWatertight(mesh, "sphere");
        // Inscribed polyhedron: strictly inside the ball, missing ~(edge / R)^2 / 4 of it.
        const double ball = 4.0 / 3.0 * kPi * std::pow(o.radius, 3);
        const double volume = signedVolume(mesh);
        EXPECT_LT(volume, ball);
        EXPECT_GT(volume, ball * (1.0 - std::pow(spacing / o.radius, 2)));
        // Every triangle faces away from the centre.
        for (const Triangle& t : mesh.triangles)
            ASSERT_GT(dot(triangleNormal(mesh, t), mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]), 0.0);
        EXPECT_GT(minTriangleArea(mesh), 0.05 * spacing * spacing);
    }
}

TEST(SampleSphere, CavityHasTheSamePointsReversed)
{
    SphereOptions o;
    o.radius = 5.0;
    o.spacing = 0.25;
    const TriMesh sphere = makeSphere(o);
    o.cavity = true;
    const TriMesh cavity = makeSphere(o);
    expectWatertight(cavity, "cavity");
    ASSERT_EQ(sphere.numTriangles(), cavity.numTriangles());
    EXPECT_EQ(0, std::memcmp(sphere.points.data(), cavity.points.data(), sphere.points.size() * sizeof(Vec3)));
    EXPECT_LT(signedVolume(cavity), 0.0);
    EXPECT_EQ(signedVolume(cavity), -signedVolume(sphere));
}

TEST(SampleSphere, MeanEdgeLengthMatchesSpacing)
{
    for (const auto& [radius, spacing] : {std::pair{10.0, 0.2}, std::pair{2.0, 0.05}, std::pair{1.0, 0.1}}) {
        SphereOptions o;
        o.radius = radius;
        o.spacing = spacing;
        const double mean = analyzeEdges(makeSphere(o)).meanLength;
        EXPECT_NEAR(mean / spacing, 1.0, 0.15) << "radius " << radius << " spacing " << spacing;
    }
}

TEST(SampleSphere, CoarseSpacingStillGivesAValidMesh)
{
    SphereOptions o;
    o.radius = 1.0;
    o.spacing = 100.0;  // k = 1: the icosahedron itself
    const TriMesh mesh = makeSphere(o);
    EXPECT_EQ(mesh.numVertices(), 12u);
    expectWatertight(mesh, "icosahedron");
    EXPECT_GT(signedVolume(mesh), 0.0);
}

// ---------------------------------------------------------------------------------------
// Cube
// ---------------------------------------------------------------------------------------

TEST(SampleCube, WatertightWithExactVolume)
{
    for (const auto& [side, spacing] : {std::pair{10.0, 0.25}, std::pair{3.0, 0.1}, std::pair{1.0, 2.0}}) {
        CubeOptions o;
        o.side = side;
        o.spacing = spacing;
        const TriMesh mesh = makeCube(o);
        expectWatertight(mesh, "cube");
        const int n = std::max(1, int(std::round(side / spacing)));
        EXPECT_EQ(mesh.numVertices(), std::size_t(6 * n * n + 2));
        EXPECT_NEAR(signedVolume(mesh), side * side * side, 1e-9 * side * side * side);
        EXPECT_GT(minTriangleArea(mesh), 0.05 * std::pow(side / n, 2));
    }
}

TEST(SampleCube, CornersEdgesAndFacesExact)
{
    CubeOptions o;
    o.side = 4.0;
    o.spacing = 0.2;
    const TriMesh mesh = makeCube(o);
    int corners = 0;
    std::size_t onEdges = 0;
    bool jitteredOffLattice = false;
    for (const Vec3& p : mesh.points) {
        int onPlanes = 0;
        for (int a = 0; a < 3; ++a) {
            ASSERT_GE(p[a], 0.0);
            ASSERT_LE(p[a], o.side);
            onPlanes += (p[a] == 0.0 || p[a] == o.side);
            const double cells = p[a] / (o.side / 20);
            jitteredOffLattice = jitteredOffLattice || std::abs(cells - std::round(cells)) > 0.01;
        }
        ASSERT_GE(onPlanes, 1) << "vertex off the surface";
        corners += onPlanes == 3;
        onEdges += onPlanes == 2;
    }
    EXPECT_EQ(corners, 8);
    EXPECT_EQ(onEdges, 12u * 19u);
    EXPECT_TRUE(jitteredOffLattice);
    // Each triangle lies in one face and points out of the cube.
    const Vec3 centre{2.0, 2.0, 2.0};
    for (const Triangle& t : mesh.triangles) {
        const Vec3 mid = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) / 3.0;
        ASSERT_GT(dot(triangleNormal(mesh, t), mid - centre), 0.0);
    }
    EXPECT_NEAR(analyzeEdges(mesh).meanLength / o.spacing, 1.0, 0.15);
}

// ---------------------------------------------------------------------------------------
// Rounded tablet
// ---------------------------------------------------------------------------------------

TEST(SampleRoundedTablet, ClosedOutwardWithTheMarksWhereItSaysAndABulgingReverse)
{
    RoundedTabletOptions o;
    o.spacing = 0.3;
    o.roughness = 0.005;
    const RoundedTablet tablet = makeRoundedTablet(o);
    expectWatertight(tablet.mesh, "rounded tablet");
    // Outward, and the volume of the rounded box (the box less its edges' and corners'
    // rounding) within the bulges' and the marks' share: a face rising by b (1 − x²/a²)(1 − y²/b²)
    // adds less than 4/9 b w h, a mark takes less than π r² depth.
    const double r = o.rounding, w = o.width, h = o.height, t = o.thickness;
    const double box = w * h * t - (4 - kPi) * r * r * (w + h + t - 6 * r) - (8 - 4.0 / 3.0 * kPi) * r * r * r;
    const double bulges = (o.obverseBulge + o.reverseBulge) * w * h * 4.0 / 9.0;
    const double marks = double(tablet.marks.size()) * kPi * o.markRadius * o.markRadius * o.markDepth;
    EXPECT_GT(signedVolume(tablet.mesh), box - marks);
    EXPECT_LT(signedVolume(tablet.mesh), box + bulges);
    EXPECT_GT(signedVolume(tablet.mesh), box + 0.25 * bulges);  // the bulges are there
    // A different number of marks on each side, as asked.
    std::array<int, 6> count{};
    for (const TabletMark& m : tablet.marks) ++count[std::size_t(m.side)];
    EXPECT_EQ(count, o.marks);
    // Each mark is pressed in: the surface's deepest point within its radius lies its depth
    // below its centre, within the noise and the lattice (the vertex nearest the axis, less
    // than a spacing away, lies at most (1 − (s/r)²)² of the depth down).
    for (const TabletMark& m : tablet.marks) {
        SCOPED_TRACE(tabletSideName(m.side));
        double deepest = 0, nearestAxis = 1e9;
        for (const Vec3& p : tablet.mesh.points) {
            const Vec3 d = p - m.centre;
            const double along = dot(d, m.normal), across = norm(d - m.normal * along);
            if (across < m.radius && std::abs(along) < 2 * m.depth) deepest = std::min(deepest, along);
            if (across < nearestAxis && std::abs(along) < 2 * m.depth) nearestAxis = across;
        }
        EXPECT_LT(nearestAxis, o.spacing);
        const double lattice = 1 - std::pow(1 - std::pow(o.spacing / m.radius, 2), 2);
        EXPECT_LE(deepest, -(1 - lattice) * m.depth + o.roughness);
        EXPECT_GE(deepest, -m.depth - o.roughness);
    }
    // The reverse bulges more than the obverse rises: its centre lies further from the middle.
    double top = 0, bottom = 0;
    for (const Vec3& p : tablet.mesh.points)
        if (std::abs(p.x) < 0.5 && std::abs(p.y) < 0.5) top = std::max(top, p.z), bottom = std::min(bottom, p.z);
    EXPECT_NEAR(top, 0.5 * t + o.obverseBulge, 0.02 + o.roughness);
    EXPECT_NEAR(bottom, -0.5 * t - o.reverseBulge, 0.02 + o.roughness);
}

TEST(SampleRoundedTablet, MarksThatDoNotFitAreRefused)
{
    RoundedTabletOptions o;
    o.marks = {6, 5, 1, 2, 40, 3};
    EXPECT_THROW(makeRoundedTablet(o), InvalidInputError);
    o = {};
    o.rounding = 5.0;
    EXPECT_THROW(makeRoundedTablet(o), InvalidInputError);
    o = {};
    o.marks[0] = -1;
    EXPECT_THROW(makeRoundedTablet(o), InvalidInputError);
}

// ---------------------------------------------------------------------------------------
// Height fields
// ---------------------------------------------------------------------------------------

TEST(SampleHeightField, OpenPatchIsABorderedManifoldWithRectangularOutline)
{
    for (const HeightFieldKind kind : kAllKinds) {
        SCOPED_TRACE(kindName(kind));
        const HeightFieldOptions o = heightField(kind);
        const TriMesh mesh = makeHeightField(o);
        const int nx = int(std::round(o.width / o.spacing)), ny = int(std::round(o.height / o.spacing));
        EXPECT_EQ(mesh.numVertices(), std::size_t(nx + 1) * std::size_t(ny + 1));
        const EdgeReport r = analyzeEdges(mesh);
        EXPECT_EQ(r.numDegenerate, 0u);
        EXPECT_EQ(r.numNonManifold, 0u);
        EXPECT_EQ(r.numInconsistent, 0u);
        // The border: one loop of 2 (nx + ny) edges, each on a side of the rectangle,
        // covering the outline exactly, and running counter-clockwise seen from above.
        ASSERT_EQ(r.border.size(), std::size_t(2 * (nx + ny)));
        std::vector<int> degree(mesh.numVertices(), 0);
        double length = 0, shoelace = 0;
        for (const auto& e : r.border) {
            const Vec3 &a = mesh.points[e[0]], &b = mesh.points[e[1]];
            const bool onSide = (a.x == 0 && b.x == 0) || (a.x == o.width && b.x == o.width) ||
                                (a.y == 0 && b.y == 0) || (a.y == o.height && b.y == o.height);
            ASSERT_TRUE(onSide) << "border edge off the rectangle: (" << a.x << "," << a.y << ")-(" << b.x << "," << b.y << ")";
            ++degree[e[0]];
            ++degree[e[1]];
            length += std::hypot(b.x - a.x, b.y - a.y);
            shoelace += a.x * b.y - b.x * a.y;
        }
        for (const auto& e : r.border) {
            ASSERT_EQ(degree[e[0]], 2);
            ASSERT_EQ(degree[e[1]], 2);
        }
        EXPECT_NEAR(length, 2 * (o.width + o.height), 1e-9 * (o.width + o.height));
        EXPECT_NEAR(0.5 * shoelace, o.width * o.height, 1e-9 * o.width * o.height);
        // Normals up: the solid is below.
        for (const Triangle& t : mesh.triangles) ASSERT_GT(triangleNormal(mesh, t).z, 0.0);
        EXPECT_GT(minTriangleArea(mesh), 0.05 * o.spacing * o.spacing);
        EXPECT_NEAR(r.meanLength / o.spacing, 1.0, 0.15);
    }
}

TEST(SampleHeightField, TopVerticesSampleHeightFieldValueExactly)
{
    for (const HeightFieldKind kind : kAllKinds) {
        SCOPED_TRACE(kindName(kind));
        HeightFieldOptions o = heightField(kind);
        o.width = 8.0;
        o.height = 6.0;
        o.seed = 7;
        const TriMesh mesh = makeHeightField(o);
        std::size_t mismatches = 0;
        for (const Vec3& p : mesh.points) mismatches += p.z != heightFieldValue(o, p.x, p.y);
        EXPECT_EQ(mismatches, 0u);
    }
    EXPECT_EQ(heightFieldValue(heightField(HeightFieldKind::Plane), 3.0, -4.0), 0.0);
}

TEST(SampleHeightField, SlabIsWatertightAndKeepsTheOpenPatchOnTop)
{
    for (const HeightFieldKind kind : kAllKinds) {
        SCOPED_TRACE(kindName(kind));
        HeightFieldOptions o = heightField(kind);
        o.width = 9.0;
        o.height = 7.0;
        o.spacing = 0.15;
        o.thickness = 2.5;
        const TriMesh open = makeHeightField(o);
        o.closed = true;
        const TriMesh slab = makeHeightField(o);
        expectWatertight(slab, "slab");
        ASSERT_GT(slab.numVertices(), open.numVertices());
        EXPECT_EQ(0, std::memcmp(slab.points.data(), open.points.data(), open.points.size() * sizeof(Vec3)));
        EXPECT_EQ(0, std::memcmp(slab.triangles.data(), open.triangles.data(), open.triangles.size() * sizeof(Triangle)));
        // The slab encloses exactly the prisms under the top triangles, down to -thickness.
        double prisms = 0;
        for (const Triangle& t : open.triangles) {
            const Vec3 &a = open.points[t[0]], &b = open.points[t[1]], &c = open.points[t[2]];
            const double area = 0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
            prisms += area * ((a.z + b.z + c.z) / 3.0 + o.thickness);
        }
        const double volume = signedVolume(slab);
        EXPECT_GT(volume, 0.0);
        EXPECT_NEAR(volume, prisms, 1e-9 * prisms);
        if (kind == HeightFieldKind::Plane) {
            EXPECT_NEAR(volume, o.width * o.height * o.thickness, 1e-9 * volume);
        }
        double zmin = std::numeric_limits<double>::infinity();
        for (const Vec3& p : slab.points) zmin = std::min(zmin, p.z);
        EXPECT_EQ(zmin, -o.thickness);
        EXPECT_GT(minTriangleArea(slab), 0.02 * o.spacing * o.spacing);
        EXPECT_NEAR(analyzeEdges(slab).meanLength / o.spacing, 1.0, 0.15);
    }
}

TEST(SampleHeightField, TabletHasWedgeImpressionsAwayFromTheBorder)
{
    const HeightFieldOptions o = heightField(HeightFieldKind::Tablet);
    HeightFieldOptions plain = o;  // the same curved face without wedges and noise
    plain.wedgeDensity = 0;
    plain.noise = 0;
    const TriMesh mesh = makeHeightField(o);
    double deepest = 0;
    std::size_t indented = 0;
    for (const Vec3& p : mesh.points) {
        const double d = p.z - heightFieldValue(plain, p.x, p.y);
        deepest = std::min(deepest, d);
        indented += d < -0.05;
        const double toBorder = std::min({p.x, o.width - p.x, p.y, o.height - p.y});
        if (toBorder < o.wedgeMargin) {
            ASSERT_LE(std::abs(d), o.noise) << "wedge inside the margin at " << p.x << "," << p.y;
        }
    }
    // Wedges 0.6 - 1.4 x 1.5 mm long, 0.2 x length deep.
    EXPECT_LT(deepest, -0.15);
    EXPECT_GT(deepest, -0.2 * 1.4 * o.wedgeSize - 0.01);
    EXPECT_GT(indented, mesh.numVertices() / 100);
    // The face itself is convex and sags by `sag` at the middle of the longer side.
    EXPECT_EQ(heightFieldValue(plain, 0.5 * o.width, 0.5 * o.height), 0.0);
    EXPECT_NEAR(heightFieldValue(plain, 0.0, 0.5 * o.height), -o.sag, 1e-12);
    // No wedges requested: nothing below the plain surface beyond the noise.
    HeightFieldOptions smooth = o;
    smooth.wedgeDensity = 0;
    for (const Vec3& p : makeHeightField(smooth).points)
        ASSERT_LE(std::abs(p.z - heightFieldValue(plain, p.x, p.y)), o.noise);
}

TEST(SampleHeightField, TabletLayoutDoesNotDependOnTheSpacing)
{
    // The same tablet sampled for two resolutions differs only by the crease rounding
    // (at most half the blend height, 0.05 mm x slope) near the wedges.
    HeightFieldOptions fine = heightField(HeightFieldKind::Tablet), coarse = fine;
    fine.noise = coarse.noise = 0;
    fine.spacing = 0.02;
    coarse.spacing = 0.1;
    double maxDiff = 0, deepestFine = 0, deepestCoarse = 0;
    for (double y = 0; y <= fine.height; y += 0.013)
        for (double x = 0; x <= fine.width; x += 0.011) {
            const double a = heightFieldValue(fine, x, y), b = heightFieldValue(coarse, x, y);
            maxDiff = std::max(maxDiff, std::abs(a - b));
            deepestFine = std::min(deepestFine, a);
            deepestCoarse = std::min(deepestCoarse, b);
        }
    EXPECT_GT(maxDiff, 0.0);
    EXPECT_LT(maxDiff, 0.1);
    EXPECT_NEAR(deepestFine, deepestCoarse, 0.05);
    // Another seed moves the wedges.
    HeightFieldOptions other = coarse;
    other.seed = 2;
    double seedDiff = 0;
    for (double y = 0; y <= fine.height; y += 0.05)
        for (double x = 0; x <= fine.width; x += 0.05)
            seedDiff = std::max(seedDiff, std::abs(heightFieldValue(other, x, y) - heightFieldValue(coarse, x, y)));
    EXPECT_GT(seedDiff, 0.1);
}

TEST(SampleHeightField, TerrainReliefFollowsTheOption)
{
    for (const double relief : {0.5, 2.0}) {
        HeightFieldOptions o = heightField(HeightFieldKind::Terrain);
        o.relief = relief;
        o.noise = 0;
        double zmin = 0, zmax = 0;
        for (const Vec3& p : makeHeightField(o).points) {
            zmin = std::min(zmin, p.z);
            zmax = std::max(zmax, p.z);
        }
        EXPECT_GT(zmax - zmin, 0.5 * relief);
        EXPECT_LT(zmax - zmin, 6.0 * relief);
    }
}

TEST(SampleHeightField, BenchmarkTabletHasAboutOnePointOneMillionVertices)
{
    HeightFieldOptions o = heightField(HeightFieldKind::Tablet);
    o.width = o.height = 31.6;
    o.spacing = 0.03;
    const TriMesh mesh = makeHeightField(o);
    EXPECT_EQ(mesh.numVertices(), 1054u * 1054u);
    EXPECT_EQ(mesh.numTriangles(), 2u * 1053u * 1053u);
}

// Scanner-like holes: the asked number, apart, faces gone around each, vertices kept, the
// same for the same seed; each hole becomes one border loop of the otherwise closed sphere.
TEST(SampleHoles, PunchHolesMakesSeparateHolesAndKeepsVertices)
{
    SphereOptions so;
    so.radius = 5.0;
    so.spacing = 0.2;
    const TriMesh intact = makeSphere(so);
    TriMesh a = intact, b = intact;
    HoleOptions ho;
    ho.count = 8;
    ho.minSize = 0.1;
    ho.maxSize = 0.4;
    ho.seed = 3;
    const HoleReport report = punchHoles(a, ho);
    punchHoles(b, ho);
    EXPECT_EQ(report.holes, 8u);
    EXPECT_GE(report.facesRemoved, 8u * 6u);
    EXPECT_EQ(a.points, intact.points);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.numTriangles() + report.facesRemoved, intact.numTriangles());
    // Border loops: count the border edges' connected pieces through shared vertices.
    std::unordered_map<std::uint64_t, int> edgeCount;
    for (const Triangle& t : a.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t u = t[std::size_t(k)], v = t[std::size_t((k + 1) % 3)];
            ++edgeCount[std::uint64_t(std::min(u, v)) << 32 | std::max(u, v)];
        }
    std::vector<std::uint32_t> parent(a.numVertices());
    for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = std::uint32_t(i);
    const auto root = [&](std::uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    std::vector<std::uint32_t> borderVertices;
    for (const auto& [key, count] : edgeCount)
        if (count == 1) {
            const std::uint32_t u = std::uint32_t(key >> 32), v = std::uint32_t(key & 0xffffffffu);
            parent[root(u)] = root(v);
            borderVertices.push_back(u);
        }
    std::vector<std::uint32_t> loops;
    for (std::uint32_t v : borderVertices) loops.push_back(root(v));
    std::sort(loops.begin(), loops.end());
    EXPECT_EQ(std::unique(loops.begin(), loops.end()) - loops.begin(), 8);
    ho.maxSize = 0;
    EXPECT_THROW(punchHoles(a, ho), InvalidInputError);
}

// ---------------------------------------------------------------------------------------
// Determinism
// ---------------------------------------------------------------------------------------

namespace {

std::vector<TriMesh> allSamples(std::uint64_t seed)
{
    std::vector<TriMesh> meshes;
    SphereOptions s;
    s.radius = 3.0;
    s.spacing = 0.2;
    s.seed = seed;
    meshes.push_back(makeSphere(s));
    CubeOptions c;
    c.side = 3.0;
    c.spacing = 0.2;
    c.seed = seed;
    meshes.push_back(makeCube(c));
    for (const HeightFieldKind kind : kAllKinds)
        for (const bool closed : {false, true}) {
            HeightFieldOptions h = heightField(kind, closed);
            h.width = 7.0;
            h.height = 5.0;
            h.spacing = 0.1;
            h.thickness = 3.0;
            h.seed = seed;
            meshes.push_back(makeHeightField(h));
        }
    RoundedTabletOptions t;
    t.width = 6.0;
    t.height = 8.0;
    t.thickness = 4.0;
    t.rounding = 1.0;
    t.markRadius = 0.3;
    t.markDepth = 0.1;
    t.marks = {2, 2, 1, 1, 1, 1};
    t.spacing = 0.2;
    t.roughness = 0.01;
    t.seed = seed;
    meshes.push_back(makeRoundedTablet(t).mesh);
    return meshes;
}

} // namespace

TEST(SampleDeterminism, SameSeedSameMeshOtherSeedOtherMesh)
{
    const auto a = allSamples(42), b = allSamples(42), c = allSamples(43);
    ASSERT_EQ(a.size(), c.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_TRUE(identical(a[i], b[i])) << "sample " << i;
        // Plane patches differ only in the xy jitter and diagonals; all must differ.
        EXPECT_FALSE(identical(a[i], c[i])) << "sample " << i;
        EXPECT_NE(fingerprint(a[i]), fingerprint(c[i])) << "sample " << i;
    }
}

TEST(SampleDeterminism, IndependentOfTheThreadCount)
{
    const auto parallel = allSamples(5);
    std::vector<TriMesh> serial;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial = allSamples(5);
    }
    for (std::size_t i = 0; i < parallel.size(); ++i) EXPECT_TRUE(identical(parallel[i], serial[i])) << "sample " << i;
}

/// The bit patterns of the samples are part of the contract ("the same mesh on every
/// machine"): these fingerprints were recorded on x86-64 (GCC 12, Debian 12). A change to
/// the generators that alters the meshes on purpose must update them; a failure without
/// such a change means the output is not portable (e.g. compiled with FMA contraction).
TEST(SampleDeterminism, GoldenFingerprints)
{
    const auto meshes = allSamples(2024);
    const std::uint64_t expected[] = {
        0x0d750bf9a31d98daULL,  // sphere
        0x1d57b28dbba4ed23ULL,  // cube
        0xe7ec0d1beac9731dULL,  // plane
        0x7d68edfdf84f8cd3ULL,  // plane slab
        0x2bba7f1453f7eca4ULL,  // terrain
        0xe735cd1ac3f56f6fULL,  // terrain slab
        0x957d88e48e3d503cULL,  // tablet
        0x0d8867b97a6afea1ULL,  // tablet slab
        0x853f7ddef1f99e1fULL,  // rounded tablet
    };
    ASSERT_EQ(meshes.size(), std::size(expected));
    for (std::size_t i = 0; i < meshes.size(); ++i)
        EXPECT_EQ(fingerprint(meshes[i]), expected[i]) << "sample " << i << ": 0x" << std::hex << fingerprint(meshes[i]);
}

// Scan-like sampling: the same surface, sampled as scanners and meshers do. Checked: the
// triangles' aspect along x and y, the vertex density across the patch, the white noise's
// amplitude against the height field, and a valid closed slab with long walls around it.
TEST(SampleHeightField, ScanLikeSamplingHasTheAskedProperties)
{
    HeightFieldOptions o = heightField(HeightFieldKind::Terrain);
    o.width = 12.0;
    o.height = 12.0;
    o.spacing = 0.1;
    o.anisotropy = 3;
    o.densityVariation = 4;
    o.roughness = 0.01;
    const TriMesh mesh = makeHeightField(o);
    // Aspect: mean |dx| / mean |dy| of the lattice's row and column edges (index k + 1 and
    // k + row; the first row is the border y = 0).
    std::size_t row = 0;
    while (mesh.points[row].y == 0) ++row;
    double dx = 0, dy = 0;
    std::size_t n = 0;
    for (std::size_t k = row + 1; k + row + 1 < mesh.numVertices(); k += 37) {
        if (k % row == row - 1) continue;  // the row's last vertex
        dx += std::abs(mesh.points[k + 1].x - mesh.points[k].x);
        dy += std::abs(mesh.points[k + row].y - mesh.points[k].y);
        ++n;
    }
    ASSERT_GT(n, 100u);
    EXPECT_NEAR(dx / dy, 3.0, 0.3);
    // Density: x = W F(u / W), F(s) = s + α sin(2πs) / (2π), α = 1/3, spaces the columns
    // F'(0) / F'(1/2) = (1 + α) / (1 − α) = 2 times wider at the border than in the middle
    // (the same along y: 4 : 1 in vertices per area).
    const auto meanColumnGap = [&](double a, double b) {
        double sum = 0;
        std::size_t count = 0;
        for (std::size_t k = row + 1; k + 1 < mesh.numVertices(); ++k)
            if (k % row != row - 1 && mesh.points[k].x >= a && mesh.points[k].x < b) {
                sum += mesh.points[k + 1].x - mesh.points[k].x;
                ++count;
            }
        return sum / double(count);
    };
    EXPECT_NEAR(meanColumnGap(0, 0.4) / meanColumnGap(5.8, 6.2), 2.0, 0.15);
    // Noise: |z − h| up to the roughness, spread over it (not smooth, not zero).
    double largest = 0, sum = 0;
    for (const Vec3& p : mesh.points) {
        const double d = std::abs(p.z - heightFieldValue(o, p.x, p.y));
        largest = std::max(largest, d);
        sum += d;
    }
    EXPECT_LE(largest, 0.01);
    EXPECT_GT(largest, 0.009);
    EXPECT_NEAR(sum / double(mesh.numVertices()), 0.005, 0.0005);
    o.closed = true;
    o.thickness = 3;
    o.wallStep = 1.5;
    const TriMesh slab = makeHeightField(o);
    expectWatertight(slab, "scan-like slab with long walls");
    EXPECT_GT(signedVolume(slab), 0.0);
}

// ---------------------------------------------------------------------------------------
// Invalid options
// ---------------------------------------------------------------------------------------

TEST(SampleOptions, InvalidValuesThrowInvalidInputError)
{
    SphereOptions s;
    s.spacing = 0;
    EXPECT_THROW(makeSphere(s), InvalidInputError);
    s = {};
    s.radius = -1;
    EXPECT_THROW(makeSphere(s), InvalidInputError);
    s = {};
    s.center.x = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(makeSphere(s), InvalidInputError);
    s = {};
    s.spacing = 1e-6;  // 10^15 vertices
    EXPECT_THROW(makeSphere(s), InvalidInputError);

    CubeOptions c;
    c.side = std::numeric_limits<double>::infinity();
    EXPECT_THROW(makeCube(c), InvalidInputError);

    HeightFieldOptions h;
    h.width = 0;
    EXPECT_THROW(makeHeightField(h), InvalidInputError);
    EXPECT_THROW(heightFieldValue(h, 0, 0), InvalidInputError);
    h = {};
    h.noise = -1;
    EXPECT_THROW(makeHeightField(h), InvalidInputError);
    h = {};
    h.spacing = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(makeHeightField(h), InvalidInputError);
    // A slab whose bottom does not reach below the terrain.
    h = heightField(HeightFieldKind::Terrain, true);
    h.relief = 3.0;
    h.thickness = 0.5;
    EXPECT_THROW(makeHeightField(h), InvalidInputError);
}

// ---------------------------------------------------------------------------------------
// msii-samples command line (error paths only: they do not need the PLY writer)
// ---------------------------------------------------------------------------------------

namespace {

RunResult runSamples(const std::string& args) { return runProgram(MSII_SAMPLES_EXE, args, ::testing::TempDir()); }

bool samplesExecutableExists() { return std::ifstream(MSII_SAMPLES_EXE).good(); }

void expectUsageError(const std::string& args, const std::string& mentions)
{
    SCOPED_TRACE(args);
    const RunResult r = runSamples(args);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.rfind("msii-samples: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
}

} // namespace

TEST(SampleCli, ListsTheShapes)
{
    ASSERT_TRUE(samplesExecutableExists()) << MSII_SAMPLES_EXE << " is missing: the tests need it built";
    const RunResult r = runSamples("--list");
    EXPECT_EQ(r.code, 0);
    const std::string lines = "\n" + r.out;
    for (const char* shape :
         {"sphere", "cavity", "cube", "plane", "terrain", "tablet", "rounded-tablet", "vessel", "sherd", "seal"})
        EXPECT_NE(lines.find(std::string("\n") + shape + " "), std::string::npos) << shape;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 10);
}

TEST(SampleCli, HelpExitsZero)
{
    ASSERT_TRUE(samplesExecutableExists()) << MSII_SAMPLES_EXE << " is missing: the tests need it built";
    const RunResult r = runSamples("--help");
    EXPECT_EQ(r.code, 0);
    EXPECT_NE(r.out.find("--spacing"), std::string::npos);
}

TEST(SampleCli, BadOptionsExitTwoWithOneLine)
{
    ASSERT_TRUE(samplesExecutableExists()) << MSII_SAMPLES_EXE << " is missing: the tests need it built";
    const std::string out = " --output '" + ::testing::TempDir() + "never_written.ply'";
    expectUsageError("teapot" + out, "teapot");
    expectUsageError("sphere", "--output");
    expectUsageError("--output x.ply", "SHAPE");
    expectUsageError("sphere --spacing -1" + out, "spacing");
    expectUsageError("sphere --spacing abc" + out, "abc");
    expectUsageError("cube --radius 3" + out, "--radius");
    expectUsageError("sphere --center 1,2" + out, "--center");
    expectUsageError("terrain --thickness 2" + out, "--closed");
    expectUsageError("terrain --closed --thickness 0.01 --relief 3" + out, "thickness");
    expectUsageError("sphere --no-such-option" + out, "--no-such-option");
    expectUsageError("sphere --seed -3" + out, "--seed");
    EXPECT_FALSE(std::ifstream(::testing::TempDir() + "never_written.ply").good());
}

// The streamed writer (a 50M-vertex terrain without holding it) writes byte for byte what
// writePly writes for makeHeightField, for every kind, band boundaries included (130 rows =
// two full bands of 64 and a short one), float and double points; and the msii-samples
// program streams open height fields.
TEST(SampleHeightField, StreamedFileEqualsTheMeshWritten)
{
    const std::string dir = ::testing::TempDir();
    for (HeightFieldKind kind : {HeightFieldKind::Plane, HeightFieldKind::Terrain, HeightFieldKind::Tablet}) {
        HeightFieldOptions o;
        o.kind = kind;
        o.width = 9.7;
        o.height = 13.0;
        o.spacing = 0.1;  // 97 x 130 cells
        o.seed = 5;
        for (bool doublePoints : {false, true}) {
            SCOPED_TRACE(std::to_string(int(kind)) + (doublePoints ? " double" : " float"));
            WritePlyOptions po;
            po.forceDoublePoints = doublePoints;
            po.comments = {"msii-samples test"};
            const TriMesh mesh = makeHeightField(o);
            writePly(dir + "held.ply", mesh, {}, po);
            const StreamedMeshCounts counts = writeHeightFieldPly(o, dir + "streamed.ply", po);
            EXPECT_EQ(counts.vertices, mesh.numVertices());
            EXPECT_EQ(counts.triangles, mesh.numTriangles());
            const std::string held = readFile(dir + "held.ply");
            EXPECT_GT(held.size(), 100000u);
            EXPECT_TRUE(readFile(dir + "streamed.ply") == held);
        }
    }
    HeightFieldOptions closed;
    closed.closed = true;
    EXPECT_THROW(writeHeightFieldPly(closed, dir + "closed.ply", {}), InvalidInputError);
    EXPECT_FALSE(std::ifstream(dir + "closed.ply").good());
}

TEST(SampleCli, OpenHeightFieldsAreStreamedToTheSameFile)
{
    ASSERT_TRUE(samplesExecutableExists()) << MSII_SAMPLES_EXE << " is missing: the tests need it built";
    const std::string file = ::testing::TempDir() + "cli_terrain.ply";
    const RunResult r = runSamples("terrain --width 6 --height 4 --spacing 0.05 --seed 9 -q --output '" + file + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    HeightFieldOptions o;
    o.kind = HeightFieldKind::Terrain;
    o.width = 6;
    o.height = 4;
    o.spacing = 0.05;
    o.seed = 9;
    const std::string held = ::testing::TempDir() + "cli_terrain_held.ply";
    WritePlyOptions po;
    po.comments = {"msii-samples terrain seed 9 width 6 height 4 spacing 0.05"};
    writePly(held, makeHeightField(o), {}, po);
    EXPECT_TRUE(readFile(file) == readFile(held));
}
