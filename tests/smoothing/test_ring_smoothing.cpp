/// Tests of smoothing/ring_smoothing.h: invariants (constants, linear fields), hand-computed
/// rings (Eq. 13–17), the median on a spike, total variation, near-zero edges, NaN values,
/// borders and thread-count independence.

#include <msii/smoothing/ring_smoothing.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

using namespace msii;

namespace {

constexpr double kPi = 3.14159265358979323846;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Uniform in [0, 1) from the raw generator (std::uniform_real_distribution differs between
/// standard libraries; mt19937's output does not).
double uniform01(std::mt19937& rng) { return double(rng()) / 4294967296.0; }

/// An nx × ny grid in the plane z = 0 with spacing h, each vertex moved by up to ±jitter·h in
/// x and y (fixed seed). Each cell is split along the diagonal that keeps both triangles
/// counter-clockwise, the shorter one if both do; without jitter always (i,j)–(i+1,j+1).
TriMesh gridMesh(int nx, int ny, double h = 1.0, double jitter = 0.0, unsigned seed = 1)
{
    TriMesh mesh;
    std::mt19937 rng(seed);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            double x = i * h, y = j * h;
            if (jitter > 0) {
                x += (2 * uniform01(rng) - 1) * jitter * h;
                y += (2 * uniform01(rng) - 1) * jitter * h;
            }
            mesh.points.push_back({x, y, 0});
        }
    const auto id = [nx](int i, int j) { return std::uint32_t(j * nx + i); };
    const auto ccw = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        const Vec3& p = mesh.points[a];
        return cross(mesh.points[b] - p, mesh.points[c] - p).z > 0;
    };
    const auto length = [&](std::uint32_t a, std::uint32_t b) {
        return norm(mesh.points[b] - mesh.points[a]);
    };
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            const std::uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1),
                                d = id(i, j + 1);
            const bool acOk = ccw(a, b, c) && ccw(a, c, d);
            const bool bdOk = ccw(a, b, d) && ccw(b, c, d);
            if (!acOk && !bdOk) ADD_FAILURE() << "cell " << i << "," << j << " is folded";
            if (acOk && (!bdOk || length(a, c) <= length(b, d))) {
                mesh.triangles.push_back({a, b, c});
                mesh.triangles.push_back({a, c, d});
            } else {
                mesh.triangles.push_back({a, b, d});
                mesh.triangles.push_back({b, c, d});
            }
        }
    return mesh;
}

/// The jittered flat mesh of the linear-field tests: 30 × 30 vertices on [0,1]², jitter 0.3.
TriMesh jitteredUnitGrid(int n = 30, unsigned seed = 7)
{
    return gridMesh(n, n, 1.0 / (n - 1), 0.3, seed);
}

bool onGridBorder(std::size_t v, int nx, int ny)
{
    const int i = int(v % std::size_t(nx)), j = int(v / std::size_t(nx));
    return i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
}

/// A fan: p0 (vertex 0) at the origin and neighbours 1..k at the given distances and
/// equal angular steps, triangles (0, i, i+1) closing the ring.
TriMesh fan(const std::vector<double>& distances)
{
    TriMesh mesh;
    const std::size_t k = distances.size();
    mesh.points.push_back({0, 0, 0});
    for (std::size_t i = 0; i < k; ++i) {
        const double angle = 2 * kPi * double(i) / double(k);
        mesh.points.push_back({distances[i] * std::cos(angle), distances[i] * std::sin(angle), 0});
    }
    for (std::size_t i = 0; i < k; ++i)
        mesh.triangles.push_back({0, std::uint32_t(1 + i), std::uint32_t(1 + (i + 1) % k)});
    return mesh;
}

std::vector<float> smoothed(const TriMesh& mesh, std::vector<float> values,
                            const SmoothingOptions& options)
{
    RingSmoother(mesh, options).smooth(values);
    return values;
}

SmoothingOptions makeOptions(SmoothingFilter filter, int iterations,
                             RingWeights weights = RingWeights::Balanced,
                             BorderMode border = BorderMode::OpenRing,
                             RingRadius radius = RingRadius::Global)
{
    SmoothingOptions options;
    options.filter = filter;
    options.iterations = iterations;
    options.weights = weights;
    options.border = border;
    options.radius = radius;
    return options;
}

