// Feature metrics (paper §3.1, Eq. 4–11): scale weights and dependency matrices, every
// metric against values worked out by hand on a 3-vertex table, NaN handling, input
// errors, and thread-count independence.
#include <msii/core/errors.h>
#include <msii/metrics/feature_metrics.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

using namespace msii;

namespace {

constexpr double kTol = 1e-6;  // the table and f are float
const double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Blocks V×3 and P×3, three vertices. Against the flat reference (0.5, 0.5, 0.5, 1, 1, 1)
/// the differences d = x − o are
///   vertex 0: ( 0.125,  0,     −0.125 |  0.25,  0,    −0.25 )
///   vertex 1: (−0.25,  −0.125,  0     | −0.5,  −0.25,  0    )
///   vertex 2: ( 0.25,   0.125,  0     |  0.5,   0.25,  0.125)
/// (all values are binary fractions, exact in float).
FeatureTable smallTable()
{
    FeatureTable t;
    t.blocks = {{Invariant::Volume, 3}, {Invariant::Patch, 3}};
    t.numVertices = 3;
    t.values = {0.625f, 0.5f,   0.375f, 1.25f, 1.0f,  0.75f,   //
                0.25f,  0.375f, 0.5f,   0.5f,  0.75f, 1.0f,    //
                0.75f,  0.625f, 0.5f,   1.5f,  1.25f, 1.125f};
    return t;
}

MetricOptions kindOnly(MetricKind kind)
{
    MetricOptions o;
    o.kind = kind;
    return o;
}

MetricOptions pNorm(double p, bool weighted)
{
    MetricOptions o;
    o.kind = MetricKind::PNorm;
    o.p = p;
    o.weighted = weighted;
    return o;
}

void expectValues(const MetricResult& r, const std::vector<double>& expected, const char* what)
{
    ASSERT_EQ(r.values.size(), expected.size()) << what;
    for (std::size_t i = 0; i < expected.size(); ++i)
        EXPECT_NEAR(r.values[i], expected[i], kTol) << what << ", vertex " << i;
    EXPECT_EQ(r.numUndefined, 0u) << what;
    EXPECT_EQ(r.numNegativeForms, 0u) << what;
}

/// A table of random features around the flat values, a few NaN vertices.
FeatureTable randomTable(std::size_t numVertices, std::vector<FeatureBlock> blocks, unsigned seed)
{
    FeatureTable t;
    t.blocks = std::move(blocks);
    t.numVertices = numVertices;
    const std::size_t dim = t.dimension();
    t.values.resize(numVertices * dim);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.3f, 0.3f);
    for (std::size_t i = 0; i < numVertices; ++i) {
        std::size_t e = 0;
        for (const FeatureBlock& b : t.blocks)
            for (int j = 0; j < b.count; ++j, ++e) t.values[i * dim + e] = float(flatValue(b.invariant)) + u(rng);
    }
    for (std::size_t i = 7; i < numVertices; i += 211) t.values[i * dim + (i % dim)] = float(kNaN);
    return t;
}

} // namespace

// --- names and flat values ----------------------------------------------------------------

TEST(FeatureMetrics, LettersFlatValuesAndFlatReference)
{
    EXPECT_EQ(invariantLetter(Invariant::Volume), 'V');
    EXPECT_EQ(invariantLetter(Invariant::Sphere), 'S');
    EXPECT_EQ(invariantLetter(Invariant::Patch), 'P');
    EXPECT_EQ(invariantLetter(Invariant::Line), 'L');
    EXPECT_EQ(flatValue(Invariant::Volume), 0.5);
    EXPECT_EQ(flatValue(Invariant::Sphere), 0.5);
    EXPECT_EQ(flatValue(Invariant::Patch), 1.0);
    EXPECT_EQ(flatValue(Invariant::Line), 1.0);

    FeatureTable t;
    t.blocks = {{Invariant::Patch, 2}, {Invariant::Sphere, 1}, {Invariant::Line, 1}, {Invariant::Volume, 2}};
    EXPECT_EQ(t.dimension(), 6u);
    EXPECT_EQ(flatReference(t), (std::vector<double>{1, 1, 0.5, 1, 0.5, 0.5}));
}

// --- Eq. 4–7: scale weights ---------------------------------------------------------------

TEST(FeatureMetrics, ScaleWeightsByHandForThreeScales)
{
    const std::vector<double> v = scaleWeights(Invariant::Volume, 3);
    ASSERT_EQ(v.size(), 3u);
    EXPECT_DOUBLE_EQ(v[0], 1.0 / 27);   // (1³ − 0³)/3³
    EXPECT_DOUBLE_EQ(v[1], 7.0 / 27);   // (2³ − 1³)/3³
    EXPECT_DOUBLE_EQ(v[2], 19.0 / 27);  // (3³ − 2³)/3³
    const std::vector<double> p = scaleWeights(Invariant::Patch, 3);
    ASSERT_EQ(p.size(), 3u);
    EXPECT_DOUBLE_EQ(p[0], 1.0 / 9);  // (1² − 0²)/3²
    EXPECT_DOUBLE_EQ(p[1], 3.0 / 9);  // (2² − 1²)/3²
    EXPECT_DOUBLE_EQ(p[2], 5.0 / 9);  // (3² − 2²)/3²
    for (Invariant inv : {Invariant::Sphere, Invariant::Line}) {
        const std::vector<double> s = scaleWeights(inv, 3);
        ASSERT_EQ(s.size(), 3u);
        for (double w : s) EXPECT_DOUBLE_EQ(w, 1.0 / 3);
    }
}

