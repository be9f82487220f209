// Mesh preparation (mesh/prepare_mesh.h): every repair kind gives the clean mesh's values
// where the geometry is the clean mesh's; pin-holes in closed scans are filled so that
// almost every vertex has values, close to the intact mesh's; the outer border of an open
// surface stays a border; what cannot be repaired, and with repair off what would need
// it, is refused with one sentence.
#include <msii/core/errors.h>
#include <msii/invariants/invariants.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

using namespace msii;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

/// The four invariants' columns, mapped to the input's vertices.
struct Values {
    std::vector<std::vector<float>> columns[4];  // V, S, P, L: [radius][vertex]
    std::vector<double> radii;
    double medianEdge = 0;
};

Values computeOn(const PrepareMeshResult& prepared, const InvariantsOptions& options)
{
    const InvariantsResult r = computeInvariants(prepared.mesh, options);
    Values v;
    const std::vector<std::vector<float>>* from[4] = {&r.features[Invariant::Volume], &r.features[Invariant::Sphere], &r.features[Invariant::Patch],
                                                      &r.features[Invariant::Line]};
    for (int q = 0; q < 4; ++q)
        for (const auto& column : *from[q]) v.columns[q].push_back(toInputVertices(prepared, column));
    v.radii = r.plan.radii;
    v.medianEdge = r.stats.medianEdge;
    return v;
}

InvariantsOptions smallOptions(double radius, double voxel)
{
    InvariantsOptions o;
    o.radius = radius;
    o.scales = 4;
    o.voxelSize = voxel;  // fixed, so that a changed median edge does not move the grid
    return o;
}

/// A closed sphere of about 4,000 vertices, its vertices renumbered in the order the
/// triangles first use them (as a triangle soup would be merged back).
TriMesh cleanSphere()
{
    samples::SphereOptions so;
    so.radius = 5.0;
    so.spacing = 0.25;
    so.seed = 3;
    TriMesh m = samples::makeSphere(so);
    // Float-exact coordinates (STL files hold floats).
    for (Vec3& p : m.points) p = {double(float(p.x)), double(float(p.y)), double(float(p.z))};
    std::vector<std::uint32_t> order(m.numVertices(), PrepareMeshResult::kNoVertex);
    TriMesh out;
    for (Triangle& t : m.triangles)
        for (std::uint32_t& v : t) {
            if (order[v] == PrepareMeshResult::kNoVertex) {
                order[v] = std::uint32_t(out.points.size());
                out.points.push_back(m.points[v]);
            }
            v = order[v];
        }
    out.triangles = m.triangles;
    return out;
}

/// Number of values compared, and the largest difference; NaN against a number counts as
/// infinitely different.
struct Comparison {
    std::size_t compared = 0;
    double largest = 0;
};

/// Compares @p got (input vertices of a repaired mesh) at vertex map[i] with @p want at
/// vertex i, over all invariants and radii.
Comparison compareValues(const Values& want, const Values& got, const std::vector<std::uint32_t>& map)
{
    Comparison c;
    for (int q = 0; q < 4; ++q) {
        EXPECT_EQ(want.columns[q].size(), got.columns[q].size());
        for (std::size_t j = 0; j < want.columns[q].size(); ++j)
            for (std::size_t i = 0; i < map.size(); ++i) {
                const float a = want.columns[q][j][i], b = got.columns[q][j][map[i]];
                if (std::isnan(a) && std::isnan(b)) continue;
                ++c.compared;
                c.largest = std::max(c.largest, std::isnan(a) != std::isnan(b) ? INFINITY : double(std::abs(a - b)));
            }
    }
    return c;
}

std::vector<std::uint32_t> identity(std::size_t n)
{
    std::vector<std::uint32_t> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = std::uint32_t(i);
    return v;
}

bool hasChange(const PrepareMeshResult& r, const std::string& kind, std::size_t count)
{
    for (const Diagnostic& c : r.changes)
        if (c.kind == kind) return c.count == count;
    return false;
}

