#include <msii/core/feature_set.h>

#include <msii/core/errors.h>

#include <algorithm>

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

std::vector<Invariant> parseInvariantList(const std::string& text)
{
    const auto separator = [](char c) { return c == ',' || c == ' ' || c == '\t'; };
    std::vector<Invariant> out;
    for (std::size_t i = 0; i < text.size();) {
        if (separator(text[i])) {
            ++i;
            continue;
        }
        std::size_t end = i;
        while (end < text.size() && !separator(text[end])) ++end;
        const std::string entry = text.substr(i, end - i);
        for (const char c : entry) {
            const std::optional<Invariant> inv = invariantOfLetter(c);
            if (!inv)
                throw InvalidInputError("unknown invariant '" + entry +
                                        "' (the invariants are V, S, P and L, written e.g. VSPL, V,S or v s)");
            if (std::find(out.begin(), out.end(), *inv) != out.end())
                throw InvalidInputError(std::string("the invariant ") + invariantLetter(*inv) + " is listed twice in '" +
                                        text + "'");
            out.push_back(*inv);
        }
        i = end;
    }
    if (out.empty()) throw InvalidInputError("the list of invariants selects nothing (choose any of V, S, P and L, e.g. VSPL or V,S)");
    return out;
}

std::string invariantLetters(const std::vector<Invariant>& invariants)
{
    std::string letters;
    for (Invariant i : invariants) letters += invariantLetter(i);
    return letters;
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
        for (const std::vector<float>& column : c)
            if (!column.empty()) return column.size();  // a radius not computed has an empty column
    return 0;
}

} // namespace msii