TEST(FeatureMetrics, ScaleWeightsOfOneScaleAreOne)
{
    for (Invariant inv : {Invariant::Volume, Invariant::Sphere, Invariant::Patch, Invariant::Line}) {
        EXPECT_EQ(scaleWeights(inv, 1), std::vector<double>{1.0});
        EXPECT_EQ(weightError(scaleWeights(inv, 1)), 0.0);
    }
}

TEST(FeatureMetrics, ScaleWeightsSumToOneWithinTheirReportedError)
{
    for (Invariant inv : {Invariant::Volume, Invariant::Sphere, Invariant::Patch, Invariant::Line}) {
        for (int n : {3, 16, 1000}) {
            const std::vector<double> w = scaleWeights(inv, n);
            ASSERT_EQ(w.size(), std::size_t(n));
            double sum = 0;
            for (double x : w) {
                EXPECT_GT(x, 0);
                sum += x;
            }
            const double eps = weightError(w);  // Eq. 7
            EXPECT_EQ(std::abs(1.0 - sum), std::abs(eps)) << invariantLetter(inv) << " n = " << n;
            EXPECT_LT(std::abs(eps), 1e-12) << invariantLetter(inv) << " n = " << n;
        }
    }
    // V grows with the shell volume, P with the ring area: ascending; the last V weight of
    // n = 16 is (16³ − 15³)/16³.
    const std::vector<double> v16 = scaleWeights(Invariant::Volume, 16);
    EXPECT_DOUBLE_EQ(v16[15], (4096.0 - 3375.0) / 4096.0);
    EXPECT_TRUE(std::is_sorted(v16.begin(), v16.end()));
    EXPECT_DOUBLE_EQ(scaleWeights(Invariant::Patch, 16)[15], (256.0 - 225.0) / 256.0);
}

// --- Eq. 9–10: dependency matrices --------------------------------------------------------

