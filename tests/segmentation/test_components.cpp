/// Tests of segmentation/components.h: discs on an irregular plane (count, size filter,
/// areas, centroids, boxes, labels, ordering), the `below` mode, the area filter, NaN
/// values, disconnected pieces (exact areas and centroids, tie order, isolated vertices),
/// Gaussian dimples, the wedge pits of the generated tablet, and bad input.

#include <msii/segmentation/components.h>

#include <msii/core/errors.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../support/flat_patch.h"

using namespace msii;
using msii::test::flatPatch;

namespace {

constexpr double kPi = 3.14159265358979323846;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Disc {
    double cx, cy, r;
};

bool inside(const Vec3& p, const Disc& d)
{
    return std::hypot(p.x - d.cx, p.y - d.cy) < d.r;
}

/// 1 inside any of the discs, 0 elsewhere.
std::vector<float> discField(const TriMesh& mesh, const std::vector<Disc>& discs)
{
    std::vector<float> f(mesh.numVertices(), 0.0f);
    for (std::size_t v = 0; v < f.size(); ++v) {
        for (const Disc& d : discs) {
            if (inside(mesh.points[v], d)) f[v] = 1.0f;
        }
    }
    return f;
}

double maxEdgeLength(const TriMesh& mesh)
{
    double e = 0;
    for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) e = std::max(e, norm(mesh.points[t[k]] - mesh.points[t[(k + 1) % 3]]));
    }
    return e;
}

/// Appends @p b (shifted by @p offset) to @p a.
void append(TriMesh& a, const TriMesh& b, const Vec3& offset)
{
    const auto base = std::uint32_t(a.points.size());
    for (const Vec3& p : b.points) a.points.push_back(p + offset);
    for (const Triangle& t : b.triangles) a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

constexpr double kSpacing = 0.1;
/// Seven well separated discs of different radii (gaps >= 1.5 mm, >= 1 mm from the border)
/// and a tiny one (~13 vertices) below the size filter.
const std::vector<Disc> kDiscs = {{3.5, 3.5, 2.5}, {10, 3.5, 1.0},  {16.5, 3.5, 1.8}, {3.5, 10, 1.4},
                                  {10, 10, 2.2},   {16.5, 10, 0.8}, {3.5, 16.5, 1.2}};
const Disc kTiny = {16.5, 16.5, 0.2};

std::vector<Disc> allDiscs()
{
    std::vector<Disc> discs = kDiscs;
    discs.push_back(kTiny);
    return discs;
}

} // namespace