/// Smooth field plus uniform noise in [−amplitude, amplitude) (fixed seed).
std::vector<float> noisyField(const TriMesh& mesh, double amplitude, unsigned seed = 3)
{
    std::mt19937 rng(seed);
    std::vector<float> values;
    for (const Vec3& p : mesh.points)
        values.push_back(float(std::sin(3 * p.x) * std::cos(2 * p.y) +
                               amplitude * (2 * uniform01(rng) - 1)));
    return values;
}

/// Σ over unique edges of |f_a − f_b|.
double totalVariation(const TriMesh& mesh, const std::vector<float>& f)
{
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            edges.push_back(std::minmax(t[k], t[(k + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    double tv = 0;
    for (const auto& [a, b] : edges) tv += std::abs(double(f[a]) - double(f[b]));
    return tv;
}

double maxAbsDifference(const std::vector<float>& a, const std::vector<float>& b)
{
    double m = 0;
    for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a[i]) - b[i]));
    return m;
}

} // namespace

TEST(RingSmoothing, ConstantFieldIsKept)
{
    const TriMesh mesh = jitteredUnitGrid();
    const std::vector<float> values(mesh.numVertices(), 0.7f);
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median})
        for (auto radius : {RingRadius::Global, RingRadius::Ring})
            for (auto weights : {RingWeights::Balanced, RingWeights::IsoscelesArea}) {
                const auto result = smoothed(
                    mesh, values, makeOptions(filter, 30, weights, BorderMode::OpenRing, radius));
                EXPECT_LE(maxAbsDifference(result, values), 1e-6);
            }
}

TEST(RingSmoothing, BalancedMeanKeepsLinearFieldOnIrregularMesh)
{
    const int n = 30;
    const TriMesh mesh = jitteredUnitGrid(n);
    std::vector<float> values;
    for (const Vec3& p : mesh.points) values.push_back(float(0.3 + 2 * p.x - 1.5 * p.y));

    // One pass over the open rings: the border moves (its fans are not closed), the
    // interior does not.
    const auto once = smoothed(mesh, values, makeOptions(SmoothingFilter::Mean, 1));
    double maxInterior = 0, maxBorder = 0;
    for (std::size_t v = 0; v < values.size(); ++v) {
        double& maxChange = onGridBorder(v, n, n) ? maxBorder : maxInterior;
        maxChange = std::max(maxChange, std::abs(double(once[v]) - values[v]));
    }
    EXPECT_LE(maxInterior, 1e-5);
    EXPECT_GT(maxBorder, 1e-4);  // so the interior check is not vacuous

    // 30 passes with the border kept: nothing feeds errors inward.
    const auto thirty = smoothed(
        mesh, values,
        makeOptions(SmoothingFilter::Mean, 30, RingWeights::Balanced, BorderMode::Keep));
    EXPECT_LE(maxAbsDifference(thirty, values), 1e-5);
}

TEST(RingSmoothing, IsoscelesAreaMeanMovesLinearFieldOnIrregularMesh)
{
    // Eq. 15's weights do not put the small triangles' weighted centroid at p0 on irregular
    // rings, so even a linear field drifts; this is why RingWeights::Balanced exists.
    const int n = 30;
    const TriMesh mesh = jitteredUnitGrid(n);
    std::vector<float> values;
    for (const Vec3& p : mesh.points) values.push_back(float(0.3 + 2 * p.x - 1.5 * p.y));
    const auto once = smoothed(mesh, values,
                               makeOptions(SmoothingFilter::Mean, 1, RingWeights::IsoscelesArea));
    double maxInterior = 0;
    for (std::size_t v = 0; v < values.size(); ++v)
        if (!onGridBorder(v, n, n))
            maxInterior = std::max(maxInterior, std::abs(double(once[v]) - values[v]));
    EXPECT_GT(maxInterior, 1e-4);
}

