#pragma once
// Test support: mesh properties computed independently of the engine (edges and their use,
// watertightness, orientation, signed volume, bit-for-bit identity and fingerprints), so that
// the tests of the sample generators do not rely on the engine's own mesh checks.
#include <msii/mesh/trimesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <limits>
#include <unordered_map>
#include <vector>

namespace msii::test {

/// How the edges of a mesh are used.
struct EdgeReport {
    std::size_t numEdges = 0;
    std::size_t numNonManifold = 0;    ///< in more than two faces
    std::size_t numInconsistent = 0;   ///< in two faces, traversed the same way
    std::size_t numDegenerate = 0;     ///< faces with a repeated index
    std::vector<std::array<std::uint32_t, 2>> border;  ///< edges of one face, as traversed
    double meanLength = 0;
};

/// The edges of @p mesh: how often and which way round each is used, the border, the mean length.
inline EdgeReport analyzeEdges(const TriMesh& mesh)
{
    struct Use {
        int count = 0;
        int forward = 0;  // traversed from lower to higher index
        std::array<std::uint32_t, 2> first{};
    };
    std::unordered_map<std::uint64_t, Use> edges;
    edges.reserve(mesh.numTriangles() * 2);
    EdgeReport r;
    for (const Triangle& t : mesh.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) ++r.numDegenerate;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
            const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
            Use& u = edges[key];
            if (u.count == 0) u.first = {a, b};
            ++u.count;
            u.forward += a < b;
        }
    }
    double total = 0;
    for (const auto& [key, u] : edges) {
        const auto a = std::uint32_t(key >> 32), b = std::uint32_t(key & 0xffffffffULL);
        total += norm(mesh.points[a] - mesh.points[b]);
        if (u.count > 2) ++r.numNonManifold;
        if (u.count == 2 && u.forward != 1) ++r.numInconsistent;
        if (u.count == 1) r.border.push_back(u.first);
    }
    r.numEdges = edges.size();
    r.meanLength = edges.empty() ? 0 : total / double(edges.size());
    return r;
}

/// Sum of signed tetrahedron volumes (origin, triangle): the enclosed volume of a closed,
/// outward-oriented mesh.
inline double signedVolume(const TriMesh& mesh)
{
    double v = 0;
    for (const Triangle& t : mesh.triangles)
        v += dot(mesh.points[t[0]], cross(mesh.points[t[1]], mesh.points[t[2]]));
    return v / 6.0;
}

inline Vec3 triangleNormal(const TriMesh& mesh, const Triangle& t)  // area-weighted x 2
{
    return cross(mesh.points[t[1]] - mesh.points[t[0]], mesh.points[t[2]] - mesh.points[t[0]]);
}

inline double minTriangleArea(const TriMesh& mesh)
{
    double m = std::numeric_limits<double>::infinity();
    for (const Triangle& t : mesh.triangles) m = std::min(m, 0.5 * norm(triangleNormal(mesh, t)));
    return m;
}

inline void expectWatertight(const TriMesh& mesh, const char* what)
{
    SCOPED_TRACE(what);
    ASSERT_FALSE(mesh.empty());
    const EdgeReport r = analyzeEdges(mesh);
    EXPECT_EQ(r.numDegenerate, 0u);
    EXPECT_EQ(r.numNonManifold, 0u);
    EXPECT_EQ(r.numInconsistent, 0u);
    EXPECT_EQ(r.border.size(), 0u);
    // Euler characteristic of a sphere (V - E + F = 2): one closed genus-0 component.
    EXPECT_EQ(std::int64_t(mesh.numVertices()) - std::int64_t(r.numEdges) + std::int64_t(mesh.numTriangles()), 2);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t) ASSERT_LT(i, mesh.numVertices());
}

inline bool identical(const TriMesh& a, const TriMesh& b)
{
    return a.points.size() == b.points.size() && a.triangles.size() == b.triangles.size() &&
           std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3)) == 0 &&
           std::memcmp(a.triangles.data(), b.triangles.data(), a.triangles.size() * sizeof(Triangle)) == 0;
}

/// FNV-1a over the bit patterns of the points and the indices.
inline std::uint64_t fingerprint(const TriMesh& mesh)
{
    std::uint64_t h = 0xcbf29ce484222325ULL;
    const auto add = [&h](const void* data, std::size_t size) {
        const auto* p = static_cast<const unsigned char*>(data);
        for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
    };
    for (const Vec3& p : mesh.points) {
        const double c[3] = {p.x, p.y, p.z};
        for (double v : c) {
            std::uint64_t bits;
            std::memcpy(&bits, &v, sizeof bits);
            add(&bits, sizeof bits);
        }
    }
    for (const Triangle& t : mesh.triangles) add(t.data(), sizeof t);
    return h;
}

} // namespace msii::test