TEST(Components, DiscsOnIrregularPlane)
{
    const TriMesh mesh = flatPatch(20, 20, kSpacing);
    const std::vector<float> f = discField(mesh, allDiscs());
    ComponentOptions options;
    options.threshold = 0.5;
    options.minVertices = 30;  // the smallest kept disc has ~200 vertices, the tiny one ~13
    const ComponentResult result = findComponents(mesh, f, options);

    ASSERT_EQ(result.components.size(), kDiscs.size());
    EXPECT_EQ(result.droppedComponents, 1u);
    ASSERT_EQ(result.label.size(), mesh.numVertices());

    // Distinct radii: label k belongs to the k-th largest disc.
    std::vector<Disc> byArea = kDiscs;
    std::sort(byArea.begin(), byArea.end(), [](const Disc& a, const Disc& b) { return a.r > b.r; });
    const double emax = maxEdgeLength(mesh);
    for (std::size_t k = 0; k < byArea.size(); ++k) {
        const Component& c = result.components[k];
        const Disc& d = byArea[k];
        SCOPED_TRACE("disc r = " + std::to_string(d.r));
        EXPECT_EQ(c.label, k + 1);
        if (k > 0) {
            EXPECT_LT(c.area, result.components[k - 1].area);
        }
        // The cells of the selected vertices cover the disc of radius r - emax and stay
        // within r + emax, so |area - pi r^2| <= 2 pi r emax + pi emax^2 for sure; on this
        // Delaunay-like mesh the boundary errors cancel much better: <= 2 pi r * spacing.
        EXPECT_NEAR(c.area, kPi * d.r * d.r, 2 * kPi * d.r * kSpacing);
        EXPECT_NEAR(c.area, kPi * d.r * d.r, 0.03 * kPi * d.r * d.r);
        EXPECT_LT(std::hypot(c.centroid.x - d.cx, c.centroid.y - d.cy), kSpacing);
        EXPECT_EQ(c.centroid.z, 0.0);
        // Box: inside the disc's square, reaching to within one edge of it.
        EXPECT_GE(c.boxMin.x, d.cx - d.r);
        EXPECT_GE(c.boxMin.y, d.cy - d.r);
        EXPECT_LE(c.boxMax.x, d.cx + d.r);
        EXPECT_LE(c.boxMax.y, d.cy + d.r);
        EXPECT_LT(c.boxMin.x, d.cx - d.r + emax);
        EXPECT_LT(c.boxMin.y, d.cy - d.r + emax);
        EXPECT_GT(c.boxMax.x, d.cx + d.r - emax);
        EXPECT_GT(c.boxMax.y, d.cy + d.r - emax);
        // Vertices: exactly those inside the disc, all carrying this label.
        std::size_t count = 0;
        for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
            if (!inside(mesh.points[v], d)) continue;
            ++count;
            EXPECT_EQ(result.label[v], c.label);
        }
        EXPECT_EQ(c.vertices, count);
    }

    // Everything outside the kept discs (the tiny disc included) is label 0.
    std::size_t tinyVertices = 0;
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
        const bool inKept = std::any_of(kDiscs.begin(), kDiscs.end(),
                                        [&](const Disc& d) { return inside(mesh.points[v], d); });
        if (inside(mesh.points[v], kTiny)) ++tinyVertices;
        if (!inKept) {
            EXPECT_EQ(result.label[v], 0u);
        }
    }
    EXPECT_GT(tinyVertices, 0u);
    EXPECT_LT(tinyVertices, options.minVertices);

    // Without the size filter the tiny disc is the last (smallest) component.
    options.minVertices = 1;
    const ComponentResult all = findComponents(mesh, f, options);
    ASSERT_EQ(all.components.size(), kDiscs.size() + 1);
    EXPECT_EQ(all.droppedComponents, 0u);
    const Component& tiny = all.components.back();
    EXPECT_EQ(tiny.vertices, tinyVertices);
    EXPECT_LT(std::hypot(tiny.centroid.x - kTiny.cx, tiny.centroid.y - kTiny.cy), kSpacing);

    // Deterministic: the same result again.
    const ComponentResult again = findComponents(mesh, f, options);
    EXPECT_EQ(again.label, all.label);
}

TEST(Components, AreaFilter)
{
    const TriMesh mesh = flatPatch(20, 20, kSpacing);
    const std::vector<float> f = discField(mesh, allDiscs());
    ComponentOptions options;
    options.threshold = 1.0;      // f >= 1: the discs (the threshold itself passes)
    options.minArea = kPi * 1.1 * 1.1;  // between the discs of radius 1.0 and 1.2
    const ComponentResult result = findComponents(mesh, f, options);
    ASSERT_EQ(result.components.size(), 5u);  // radii 2.5, 2.2, 1.8, 1.4, 1.2
    EXPECT_EQ(result.droppedComponents, 3u);  // radii 1.0, 0.8 and the tiny one
    EXPECT_NEAR(result.components.back().area, kPi * 1.2 * 1.2, 2 * kPi * 1.2 * kSpacing);
    for (const Component& c : result.components) {
        EXPECT_GE(c.area, options.minArea);
    }
}

