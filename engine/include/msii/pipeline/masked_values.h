#pragma once
/// @file masked_values.h
/// @brief The last stage of the pipeline: counting the values masked (NaN) because their ball
/// reaches a border of an open surface, over the input's vertices, and the warning when most
/// of them are masked at the largest radius; and the vertices whose ball rests partly on
/// surface that is not in the input (filled holes, the continuation past borders). The same
/// counts for one piece, tiles and DEM windows (whose own cells are counted, not their halos).

#include <msii/core/diagnostics.h>
#include <msii/core/feature_set.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace msii {

/// Masked values per radius, counted in the first invariant computed (V whenever it was:
/// every invariant is masked where its ball reaches a border, docs/method.md, Borders).
struct MaskedValues {
    std::vector<std::size_t> perRadius;  ///< vertices whose value is NaN, per radius
    std::size_t vertices = 0;            ///< vertices counted
    /// Vertices with a filled share above 0 (ComputeResult::filledShare).
    std::size_t withFilledShare = 0;

    /// Counts every row of @p features and @p filledShare (pass only vertices that are in a
    /// face: a vertex in no face has no values and is not counted).
    void add(const FeatureSet& features, const std::vector<float>& filledShare);
    /// Counts the rows @p rows of @p features and @p filledShare (none if empty).
    void add(const FeatureSet& features, const std::vector<float>& filledShare, const std::vector<std::uint32_t>& rows);
    /// Counts the rows i of @p features and @p filledShare where @p counted[i] is not 0.
    void addWhere(const FeatureSet& features, const std::vector<float>& filledShare, const std::vector<char>& counted);
    /// vertex·radius pairs masked, all radii.
    std::size_t total() const;
    /// The "mostly_masked" diagnostic when more than half of the vertices are masked at the
    /// largest of @p radii (many holes, or a radius large for the patch), with the largest
    /// radius at which at least half have values (figure radius_with_half, 0 if none).
    std::optional<Diagnostic> mostlyMasked(const std::vector<double>& radii) const;
};

} // namespace msii