class RepairKinds : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        clean = new TriMesh(cleanSphere());
        const MeshStats stats = computeMeshStats(*clean);
        options = smallOptions(12 * stats.medianEdge, 0.5 * stats.medianEdge);
        const PrepareMeshResult prepared = prepareMesh(*clean);
        ASSERT_TRUE(prepared.changes.empty());
        want = new Values(computeOn(prepared, options));
    }
    static void TearDownTestSuite()
    {
        delete clean;
        delete want;
    }
    /// The repaired mesh's values at the clean mesh's vertices (map: clean -> repaired input).
    static void expectIdentical(const TriMesh& broken, const std::vector<std::uint32_t>& map, const std::string& kind,
                                std::size_t count)
    {
        const PrepareMeshResult prepared = prepareMesh(broken);
        EXPECT_TRUE(hasChange(prepared, kind, count)) << kind;
        EXPECT_EQ(prepared.mesh.triangles, clean->triangles) << kind;
        const Comparison c = compareValues(*want, computeOn(prepared, options), map);
        EXPECT_EQ(c.compared, 4 * options.scales * clean->numVertices()) << kind;
        EXPECT_EQ(c.largest, 0.0) << kind;
        // Repair off: refused with one sentence.
        PrepareMeshOptions strict;
        strict.repair = false;
        try {
            prepareMesh(broken, strict);
            ADD_FAILURE() << kind << " was not refused with repair off";
        } catch (const InvalidInputError& e) {
            EXPECT_NE(std::string(e.what()).find("repair is off"), std::string::npos) << e.what();
        }
    }
    static TriMesh* clean;
    static Values* want;
    static InvariantsOptions options;
};
TriMesh* RepairKinds::clean = nullptr;
Values* RepairKinds::want = nullptr;
InvariantsOptions RepairKinds::options;

} // namespace

TEST_F(RepairKinds, DuplicateFaces)
{
    TriMesh m = *clean;
    m.triangles.push_back(m.triangles[10]);
    const Triangle t = m.triangles[20];
    m.triangles.push_back({t[1], t[2], t[0]});  // the same face, another start
    expectIdentical(m, identity(clean->numVertices()), "duplicate_faces_removed", 2);
}

TEST_F(RepairKinds, DegenerateFaces)
{
    TriMesh m = *clean;
    m.triangles.push_back({5, 5, 6});  // repeated index
    m.points.push_back((m.points[1] + m.points[2]) * 0.5);
    m.triangles.push_back({1, 2, std::uint32_t(m.numVertices() - 1)});  // zero area (a vertex on the edge... )
    m.points.back() = m.points[1];  // ... exactly on a corner: no area at all
    // The extra vertex sits at vertex 1's position: it is merged, then its face is degenerate.
    const PrepareMeshResult prepared = prepareMesh(m);
    EXPECT_TRUE(hasChange(prepared, "degenerate_faces_removed", 2));
    EXPECT_TRUE(hasChange(prepared, "duplicate_vertices_merged", 1));
    EXPECT_EQ(prepared.mesh.triangles, clean->triangles);
    const Comparison c = compareValues(*want, computeOn(prepared, options), identity(clean->numVertices()));
    EXPECT_EQ(c.compared, 4 * options.scales * clean->numVertices());
    EXPECT_EQ(c.largest, 0.0);
    // The merged vertex has the values of the one it was merged with.
    const Values got = computeOn(prepared, options);
    for (int q = 0; q < 4; ++q) EXPECT_EQ(got.columns[q][3][m.numVertices() - 1], got.columns[q][3][1]);
}

TEST_F(RepairKinds, OneFlippedFace)
{
    TriMesh m = *clean;
    std::swap(m.triangles[100][1], m.triangles[100][2]);
    expectIdentical(m, identity(clean->numVertices()), "faces_reoriented", 1);
}