TEST(Components, BelowSelectsTheComplement)
{
    const TriMesh mesh = flatPatch(20, 20, kSpacing);
    const std::vector<Disc> discs = allDiscs();
    const std::vector<float> f = discField(mesh, discs);
    ComponentOptions options;
    options.threshold = 0.5;
    options.below = true;
    const ComponentResult result = findComponents(mesh, f, options);
    ASSERT_EQ(result.components.size(), 1u);  // the plane minus the discs is connected
    EXPECT_EQ(result.droppedComponents, 0u);
    double discArea = 0, perimeter = 0;
    for (const Disc& d : discs) {
        discArea += kPi * d.r * d.r;
        perimeter += 2 * kPi * d.r;
    }
    const Component& c = result.components[0];
    EXPECT_NEAR(c.area, 400.0 - discArea, perimeter * kSpacing);
    std::size_t zeros = 0;
    for (std::size_t v = 0; v < f.size(); ++v) {
        EXPECT_EQ(result.label[v], f[v] == 0.0f ? 1u : 0u);
        zeros += f[v] == 0.0f;
    }
    EXPECT_EQ(c.vertices, zeros);
    // The rectangle's corners are vertices: the box is exact.
    EXPECT_EQ(c.boxMin.x, 0.0);
    EXPECT_EQ(c.boxMin.y, 0.0);
    EXPECT_EQ(c.boxMax.x, 20.0);
    EXPECT_EQ(c.boxMax.y, 20.0);

    // The threshold itself passes: f <= 0 is the same selection.
    options.threshold = 0;
    const ComponentResult atZero = findComponents(mesh, f, options);
    ASSERT_EQ(atZero.components.size(), 1u);
    EXPECT_EQ(atZero.components[0].vertices, zeros);
    EXPECT_EQ(atZero.label, result.label);
}

TEST(Components, OneTriangleByHand)
{
    // Area 3; each selected corner gets a cell of 1. Every edge must connect: with corner k
    // unselected only the opposite edge joins the other two.
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
    mesh.triangles = {{0, 1, 2}};
    for (int k = 0; k < 3; ++k) {
        SCOPED_TRACE("unselected corner " + std::to_string(k));
        std::vector<float> f(3, 1.0f);
        f[k] = 0.0f;
        const ComponentResult result = findComponents(mesh, f, {0.5});
        ASSERT_EQ(result.components.size(), 1u);
        const Component& c = result.components[0];
        EXPECT_EQ(c.vertices, 2u);
        EXPECT_DOUBLE_EQ(c.area, 2.0);
        const Vec3 mid = (mesh.points[(k + 1) % 3] + mesh.points[(k + 2) % 3]) * 0.5;
        EXPECT_NEAR(c.centroid.x, mid.x, 1e-15);
        EXPECT_NEAR(c.centroid.y, mid.y, 1e-15);
        EXPECT_EQ(result.label[k], 0u);
        EXPECT_EQ(result.label[(k + 1) % 3], 1u);
        EXPECT_EQ(result.label[(k + 2) % 3], 1u);
    }
    const ComponentResult single = findComponents(mesh, {0, 0, 1}, {0.5});
    ASSERT_EQ(single.components.size(), 1u);
    EXPECT_DOUBLE_EQ(single.components[0].area, 1.0);
    EXPECT_EQ(single.components[0].centroid, Vec3(0, 3, 0));
}

