#pragma once
/// @file feature_set.h
/// @brief The shared vocabulary of results: the four invariants of paper Eq. 2 and the
/// per-vertex feature columns keyed by invariant and radius. Computation fills a FeatureSet;
/// io, metrics, smoothing, maps, the CLI and Python read it.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace msii {

/// The integral invariants (paper Eq. 2), each normalised so that a plane gives 1/2 (V, S)
/// or 1 (P, L) (docs/method.md, Normalisation).
enum class Invariant { Volume, Sphere, Patch, Line };

inline constexpr std::array<Invariant, 4> kAllInvariants{Invariant::Volume, Invariant::Sphere, Invariant::Patch,
                                                         Invariant::Line};

/// 'V', 'S', 'P' or 'L'.
char invariantLetter(Invariant invariant);
/// The invariant of letter 'V', 'S', 'P' or 'L' (either case); none for other characters.
std::optional<Invariant> invariantOfLetter(char letter);

/// Parses a list of invariants as users write it, the same for the command line, Python and
/// the JSON record: letters of V, S, P and L in any case, together or separated by commas or
/// spaces ("VSPL", "V,S,P,L", "v, s" and "vs" are alike); order kept, each at most once.
/// @throw InvalidInputError naming the entry that is not an invariant (or listed twice),
///        with the ones that are.
std::vector<Invariant> parseInvariantList(const std::string& text);
/// The letters of @p invariants, e.g. "VSPL" (parseInvariantList reads it back).
std::string invariantLetters(const std::vector<Invariant>& invariants);

using FeatureColumns = std::vector<std::vector<float>>;  ///< [j][vertex], radius ascending

/// Per-vertex features: for each invariant either no columns (not computed) or one column
/// per radius, each with one value per vertex; NaN marks a masked value (its ball reaches
/// an open border).
struct FeatureSet {
    std::vector<double> radii;                  ///< ascending (mesh units)
    std::array<FeatureColumns, 4> columns;      ///< indexed by Invariant

    FeatureColumns& operator[](Invariant i) { return columns[std::size_t(i)]; }
    const FeatureColumns& operator[](Invariant i) const { return columns[std::size_t(i)]; }
    bool has(Invariant i) const { return !columns[std::size_t(i)].empty(); }
    /// The computed invariants, in the order V, S, P, L.
    std::vector<Invariant> invariants() const;
    /// Vertices per column (0 if nothing was computed).
    std::size_t numVertices() const;
};

} // namespace msii
