#include <msii/io/feature_properties.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <utility>

namespace msii {

std::string featureName(char letter, std::size_t j)
{
    const std::string digits = std::to_string(j + 1);
    return std::string(1, letter) + (digits.size() < 2 ? "_0" : "_") + digits;
}

namespace {

/// featureProperties: the columns copied, or moved out of @p movable (the same set) where given.
std::vector<VertexProperty> propertiesOf(const FeatureSet& features, FeatureSet* movable)
{
    std::vector<VertexProperty> props;
    const std::vector<Invariant> invariants = features.invariants();
    const FeatureColumns* quality = invariants.empty() ? nullptr : &features[invariants.front()];
    // quality and valid_radii first (from the first invariant's columns, before they move),
    // placed after the columns.
    std::vector<VertexProperty> tail;
    if (quality) {
        const std::size_t nv = features.numVertices();
        VertexProperty value{"quality", std::vector<float>(nv, qualityStandIn(features))};
        VertexProperty count{"valid_radii", std::vector<float>(nv, 0.0f), /*integer=*/true};
        // The columns computed, largest radius first (a DEM's default bands compute four of N).
        std::vector<const float*> computed;
        for (std::size_t j = quality->size(); j-- > 0;)
            if (!(*quality)[j].empty()) computed.push_back((*quality)[j].data());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                int valid = 0;
                for (const float* column : computed)
                    if (!std::isnan(column[i]) && valid++ == 0) value.values[i] = column[i];
                count.values[i] = float(valid);
            }
        });
        tail.push_back(std::move(value));
        tail.push_back(std::move(count));
    }
    for (Invariant inv : invariants) {
        const FeatureColumns& columns = features[inv];
        for (std::size_t j = 0; j < columns.size(); ++j)
            if (!columns[j].empty())
                props.push_back({featureName(invariantLetter(inv), j), movable ? std::move((*movable)[inv][j]) : columns[j]});
    }
    for (VertexProperty& p : tail) props.push_back(std::move(p));
    return props;
}

} // namespace

std::vector<VertexProperty> featureProperties(const FeatureSet& features)
{
    return propertiesOf(features, nullptr);
}

std::vector<VertexProperty> featureProperties(FeatureSet&& features) { return propertiesOf(features, &features); }

std::vector<VertexProperty> outputProperties(const FeatureSet& features, std::vector<float> filledShare)
{
    std::vector<VertexProperty> props = featureProperties(features);
    if (!filledShare.empty()) props.push_back({"filled_share", std::move(filledShare)});
    return props;
}

std::vector<VertexProperty> outputProperties(FeatureSet&& features, std::vector<float> filledShare)
{
    std::vector<VertexProperty> props = featureProperties(std::move(features));
    if (!filledShare.empty()) props.push_back({"filled_share", std::move(filledShare)});
    return props;
}

std::vector<std::string> outputPropertyNames(const std::vector<Invariant>& invariants, int scales)
{
    std::vector<std::string> names;
    for (Invariant inv : invariants)
        for (int j = 0; j < scales; ++j) names.push_back(featureName(invariantLetter(inv), std::size_t(j)));
    if (!invariants.empty()) names.insert(names.end(), {"quality", "valid_radii"});
    names.push_back("filled_share");
    return names;
}

namespace {

std::string lowerCase(std::string text)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text;
}

/// "V_01 ... V_16, S_01 ... S_16, quality, ...": the names with runs of one letter shortened.
std::string shortList(const std::vector<std::string>& names)
{
    std::string out;
    for (std::size_t i = 0; i < names.size();) {
        std::size_t end = i + 1;
        const auto numbered = [&](std::size_t k) { return names[k].size() > 2 && names[k][1] == '_' && std::isdigit(names[k][2]); };
        while (numbered(i) && end < names.size() && numbered(end) && names[end][0] == names[i][0]) ++end;
        out += (out.empty() ? "" : ", ") + names[i] + (end - i > 1 ? " ... " + names[end - 1] : "");
        i = end;
    }
    return out;
}

} // namespace

std::vector<std::string> parseFeatureNames(const std::string& text, const std::vector<std::string>& available)
{
    std::vector<std::string> out;
    for (std::size_t i = 0; i < text.size();) {
        if (text[i] == ',' || text[i] == ' ' || text[i] == '\t') {
            ++i;
            continue;
        }
        const std::size_t end = std::min(text.find_first_of(", \t", i), text.size());
        const std::string name = text.substr(i, end - i);
        // A letter alone (V, S, P, L): that invariant at every radius, in order.
        if (name.size() == 1 && std::string("VSPLvspl").find(name[0]) != std::string::npos) {
            const char letter = char(std::toupper(static_cast<unsigned char>(name[0])));
            std::size_t added = 0;
            for (const std::string& a : available)
                if (a.size() > 2 && a[0] == letter && a[1] == '_') out.push_back(a), ++added;
            if (added > 0) {
                i = end;
                continue;
            }
        }
        const auto found = std::find_if(available.begin(), available.end(),
                                        [&](const std::string& a) { return lowerCase(a) == lowerCase(name); });
        if (found == available.end())
            throw InvalidInputError("there is no feature '" + name + "' (there are " + shortList(available) + ")");
        out.push_back(*found);
        i = end;
    }
    if (out.empty()) throw InvalidInputError("the list of features selects nothing (e.g. quality,V_04)");
    return out;
}

std::string invariantFormula(Invariant invariant)
{
    switch (invariant) {
    case Invariant::Volume: return "V/|B_r|";
    case Invariant::Sphere: return "S/(4 pi r^2)";
    case Invariant::Patch: return "P/(pi r^2)";
    case Invariant::Line: return "L/(2 pi r)";
    }
    return "";
}

std::string featureLegend()
{
    const auto entry = [](Invariant i) { return std::string(1, invariantLetter(i)) + "_jj = " + invariantFormula(i); };
    return entry(Invariant::Volume) + ", " + entry(Invariant::Sphere) + " (plane 0.5), " + entry(Invariant::Patch) +
           ", " + entry(Invariant::Line) + " (plane 1), r_j = j*R/N";
}

std::string invariantConvention(Invariant invariant)
{
    const bool share = invariant == Invariant::Volume || invariant == Invariant::Sphere;
    return invariantFormula(invariant) + (share ? " in [0,1], flat plane 0.5, convex < 0.5" : ", flat plane 1");
}

float qualityStandIn(const FeatureSet& features)
{
    for (Invariant inv : features.invariants())
        return inv == Invariant::Volume || inv == Invariant::Sphere ? 0.5f : 1.0f;
    return std::numeric_limits<float>::quiet_NaN();
}

std::string qualitySource(const FeatureSet& features)
{
    for (Invariant inv : features.invariants()) return featureName(invariantLetter(inv), features[inv].size() - 1);
    return "";
}

} // namespace msii
