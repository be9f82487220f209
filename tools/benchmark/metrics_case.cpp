/// @file metrics_case.cpp
/// @brief After compute, on the tablet's results: every metric over all computed features
/// against a vertex's vector (`msii metric`), and 30 passes of each 1-ring filter on quality
/// (`msii smooth`).
#include "benchmark.h"

#include <msii/core/stopwatch.h>
#include <msii/io/feature_table.h>
#include <msii/smoothing/ring_smoothing.h>

#include <cmath>
#include <limits>
#include <utility>

namespace msii::benchmark {

namespace {
/// One run of every metric over all computed features against a vertex's vector.
void timeMetrics(const FeatureTable& table, const std::vector<double>& reference, MetricRuns& m)
{
    for (MetricRow& row : m.metricRows) {
        const Stopwatch t;
        const MetricResult r = computeMetric(table, reference, row.options);
        row.seconds.push_back(t.seconds());
    }
}

/// One run of 30 passes of each 1-ring filter on @p quality, and of its set-up.
void timeSmoothing(const TriMesh& mesh, const std::vector<float>& quality, MetricRuns& m)
{
    for (const SmoothingFilter filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        SmoothingOptions so;
        so.filter = filter;
        so.iterations = 30;
        std::vector<float> values = quality;
        const Stopwatch setup;
        const RingSmoother smoother(mesh, so);
        const double setupSeconds = setup.seconds();
        const Stopwatch passes;
        smoother.smooth(values);
        (filter == SmoothingFilter::Mean ? m.ringSetupMean : m.ringSetupMedian).push_back(setupSeconds);
        (filter == SmoothingFilter::Mean ? m.ringMean : m.ringMedian).push_back(passes.seconds());
    }
}
} // namespace

FeatureTable featureTable(const Settings& s, const std::vector<VertexProperty>& props, std::size_t nv)
{
    std::vector<Invariant> all;
    for (const auto& [c, inv] : {std::pair{'V', Invariant::Volume}, std::pair{'S', Invariant::Sphere},
                                 std::pair{'P', Invariant::Patch}, std::pair{'L', Invariant::Line}})
        if (s.has(c)) all.push_back(inv);
    return featureTableOf(props, nv, all);
}

MetricRuns timeMetricsAndSmoothing(const Settings& s, const FeatureTable& table, std::size_t nv, const TriMesh& mesh,
                                   const std::vector<float>& quality)
{
    std::size_t refVertex = nv / 2;  // a vertex with no masked element, near the middle
    for (std::size_t i = nv / 2; i < nv; ++i) {
        const float* row = table.values.data() + i * table.dimension();
        if (std::none_of(row, row + table.dimension(), [](float v) { return std::isnan(v); })) {
            refVertex = i;
            break;
        }
    }
    const std::vector<double> reference = vertexReference(table, refVertex);
    const double inf = std::numeric_limits<double>::infinity();
    MetricRuns m;
    m.metricRows = {
        {"l1", {MetricKind::PNorm, 1, false}, {}},   {"l2w", {MetricKind::PNorm, 2, true}, {}},
        {"linfw", {MetricKind::PNorm, inf, true}, {}}, {"lp (p = 3)", {MetricKind::PNorm, 3, false}, {}},
        {"mahalanobis", {MetricKind::Mahalanobis, 2, false}, {}}, {"cosine", {MetricKind::Cosine, 2, false}, {}},
        {"correlation", {MetricKind::Correlation, 2, false}, {}},
        {"autocorrelation", {MetricKind::AutoCorrelation, 2, false}, {}},
        {"tanimoto", {MetricKind::Tanimoto, 2, false}, {}},
        {"neuclid", {MetricKind::NormalizedEuclidean, 2, false}, {}}};
    for (int run = 0; run < s.runs; ++run) {
        timeMetrics(table, reference, m);
        timeSmoothing(mesh, quality, m);
    }
    return m;
}

void printMetricRows(Report& report, const MetricRuns& metrics, std::size_t numFeatures)
{
    const std::string features = std::to_string(numFeatures) + " features";
    for (const MetricRow& m : metrics.metricRows)
        row(report, ("metric " + m.name + ", " + features).c_str(), median(m.seconds), "%8.2f");
    row(report, "1-ring set-up (mean)", median(metrics.ringSetupMean), "%8.2f");
    row(report, "1-ring mean, 30 passes", median(metrics.ringMean), "%8.2f");
    row(report, "1-ring set-up (median)", median(metrics.ringSetupMedian), "%8.2f");
    row(report, "1-ring median, 30 passes", median(metrics.ringMedian), "%8.2f");
}

} // namespace msii::benchmark
