/// Tests of mesh/mesh_check.h on small meshes with one known defect each, plus repair and
/// thread-count independence on a larger grid.

#include <msii/mesh/mesh_check.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

using namespace msii;

namespace {

/// The regular octahedron, faces counter-clockwise seen from outside.
TriMesh octahedron()
{
    TriMesh mesh;
    mesh.points = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    mesh.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return mesh;
}

/// An n x n vertex grid in the plane z = 0, two triangles per cell.
TriMesh grid(std::uint32_t n)
{
    TriMesh mesh;
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) mesh.points.push_back({double(i), double(j), 0.01 * ((i * j) % 5)});
    for (std::uint32_t j = 0; j + 1 < n; ++j)
        for (std::uint32_t i = 0; i + 1 < n; ++i) {
            const std::uint32_t v = j * n + i;
            mesh.triangles.push_back({v, v + 1, v + n + 1});
            mesh.triangles.push_back({v, v + n + 1, v + n});
        }
    return mesh;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

} // namespace

TEST(MeshCheck, OctahedronIsClosedAndClean)
{
    const MeshCheckResult r = checkMesh(octahedron());
    EXPECT_TRUE(r.closed);
    EXPECT_EQ(r.numNonFinitePoints, 0u);
    EXPECT_EQ(r.numDegenerateFaces, 0u);
    EXPECT_EQ(r.numDuplicateFaces, 0u);
    EXPECT_EQ(r.numNonManifoldEdges, 0u);
    EXPECT_EQ(r.numInconsistentEdges, 0u);
    EXPECT_EQ(r.numBorderEdges, 0u);
    EXPECT_TRUE(r.borderEdges.empty());
    EXPECT_EQ(r.numUnreferencedVertices, 0u);
    EXPECT_EQ(r.firstProblem(), "");
}

TEST(MeshCheck, OpenSquareHasFourBorderEdgesInFaceOrder)
{
    TriMesh square;
    square.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {5, 5, 5}};  // last one unused
    square.triangles = {{0, 1, 2}, {0, 2, 3}};
    const MeshCheckResult r = checkMesh(square);
    EXPECT_FALSE(r.closed);
    EXPECT_EQ(r.numBorderEdges, 4u);
    EXPECT_EQ(r.numInconsistentEdges, 0u);
    EXPECT_EQ(r.numUnreferencedVertices, 1u);
    EXPECT_EQ(r.firstProblem(), "");  // a border is not a problem
    // Each border edge as its face traverses it (so borders run counter-clockwise here).
    using Edge = std::array<std::uint32_t, 2>;
    std::vector<Edge> edges = r.borderEdges;
    std::sort(edges.begin(), edges.end());
    EXPECT_EQ(edges, (std::vector<Edge>{{0, 1}, {1, 2}, {2, 3}, {3, 0}}));
}

TEST(MeshCheck, NonFinitePoint)
{
    TriMesh mesh = octahedron();
    mesh.points[4].z = std::numeric_limits<double>::quiet_NaN();
    mesh.points[5].x = -std::numeric_limits<double>::infinity();
    const MeshCheckResult r = checkMesh(mesh);
    EXPECT_EQ(r.numNonFinitePoints, 2u);
    EXPECT_EQ(r.numDegenerateFaces, 0u);
    EXPECT_EQ(r.firstProblem(), "the mesh has 2 vertices with NaN or infinite coordinates");
}

TEST(MeshCheck, DuplicateFacesInAnyOrder)
{
    TriMesh mesh = octahedron();
    mesh.triangles.push_back({2, 4, 0});  // same as face 0, rotated
    mesh.triangles.push_back({4, 2, 0});  // same as face 0, reversed
    mesh.triangles.push_back({5, 2, 1});  // same as face 5, reversed
    const MeshCheckResult r = checkMesh(mesh);
    EXPECT_EQ(r.numDuplicateFaces, 3u);
    EXPECT_EQ(r.duplicateFaces, (std::vector<std::size_t>{8, 9, 10}));
    // The copies are not counted again as non-manifold or inconsistent edges.
    EXPECT_EQ(r.numNonManifoldEdges, 0u);
    EXPECT_EQ(r.numInconsistentEdges, 0u);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(contains(r.firstProblem(), "3 duplicate faces")) << r.firstProblem();
}