TEST_F(RepairKinds, InsideOutClosedMesh)
{
    TriMesh m = *clean;
    for (Triangle& t : m.triangles) std::swap(t[1], t[2]);
    // Turned back as a whole: the clean faces again.
    expectIdentical(m, identity(clean->numVertices()), "closed_parts_turned_outward", 1);
}

TEST_F(RepairKinds, TriangleSoup)
{
    // Three vertices of its own per triangle, as in an STL file.
    TriMesh soup;
    std::vector<std::uint32_t> firstCopy(clean->numVertices(), PrepareMeshResult::kNoVertex);
    for (const Triangle& t : clean->triangles) {
        Triangle s;
        for (int k = 0; k < 3; ++k) {
            s[std::size_t(k)] = std::uint32_t(soup.points.size());
            if (firstCopy[t[std::size_t(k)]] == PrepareMeshResult::kNoVertex) firstCopy[t[std::size_t(k)]] = s[std::size_t(k)];
            soup.points.push_back(clean->points[t[std::size_t(k)]]);
        }
        soup.triangles.push_back(s);
    }
    expectIdentical(soup, firstCopy, "duplicate_vertices_merged", soup.numVertices() - clean->numVertices());
}

TEST_F(RepairKinds, TextureSeam)
{
    // Every tenth vertex is duplicated for the faces after its first one (an OBJ seam).
    TriMesh m = *clean;
    std::vector<char> used(m.numVertices(), 0);
    std::size_t copies = 0;
    for (Triangle& t : m.triangles)
        for (std::uint32_t& v : t) {
            if (v % 10 != 0) continue;
            if (!used[v]) {
                used[v] = 1;
                continue;
            }
            m.points.push_back(m.points[v]);
            v = std::uint32_t(m.numVertices() - 1);
            ++copies;
        }
    expectIdentical(m, identity(clean->numVertices()), "duplicate_vertices_merged", copies);
}

TEST_F(RepairKinds, NonManifoldEdge)
{
    // A fin on one edge: the three faces there go, and the hole they leave is filled.
    TriMesh m = *clean;
    const Triangle t = m.triangles[500];
    const Vec3 mid = (m.points[t[0]] + m.points[t[1]]) * 0.5;
    m.points.push_back(mid * 1.05);
    m.triangles.push_back({t[0], t[1], std::uint32_t(m.numVertices() - 1)});
    PrepareMeshOptions po;
    po.maxHolePerimeter = defaultMaxHolePerimeter(options.radius);
    const PrepareMeshResult prepared = prepareMesh(m, po);
    EXPECT_TRUE(hasChange(prepared, "non_manifold_faces_removed", 3));
    EXPECT_EQ(prepared.holes.numFilled, 1u);
    EXPECT_EQ(prepared.preparedOf.back(), PrepareMeshResult::kNoVertex);  // the fin's tip is in no face now
    const Values got = computeOn(prepared, options);
    // Away from the repair (beyond the values' reach), identical; near it, close.
    const double reach = 2 * options.radius + 8 * options.voxelSize;
    std::size_t far = 0, near = 0;
    double farLargest = 0, nearLargest = 0;
    for (int q = 0; q < 4; ++q)
        for (std::size_t j = 1; j < want->columns[q].size(); ++j)
            for (std::size_t i = 0; i < clean->numVertices(); ++i) {
                const double d = std::abs(double(want->columns[q][j][i]) - double(got.columns[q][j][i]));
                ASSERT_FALSE(std::isnan(d)) << i;
                if (norm(clean->points[i] - mid) > reach) ++far, farLargest = std::max(farLargest, d);
                else ++near, nearLargest = std::max(nearLargest, d);
            }
    std::printf("non-manifold edge repaired: %zu far values (largest difference %.2e), %zu near (%.2e)\n", far,
                farLargest, near, nearLargest);
    EXPECT_GT(far, 0u);
    EXPECT_GT(near, 0u);
    EXPECT_EQ(farLargest, 0.0);
    EXPECT_LT(nearLargest, 1e-2);
}