TEST(Components, NaNIsNeverSelected)
{
    // f = 1 everywhere but a NaN strip |x - 7| < 0.3 that cuts the plane in two.
    const TriMesh mesh = flatPatch(20, 20, kSpacing);
    std::vector<float> f(mesh.numVertices(), 1.0f);
    std::size_t nanCount = 0;
    for (std::size_t v = 0; v < f.size(); ++v) {
        if (std::abs(mesh.points[v].x - 7.0) < 0.3) {
            f[v] = kNaN;
            ++nanCount;
        }
    }
    ASSERT_GT(nanCount, 0u);
    const double inf = std::numeric_limits<double>::infinity();
    for (const auto& [threshold, below] : {std::pair{0.5, false}, std::pair{-inf, false},
                                           std::pair{2.0, true}, std::pair{inf, true}}) {
        SCOPED_TRACE("threshold " + std::to_string(threshold) + (below ? " below" : " above"));
        ComponentOptions options;
        options.threshold = threshold;
        options.below = below;
        const ComponentResult result = findComponents(mesh, f, options);
        ASSERT_EQ(result.components.size(), 2u);
        // The right part (x > 7.3, ~12.7 x 20) is the larger one.
        EXPECT_GT(result.components[0].centroid.x, 7.3);
        EXPECT_LT(result.components[1].centroid.x, 6.7);
        EXPECT_NEAR(result.components[0].area, 12.7 * 20, 20 * 2 * kSpacing);
        EXPECT_NEAR(result.components[1].area, 6.7 * 20, 20 * 2 * kSpacing);
        EXPECT_EQ(result.components[0].vertices + result.components[1].vertices, f.size() - nanCount);
        for (std::size_t v = 0; v < f.size(); ++v) {
            if (std::isnan(f[v])) {
                EXPECT_EQ(result.label[v], 0u);
            } else {
                EXPECT_EQ(result.label[v], mesh.points[v].x > 7 ? 1u : 2u);
            }
        }
    }
}

TEST(Components, DisconnectedPiecesHaveExactAreasAndCentroids)
{
    // A 2 x 2 piece first, then a 4 x 3 piece beside it: the larger one is label 1 although
    // its vertices come later. Barycentric cells weight the vertices exactly like the area
    // centroid of the triangles, so for flat rectangles area and centroid are exact.
    const TriMesh small = flatPatch(2, 2, 0.25, 3);
    const TriMesh large = flatPatch(4, 3, 0.25, 4);
    TriMesh mesh;
    append(mesh, small, {10, 0, 0});
    append(mesh, large, {0, 0, 1});
    const std::vector<float> f(mesh.numVertices(), 1.0f);
    const ComponentResult result = findComponents(mesh, f);
    ASSERT_EQ(result.components.size(), 2u);
    const Component& a = result.components[0];
    const Component& b = result.components[1];
    EXPECT_NEAR(a.area, 12.0, 1e-12);
    EXPECT_NEAR(b.area, 4.0, 1e-12);
    EXPECT_EQ(a.vertices, large.numVertices());
    EXPECT_EQ(b.vertices, small.numVertices());
    EXPECT_NEAR(a.centroid.x, 2.0, 1e-12);
    EXPECT_NEAR(a.centroid.y, 1.5, 1e-12);
    EXPECT_NEAR(a.centroid.z, 1.0, 1e-12);
    EXPECT_NEAR(b.centroid.x, 11.0, 1e-12);
    EXPECT_NEAR(b.centroid.y, 1.0, 1e-12);
    EXPECT_EQ(a.boxMin.x, 0.0);
    EXPECT_EQ(a.boxMax.x, 4.0);
    EXPECT_EQ(a.boxMax.y, 3.0);
    EXPECT_EQ(b.boxMin.x, 10.0);
    EXPECT_EQ(b.boxMax.x, 12.0);
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
        EXPECT_EQ(result.label[v], v < small.numVertices() ? 2u : 1u);
    }
}