TEST(RingSmoothing, HexagonFanByHand)
{
    // Regular hexagon of radius 1: spokes and rim edges all 1, so Δ = 1 and a = 1 (Eq. 13).
    const TriMesh mesh = fan({1, 1, 1, 1, 1, 1});
    const std::vector<float> values = {1.0f, 0.0f, 0.9f, 0.1f, 0.2f, 0.3f, 1.0f};
    // Eq. 14 with a_i = a_{i+1} = 1: f^t = (3 − 1 − 1)·f0 + f_i + f_{i+1}.
    const double ft[6] = {
        1.0 + 0.0 + 0.9,  // 1.9
        1.0 + 0.9 + 0.1,  // 2.0
        1.0 + 0.1 + 0.2,  // 1.3
        1.0 + 0.2 + 0.3,  // 1.5
        1.0 + 0.3 + 1.0,  // 2.3
        1.0 + 1.0 + 0.0,  // 2.0
    };
    // Equal angles (60°) give equal weights 1/6 with both weightings.
    const double mean = (ft[0] + ft[1] + ft[2] + ft[3] + ft[4] + ft[5]) / (3 * 6);  // Eq. 16
    // Sorted f^t: 1.3, 1.5, 1.9, 2.0, 2.0, 2.3; the cumulative weight reaches exactly 1/2 at
    // the third, so Eq. 17's tie case averages the third and fourth.
    const double median = (1.9 + 2.0) / 2 / 3;
    EXPECT_NEAR(mean, 11.0 / 18, 1e-12);
    EXPECT_NEAR(median, 0.65, 1e-12);
    for (auto weights : {RingWeights::Balanced, RingWeights::IsoscelesArea}) {
        EXPECT_NEAR(smoothed(mesh, values, makeOptions(SmoothingFilter::Mean, 1, weights))[0],
                    mean, 1e-6);
        EXPECT_NEAR(smoothed(mesh, values, makeOptions(SmoothingFilter::Median, 1, weights))[0],
                    median, 1e-6);
    }
    const RingSmoother smoother(mesh, makeOptions(SmoothingFilter::Mean, 1));
    EXPECT_NEAR(smoother.info().globalDelta, 1.0, 1e-12);
    EXPECT_EQ(smoother.info().numBorderVertices, 6u);
}

TEST(RingSmoothing, PentagonFanByHand)
{
    // Radius 1, rim edges 2·sin 36° ≈ 1.18, so Δ = 1 and a = 1; five weights of 1/5: no tie.
    const TriMesh mesh = fan({1, 1, 1, 1, 1});
    const std::vector<float> values = {0.5f, 0.1f, 0.7f, 0.4f, 0.9f, 0.0f};
    const double ft[5] = {
        0.5 + 0.1 + 0.7,  // 1.3
        0.5 + 0.7 + 0.4,  // 1.6
        0.5 + 0.4 + 0.9,  // 1.8
        0.5 + 0.9 + 0.0,  // 1.4
        0.5 + 0.0 + 0.1,  // 0.6
    };
    const double mean = (ft[0] + ft[1] + ft[2] + ft[3] + ft[4]) / (3 * 5);
    // Sorted: 0.6, 1.3, 1.4, 1.6, 1.8; cumulative 0.2, 0.4, 0.6 → the third.
    const double median = 1.4 / 3;
    for (auto weights : {RingWeights::Balanced, RingWeights::IsoscelesArea}) {
        EXPECT_NEAR(smoothed(mesh, values, makeOptions(SmoothingFilter::Mean, 1, weights))[0],
                    mean, 1e-6);
        EXPECT_NEAR(smoothed(mesh, values, makeOptions(SmoothingFilter::Median, 1, weights))[0],
                    median, 1e-6);
    }
}

TEST(RingSmoothing, SquareFanMedianTie)
{
    // Spokes of length 1, 2, 1, 2 along the axes (rim edges √5): Δ = 1, so a = 1, ½, 1, ½;
    // four right angles give four weights of ¼.
    const TriMesh mesh = fan({1, 2, 1, 2});
    const std::vector<float> values = {0.5f, 0.0f, 0.3f, 1.0f, 0.9f};
    const double f0 = 0.5, a[4] = {1, 0.5, 1, 0.5}, f[4] = {0.0, 0.3, 1.0, 0.9};
    double ft[4];
    for (int i = 0; i < 4; ++i) {
        const int j = (i + 1) % 4;
        ft[i] = (3 - a[i] - a[j]) * f0 + a[i] * f[i] + a[j] * f[j];  // Eq. 14
    }
    EXPECT_NEAR(ft[0], 0.9, 1e-12);
    EXPECT_NEAR(ft[1], 1.9, 1e-12);
    EXPECT_NEAR(ft[2], 2.2, 1e-12);
    EXPECT_NEAR(ft[3], 1.2, 1e-12);
    // Sorted: 0.9, 1.2, 1.9, 2.2; the cumulative weight is exactly ½ at the second (tie):
    // the mean of the second and third. (On a 4-fan this always equals the mean, since
    // opposite triangles sum to the same; it is still neither the second nor the third.)
    const double median = (1.2 + 1.9) / 2 / 3;
    const double result =
        smoothed(mesh, values, makeOptions(SmoothingFilter::Median, 1))[0];
    EXPECT_NEAR(result, median, 1e-6);
    EXPECT_GT(std::abs(result - 1.2 / 3), 0.1);
    EXPECT_GT(std::abs(result - 1.9 / 3), 0.1);
    EXPECT_NEAR(smoothed(mesh, values, makeOptions(SmoothingFilter::Mean, 1))[0],
                (ft[0] + ft[1] + ft[2] + ft[3]) / 12, 1e-6);
}