TEST(FeatureMetrics, DependencyMatrixColumnsSumToOneAndAreUpperTriangular)
{
    for (Invariant inv : {Invariant::Volume, Invariant::Patch}) {
        for (int n : {1, 3, 16}) {
            const std::vector<double> w = dependencyMatrix(inv, n);
            ASSERT_EQ(w.size(), std::size_t(n * n));
            for (int k = 0; k < n; ++k) {
                double column = 0;
                for (int j = 0; j < n; ++j) {
                    if (j > k) {
                        EXPECT_EQ(w[j * n + k], 0.0) << "below the diagonal";
                    }
                    column += w[j * n + k];
                }
                EXPECT_NEAR(column, 1.0, 1e-12) << invariantLetter(inv) << " n = " << n << " column " << k;
                // Column k holds the scale weights of Eq. 4/6 for k + 1 scales.
                const std::vector<double> wk = scaleWeights(inv, k + 1);
                for (int j = 0; j <= k; ++j) EXPECT_NEAR(w[j * n + k], wk[j], 1e-15);
            }
        }
    }
    // n = 3 by hand (1-based w_{j,k} = a_j / b_k).
    const std::vector<double> v = dependencyMatrix(Invariant::Volume, 3);
    const std::vector<double> vExpected = {1, 1.0 / 8, 1.0 / 27,  //
                                           0, 7.0 / 8, 7.0 / 27,  //
                                           0, 0,       19.0 / 27};
    for (std::size_t i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(v[i], vExpected[i]) << i;
    const std::vector<double> p = dependencyMatrix(Invariant::Patch, 3);
    const std::vector<double> pExpected = {1, 1.0 / 4, 1.0 / 9,  //
                                           0, 3.0 / 4, 3.0 / 9,  //
                                           0, 0,       5.0 / 9};
    for (std::size_t i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(p[i], pExpected[i]) << i;
    for (Invariant inv : {Invariant::Sphere, Invariant::Line}) {
        const std::vector<double> id = dependencyMatrix(inv, 3);
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) EXPECT_EQ(id[j * 3 + k], j == k ? 1.0 : 0.0);
    }
}

// --- every metric by hand -----------------------------------------------------------------

TEST(FeatureMetrics, PNormsByHand)
{
    const FeatureTable t = smallTable();
    const std::vector<double> flat = flatReference(t);
    // Weights: V 1/27, 7/27, 19/27; P 1/9, 3/9, 5/9. Terms with d = 0 are left out.
    struct Case {
        double p;
        bool weighted;
        std::vector<double> expected;
    };
    const std::vector<Case> cases = {
        {1, false,
         {0.125 + 0.125 + 0.25 + 0.25,  //
          0.25 + 0.125 + 0.5 + 0.25,    //
          0.25 + 0.125 + 0.5 + 0.25 + 0.125}},
        {2, false,
         {std::sqrt(0.125 * 0.125 + 0.125 * 0.125 + 0.25 * 0.25 + 0.25 * 0.25),
          std::sqrt(0.25 * 0.25 + 0.125 * 0.125 + 0.5 * 0.5 + 0.25 * 0.25),
          std::sqrt(0.25 * 0.25 + 0.125 * 0.125 + 0.5 * 0.5 + 0.25 * 0.25 + 0.125 * 0.125)}},
        {3, false,
         {std::cbrt(2 * 0.125 * 0.125 * 0.125 + 2 * 0.25 * 0.25 * 0.25),
          std::cbrt(0.25 * 0.25 * 0.25 + 0.125 * 0.125 * 0.125 + 0.5 * 0.5 * 0.5 + 0.25 * 0.25 * 0.25),
          std::cbrt(0.25 * 0.25 * 0.25 + 0.125 * 0.125 * 0.125 + 0.5 * 0.5 * 0.5 + 0.25 * 0.25 * 0.25 +
                    0.125 * 0.125 * 0.125)}},
        {kInf, false, {0.25, 0.5, 0.5}},
        {1, true,
         {0.125 / 27 + 0.125 * 19 / 27 + 0.25 / 9 + 0.25 * 5 / 9,
          0.25 / 27 + 0.125 * 7 / 27 + 0.5 / 9 + 0.25 * 3 / 9,
          0.25 / 27 + 0.125 * 7 / 27 + 0.5 / 9 + 0.25 * 3 / 9 + 0.125 * 5 / 9}},
        {2, true,
         {std::sqrt(0.125 * 0.125 / 27 + 0.125 * 0.125 * 19 / 27 + 0.25 * 0.25 / 9 + 0.25 * 0.25 * 5 / 9),
          std::sqrt(0.25 * 0.25 / 27 + 0.125 * 0.125 * 7 / 27 + 0.5 * 0.5 / 9 + 0.25 * 0.25 * 3 / 9),
          std::sqrt(0.25 * 0.25 / 27 + 0.125 * 0.125 * 7 / 27 + 0.5 * 0.5 / 9 + 0.25 * 0.25 * 3 / 9 +
                    0.125 * 0.125 * 5 / 9)}},
        {3, true,
         {std::cbrt(0.125 * 0.125 * 0.125 / 27 + 0.125 * 0.125 * 0.125 * 19 / 27 + 0.25 * 0.25 * 0.25 / 9 +
                    0.25 * 0.25 * 0.25 * 5 / 9),
          std::cbrt(0.25 * 0.25 * 0.25 / 27 + 0.125 * 0.125 * 0.125 * 7 / 27 + 0.5 * 0.5 * 0.5 / 9 +
                    0.25 * 0.25 * 0.25 * 3 / 9),
          std::cbrt(0.25 * 0.25 * 0.25 / 27 + 0.125 * 0.125 * 0.125 * 7 / 27 + 0.5 * 0.5 * 0.5 / 9 +
                    0.25 * 0.25 * 0.25 * 3 / 9 + 0.125 * 0.125 * 0.125 * 5 / 9)}},
        {kInf, true,
         {std::max({0.125 / 27, 0.125 * 19 / 27, 0.25 / 9, 0.25 * 5 / 9}),
          std::max({0.25 / 27, 0.125 * 7 / 27, 0.5 / 9, 0.25 * 3 / 9}),
          std::max({0.25 / 27, 0.125 * 7 / 27, 0.5 / 9, 0.25 * 3 / 9, 0.125 * 5 / 9})}},
        // 0 < p < 1, a half-integer and a general p (each its own code path).
        {0.5, false,
         {std::pow(2 * std::sqrt(0.125) + 2 * std::sqrt(0.25), 2),
          std::pow(std::sqrt(0.25) + std::sqrt(0.125) + std::sqrt(0.5) + std::sqrt(0.25), 2),
          std::pow(std::sqrt(0.25) + std::sqrt(0.125) + std::sqrt(0.5) + std::sqrt(0.25) + std::sqrt(0.125), 2)}},
        {2.5, true,
         {std::pow(std::pow(0.125, 2.5) / 27 + std::pow(0.125, 2.5) * 19 / 27 + std::pow(0.25, 2.5) / 9 +
                       std::pow(0.25, 2.5) * 5 / 9,
                   1 / 2.5),
          std::pow(std::pow(0.25, 2.5) / 27 + std::pow(0.125, 2.5) * 7 / 27 + std::pow(0.5, 2.5) / 9 +
                       std::pow(0.25, 2.5) * 3 / 9,
                   1 / 2.5),
          std::pow(std::pow(0.25, 2.5) / 27 + std::pow(0.125, 2.5) * 7 / 27 + std::pow(0.5, 2.5) / 9 +
                       std::pow(0.25, 2.5) * 3 / 9 + std::pow(0.125, 2.5) * 5 / 9,
                   1 / 2.5)}},
        {2.7, false,
         {std::pow(2 * std::pow(0.125, 2.7) + 2 * std::pow(0.25, 2.7), 1 / 2.7),
          std::pow(std::pow(0.25, 2.7) + std::pow(0.125, 2.7) + std::pow(0.5, 2.7) + std::pow(0.25, 2.7), 1 / 2.7),
          std::pow(std::pow(0.25, 2.7) + std::pow(0.125, 2.7) + std::pow(0.5, 2.7) + std::pow(0.25, 2.7) +
                       std::pow(0.125, 2.7),
                   1 / 2.7)}},
    };
    for (const Case& c : cases) {
        const MetricResult r = computeMetric(t, flat, pNorm(c.p, c.weighted));
        expectValues(r, c.expected, (std::string(c.weighted ? "weighted " : "") + "p = " + std::to_string(c.p)).c_str());
    }
    // The flat reference is at distance 0 from itself.
    FeatureTable flatTable = t;
    flatTable.numVertices = 1;
    flatTable.values = {0.5f, 0.5f, 0.5f, 1.0f, 1.0f, 1.0f};
    EXPECT_EQ(computeMetric(flatTable, flat, pNorm(2, false)).values[0], 0.0f);
}

TEST(FeatureMetrics, MahalanobisByHand)
{
    // q = Σ_j Σ_{k≥j} d_j w_{j,k} d_k with W of Eq. 9 (V: 1, 1/8, 1/27; 7/8, 7/27; 19/27) and
    // Eq. 10 (P: 1, 1/4, 1/9; 3/4, 3/9; 5/9); terms with d = 0 are left out.
    const FeatureTable t = smallTable();
    // Vertex 0 has mixed signs, d = (0.125, 0, −0.125 | 0.25, 0, −0.25): the cross terms
    // are negative, the form stays positive.
    const double q0 = 0.125 * 0.125 * 1 + 0.125 * (-0.125) / 27 + (-0.125) * (-0.125) * 19 / 27  //
                      + 0.25 * 0.25 * 1 + 0.25 * (-0.25) / 9 + (-0.25) * (-0.25) * 5 / 9;
    const double q1 = (-0.25) * (-0.25) * 1 + (-0.25) * (-0.125) / 8 + (-0.125) * (-0.125) * 7 / 8  //
                      + (-0.5) * (-0.5) * 1 + (-0.5) * (-0.25) / 4 + (-0.25) * (-0.25) * 3 / 4;
    const double q2 = 0.25 * 0.25 * 1 + 0.25 * 0.125 / 8 + 0.125 * 0.125 * 7 / 8  //
                      + 0.5 * 0.5 * 1 + 0.5 * 0.25 / 4 + 0.5 * 0.125 / 9 + 0.25 * 0.25 * 3 / 4 +
                      0.25 * 0.125 * 3 / 9 + 0.125 * 0.125 * 5 / 9;
    EXPECT_LT(q0, 0.125 * 0.125 * (1 + 19.0 / 27) + 0.25 * 0.25 * (1 + 5.0 / 9));  // the cross terms lower it
    const MetricResult r = computeMetric(t, flatReference(t), kindOnly(MetricKind::Mahalanobis));
    expectValues(r, {std::sqrt(q0), std::sqrt(q1), std::sqrt(q2)}, "Mahalanobis");

    // S and L blocks use the identity: q = Σ d².
    FeatureTable sl;
    sl.blocks = {{Invariant::Sphere, 2}, {Invariant::Line, 2}};
    sl.numVertices = 1;
    sl.values = {0.75f, 0.25f, 1.5f, 0.5f};
    const MetricResult rsl = computeMetric(sl, flatReference(sl), kindOnly(MetricKind::Mahalanobis));
    expectValues(rsl, {std::sqrt(0.25 * 0.25 + 0.25 * 0.25 + 0.5 * 0.5 + 0.5 * 0.5)}, "Mahalanobis S, L");
}

TEST(FeatureMetrics, MahalanobisMatchesTheFullMatrixAndIsNeverNegative)
{
    // Eq. 11 straight from dependencyMatrix() (O(n²)) against the implementation's suffix
    // sums, for mixed-sign differences. The symmetric part of W (Eq. 9/10) is positive
    // definite (smallest eigenvalue ≈ 1.5/n for V, 1/n for P), so no real difference gives
    // q < 0 and the −sqrt(−q) branch is not reachable from these matrices:
    // numNegativeForms stays 0.
    const std::vector<FeatureBlock> blocks = {{Invariant::Volume, 16}, {Invariant::Patch, 16},
                                              {Invariant::Sphere, 4}, {Invariant::Volume, 1}};
    const FeatureTable t = randomTable(400, blocks, 11);
    const std::vector<double> o = flatReference(t);
    const MetricResult r = computeMetric(t, o, kindOnly(MetricKind::Mahalanobis));
    EXPECT_EQ(r.numNegativeForms, 0u);
    const std::size_t dim = t.dimension();
    std::size_t checked = 0;
    for (std::size_t i = 0; i < t.numVertices; ++i) {
        const float* x = &t.values[i * dim];
        if (std::any_of(x, x + dim, [](float v) { return std::isnan(v); })) {
            EXPECT_TRUE(std::isnan(r.values[i]));
            continue;
        }
        double q = 0;
        std::size_t off = 0;
        for (const FeatureBlock& b : blocks) {
            const std::size_t n = std::size_t(b.count);
            const std::vector<double> w = dependencyMatrix(b.invariant, b.count);
            for (std::size_t j = 0; j < n; ++j)
                for (std::size_t k = 0; k < n; ++k)
                    q += (x[off + j] - o[off + j]) * w[j * n + k] * (x[off + k] - o[off + k]);
            off += n;
        }
        ASSERT_GT(q, 0);
        EXPECT_NEAR(r.values[i], std::sqrt(q), 1e-6 * std::sqrt(q)) << i;
        ++checked;
    }
    EXPECT_GT(checked, 390u);
}

TEST(FeatureMetrics, CosineAndTanimotoByHand)
{
    // Reference: vertex 2's values, centred õ = (0.25, 0.125, 0 | 0.5, 0.25, 0.125).
    const FeatureTable t = smallTable();
    const std::vector<double> o = {0.75, 0.625, 0.5, 1.5, 1.25, 1.125};
    const double oo = 0.25 * 0.25 + 0.125 * 0.125 + 0.5 * 0.5 + 0.25 * 0.25 + 0.125 * 0.125;  // |õ|²
    // x̃·õ and |x̃|² of vertices 0 and 1 (x̃ = d of smallTable()).
    const double xo0 = 0.125 * 0.25 + 0 * 0.125 + (-0.125) * 0 + 0.25 * 0.5 + 0 * 0.25 + (-0.25) * 0.125;
    const double xx0 = 0.125 * 0.125 + 0.125 * 0.125 + 0.25 * 0.25 + 0.25 * 0.25;
    const double xo1 = (-0.25) * 0.25 + (-0.125) * 0.125 + 0 * 0 + (-0.5) * 0.5 + (-0.25) * 0.25 + 0 * 0.125;
    const double xx1 = 0.25 * 0.25 + 0.125 * 0.125 + 0.5 * 0.5 + 0.25 * 0.25;

    const MetricResult c = computeMetric(t, o, kindOnly(MetricKind::Cosine));
    expectValues(c, {xo0 / std::sqrt(xx0 * oo), xo1 / std::sqrt(xx1 * oo), 1.0}, "cosine");
    const MetricResult tn = computeMetric(t, o, kindOnly(MetricKind::Tanimoto));
    expectValues(tn, {xo0 / (xx0 + oo - xo0), xo1 / (xx1 + oo - xo1), oo / (oo + oo - oo)}, "Tanimoto");
}

TEST(FeatureMetrics, CorrelationByHand)
{
    const FeatureTable t = smallTable();
    const std::vector<double> o = {0, 1, 2, 3, 4, 5};  // mean 2.5
    const double oo = 2.5 * 2.5 + 1.5 * 1.5 + 0.5 * 0.5 + 0.5 * 0.5 + 1.5 * 1.5 + 2.5 * 2.5;
    const double m0 = (0.625 + 0.5 + 0.375 + 1.25 + 1.0 + 0.75) / 6;
    const double r0 = ((0.625 - m0) * -2.5 + (0.5 - m0) * -1.5 + (0.375 - m0) * -0.5 + (1.25 - m0) * 0.5 +
                       (1.0 - m0) * 1.5 + (0.75 - m0) * 2.5) /
                      std::sqrt(((0.625 - m0) * (0.625 - m0) + (0.5 - m0) * (0.5 - m0) + (0.375 - m0) * (0.375 - m0) +
                                 (1.25 - m0) * (1.25 - m0) + (1.0 - m0) * (1.0 - m0) + (0.75 - m0) * (0.75 - m0)) *
                                oo);
    const double m1 = (0.25 + 0.375 + 0.5 + 0.5 + 0.75 + 1.0) / 6;
    const double r1 = ((0.25 - m1) * -2.5 + (0.375 - m1) * -1.5 + (0.5 - m1) * -0.5 + (0.5 - m1) * 0.5 +
                       (0.75 - m1) * 1.5 + (1.0 - m1) * 2.5) /
                      std::sqrt(((0.25 - m1) * (0.25 - m1) + (0.375 - m1) * (0.375 - m1) + (0.5 - m1) * (0.5 - m1) +
                                 (0.5 - m1) * (0.5 - m1) + (0.75 - m1) * (0.75 - m1) + (1.0 - m1) * (1.0 - m1)) *
                                oo);
    const double m2 = (0.75 + 0.625 + 0.5 + 1.5 + 1.25 + 1.125) / 6;
    const double r2 = ((0.75 - m2) * -2.5 + (0.625 - m2) * -1.5 + (0.5 - m2) * -0.5 + (1.5 - m2) * 0.5 +
                       (1.25 - m2) * 1.5 + (1.125 - m2) * 2.5) /
                      std::sqrt(((0.75 - m2) * (0.75 - m2) + (0.625 - m2) * (0.625 - m2) + (0.5 - m2) * (0.5 - m2) +
                                 (1.5 - m2) * (1.5 - m2) + (1.25 - m2) * (1.25 - m2) + (1.125 - m2) * (1.125 - m2)) *
                                oo);
    const MetricResult r = computeMetric(t, o, kindOnly(MetricKind::Correlation));
    expectValues(r, {r0, r1, r2}, "correlation");
    // Against itself: 1.
    EXPECT_NEAR(computeMetric(t, vertexReference(t, 1), kindOnly(MetricKind::Correlation)).values[1], 1.0, kTol);
}

TEST(FeatureMetrics, AutoCorrelationByHand)
{
    const FeatureTable t = smallTable();
    const std::vector<double> o = {0, 0.5, 0, 1, 0, 1};
    // Lag-1 autocorrelation of three values a, b, c about their mean m.
    const auto r1 = [](double a, double b, double c) {
        const double m = (a + b + c) / 3;
        return ((a - m) * (b - m) + (b - m) * (c - m)) / ((a - m) * (a - m) + (b - m) * (b - m) + (c - m) * (c - m));
    };
    // d = x − o per block, then the mean over the two blocks.
    const double f0 = (r1(0.625 - 0, 0.5 - 0.5, 0.375 - 0) + r1(1.25 - 1, 1.0 - 0, 0.75 - 1)) / 2;
    const double f1 = (r1(0.25 - 0, 0.375 - 0.5, 0.5 - 0) + r1(0.5 - 1, 0.75 - 0, 1.0 - 1)) / 2;
    const double f2 = (r1(0.75 - 0, 0.625 - 0.5, 0.5 - 0) + r1(1.5 - 1, 1.25 - 0, 1.125 - 1)) / 2;
    const MetricResult r = computeMetric(t, o, kindOnly(MetricKind::AutoCorrelation));
    expectValues(r, {f0, f1, f2}, "auto-correlation");
    // The helper itself, written out for V of vertex 0: m = 1/3, deviations 7/24, −1/3, 1/24.
    EXPECT_NEAR(r1(0.625, 0, 0.375),
                ((7.0 / 24) * (-1.0 / 3) + (-1.0 / 3) * (1.0 / 24)) /
                    ((7.0 / 24) * (7.0 / 24) + (1.0 / 3) * (1.0 / 3) + (1.0 / 24) * (1.0 / 24)),
                1e-12);

    // Blocks of one element are skipped: adding an S×1 block changes nothing.
    FeatureTable t2 = smallTable();
    t2.blocks.push_back({Invariant::Sphere, 1});
    t2.values = {0.625f, 0.5f,   0.375f, 1.25f, 1.0f,  0.75f,  0.5f,  //
                 0.25f,  0.375f, 0.5f,   0.5f,  0.75f, 1.0f,   0.75f, //
                 0.75f,  0.625f, 0.5f,   1.5f,  1.25f, 1.125f, 0.25f};
    std::vector<double> o2 = o;
    o2.push_back(0.5);
    expectValues(computeMetric(t2, o2, kindOnly(MetricKind::AutoCorrelation)), {f0, f1, f2},
                 "auto-correlation with an S×1 block");
}

TEST(FeatureMetrics, NormalizedEuclideanByHand)
{
    const FeatureTable t = smallTable();
    // Population variance of one element over the three vertices.
    const auto var3 = [](double a, double b, double c) {
        const double m = (a + b + c) / 3;
        return ((a - m) * (a - m) + (b - m) * (b - m) + (c - m) * (c - m)) / 3;
    };
    const double v1 = var3(0.625, 0.25, 0.75), v2 = var3(0.5, 0.375, 0.625), v3 = var3(0.375, 0.5, 0.5);
    const double p1 = var3(1.25, 0.5, 1.5), p2 = var3(1.0, 0.75, 1.25), p3 = var3(0.75, 1.0, 1.125);
    const double f0 = std::sqrt(0.125 * 0.125 / v1 + 0 / v2 + 0.125 * 0.125 / v3 + 0.25 * 0.25 / p1 + 0 / p2 +
                                0.25 * 0.25 / p3);
    const double f1 = std::sqrt(0.25 * 0.25 / v1 + 0.125 * 0.125 / v2 + 0 / v3 + 0.5 * 0.5 / p1 +
                                0.25 * 0.25 / p2 + 0 / p3);
    const double f2 = std::sqrt(0.25 * 0.25 / v1 + 0.125 * 0.125 / v2 + 0 / v3 + 0.5 * 0.5 / p1 +
                                0.25 * 0.25 / p2 + 0.125 * 0.125 / p3);
    const MetricResult r = computeMetric(t, flatReference(t), kindOnly(MetricKind::NormalizedEuclidean));
    expectValues(r, {f0, f1, f2}, "normalised Euclidean");

    // A fourth vertex with a NaN: f NaN there, and it does not enter the variances.
    FeatureTable t4 = smallTable();
    t4.numVertices = 4;
    t4.values.insert(t4.values.end(), {0.0f, 0.0f, float(kNaN), 9.0f, 9.0f, 9.0f});
    const MetricResult r4 = computeMetric(t4, flatReference(t4), kindOnly(MetricKind::NormalizedEuclidean));
    EXPECT_NEAR(r4.values[0], f0, kTol);
    EXPECT_NEAR(r4.values[1], f1, kTol);
    EXPECT_NEAR(r4.values[2], f2, kTol);
    EXPECT_TRUE(std::isnan(r4.values[3]));
    EXPECT_EQ(r4.numUndefined, 1u);

    // An element constant over all vertices (σ = 0) is skipped.
    FeatureTable s;
    s.blocks = {{Invariant::Sphere, 2}};
    s.numVertices = 3;
    s.values = {0.75f, 0.25f, 0.75f, 0.5f, 0.75f, 0.75f};  // S_01 constant, S_02 = 0.25, 0.5, 0.75
    const double varS2 = ((0.25 - 0.5) * (0.25 - 0.5) + 0 + (0.75 - 0.5) * (0.75 - 0.5)) / 3;
    expectValues(computeMetric(s, flatReference(s), kindOnly(MetricKind::NormalizedEuclidean)),
                 {std::sqrt(0.25 * 0.25 / varS2), 0.0, std::sqrt(0.25 * 0.25 / varS2)}, "σ = 0 skipped");
}

// --- references ---------------------------------------------------------------------------

TEST(FeatureMetrics, ReferenceByVertexEqualsReferenceByVector)
{
    const FeatureTable t = smallTable();
    const std::vector<double> byVertex = vertexReference(t, 1);
    const std::vector<double> byVector = {0.25, 0.375, 0.5, 0.5, 0.75, 1.0};
    EXPECT_EQ(byVertex, byVector);
    for (MetricKind kind : {MetricKind::PNorm, MetricKind::Mahalanobis, MetricKind::Cosine, MetricKind::Correlation,
                            MetricKind::AutoCorrelation, MetricKind::Tanimoto, MetricKind::NormalizedEuclidean}) {
        const MetricResult a = computeMetric(t, byVertex, kindOnly(kind));
        const MetricResult b = computeMetric(t, byVector, kindOnly(kind));
        ASSERT_EQ(a.values.size(), 3u);
        for (std::size_t i = 0; i < 3; ++i) {
            if (std::isnan(a.values[i])) {
                EXPECT_TRUE(std::isnan(b.values[i]));
            } else {
                EXPECT_EQ(a.values[i], b.values[i]) << int(kind) << " vertex " << i;
            }
        }
    }
    // The distance of the reference vertex to itself is 0.
    EXPECT_EQ(computeMetric(t, byVertex, kindOnly(MetricKind::Mahalanobis)).values[1], 0.0f);
    EXPECT_EQ(computeMetric(t, byVertex, pNorm(kInf, true)).values[1], 0.0f);
}

TEST(FeatureMetrics, NearestVertex)
{
    TriMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    EXPECT_EQ(nearestVertex(mesh, {0.1, 0.1, 0.1}), 0u);
    EXPECT_EQ(nearestVertex(mesh, {0.2, 0.9, -0.3}), 2u);
    EXPECT_EQ(nearestVertex(mesh, {0, 0, 5}), 3u);
    EXPECT_EQ(nearestVertex(mesh, {0.9, 0, 0}), 1u);  // vertex 4 is at the same place: lowest index
    TriMesh empty;
    EXPECT_THROW(nearestVertex(empty, {0, 0, 0}), InvalidInputError);
}

// --- NaN and undefined values -------------------------------------------------------------

TEST(FeatureMetrics, NaNElementGivesNaNAndIsCounted)
{
    FeatureTable t = smallTable();
    t.values[6 + 4] = float(kNaN);  // vertex 1, P_02
    const std::vector<double> o = {0, 0.5, 0, 1, 0, 1};  // usable by every metric, no vertex is undefined
    std::vector<MetricOptions> all;
    for (MetricKind kind : {MetricKind::Mahalanobis, MetricKind::Cosine, MetricKind::Correlation,
                            MetricKind::AutoCorrelation, MetricKind::Tanimoto, MetricKind::NormalizedEuclidean})
        all.push_back(kindOnly(kind));
    for (double p : {0.5, 1.0, 2.0, 2.5, 2.7, 3.0, kInf})
        for (bool w : {false, true}) all.push_back(pNorm(p, w));
    for (const MetricOptions& opt : all) {
        const MetricResult r = computeMetric(t, o, opt);
        EXPECT_FALSE(std::isnan(r.values[0])) << int(opt.kind) << " p " << opt.p;
        EXPECT_TRUE(std::isnan(r.values[1])) << int(opt.kind) << " p " << opt.p;
        EXPECT_FALSE(std::isnan(r.values[2])) << int(opt.kind) << " p " << opt.p;
        EXPECT_EQ(r.numUndefined, 1u) << int(opt.kind) << " p " << opt.p;
        EXPECT_EQ(r.weightErrors.size(), 2u);
    }
    EXPECT_THROW(vertexReference(t, 1), InvalidInputError);
}

TEST(FeatureMetrics, ZeroVarianceVerticesAreUndefined)
{
    FeatureTable t;
    t.blocks = {{Invariant::Volume, 3}, {Invariant::Patch, 3}};
    t.numVertices = 3;
    t.values = {0.5f,  0.5f,  0.5f,  1.0f, 1.0f, 1.0f,   // the flat surface: x̃ = 0
                0.75f, 0.75f, 0.75f, 0.75f, 0.75f, 0.75f,  // all elements equal
                0.75f, 0.5f,  0.25f, 1.5f, 1.0f, 0.5f};
    const std::vector<double> o = {0.75, 0.625, 0.5, 1.5, 1.25, 1.125};

    const MetricResult c = computeMetric(t, o, kindOnly(MetricKind::Cosine));
    EXPECT_TRUE(std::isnan(c.values[0]));  // no direction
    EXPECT_EQ(c.numUndefined, 1u);
    const MetricResult tn = computeMetric(t, o, kindOnly(MetricKind::Tanimoto));
    EXPECT_EQ(tn.values[0], 0.0f);  // 0 / (0 + |õ|² − 0): defined
    EXPECT_EQ(tn.numUndefined, 0u);
    const MetricResult corr = computeMetric(t, o, kindOnly(MetricKind::Correlation));
    EXPECT_TRUE(std::isnan(corr.values[1]));  // zero variance
    EXPECT_EQ(corr.numUndefined, 1u);

    // Auto-correlation: d = x − o constant within one block makes the vertex undefined. Against
    // o = (0.25, 0, −0.25 | 1, 0.5, 1), vertex 2's V block has d = (0.5, 0.5, 0.5); every
    // other block varies.
    const std::vector<double> o2 = {0.25, 0, -0.25, 1, 0.5, 1};
    const MetricResult ac = computeMetric(t, o2, kindOnly(MetricKind::AutoCorrelation));
    EXPECT_FALSE(std::isnan(ac.values[0]));
    EXPECT_FALSE(std::isnan(ac.values[1]));
    EXPECT_TRUE(std::isnan(ac.values[2]));
    EXPECT_EQ(ac.numUndefined, 1u);
}

// --- bad input ----------------------------------------------------------------------------

TEST(FeatureMetrics, BadInputThrows)
{
    const FeatureTable t = smallTable();
    const std::vector<double> flat = flatReference(t);
    const std::vector<double> o = {0.75, 0.625, 0.5, 1.5, 1.25, 1.125};
    const MetricOptions l2 = pNorm(2, false);

    EXPECT_THROW(computeMetric(t, std::vector<double>(5, 0.5), l2), InvalidInputError);  // wrong length
    EXPECT_THROW(computeMetric(t, std::vector<double>(7, 0.5), l2), InvalidInputError);
    std::vector<double> nanRef = o;
    nanRef[3] = kNaN;
    EXPECT_THROW(computeMetric(t, nanRef, l2), InvalidInputError);
    EXPECT_THROW(computeMetric(t, nanRef, kindOnly(MetricKind::Mahalanobis)), InvalidInputError);

    for (double p : {0.0, -1.0, -kInf, kNaN}) EXPECT_THROW(computeMetric(t, o, pNorm(p, false)), InvalidInputError) << p;
    EXPECT_NO_THROW(computeMetric(t, o, pNorm(0.25, true)));

    EXPECT_THROW(computeMetric(t, flat, kindOnly(MetricKind::Cosine)), InvalidInputError);
    EXPECT_THROW(computeMetric(t, flat, kindOnly(MetricKind::Tanimoto)), InvalidInputError);
    EXPECT_THROW(computeMetric(t, std::vector<double>(6, 0.75), kindOnly(MetricKind::Correlation)), InvalidInputError);
    EXPECT_THROW(computeMetric(t, std::vector<double>(6, 0.1), kindOnly(MetricKind::Correlation)), InvalidInputError);

    EXPECT_THROW(vertexReference(t, 3), InvalidInputError);
    EXPECT_THROW(vertexReference(t, std::size_t(-1)), InvalidInputError);
    EXPECT_THROW(scaleWeights(Invariant::Volume, 0), InvalidInputError);
    EXPECT_THROW(dependencyMatrix(Invariant::Patch, -1), InvalidInputError);

    // Auto-correlation needs a block of at least 2 elements.
    FeatureTable single;
    single.blocks = {{Invariant::Volume, 1}, {Invariant::Patch, 1}};
    single.numVertices = 1;
    single.values = {0.25f, 0.75f};
    EXPECT_THROW(computeMetric(single, {0.5, 0.5}, kindOnly(MetricKind::AutoCorrelation)), InvalidInputError);

    // The table itself.
    FeatureTable shortValues = t;
    shortValues.values.pop_back();
    EXPECT_THROW(computeMetric(shortValues, o, l2), InvalidInputError);
    EXPECT_THROW(vertexReference(shortValues, 0), InvalidInputError);
    FeatureTable emptyBlock = t;
    emptyBlock.blocks.push_back({Invariant::Line, 0});
    EXPECT_THROW(computeMetric(emptyBlock, o, l2), InvalidInputError);

    // Messages: one sentence naming the value.
    try {
        computeMetric(t, std::vector<double>(5, 0.5), l2);
        FAIL();
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("5"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("6"), std::string::npos) << e.what();
    }
    try {
        vertexReference(t, 3);
        FAIL();
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("vertex 3"), std::string::npos) << e.what();
    }
}

