#include <msii/core/feature_set.h>

namespace msii {

char invariantLetter(Invariant invariant)
{
    switch (invariant) {
    case Invariant::Volume: return 'V';
    case Invariant::Sphere: return 'S';
    case Invariant::Patch: return 'P';
    case Invariant::Line: return 'L';
    }
    return '?';
}

std::optional<Invariant> invariantOfLetter(char letter)
{
    switch (letter) {
    case 'V': case 'v': return Invariant::Volume;
    case 'S': case 's': return Invariant::Sphere;
    case 'P': case 'p': return Invariant::Patch;
    case 'L': case 'l': return Invariant::Line;
    default: return std::nullopt;
    }
}

std::vector<Invariant> FeatureSet::invariants() const
{
    std::vector<Invariant> out;
    for (Invariant i : kAllInvariants)
        if (has(i)) out.push_back(i);
    return out;
}

std::size_t FeatureSet::numVertices() const
{
    for (const FeatureColumns& c : columns)
        if (!c.empty()) return c.front().size();
    return 0;
}

} // namespace msii