TEST(RingSmoothing, MedianOnSpike)
{
    // Regular grid, spacing 1, diagonals (i,j)–(i+1,j+1): an interior vertex has four axis
    // neighbours (a = 1) and two diagonal ones (a = 1/√2), two right-angled triangles
    // (both edges axes) and four 45° triangles (one of each).
    const int n = 21;
    const TriMesh mesh = gridMesh(n, n);
    const std::size_t spike = std::size_t(10 * n + 10);
    std::vector<float> values(mesh.numVertices(), 0.0f);
    values[spike] = 1.0f;

    // At the spike (neighbours 0), Eq. 14: f^t/3 = (3 − a_i − a_{i+1})/3 · f0.
    const double rightValue = (3 - 1 - 1) / 3.0;                       // 1/3
    const double slantValue = (3 - 1 - 1 / std::sqrt(2.0)) / 3.0;      // 0.43096
    struct Case {
        RingWeights weights;
        double factor;  // the spike's value after one pass
    };
    // Balanced: the two right triangles weigh 2·tan 45° / (2·tan 45° + 4·tan 22.5°) = 0.547
    // ≥ ½ → the median is 1/3. IsoscelesArea: 2·sin 90° / (2·sin 90° + 4·sin 45°) = 0.414
    // < ½ → the median is the slanted triangles' value.
    for (const Case& c : {Case{RingWeights::Balanced, rightValue},
                          Case{RingWeights::IsoscelesArea, slantValue}}) {
        const auto once = smoothed(mesh, values, makeOptions(SmoothingFilter::Median, 1, c.weights));
        EXPECT_NEAR(once[spike], c.factor, 1e-6);
        // Every other vertex (the spike's neighbours included) stays exactly 0: the spike's
        // two triangles weigh at most 0.39 of a neighbour's ring.
        for (std::size_t v = 0; v < once.size(); ++v)
            if (v != spike) {
                ASSERT_EQ(once[v], 0.0f) << "vertex " << v;
            }

        // The neighbours stay 0, so each pass multiplies the spike by the factor: below 1e-3
        // after ceil(ln 1e-3 / ln factor) passes (7 for 1/3, 9 for 0.431), not one earlier.
        const int passes = int(std::ceil(std::log(1e-3) / std::log(c.factor)));
        EXPECT_EQ(passes, c.weights == RingWeights::Balanced ? 7 : 9);
        const auto enough =
            smoothed(mesh, values, makeOptions(SmoothingFilter::Median, passes, c.weights));
        EXPECT_LT(enough[spike], 1e-3);
        EXPECT_NEAR(enough[spike], std::pow(c.factor, passes), 1e-7);
        const auto fewer =
            smoothed(mesh, values, makeOptions(SmoothingFilter::Median, passes - 1, c.weights));
        EXPECT_GT(fewer[spike], 1e-3);
    }
}

TEST(RingSmoothing, TotalVariationDecreasesMonotonically)
{
    const TriMesh mesh = jitteredUnitGrid();
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        const RingSmoother smoother(mesh, makeOptions(filter, 1));
        std::vector<float> values = noisyField(mesh, 0.3);
        double previous = totalVariation(mesh, values);
        for (int pass = 0; pass < 10; ++pass) {
            smoother.smooth(values);
            const double tv = totalVariation(mesh, values);
            if (pass == 0) {
                EXPECT_LT(tv, 0.9 * previous) << "filter " << int(filter);
            }
            EXPECT_LE(tv, previous) << "filter " << int(filter) << ", pass " << pass;
            previous = tv;
        }
    }
}

