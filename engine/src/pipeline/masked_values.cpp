#include <msii/pipeline/masked_values.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace msii {

namespace {

/// The columns counted: the first invariant present's (none if nothing was computed).
const FeatureColumns* countedColumns(const FeatureSet& features)
{
    const std::vector<Invariant> present = features.invariants();
    return present.empty() ? nullptr : &features[present.front()];
}

} // namespace

void MaskedValues::add(const FeatureSet& features, const std::vector<float>& filledShare)
{
    for (float s : filledShare) withFilledShare += s > 0;
    const FeatureColumns* columns = countedColumns(features);
    if (!columns) return;
    perRadius.resize(columns->size(), 0);
    for (std::size_t j = 0; j < columns->size(); ++j)
        for (float v : (*columns)[j]) perRadius[j] += std::isnan(v);
    vertices += features.numVertices();
}

namespace {

/// rowOf's "no row".
constexpr std::size_t kNoRow = std::numeric_limits<std::size_t>::max();

/// Adds to @p m the rows of @p features and @p filledShare that @p rowOf gives for k in
/// [0, n) (none where it gives kNoRow), in parallel: a DEM's window has millions of cells,
/// and counts add up alike in any order.
template <class RowOf>
void addRows(MaskedValues& m, const FeatureSet& features, const std::vector<float>& filledShare, std::size_t n,
             RowOf rowOf)
{
    const FeatureColumns* columns = countedColumns(features);
    const std::size_t radii = columns ? columns->size() : 0;
    // In one pass: the rows with a filled share, the NaN per radius computed (a DEM's bands
    // need a few radii; the others' columns are empty), and the rows.
    std::vector<const float*> counted;
    std::vector<std::size_t> radiusOf;
    for (std::size_t j = 0; j < radii; ++j)
        if (!(*columns)[j].empty()) counted.push_back((*columns)[j].data()), radiusOf.push_back(j);
    using Counts = std::vector<std::size_t>;  // withFilledShare, vertices, then per column counted
    const Counts sums = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, 1 << 16), Counts(2 + counted.size(), 0),
        [&](const tbb::blocked_range<std::size_t>& range, Counts c) {
            for (std::size_t k = range.begin(); k < range.end(); ++k) {
                const std::size_t i = rowOf(k);
                if (i == kNoRow) continue;
                c[0] += filledShare[i] > 0;
                ++c[1];
                for (std::size_t j = 0; j < counted.size(); ++j) c[2 + j] += std::isnan(counted[j][i]);
            }
            return c;
        },
        [](Counts a, const Counts& b) {
            for (std::size_t j = 0; j < a.size(); ++j) a[j] += b[j];
            return a;
        });
    m.withFilledShare += sums[0];
    if (!columns) return;
    m.perRadius.resize(radii, 0);
    for (std::size_t j = 0; j < counted.size(); ++j) m.perRadius[radiusOf[j]] += sums[2 + j];
    m.vertices += sums[1];
}

} // namespace

void MaskedValues::add(const FeatureSet& features, const std::vector<float>& filledShare,
                       const std::vector<std::uint32_t>& rows)
{
    addRows(*this, features, filledShare, rows.size(), [&](std::size_t k) { return std::size_t(rows[k]); });
}

void MaskedValues::addWhere(const FeatureSet& features, const std::vector<float>& filledShare, const std::vector<char>& counted)
{
    addRows(*this, features, filledShare, counted.size(), [&](std::size_t k) { return counted[k] ? k : kNoRow; });
}

std::size_t MaskedValues::total() const
{
    std::size_t sum = 0;
    for (std::size_t m : perRadius) sum += m;
    return sum;
}

std::optional<Diagnostic> MaskedValues::mostlyMasked(const std::vector<double>& radii) const
{
    if (vertices == 0 || radii.empty() || perRadius.size() != radii.size()) return std::nullopt;
    const auto share = [&](std::size_t j) { return double(perRadius[j]) / double(vertices); };
    const std::size_t last = radii.size() - 1;
    if (share(last) <= 0.5) return std::nullopt;
    std::ostringstream msg;
    msg << std::setprecision(3) << int(std::lround(100.0 * share(last)))
        << " % of the vertices are masked (NaN) at the largest radius " << radii[last]
        << ", as their ball reaches a border of the open mesh (its edge or holes); ";
    std::size_t kept = radii.size();  // the largest radius with at least half unmasked
    for (std::size_t j = 0; j < radii.size(); ++j)
        if (share(j) <= 0.5) kept = j;
    if (kept == radii.size())
        msg << "more than half are even at the smallest radius: fill the holes or use a much smaller largest radius";
    else
        msg << "at r = " << radii[kept] << " at least half have values: a smaller largest radius keeps more";
    return Diagnostic{"mostly_masked",
                      perRadius[last],
                      {{"masked_share", share(last)},
                       {"largest_radius", radii[last]},
                       {"radius_with_half", kept == radii.size() ? 0.0 : radii[kept]}},
                      msg.str()};
}

} // namespace msii