TEST(PrepareMesh, NonManifoldVertexIsSplit)
{
    // Two tetrahedra sharing one vertex.
    TriMesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 4, 5}, {0, 6, 4}, {0, 5, 6}, {4, 6, 5}};
    const PrepareMeshResult r = prepareMesh(m);
    EXPECT_TRUE(hasChange(r, "non_manifold_vertices_split", 1));
    ASSERT_EQ(r.mesh.numVertices(), 8u);
    EXPECT_EQ(r.mesh.points[7], m.points[0]);
    EXPECT_TRUE(checkMesh(r.mesh).closed);
    EXPECT_EQ(r.preparedOf[0], 0u);  // the input vertex keeps the first fan
}

TEST(PrepareMesh, WhatCannotBeRepairedIsRefused)
{
    TriMesh m = cleanSphere();
    const auto refused = [](const TriMesh& mesh, const char* words) {
        try {
            prepareMesh(mesh);
            ADD_FAILURE() << "not refused: " << words;
        } catch (const InvalidInputError& e) {
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    TriMesh noFaces = m;
    noFaces.triangles.clear();
    refused(noFaces, "no faces");
    TriMesh nan = m;
    nan.points[7].y = std::nan("");
    refused(nan, "1 vertex with NaN");
    TriMesh outOfRange = m;
    outOfRange.triangles[3][1] = std::uint32_t(m.numVertices() + 5);
    refused(outOfRange, "face 3 refers to vertex");
    TriMesh onlyDegenerate = m;
    for (Triangle& t : onlyDegenerate.triangles) t = {0, 0, 1};
    refused(onlyDegenerate, "no faces with an area");
}

namespace {

/// Whether the faces around @p v bend by more than 60° (a sharp edge or corner): a hole there
/// loses the crease's own point, which no fill can know (docs/limits.md).
bool onSharpEdge(const TriMesh& mesh, std::uint32_t v)
{
    std::vector<Vec3> normals;
    for (const Triangle& t : mesh.triangles)
        if (t[0] == v || t[1] == v || t[2] == v)
            normals.push_back(normalized(cross(mesh.points[t[1]] - mesh.points[t[0]], mesh.points[t[2]] - mesh.points[t[0]])));
    for (const Vec3& a : normals)
        for (const Vec3& b : normals)
            if (dot(a, b) < 0.5) return true;
    return false;
}

/// Removes the faces around @p count vertices spread over the mesh (pin-holes), at least
/// @p apart from each other and not on sharp edges; returns the vertices.
std::vector<std::uint32_t> punchPinHoles(TriMesh& mesh, std::size_t count, double apart, std::uint64_t seed)
{
    std::vector<std::uint32_t> centres;
    std::uint64_t state = seed;
    const auto next = [&] {
        state += 0x9E3779B97F4A7C15ull;
        std::uint64_t z = state;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    };
    for (int tries = 0; centres.size() < count && tries < 100000; ++tries) {
        const std::uint32_t v = std::uint32_t(next() % mesh.numVertices());
        if (std::all_of(centres.begin(), centres.end(),
                        [&](std::uint32_t c) { return norm(mesh.points[c] - mesh.points[v]) > apart; }) &&
            !onSharpEdge(mesh, v))
            centres.push_back(v);
    }
    std::vector<char> gone(mesh.numVertices(), 0);
    for (std::uint32_t c : centres) gone[c] = 1;
    mesh.triangles.erase(std::remove_if(mesh.triangles.begin(), mesh.triangles.end(),
                                        [&](const Triangle& t) { return gone[t[0]] || gone[t[1]] || gone[t[2]]; }),
                         mesh.triangles.end());
    return centres;
}

/// The pin-hole check: at R = 30 median edges, >= 99.5 % of the vertices have values at R,
/// and every value at radii of >= 3 median edges is within 2e-3 (V, S) and 5e-3 (P, L) of
/// the intact mesh's. P and L from the kernels alone on both meshes, so that what differs is
/// the filling's, not which values the check evaluated exactly on one mesh or the other.
void checkPinHoles(const TriMesh& intact, const char* title)
{
    const MeshStats stats = computeMeshStats(intact);
    InvariantsOptions o;
    o.radius = 30 * stats.medianEdge;
    o.scales = 16;
    o.patchLineExactWhereBlurred = false;
    PrepareMeshOptions po;
    po.maxHolePerimeter = defaultMaxHolePerimeter(o.radius);
    po.radius = o.radius;
    const PrepareMeshResult whole = prepareMesh(intact, po);
    ASSERT_TRUE(whole.changes.empty());
    const InvariantsResult plan = planInvariants(whole.mesh, o);
    o.voxelSize = plan.plan.voxelSize;  // the intact mesh's grid for both
    const Values want = computeOn(whole, o);

    TriMesh holed = intact;
    const std::vector<std::uint32_t> centres = punchPinHoles(holed, 12, 10 * stats.medianEdge, 7);
    ASSERT_GE(centres.size(), 10u) << title;
    const PrepareMeshResult prepared = prepareMesh(holed, po);
    EXPECT_EQ(prepared.holes.numFilled, centres.size()) << title;
    EXPECT_EQ(prepared.numIsolatedVertices, centres.size()) << title;
    ASSERT_FALSE(prepared.filledShare.empty());
    const Values got = computeOn(prepared, o);

    const std::size_t nv = intact.numVertices(), last = want.radii.size() - 1;
    std::size_t withValues = 0;
    for (std::size_t i = 0; i < nv; ++i) withValues += !std::isnan(got.columns[0][last][i]);
    const double share = double(withValues) / double(nv);

    const char* names = "VSPL";
    double largest[4] = {0, 0, 0, 0};
    std::size_t compared = 0;
    for (int q = 0; q < 4; ++q)
        for (std::size_t j = 0; j < want.radii.size(); ++j) {
            if (want.radii[j] < 3 * stats.medianEdge) continue;
            for (std::size_t i = 0; i < nv; ++i) {
                if (std::find(centres.begin(), centres.end(), std::uint32_t(i)) != centres.end()) continue;
                const float a = want.columns[q][j][i], b = got.columns[q][j][i];
                ASSERT_FALSE(std::isnan(a)) << title << " intact value NaN at " << i;
                ASSERT_FALSE(std::isnan(b)) << title << " " << names[q] << " NaN at vertex " << i << " radius " << j;
                largest[q] = std::max(largest[q], double(std::abs(a - b)));
                ++compared;
            }
        }
    std::printf("%s: %zu vertices, %zu pin-holes filled (largest %.3g around, %.3g area), values at R: %.2f %%, "
                "largest difference V %.2e S %.2e P %.2e L %.2e over %zu values\n",
                title, nv, prepared.holes.numFilled, prepared.holes.largestPerimeter, prepared.holes.areaAdded,
                100 * share, largest[0], largest[1], largest[2], largest[3], compared);
    EXPECT_GE(share, 0.995) << title;
    EXPECT_GT(compared, 0u);
    EXPECT_LE(largest[0], 2e-3) << title;
    EXPECT_LE(largest[1], 2e-3) << title;
    EXPECT_LE(largest[2], 5e-3) << title;
    EXPECT_LE(largest[3], 5e-3) << title;
    // filled_share: zero far from the holes, positive at their rims, at most 1.
    float largestShare = 0;
    for (float s : prepared.filledShare) largestShare = std::max(largestShare, s);
    EXPECT_GT(largestShare, 0.0f);
    EXPECT_LE(largestShare, 1.0f);
}

} // namespace

TEST(PrepareMesh, PinHolesInAClosedSphere)
{
    samples::SphereOptions so;
    so.radius = 10.0;
    so.spacing = 0.2;
    so.seed = 11;
    checkPinHoles(samples::makeSphere(so), "sphere");
}

TEST(PrepareMesh, PinHolesInAClosedTabletSlab)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = 16;
    ho.height = 12;
    ho.spacing = 0.08;
    ho.closed = true;
    ho.thickness = 3;
    ho.seed = 4;
    checkPinHoles(samples::makeHeightField(ho), "tablet slab");
}

TEST(PrepareMesh, OpenTabletKeepsItsOuterBorderMasked)
{
    samples::HeightFieldOptions ho;
    ho.width = 10;
    ho.height = 8;
    ho.spacing = 0.1;
    const TriMesh open = samples::makeHeightField(ho);
    InvariantsOptions o;
    o.radius = 1.0;
    o.scales = 4;
    PrepareMeshOptions po;
    po.maxHolePerimeter = defaultMaxHolePerimeter(o.radius);
    po.radius = o.radius;
    const PrepareMeshResult prepared = prepareMesh(open, po);
    EXPECT_EQ(prepared.holes.numFilled, 0u);
    EXPECT_EQ(prepared.holes.numTooLarge, 1u);
    EXPECT_EQ(prepared.mesh.triangles, open.triangles);
    // The same values and the same mask as the mesh computed as it is.
    const InvariantsResult direct = computeInvariants(open, o);
    const Values got = computeOn(prepared, o);
    std::size_t masked = 0, compared = 0;
    for (std::size_t i = 0; i < open.numVertices(); ++i) {
        const float a = direct.features[Invariant::Volume].back()[i], b = got.columns[0].back()[i];
        masked += std::isnan(a);
        EXPECT_EQ(std::isnan(a), std::isnan(b)) << i;
        if (!std::isnan(a)) {
            EXPECT_EQ(a, b) << i;
            ++compared;
        }
    }
    EXPECT_GT(masked, 0u);
    EXPECT_GT(compared, 0u);

    // A small loose open piece whose outline is shorter than the limit is not closed either:
    // its outline is its outer border.
    samples::HeightFieldOptions small = ho;
    small.kind = samples::HeightFieldKind::Plane;
    small.width = small.height = 0.6;
    PrepareMeshOptions generous = po;
    generous.maxHolePerimeter = 100;
    const PrepareMeshResult piece = prepareMesh(samples::makeHeightField(small), generous);
    EXPECT_EQ(piece.holes.numFilled, 0u);
    EXPECT_EQ(piece.holes.numOuterBorders, 1u);
}

TEST(PrepareMesh, FillHolesZeroFillsNone)
{
    samples::SphereOptions so;
    so.radius = 5.0;
    so.spacing = 0.3;
    TriMesh m = samples::makeSphere(so);
    punchPinHoles(m, 3, 2.0, 1);
    PrepareMeshOptions po;
    po.maxHolePerimeter = 0;
    const PrepareMeshResult r = prepareMesh(m, po);
    EXPECT_EQ(r.holes.numFilled, 0u);
    EXPECT_EQ(r.mesh.numTriangles(), m.numTriangles());
    EXPECT_FALSE(checkMesh(r.mesh).closed);
}

// filled_share against its closed form: a plane whose half x > 0 is fill. At a vertex a
// distance d from the line x = 0, the ball of radius R meets the fill in a circular segment
// (on the surface's side) or in the disc less one (on the fill's side). The plane
// is large (lines at ±4R), tilted and far from the origin, and its grid is jittered, as a
// scan's would be; the pieces of R/16 take the areas to within a few thousandths.
TEST(PrepareMesh, FillShareOfAHalfPlaneIsTheDiscSegment)
{
    const double R = 1.3, step = 0.11;
    const int n = int(std::ceil(4 * R / step));
    const Vec3 origin{3.1e5, 5.4e6, 412.0}, u = normalized(Vec3{1, 0, 0.3}), tilt{0, 1, -0.2};
    const Vec3 w = normalized(tilt - u * dot(u, tilt));
    std::uint32_t seed = 11;
    const auto jitter = [&] {
        seed = seed * 1664525u + 1013904223u;
        return (double(seed >> 8) / double(1u << 24) - 0.5) * 0.3 * step;
    };
    // Columns x = i·step for i in [-n, n], jittered both ways except column 0 across the
    // line, so that x = 0 stays the border between the surface and the fill.
    TriMesh mesh;
    const int side = 2 * n + 1;
    std::vector<double> xs;
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j) {
            const double x = i * step + (i == 0 ? 0.0 : jitter()), y = j * step + jitter();
            xs.push_back(x);
            mesh.points.push_back(origin + u * x + w * y);
        }
    std::vector<Triangle> surface, fill;
    for (int i = 0; i + 1 < side; ++i)
        for (int j = 0; j + 1 < side; ++j) {
            const auto at = [&](int a, int b) { return std::uint32_t(a * side + b); };
            auto& to = i - n >= 0 ? fill : surface;  // columns i - n, i - n + 1
            to.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            to.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    mesh.triangles = surface;
    mesh.triangles.insert(mesh.triangles.end(), fill.begin(), fill.end());
    const std::vector<float> share = fillShare(mesh, surface.size(), R);
    ASSERT_EQ(share.size(), mesh.numVertices());

    const auto segment = [&](double d) {  // the disc's part beyond the line at distance d
        return (R * R * std::acos(d / R) - d * std::sqrt(R * R - d * d)) / (M_PI * R * R);
    };
    double largest = 0;
    std::size_t compared = 0;
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j) {
            const std::size_t v = std::size_t((i + n) * side + (j + n));
            const double x = xs[v], y = dot(mesh.points[v] - origin, w);
            if (std::abs(y) > 4 * R - R - 2 * step) continue;  // its ball would leave the plane
            if (std::abs(x) > 4 * R - R - 2 * step) continue;
            const double want = x >= R ? 1.0 : x <= -R ? 0.0 : x >= 0 ? 1.0 - segment(x) : segment(-x);
            largest = std::max(largest, std::abs(double(share[v]) - want));
            ++compared;
        }
    std::printf("filled_share on a half plane of fill: %zu vertices, largest difference %.2e\n", compared, largest);
    EXPECT_GT(compared, 500u);
    EXPECT_LE(largest, 5e-3);
    // Only the vertices asked for get a share.
    const std::vector<float> some = fillShare(mesh, surface.size(), R, 10);
    for (std::size_t v = 10; v < some.size(); ++v) ASSERT_EQ(some[v], 0.0f);

    // A second copy 2^21 R away, where the cells' keys of the two copies coincide: each
    // copy keeps its own shares (the first bit for bit, the copy within rounding).
    TriMesh twice;
    const std::size_t nv = mesh.numVertices();
    const Vec3 shift{std::ldexp(R, 21), 0, 0};
    twice.points = mesh.points;
    for (const Vec3& q : mesh.points) twice.points.push_back(q + shift);
    const auto copy = [&](const std::vector<Triangle>& from, std::uint32_t offset) {
        for (const Triangle& t : from) twice.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    };
    copy(surface, 0), copy(surface, std::uint32_t(nv)), copy(fill, 0), copy(fill, std::uint32_t(nv));
    const std::vector<float> both = fillShare(twice, 2 * surface.size(), R);
    double largestCopy = 0;
    for (std::size_t v = 0; v < nv; ++v) {
        ASSERT_EQ(both[v], share[v]) << "vertex " << v;
        largestCopy = std::max(largestCopy, double(std::abs(both[nv + v] - share[v])));
    }
    EXPECT_LE(largestCopy, 1e-3);
}