TEST(RingSmoothing, NearZeroEdgeFreezesGlobalRadius)
{
    const int n = 20;
    TriMesh mesh = gridMesh(n, n);
    const std::uint32_t moved = 5 * n + 5, close = 5 * n + 6;
    mesh.points[moved] = mesh.points[close] - Vec3(1e-6, 0, 0);
    const std::vector<float> values = noisyField(mesh, 1.0);

    const RingSmoother global(mesh, makeOptions(SmoothingFilter::Mean, 30));
    EXPECT_TRUE(global.info().globalDeltaTooSmall);
    EXPECT_NEAR(global.info().globalDelta, 1e-6, 1e-9);
    EXPECT_NEAR(global.info().medianEdge, 1.0, 1e-12);
    std::vector<float> result = values;
    global.smooth(result);
    // The two ends of the short edge see each other with a = 1 and average each other out;
    // everything else sees Δ/|edge| ≈ 1e-6 of its neighbours' differences per pass.
    double maxOthers = 0;
    for (std::size_t v = 0; v < values.size(); ++v)
        if (v != moved && v != close)
            maxOthers = std::max(maxOthers, std::abs(double(result[v]) - values[v]));
    EXPECT_LT(maxOthers, 1e-3);

    const auto ring = smoothed(mesh, values,
                               makeOptions(SmoothingFilter::Mean, 30, RingWeights::Balanced,
                                           BorderMode::OpenRing, RingRadius::Ring));
    EXPECT_GT(maxAbsDifference(ring, values), 1e-2);

    EXPECT_FALSE(RingSmoother(gridMesh(n, n)).info().globalDeltaTooSmall);
}

TEST(RingSmoothing, NanNeighbourDropsItsTriangles)
{
    // Hexagon (Δ = 1, a = 1) with rim vertex 4 missing: the centre's triangles (3,4) and
    // (4,5) are left out and the other four keep equal weights ¼.
    const TriMesh mesh = fan({1, 1, 1, 1, 1, 1});
    const std::vector<float> values = {1.0f, 0.0f, 0.8f, 0.1f, kNaN, 0.3f, 0.6f};
    const double ft[4] = {
        1.0 + 0.0 + 0.8,  // (1,2): 1.8
        1.0 + 0.8 + 0.1,  // (2,3): 1.9
        1.0 + 0.3 + 0.6,  // (5,6): 1.9
        1.0 + 0.6 + 0.0,  // (6,1): 1.6
    };
    const double mean = (ft[0] + ft[1] + ft[2] + ft[3]) / 12;
    const double median = (1.8 + 1.9) / 2 / 3;  // sorted 1.6, 1.8, 1.9, 1.9: tie at the second
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        const auto result = smoothed(mesh, values, makeOptions(filter, 1));
        EXPECT_NEAR(result[0], filter == SmoothingFilter::Mean ? mean : median, 1e-6);
        EXPECT_TRUE(std::isnan(result[4]));
        for (std::size_t v : {1, 2, 3, 5, 6}) EXPECT_TRUE(std::isfinite(result[v])) << v;
        // Rim vertex 3 only has triangles (0,2,3) and (0,3,4); the latter is left out.
        // After several passes the NaN is still isolated.
        const auto many = smoothed(mesh, values, makeOptions(filter, 30));
        for (std::size_t v = 0; v < many.size(); ++v)
            EXPECT_EQ(std::isnan(many[v]), v == 4) << v;
    }
}

TEST(RingSmoothing, NanInConstantField)
{
    const int n = 15;
    const TriMesh mesh = gridMesh(n, n, 1.0, 0.3, 11);
    std::vector<float> values(mesh.numVertices(), 2.5f);
    const std::size_t hole = std::size_t(7 * n + 7);
    values[hole] = kNaN;
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median})
        for (auto weights : {RingWeights::Balanced, RingWeights::IsoscelesArea}) {
            const auto result = smoothed(mesh, values, makeOptions(filter, 30, weights));
            for (std::size_t v = 0; v < result.size(); ++v) {
                if (v == hole) {
                    EXPECT_TRUE(std::isnan(result[v]));
                } else {
                    EXPECT_NEAR(result[v], 2.5, 1e-6) << v;
                }
            }
        }
}

