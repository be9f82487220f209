#pragma once
/// @file diagnostics.h
/// @brief Coded diagnostics: what the engine noticed or changed, as data. Programs branch on
/// `kind` and read the figures; `message` is one sentence for people and names no
/// command-line flag or function argument (the CLI and Python add how to change things).

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace msii {

struct Diagnostic {
    /// A stable code in snake_case, e.g.:
    /// - mesh preparation: "duplicate_faces_removed", "faces_reoriented", "holes_filled"
    ///   (figures largest_perimeter, area_added), "holes_not_filled", "isolated_vertices" ...;
    /// - computation: "smallest_radius_below_edge" (figures radius, median_edge),
    ///   "mostly_masked" (figures masked_share, largest_radius, radius_with_half);
    /// - DEMs: "undeclared_nodata" (count: cells; figures value_1 … value_4, the heights).
    std::string kind;
    std::size_t count = 0;  ///< what the kind counts (faces, holes, vertices ...); 0 if nothing
    std::vector<std::pair<std::string, double>> figures;  ///< further numbers, by name
    std::string message;    ///< one sentence

    /// The figure called @p name, or @p otherwise if there is none.
    double figure(const std::string& name, double otherwise = 0) const
    {
        for (const auto& [n, v] : figures)
            if (n == name) return v;
        return otherwise;
    }
};

} // namespace msii