// --- result bookkeeping and threads -------------------------------------------------------

TEST(FeatureMetrics, WeightErrorsAreFilledPerBlock)
{
    const FeatureTable t = randomTable(10, {{Invariant::Volume, 16}, {Invariant::Patch, 7}, {Invariant::Line, 3}}, 3);
    const MetricResult r = computeMetric(t, flatReference(t), kindOnly(MetricKind::Mahalanobis));
    ASSERT_EQ(r.weightErrors.size(), 3u);
    EXPECT_EQ(r.weightErrors[0], weightError(scaleWeights(Invariant::Volume, 16)));
    EXPECT_EQ(r.weightErrors[1], weightError(scaleWeights(Invariant::Patch, 7)));
    EXPECT_EQ(r.weightErrors[2], weightError(scaleWeights(Invariant::Line, 3)));
    for (double eps : r.weightErrors) EXPECT_LT(std::abs(eps), 1e-12);

    FeatureTable none = t;
    none.numVertices = 0;
    none.values.clear();
    const MetricResult rn = computeMetric(none, flatReference(none), kindOnly(MetricKind::NormalizedEuclidean));
    EXPECT_TRUE(rn.values.empty());
    EXPECT_EQ(rn.weightErrors.size(), 3u);
}

TEST(FeatureMetrics, ResultsDoNotDependOnThreadCount)
{
    const FeatureTable t = randomTable(5000, {{Invariant::Volume, 16}, {Invariant::Patch, 16}}, 5);
    const std::vector<double> o = vertexReference(t, 0);
    std::vector<MetricOptions> all;
    for (MetricKind kind : {MetricKind::NormalizedEuclidean, MetricKind::Mahalanobis, MetricKind::Cosine,
                            MetricKind::Correlation, MetricKind::AutoCorrelation, MetricKind::Tanimoto})
        all.push_back(kindOnly(kind));
    all.push_back(pNorm(2.7, true));
    for (const MetricOptions& opt : all) {
        std::vector<float> one, two;
        {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
            one = computeMetric(t, o, opt).values;
        }
        {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
            two = computeMetric(t, o, opt).values;
        }
        ASSERT_EQ(one.size(), 5000u);
        ASSERT_EQ(two.size(), 5000u);
        EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(float)), 0) << int(opt.kind);
    }
}