TEST(Components, EqualAreasAreOrderedBySmallestVertexAndIsolatedVerticesCount)
{
    // Two copies of one piece (the second lifted in z: bit-identical areas) and a selected
    // vertex that belongs to no triangle.
    const TriMesh piece = flatPatch(3, 2, 0.25, 5);
    TriMesh mesh;
    append(mesh, piece, {0, 0, 0});
    append(mesh, piece, {0, 0, 5});
    mesh.points.push_back({7, 8, 9});
    std::vector<float> f(mesh.numVertices(), 1.0f);
    const ComponentResult result = findComponents(mesh, f);
    ASSERT_EQ(result.components.size(), 3u);
    EXPECT_EQ(result.components[0].area, result.components[1].area);
    EXPECT_EQ(result.label.front(), 1u);                       // the piece holding vertex 0
    EXPECT_EQ(result.label[piece.numVertices()], 2u);
    EXPECT_NEAR(result.components[1].centroid.z, 5.0, 1e-12);
    const Component& isolated = result.components[2];
    EXPECT_EQ(isolated.vertices, 1u);
    EXPECT_EQ(isolated.area, 0.0);
    EXPECT_EQ(isolated.centroid, Vec3(7, 8, 9));
    EXPECT_EQ(isolated.boxMin, Vec3(7, 8, 9));
    EXPECT_EQ(isolated.boxMax, Vec3(7, 8, 9));
    EXPECT_EQ(result.label.back(), 3u);

    // minArea > 0 drops the isolated vertex (area 0), keeps the rest.
    ComponentOptions options;
    options.minArea = 1e-9;
    const ComponentResult filtered = findComponents(mesh, f, options);
    EXPECT_EQ(filtered.components.size(), 2u);
    EXPECT_EQ(filtered.droppedComponents, 1u);
    EXPECT_EQ(filtered.label.back(), 0u);
}

TEST(Components, GaussianDimples)
{
    // z = -sum a_k exp(-|p - c_k|^2 / (2 s_k^2)); f = -z >= t selects the disc of radius
    // s_k sqrt(2 ln(a_k / t)) around each dimple deeper than t (neighbours are >= 6 mm,
    // i.e. >= 7 sigma, away: their contribution is < 1e-10).
    struct Dimple {
        double cx, cy, a, s;
    };
    const std::vector<Dimple> dimples = {{4, 4, 0.3, 0.8},   {10, 4, 0.2, 0.6},  {16, 4, 0.5, 0.7},
                                         {4, 10, 0.15, 0.9}, {10, 10, 0.4, 0.5}, {16, 10, 0.25, 0.8},
                                         {10, 16, 0.05, 0.8}};  // the last one is too shallow
    const double t = 0.08;
    TriMesh mesh = flatPatch(20, 20, kSpacing, 7);
    std::vector<float> f(mesh.numVertices());
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
        Vec3& p = mesh.points[v];
        double z = 0;
        for (const Dimple& d : dimples) {
            const double r2 = (p.x - d.cx) * (p.x - d.cx) + (p.y - d.cy) * (p.y - d.cy);
            z -= d.a * std::exp(-r2 / (2 * d.s * d.s));
        }
        p.z = z;
        f[v] = float(-z);
    }
    ComponentOptions options;
    options.threshold = t;
    const ComponentResult result = findComponents(mesh, f, options);
    ASSERT_EQ(result.components.size(), 6u);
    for (const Dimple& d : dimples) {
        if (d.a < t) continue;
        const double r = d.s * std::sqrt(2 * std::log(d.a / t));
        SCOPED_TRACE("dimple at " + std::to_string(d.cx) + ", " + std::to_string(d.cy));
        const auto it = std::find_if(result.components.begin(), result.components.end(), [&](const Component& c) {
            return std::hypot(c.centroid.x - d.cx, c.centroid.y - d.cy) < kSpacing;
        });
        ASSERT_NE(it, result.components.end());
        // The surface area of the curved cap is slightly above its projected disc area:
        // compare to the disc with the boundary tolerance plus the slope excess (<= 1 + g^2/2
        // with the largest gradient g = a / (s sqrt(e)) of a Gaussian).
        const double g = d.a / (d.s * std::sqrt(std::exp(1.0)));
        EXPECT_NEAR(it->area, kPi * r * r, 2 * kPi * r * kSpacing + kPi * r * r * g * g / 2);
        EXPECT_LE(it->boxMax.z, -t + 1e-6);
    }
}

