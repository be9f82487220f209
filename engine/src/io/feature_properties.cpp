#include <msii/io/feature_properties.h>

#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace msii {

namespace {
std::array<std::pair<char, const FeatureColumns*>, 4> ordered(const Features& f)
{
    return {{{'V', f.volume}, {'S', f.sphere}, {'P', f.patch}, {'L', f.line}}};
}
} // namespace

Features featuresOf(const VolumeSphereResult& vs, const PatchLineResult& pl)
{
    return {&vs.volume, &vs.sphere, &pl.patch, &pl.line};
}

std::string featureName(char letter, std::size_t j)
{
    const std::string digits = std::to_string(j + 1);
    return std::string(1, letter) + (digits.size() < 2 ? "_0" : "_") + digits;
}

std::vector<VertexProperty> featureProperties(const Features& features)
{
    std::vector<VertexProperty> props;
    const FeatureColumns* quality = nullptr;
    for (const auto& [letter, columns] : ordered(features)) {
        if (!columns || columns->empty()) continue;
        for (std::size_t j = 0; j < columns->size(); ++j)
            props.push_back({featureName(letter, j), (*columns)[j]});
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

float qualityStandIn(const Features& features)
{
    for (const auto& [letter, columns] : ordered(features))
        if (columns && !columns->empty()) return letter == 'V' || letter == 'S' ? 0.5f : 1.0f;
    return std::numeric_limits<float>::quiet_NaN();
}

std::string qualitySource(const Features& features)
{
    for (const auto& [letter, columns] : ordered(features))
        if (columns && !columns->empty()) return featureName(letter, columns->size() - 1);
    return "";
}

} // namespace msii
