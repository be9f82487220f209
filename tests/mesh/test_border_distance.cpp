// Border distances (mesh/border_distance.h) against brute force: the distance from every
// vertex to the nearest border edge (segment), capped, on an open tablet with a hole, with
// its vertices in index order and shuffled (the grid looks cells up once per run of
// vertices in the same cell), for caps from below an edge length to beyond the mesh.
#include <msii/mesh/border_distance.h>
#include <msii/mesh/mesh_check.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

using namespace msii;

namespace {

/// A 6 × 4 mm tablet patch with a hole of radius 0.8 mm about (2, 2): an outer and an
/// inner border.
TriMesh tabletWithHole()
{
    samples::HeightFieldOptions ho;
    ho.width = 6;
    ho.height = 4;
    ho.spacing = 0.1;
    ho.wedgeMargin = 0.5;
    ho.seed = 3;
    TriMesh mesh = samples::makeHeightField(ho);
    const Vec3 centre(2, 2, 0);
    std::vector<std::array<std::uint32_t, 3>> kept;
    for (const auto& t : mesh.triangles) {
        const Vec3 c = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) / 3.0;
        if (std::hypot(c.x - centre.x, c.y - centre.y) > 0.8) kept.push_back(t);
    }
    mesh.triangles = kept;
    return mesh;
}

/// The same mesh with its vertices renumbered in random order.
TriMesh shuffled(const TriMesh& mesh, std::uint32_t seed)
{
    std::vector<std::uint32_t> newIndex(mesh.numVertices());
    std::iota(newIndex.begin(), newIndex.end(), 0u);
    std::mt19937 rng(seed);
    std::shuffle(newIndex.begin(), newIndex.end(), rng);
    TriMesh out;
    out.points.resize(mesh.numVertices());
    for (std::size_t i = 0; i < mesh.numVertices(); ++i) out.points[newIndex[i]] = mesh.points[i];
    for (const auto& t : mesh.triangles) out.triangles.push_back({newIndex[t[0]], newIndex[t[1]], newIndex[t[2]]});
    return out;
}

/// Distance from p to the segment [a, b], by projection onto the line.
double segmentDistance(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 ab = b - a;
    const double t = std::clamp(dot(p - a, ab) / dot(ab, ab), 0.0, 1.0);
    return norm(p - (a + ab * t));
}

void expectBruteForce(const TriMesh& mesh, double cap)
{
    const auto edges = checkMesh(mesh).borderEdges;
    ASSERT_GT(edges.size(), 100u);
    const std::vector<double> fast = borderDistance(mesh, edges, cap);
    ASSERT_EQ(fast.size(), mesh.numVertices());
    std::size_t capped = 0, onBorder = 0;
    for (std::size_t i = 0; i < mesh.numVertices(); ++i) {
        double best = cap;
        for (const auto& e : edges)
            best = std::min(best, segmentDistance(mesh.points[i], mesh.points[e[0]], mesh.points[e[1]]));
        ASSERT_NEAR(fast[i], best, 1e-12) << "vertex " << i << ", cap " << cap;
        capped += best == cap;
        onBorder += best == 0;
    }
    // Both cases occur (except that a cap beyond the mesh caps nothing).
    EXPECT_GT(onBorder, 0u);
    if (cap < 1) {
        EXPECT_GT(capped, 0u);
    }
}

} // namespace

TEST(BorderDistance, EqualsBruteForceInIndexOrder)
{
    const TriMesh mesh = tabletWithHole();
    for (double cap : {0.05, 0.3, 1.2, 100.0}) expectBruteForce(mesh, cap);
}

TEST(BorderDistance, EqualsBruteForceWithShuffledVertices)
{
    const TriMesh mesh = shuffled(tabletWithHole(), 11);
    for (double cap : {0.05, 0.3, 1.2, 100.0}) expectBruteForce(mesh, cap);
}

TEST(BorderDistance, ClosedMeshOrNoCapGivesTheCap)
{
    const TriMesh mesh = tabletWithHole();
    const std::vector<double> none = borderDistance(mesh, {}, 2.5);
    EXPECT_TRUE(std::all_of(none.begin(), none.end(), [](double d) { return d == 2.5; }));
    const std::vector<double> zero = borderDistance(mesh, checkMesh(mesh).borderEdges, 0.0);
    EXPECT_TRUE(std::all_of(zero.begin(), zero.end(), [](double d) { return d == 0.0; }));
}
