#pragma once
/// @file extend_borders.h
/// @brief Continues an open surface past its borders for the computation (docs/method.md,
/// "Values up to the border"): every border left open after hole filling (the rim of a
/// one-sided scan, a DEM's edge, a gap too large to fill, a hole CGAL could not
/// triangulate) gets a skirt that carries the surface's tangent plane at the border out to
/// a given width, with half the surface's own heights above that plane mirrored through the
/// border (so that curvature and roughness partly go on). The balls of vertices near a border then see a surface everywhere, as
/// they do over a filled hole; how much of each ball rests on the skirt is reported
/// (fillShare). A plane and a uniform slope continue as themselves, so their values are
/// exact up to the border; values whose ball does not reach a border do not change.

#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <vector>

namespace msii {

struct ExtendBordersOptions {
    /// How far the skirt reaches past the border (mesh units), e.g. the computation's reach.
    double width = 0;
    /// Radius around each border vertex over which the tangent plane is fitted and the
    /// outward direction is averaged along the border (mesh units): larger is steadier on
    /// noisy scans, smaller follows curvature; docs/method.md gives the choice.
    double fitRadius = 0;
    /// Distance between the skirt's first rings (mesh units), e.g. the median edge; farther
    /// rings grow apart by 15 % of their distance.
    double step = 0;
    /// Vertices on cuts through a larger surface (a DEM window's inner edges, a tile's
    /// sides): border edges between two of them are not borders of the surface and get no
    /// skirt. Empty or one flag per vertex.
    std::vector<char> onCut;
};

struct ExtendBordersResult {
    std::size_t numChains = 0;         ///< border loops (or runs between cuts) extended
    std::size_t numBorderVertices = 0; ///< vertices the skirts start from
    std::size_t numTrimmed = 0;        ///< skirt columns stopped where another border is nearer
    double areaAdded = 0;              ///< area of the skirt triangles
    std::size_t firstNewVertex = 0;    ///< new vertices are mesh.points[firstNewVertex ...]
    std::size_t firstNewTriangle = 0;  ///< new triangles are mesh.triangles[firstNewTriangle ...]
};

/// Appends a skirt past every border of @p mesh (nothing else changes). Deterministic and
/// local: the skirt near a point depends only on the mesh within 3 width + fitRadius of it,
/// so that tiles and DEM windows with that much margin build the same skirt as the whole.
/// @pre The mesh is edge- and vertex-manifold and consistently oriented
///      (mesh/prepare_mesh.h makes it so).
ExtendBordersResult extendBorders(TriMesh& mesh, const ExtendBordersOptions& options);

} // namespace msii
