#include <msii/pipeline/masked_values.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <functional>
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
    const auto count = [&](auto&& counts) {
        return tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, n, 1 << 16), std::size_t(0),
            [&](const tbb::blocked_range<std::size_t>& range, std::size_t sum) {
                for (std::size_t k = range.begin(); k < range.end(); ++k)
                    if (const std::size_t i = rowOf(k); i != kNoRow) sum += counts(i);
                return sum;
            },
            std::plus<std::size_t>());
    };
    m.withFilledShare += count([&](std::size_t i) { return filledShare[i] > 0; });
    const FeatureColumns* columns = countedColumns(features);
    if (!columns) return;
    m.perRadius.resize(columns->size(), 0);
    for (std::size_t j = 0; j < columns->size(); ++j)
        if (!(*columns)[j].empty())  // a radius not computed (a DEM's bands need a few)
            m.perRadius[j] += count([&](std::size_t i) { return std::isnan((*columns)[j][i]); });
    m.vertices += count([](std::size_t) { return true; });
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
