/// Tests of mesh/mesh_stats.h against hand-computed values and for thread-count independence.

#include <msii/mesh/mesh_stats.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <limits>

using namespace msii;

namespace {

/// The unit square as two unit right triangles.
TriMesh unitSquare()
{
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    return mesh;
}

} // namespace

TEST(MeshStats, UnitRightTriangles)
{
    const MeshStats s = computeMeshStats(unitSquare());
    EXPECT_EQ(s.numVertices, 4u);
    EXPECT_EQ(s.numTriangles, 2u);
    EXPECT_EQ(s.bboxMin, Vec3(0, 0, 0));
    EXPECT_EQ(s.bboxMax, Vec3(1, 1, 0));
    EXPECT_DOUBLE_EQ(s.diagonal, std::sqrt(2.0));
    // Edges of both faces: 1, 1, sqrt2 and sqrt2, 1, 1.
    EXPECT_EQ(s.minEdge, 1.0);
    EXPECT_EQ(s.medianEdge, 1.0);
    EXPECT_EQ(s.maxEdge, std::sqrt(2.0));
    EXPECT_DOUBLE_EQ(s.meanEdge, (4 + 2 * std::sqrt(2.0)) / 6);
    EXPECT_DOUBLE_EQ(s.area, 1.0);
}

TEST(MeshStats, ScaledAndTranslated)
{
    TriMesh mesh = unitSquare();
    for (Vec3& p : mesh.points) p = p * 3.0 + Vec3(10, -20, 5);
    const MeshStats s = computeMeshStats(mesh);
    EXPECT_EQ(s.bboxMin, Vec3(10, -20, 5));
    EXPECT_EQ(s.bboxMax, Vec3(13, -17, 5));
    EXPECT_DOUBLE_EQ(s.medianEdge, 3.0);
    EXPECT_DOUBLE_EQ(s.maxEdge, 3 * std::sqrt(2.0));
    EXPECT_DOUBLE_EQ(s.area, 9.0);
}

TEST(MeshStats, NonFinitePointsAreSkipped)
{
    TriMesh mesh = unitSquare();
    mesh.points.push_back({std::numeric_limits<double>::quiet_NaN(), 0, 0});
    mesh.points.push_back({0, std::numeric_limits<double>::infinity(), 0});
    mesh.triangles.push_back({2, 3, 4});
    mesh.triangles.push_back({4, 5, 0});
    const MeshStats s = computeMeshStats(mesh);
    EXPECT_EQ(s.numVertices, 6u);
    EXPECT_EQ(s.bboxMax, Vec3(1, 1, 0));
    EXPECT_DOUBLE_EQ(s.area, 1.0);
    EXPECT_EQ(s.minEdge, 1.0);
    EXPECT_EQ(s.maxEdge, std::sqrt(2.0));
    // The finite edge 2-3 of the third face counts: 7 edges, 5 of length 1.
    EXPECT_DOUBLE_EQ(s.meanEdge, (5 + 2 * std::sqrt(2.0)) / 7);
}

TEST(MeshStats, EmptyMesh)
{
    const MeshStats s = computeMeshStats(TriMesh{});
    EXPECT_EQ(s.numVertices, 0u);
    EXPECT_EQ(s.diagonal, 0.0);
    EXPECT_EQ(s.medianEdge, 0.0);
    EXPECT_EQ(s.area, 0.0);
}

TEST(MeshStats, SameResultWithAnyThreadCount)
{
    // A wavy 500 x 500 grid: sums over ~750k edges, where the addition order shows.
    TriMesh mesh;
    const std::uint32_t n = 500;
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i)
            mesh.points.push_back({i * 0.1, j * 0.1, 0.05 * std::sin(0.37 * i) * std::cos(0.21 * j)});
    for (std::uint32_t j = 0; j + 1 < n; ++j)
        for (std::uint32_t i = 0; i + 1 < n; ++i) {
            const std::uint32_t v = j * n + i;
            mesh.triangles.push_back({v, v + 1, v + n + 1});
            mesh.triangles.push_back({v, v + n + 1, v + n});
        }
    MeshStats one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = computeMeshStats(mesh);
    }
    for (int repeat = 0; repeat < 3; ++repeat) {
        const MeshStats many = computeMeshStats(mesh);
        EXPECT_EQ(many.area, one.area);
        EXPECT_EQ(many.meanEdge, one.meanEdge);
        EXPECT_EQ(many.medianEdge, one.medianEdge);
    }
    // The waves add a little to the flat 49.9 x 49.9.
    EXPECT_GT(one.area, 49.9 * 49.9);
    EXPECT_LT(one.area, 49.9 * 49.9 * 1.01);
    EXPECT_NEAR(one.medianEdge, 0.1, 0.01);
}
