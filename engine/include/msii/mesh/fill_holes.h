#pragma once
/// @file fill_holes.h
/// @brief Closes the small holes of a scan for the computation (docs/method.md, "Mesh
/// preparation"): every border loop up to a perimeter is triangulated, refined to the
/// density of its rim and faired (CGAL Polygon Mesh Processing,
/// `triangulate_refine_and_fair_hole`), so that the balls of nearby vertices see the
/// surface the scan means instead of a border. The outer border of an open surface and
/// loops longer than the limit stay open (their neighbourhood stays masked).

#include <msii/mesh/trimesh.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace msii {

struct FillHolesOptions {
    /// Border loops whose length is at most this are filled (mesh units); 0 fills none.
    double maxPerimeter = 0;
    /// The longest loop of a connected part is its outer border, not a hole, when a disc of
    /// its perimeter would cover more than this share of the part's area (an open one-sided
    /// scan or a small loose fragment); a pin-hole in a closed scan covers almost nothing.
    double outerBorderAreaShare = 0.25;
};

struct FillHolesResult {
    std::size_t numFilled = 0;        ///< loops filled
    std::size_t numTooLarge = 0;      ///< loops longer than maxPerimeter, left open
    std::size_t numOuterBorders = 0;  ///< loops taken for an outer border, left open
    std::size_t numFailed = 0;        ///< loops CGAL could not triangulate, left open
    double largestPerimeter = 0;      ///< of the loops filled
    double areaAdded = 0;             ///< area of the new triangles
    std::size_t firstNewVertex = 0;   ///< new vertices are mesh.points[firstNewVertex ...]
    std::size_t firstNewTriangle = 0; ///< new triangles are mesh.triangles[firstNewTriangle ...]
};

/// Fills the holes of @p mesh in place: new vertices and triangles are appended, nothing
/// else changes. Deterministic: holes are filled in parallel but appended in the order of
/// their smallest vertex.
/// @pre The mesh is edge- and vertex-manifold and consistently oriented (mesh/prepare_mesh.h
///      makes it so); @p borderEdges are its border edges in the direction of their face
///      (MeshCheckResult::borderEdges).
FillHolesResult fillHoles(TriMesh& mesh, const std::vector<std::array<std::uint32_t, 2>>& borderEdges,
                          const FillHolesOptions& options);

} // namespace msii