TEST(MeshCheck, DegenerateFaces)
{
    TriMesh mesh = octahedron();
    mesh.points.push_back({0.5, 0.5, 0});  // on the segment from vertex 0 to vertex 2
    mesh.triangles.push_back({0, 0, 3});   // repeated index
    mesh.triangles.push_back({0, 6, 2});   // collinear points
    mesh.triangles.push_back({0, 1, 99});  // index out of range
    const MeshCheckResult r = checkMesh(mesh);
    EXPECT_EQ(r.numDegenerateFaces, 3u);
    EXPECT_EQ(r.degenerateFaces, (std::vector<std::size_t>{8, 9, 10}));
    EXPECT_TRUE(r.closed);  // edges are judged without the bad faces
    EXPECT_EQ(r.numUnreferencedVertices, 1u);
    EXPECT_EQ(r.firstProblem(),
              "the mesh has 3 degenerate faces (repeated or invalid vertex indices, or zero area)");

    // A sliver far below the resolution counts too; a small but real face does not.
    TriMesh slivers = octahedron();
    slivers.points.push_back({0.5, 0.5 + 1e-13, 0});
    slivers.points.push_back({0.5, 0.5 + 1e-3, 0});
    slivers.triangles.push_back({0, 6, 2});
    slivers.triangles.push_back({0, 7, 2});
    EXPECT_EQ(checkMesh(slivers).degenerateFaces, (std::vector<std::size_t>{8}));
}

TEST(MeshCheck, NonManifoldEdge)
{
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
    mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};  // three faces on edge 0-1
    const MeshCheckResult r = checkMesh(mesh);
    EXPECT_EQ(r.numNonManifoldEdges, 1u);
    EXPECT_EQ(r.numBorderEdges, 6u);
    EXPECT_FALSE(r.closed);
    EXPECT_EQ(r.firstProblem(), "the mesh has 1 non-manifold edge (shared by more than two faces)");
}

// Repair: the faces around non-manifold edges go, the others stay (in order), and the
// rest is a valid open mesh.
TEST(MeshCheck, RemoveNonManifoldFaces)
{
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {1, 1, 0}, {2, 0, 0}};
    // Three faces on edge 0-1, and two good faces beyond: 1-5-2 and 1-6-5.
    mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {1, 5, 2}, {1, 6, 5}};
    EXPECT_EQ(removeNonManifoldFaces(mesh), 3u);
    EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{1, 5, 2}, {1, 6, 5}}));
    const MeshCheckResult r = checkMesh(mesh);
    EXPECT_EQ(r.numNonManifoldEdges, 0u);
    EXPECT_EQ(r.firstProblem(), "");
    EXPECT_EQ(r.numBorderEdges, 4u);
    EXPECT_EQ(removeNonManifoldFaces(mesh), 0u);  // nothing left to remove
}

TEST(MeshCheck, FlippedFaceGivesInconsistentEdges)
{
    TriMesh mesh = octahedron();
    std::swap(mesh.triangles[3][0], mesh.triangles[3][1]);
    const MeshCheckResult r = checkMesh(mesh);
    EXPECT_TRUE(r.closed);
    EXPECT_EQ(r.numInconsistentEdges, 3u);
    EXPECT_EQ(r.firstProblem(), "");  // orientation is reported, but does not block
}

TEST(MeshCheck, RemoveBadFaces)
{
    TriMesh mesh = octahedron();
    mesh.triangles.insert(mesh.triangles.begin() + 2, {1, 1, 3});
    mesh.triangles.push_back({4, 0, 2});
    const MeshCheckResult r = checkMesh(mesh);
    ASSERT_EQ(r.numDegenerateFaces + r.numDuplicateFaces, 2u);
    EXPECT_EQ(removeBadFaces(mesh, r), 2u);
    EXPECT_EQ(mesh.triangles, octahedron().triangles);
    EXPECT_EQ(mesh.numVertices(), 6u);
    EXPECT_EQ(checkMesh(mesh).firstProblem(), "");
    EXPECT_EQ(removeBadFaces(mesh, checkMesh(mesh)), 0u);
}

TEST(MeshCheck, GridResultsDoNotDependOnThreads)
{
    const std::uint32_t n = 400;
    TriMesh mesh = grid(n);
    // Some defects spread over the mesh.
    for (std::uint32_t k = 0; k < 50; ++k) mesh.triangles.push_back(mesh.triangles[k * 997]);
    std::swap(mesh.triangles[1234][0], mesh.triangles[1234][2]);
    mesh.triangles.push_back({5, 5, 6});

    MeshCheckResult one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = checkMesh(mesh);
    }
    const MeshCheckResult many = checkMesh(mesh);
    EXPECT_EQ(one.numBorderEdges, 4u * (n - 1));
    EXPECT_EQ(one.numDuplicateFaces, 50u);
    EXPECT_EQ(one.numDegenerateFaces, 1u);
    EXPECT_EQ(one.numInconsistentEdges, 3u);
    EXPECT_EQ(one.numNonManifoldEdges, 0u);
    EXPECT_EQ(many.borderEdges, one.borderEdges);
    EXPECT_EQ(many.duplicateFaces, one.duplicateFaces);
    EXPECT_EQ(many.degenerateFaces, one.degenerateFaces);
    EXPECT_EQ(many.numInconsistentEdges, one.numInconsistentEdges);
}
