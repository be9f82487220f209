#include <msii/io/feature_properties.h>

#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace msii {

std::string featureName(char letter, std::size_t j)
{
    const std::string digits = std::to_string(j + 1);
    return std::string(1, letter) + (digits.size() < 2 ? "_0" : "_") + digits;
}

std::vector<VertexProperty> featureProperties(const FeatureSet& features)
{
    std::vector<VertexProperty> props;
    const FeatureColumns* quality = nullptr;
    for (Invariant inv : features.invariants()) {
        const FeatureColumns* columns = &features[inv];
        for (std::size_t j = 0; j < columns->size(); ++j)
            props.push_back({featureName(invariantLetter(inv), j), (*columns)[j]});
        if (!quality) quality = columns;
    }
    if (quality) {
        const std::size_t nv = quality->back().size();
        VertexProperty value{"quality", std::vector<float>(nv, qualityStandIn(features))};
        VertexProperty count{"valid_radii", std::vector<float>(nv, 0.0f), /*integer=*/true};
        for (std::size_t i = 0; i < nv; ++i) {
            int valid = 0;
            for (std::size_t j = quality->size(); j-- > 0;)
                if (!std::isnan((*quality)[j][i])) {
                    if (valid++ == 0) value.values[i] = (*quality)[j][i];
                }
            count.values[i] = float(valid);
        }
        props.push_back(std::move(value));
        props.push_back(std::move(count));
    }
    return props;
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