TEST(Components, TabletWedgePits)
{
    // f = depth below the wedge-free surface (same noise, same curvature). Each wedge pit
    // deeper than 0.02 mm is one component; the pits can overlap, so the expected count
    // comes from the analytic surface: 4-connected regions of depth >= 0.02 mm on a
    // 0.02 mm grid (5 x finer than the mesh), counted by a plain flood fill.
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Tablet;
    o.width = 16;
    o.height = 12;
    o.spacing = 0.1;
    o.wedgeDensity = 0.06;  // round(0.06 * 14 * 10) = 8 wedges placed
    samples::HeightFieldOptions flat = o;
    flat.wedgeDensity = 0;
    const TriMesh mesh = samples::makeHeightField(o);
    std::vector<float> f(mesh.numVertices());
    for (std::size_t v = 0; v < f.size(); ++v) {
        const Vec3& p = mesh.points[v];
        f[v] = float(samples::heightFieldValue(flat, p.x, p.y) - p.z);
    }
    const double t = 0.02;

    const double step = 0.02;
    const int nx = int(std::lround(o.width / step)) + 1, ny = int(std::lround(o.height / step)) + 1;
    std::vector<char> deep(std::size_t(nx) * ny, 0);
    for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
            const double x = i * step, y = j * step;
            deep[std::size_t(j) * nx + i] =
                samples::heightFieldValue(flat, x, y) - samples::heightFieldValue(o, x, y) >= t;
        }
    }
    std::size_t expected = 0;
    std::vector<std::size_t> stack;
    for (std::size_t start = 0; start < deep.size(); ++start) {
        if (deep[start] != 1) continue;
        ++expected;
        deep[start] = 2;
        stack.push_back(start);
        while (!stack.empty()) {
            const std::size_t c = stack.back();
            stack.pop_back();
            const int i = int(c % nx), j = int(c / nx);
            const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
            for (int k = 0; k < 4; ++k) {
                const int a = i + di[k], b = j + dj[k];
                if (a < 0 || b < 0 || a >= nx || b >= ny) continue;
                const std::size_t q = std::size_t(b) * nx + a;
                if (deep[q] == 1) {
                    deep[q] = 2;
                    stack.push_back(q);
                }
            }
        }
    }
    ASSERT_GE(expected, 3u);
    ASSERT_LE(expected, 8u);

    ComponentOptions options;
    options.threshold = t;
    const ComponentResult result = findComponents(mesh, f, options);
    EXPECT_EQ(result.components.size(), expected);
    for (const Component& c : result.components) {
        // Pits stay out of the 1 mm margin; a wedge pit (0.6-2.1 mm long) has an outline
        // area of ~0.1-1 mm^2 per wedge.
        EXPECT_GT(c.boxMin.x, o.wedgeMargin);
        EXPECT_LT(c.boxMax.x, o.width - o.wedgeMargin);
        EXPECT_GT(c.boxMin.y, o.wedgeMargin);
        EXPECT_LT(c.boxMax.y, o.height - o.wedgeMargin);
        EXPECT_GT(c.area, 0.05);
    }
}

TEST(Components, BadInputThrows)
{
    const TriMesh mesh = flatPatch(2, 2, 0.5);
    const std::vector<float> f(mesh.numVertices(), 1.0f);
    EXPECT_THROW(findComponents(mesh, std::vector<float>(mesh.numVertices() - 1, 1.0f)), InvalidInputError);
    EXPECT_THROW(findComponents(mesh, std::vector<float>{}), InvalidInputError);
    ComponentOptions nanThreshold;
    nanThreshold.threshold = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(findComponents(mesh, f, nanThreshold), InvalidInputError);
    ComponentOptions nanArea;
    nanArea.minArea = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(findComponents(mesh, f, nanArea), InvalidInputError);
    TriMesh broken = mesh;
    broken.triangles.back()[2] = std::uint32_t(mesh.numVertices());
    EXPECT_THROW(findComponents(broken, f), InvalidInputError);

    // An empty mesh with an empty function is valid: no components.
    const ComponentResult empty = findComponents(TriMesh{}, {});
    EXPECT_TRUE(empty.components.empty());
    EXPECT_TRUE(empty.label.empty());
}
