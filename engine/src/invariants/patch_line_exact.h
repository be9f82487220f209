#pragma once
/// @file patch_line_exact.h
/// @brief Step 8 of P and L (msii/invariants/patch_line.h): exact sums where the kernels blur.
/// The (vertex, radius) pairs that the check flags are evaluated from the mesh's own
/// triangles, as the exact mode does (invariants/exact.h), in one walk per vertex over
/// the triangles within its largest flagged radius: a triangle wholly inside a flagged
/// radius adds its area to it and to every larger one, and only the triangles a flagged
/// sphere cuts are clipped, at the flagged radii that cut them; the same clips give L's
/// arcs. The sums are kept in fixed point (integers), so they do not depend on the order
/// in which the triangles are found: tiles, windows and thread counts agree bit for bit.
/// Private to the engine (patch_line.cpp).

#include <msii/core/run_context.h>
#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace msii::detail {

/// What evaluatePairsExactly did.
struct ExactPairsCount {
    std::size_t vertices = 0;  ///< vertices with at least one pair evaluated
    std::size_t pairs = 0;     ///< (vertex, radius) pairs evaluated
};

/// Replaces the values of the pairs with @p flagged[j][i] set by the exact P̂ = P/(π r²) and
/// L̂ = L/(2π r) of @p mesh (into @p patch and @p line, [j][i], either may be empty: not
/// asked for). @p radii ascending. The triangles are found through cells of edge
/// @p cellSize (a few edges: a cell that no flagged sphere cuts is added whole).
ExactPairsCount evaluatePairsExactly(const TriMesh& mesh, const std::vector<double>& radii, double cellSize,
                                     const std::vector<std::vector<std::uint8_t>>& flagged,
                                     std::vector<std::vector<float>>& patch, std::vector<std::vector<float>>& line,
                                     RunContext* progress);

} // namespace msii::detail