TEST(RingSmoothing, KeepBorderKeepsBorderValuesExactly)
{
    const int n = 30;
    const TriMesh mesh = jitteredUnitGrid(n);
    const std::vector<float> values = noisyField(mesh, 0.3);
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        const RingSmoother smoother(
            mesh, makeOptions(filter, 5, RingWeights::Balanced, BorderMode::Keep));
        EXPECT_EQ(smoother.info().numBorderVertices, std::size_t(4 * (n - 1)));
        std::vector<float> result = values;
        smoother.smooth(result);
        std::size_t changedInterior = 0;
        for (std::size_t v = 0; v < values.size(); ++v) {
            if (onGridBorder(v, n, n)) {
                EXPECT_EQ(result[v], values[v]) << v;
            } else {
                changedInterior += result[v] != values[v];
            }
        }
        EXPECT_GT(changedInterior, values.size() / 2);
    }
}

TEST(RingSmoothing, ResultDoesNotDependOnThreadCount)
{
    const TriMesh mesh = gridMesh(200, 200, 1.0, 0.3, 5);
    const std::vector<float> values = noisyField(mesh, 0.5);
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        std::vector<float> results[2];
        for (int threads = 1; threads <= 2; ++threads) {
            tbb::global_control control(tbb::global_control::max_allowed_parallelism,
                                        std::size_t(threads));
            results[threads - 1] = smoothed(mesh, values, makeOptions(filter, 30));
        }
        ASSERT_EQ(results[0].size(), results[1].size());
        EXPECT_EQ(std::memcmp(results[0].data(), results[1].data(),
                              results[0].size() * sizeof(float)),
                  0);
    }
}

TEST(RingSmoothing, InfoOnSmallGrid)
{
    TriMesh mesh = gridMesh(3, 3);
    mesh.points.push_back({10, 10, 0});  // isolated
    const RingSmoother smoother(mesh);
    const SmoothingInfo& info = smoother.info();
    EXPECT_EQ(info.globalDelta, 1.0);
    // 16 unique edges: 12 of length 1, 4 diagonals of √2.
    EXPECT_EQ(info.medianEdge, 1.0);
    EXPECT_FALSE(info.globalDeltaTooSmall);
    EXPECT_EQ(info.numBorderVertices, 8u);
    EXPECT_EQ(info.numIsolatedVertices, 1u);

    std::vector<float> values = {0, 1, 2, 3, 4, 5, 6, 7, 8, 42};
    smoother.smooth(values);
    EXPECT_EQ(values[9], 42.0f);  // isolated: kept
}

TEST(RingSmoothing, ZeroIterationsLeaveValuesUnchanged)
{
    const TriMesh mesh = jitteredUnitGrid();
    const std::vector<float> values = noisyField(mesh, 0.3);
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        std::vector<float> result = values;
        RunContext progress;
        smoothField(mesh, result, makeOptions(filter, 0), &progress);
        EXPECT_EQ(result, values);
    }
}

TEST(RingSmoothing, NonManifoldAndDegenerateTrianglesDoNotBreak)
{
    // Three triangles on edge (0,1), a degenerate one with a repeated corner and one with a
    // zero-length edge (vertex 5 duplicates vertex 0's position).
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}, {0, 0, 0}};
    mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {2, 2, 4}, {0, 5, 2}};
    const std::vector<float> values = {1, 2, 3, 4, 5, 6};
    for (auto filter : {SmoothingFilter::Mean, SmoothingFilter::Median})
        for (auto radius : {RingRadius::Global, RingRadius::Ring}) {
            SmoothingOptions options = makeOptions(filter, 3);
            options.radius = radius;
            const auto result = smoothed(mesh, values, options);
            for (float f : result) {
                EXPECT_TRUE(std::isfinite(f));
                EXPECT_GE(f, 1.0f);
                EXPECT_LE(f, 6.0f);
            }
        }
    EXPECT_EQ(RingSmoother(mesh).info().globalDelta, 1.0);  // edge (0,1); (0,5) is zero
}

TEST(RingSmoothing, BadInputThrows)
{
    const TriMesh mesh = gridMesh(3, 3);
    EXPECT_THROW(RingSmoother(mesh, makeOptions(SmoothingFilter::Mean, -1)), InvalidInputError);
    TriMesh noTriangles;
    noTriangles.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    EXPECT_THROW(RingSmoother{noTriangles}, InvalidInputError);
    EXPECT_THROW(RingSmoother{TriMesh{}}, InvalidInputError);
    const RingSmoother smoother(mesh);
    std::vector<float> wrong(8, 0.0f);
    EXPECT_THROW(smoother.smooth(wrong), InvalidInputError);
    std::vector<float> alsoWrong(10, 0.0f);
    EXPECT_THROW(smoothField(mesh, alsoWrong), InvalidInputError);
}
