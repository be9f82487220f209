#include <msii/io/feature_properties.h>

#include <string>

namespace msii {

namespace {
/// "V_07": two digits at least (N > 99 gives three).
std::string numbered(const char* prefix, std::size_t j)
{
    const std::string digits = std::to_string(j);
    return std::string(prefix) + (digits.size() < 2 ? "_0" : "_") + digits;
}
} // namespace

std::vector<VertexProperty> featureProperties(const VolumeSphereResult& invariants)
{
    std::vector<VertexProperty> props;
    const std::size_t n = invariants.volume.size();
    for (std::size_t j = 0; j < n; ++j) props.push_back({numbered("V", j + 1), invariants.volume[j]});
    for (std::size_t j = 0; j < invariants.sphere.size(); ++j)
        props.push_back({numbered("S", j + 1), invariants.sphere[j]});
    if (n > 0) props.push_back({"quality", invariants.volume.back()});
    return props;
}

} // namespace msii
