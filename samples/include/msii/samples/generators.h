#pragma once
/// @file generators.h
/// @brief Deterministic, seedable sample meshes for tests, the demo and the benchmark.
/// Every generator triangulates irregularly, like a scanner: vertices are jittered off a
/// regular lattice and the diagonals are chosen at random, with the given mean vertex
/// spacing. The same options (including the seed) give the same mesh on every machine.
/// Units are millimetres by convention. Orientation: triangles are counter-clockwise seen
/// from outside the solid, so normals point out of the material.
///
/// @note Spacing. `spacing` is the mean vertex spacing: the lattice is chosen so that each
/// vertex owns about spacing^2 of surface, i.e. the vertex count is ~ area / spacing^2:
///   - height field: an (nx+1) x (ny+1) lattice, nx = round(width / spacing),
///     ny = round(height / spacing) (at least 1 each); e.g. 31.6 x 31.6 mm at 0.03 mm
///     gives 1054^2 = 1,110,916 vertices;
///   - cube: n = round(side / spacing) cells per edge, 6 n^2 + 2 vertices;
///   - sphere: icosahedron with every edge split into k = round(sqrt(0.4 pi) radius /
///     spacing) segments (k >= 1), 10 k^2 + 2 vertices (radius 10, spacing 0.15: k = 75,
///     56,252 vertices).
/// The mean edge length is then ~1.1 x spacing: 1.12 - 1.13 x on flat lattices (the
/// diagonals are sqrt(2) longer), up to ~1.14 x on the tablet (slopes), 1.09 x on the
/// sphere (no triangulation with area / spacing^2 vertices gets below 1.075 x, the
/// equilateral one).
///
/// @note Irregularity. Lattice vertices move by up to 0.25 lattice steps (uniform in a disc
/// in the surface; along the edge for vertices on an edge or border; corners stay), which
/// provably keeps every triangle non-degenerate and correctly oriented. Each quad takes its
/// shorter diagonal with probability 0.9 and the other one otherwise (scanner meshers are
/// Delaunay-like, but not perfectly). The sphere keeps the geodesic connectivity (valence
/// 6, twelve of valence 5) and is irregular through the jitter only.
///
/// @note Determinism. Randomness comes from a counter-based hash (splitmix64 finaliser)
/// of (seed, purpose, lattice index), never from std:: distributions, so results do not
/// depend on the standard library or on the thread count (per-vertex work runs in TBB).
/// Only correctly rounded IEEE-754 operations are used (+, -, *, /, sqrt, floor, round;
/// no exp/sin/...), so builds without floating-point contraction (no FMA fusing) give
/// bit-identical meshes.

#include <msii/io/write_ply.h>
#include <msii/mesh/trimesh.h>
#include <msii/terrain/dem.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace msii::samples {

/// Closed sphere of the given radius (all vertices exactly on it), built from a subdivided
/// icosahedron whose vertices are jittered along the sphere. cavity = true flips the
/// orientation: the solid is then everything outside the sphere (the wall of a spherical
/// cavity), so the closed forms of the concave case apply. The points are identical for
/// both values of cavity; only the triangles are reversed (signed volume < 0).
struct SphereOptions {
    double radius = 10.0;     ///< mm
    double spacing = 0.2;     ///< mean vertex spacing (see the file note), mm
    bool cavity = false;
    Vec3 center{};            ///< mm
    std::uint64_t seed = 1;
};
/// @throw InvalidInputError if radius or spacing is not a positive finite number, the
///        center is not finite, or the mesh would exceed 200 million vertices.
TriMesh makeSphere(const SphereOptions& options);

/// Closed axis-aligned cube [0, side]^3 with irregular triangulation of each face; the 8
/// corners are vertices, edge vertices lie exactly on the edges, face vertices exactly in
/// the face planes (so the enclosed volume is side^3 up to rounding).
struct CubeOptions {
    double side = 10.0;       ///< mm
    double spacing = 0.25;    ///< mean vertex spacing (see the file note), mm
    std::uint64_t seed = 1;
};
/// @throw InvalidInputError if side or spacing is not a positive finite number or the mesh
///        would exceed 200 million vertices.
TriMesh makeCube(const CubeOptions& options);

/// A whole clay tablet, closed: a box of width (x) × height (y) × thickness (z) with its
/// edges and corners rounded, centred on the origin; its obverse (+z) rises by obverseBulge
/// at the centre and its reverse (−z) bulges by reverseBulge (the flatter obverse, the more
/// convex reverse of a real tablet); round impressions (marks) are pressed into the flat part
/// of each of its six sides, a different number on each by default, so that a test can tell
/// the sides apart. Seen from the obverse with +y up: top +y, bottom −y, left −x, right +x.
/// The triangulation is irregular (a jittered box lattice mapped onto the rounded box, as
/// makeCube's, denser where the rounding compresses it) and faces outward.
enum class TabletSide { Obverse, Reverse, Top, Bottom, Left, Right };
/// "obverse", "reverse", "top", "bottom", "left", "right".
const char* tabletSideName(TabletSide side);
struct RoundedTabletOptions {
    double width = 24.0, height = 32.0, thickness = 10.0;  ///< mm, along x, y and z
    double rounding = 2.5;      ///< radius of the rounded edges and corners, mm
    double obverseBulge = 0.1;  ///< rise of the obverse's centre, mm
    double reverseBulge = 1.5;  ///< rise of the reverse's centre, mm
    /// Marks per side, in TabletSide order (obverse, reverse, top, bottom, left, right).
    std::array<int, 6> marks{6, 5, 1, 2, 4, 3};
    double markRadius = 1.0;    ///< mm
    double markDepth = 0.4;     ///< depth of a mark's centre, mm (profile depth (1 − d²/r²)²)
    double spacing = 0.25;      ///< mean vertex spacing of the box lattice, mm
    double roughness = 0.0;     ///< white scanner noise: each vertex moved along the normal by up to this, mm
    std::uint64_t seed = 1;
};
struct TabletMark {
    TabletSide side;
    Vec3 centre;  ///< on the surface before the mark was pressed in (its projection marks the mark's centre in any view of its side)
    Vec3 normal;  ///< the side's outward axis
    double radius = 0, depth = 0;
};
struct RoundedTablet {
    TriMesh mesh;
    std::vector<TabletMark> marks;  ///< side by side in TabletSide order
};
/// @throw InvalidInputError for sizes that are not positive, a rounding of half the smallest
///        side or more, marks deeper than the rounding or that do not fit on their side.
RoundedTablet makeRoundedTablet(const RoundedTabletOptions& options);

/// A height field z = h(x, y) over [0, width] x [0, height], as an open patch (normals up,
/// so the solid is below) or as a closed slab (the same top surface, a flat bottom at
/// z = -thickness and side walls). In the slab the top vertices come first, in the same
/// order and at the same positions as in the open patch of the same options (and the top
/// triangles come first, identical too). The patch outline is exactly the rectangle:
/// border vertices move only along the border. Vertex (i, j) of the lattice has index
/// j * (nx + 1) + i (x fastest).
enum class HeightFieldKind {
    Plane,    ///< h = 0
    Terrain,  ///< smooth random hills and valleys (sum of seeded Gaussian-like bumps), amplitude ~ relief
    Tablet,   ///< gently curved clay surface with wedge-shaped stylus impressions + noise
};
struct HeightFieldOptions {
    HeightFieldKind kind = HeightFieldKind::Tablet;
    double width = 20.0;      ///< mm, along x
    double height = 15.0;     ///< mm, along y
    double spacing = 0.1;     ///< mean vertex spacing (see the file note), mm
    bool closed = false;      ///< closed slab instead of an open patch
    double thickness = 5.0;   ///< slab thickness below z = 0, mm (must exceed the depth of the top)
    /// Closed slab: 0 = walls and bottom as fine as the top; > 0 = as many meshers make
    /// them, a few long triangles: each wall zips the fine top border to bottom vertices
    /// this far apart (mm), and the flat bottom is a fan around its centre.
    double wallStep = 0.0;
    double relief = 1.0;      ///< Terrain: hill amplitude (standard deviation ~ relief / 2), mm
    double hillWidth = 2.5;   ///< Terrain: typical hill width (Gaussian sigma), mm
    double sag = 0.3;         ///< Tablet: drop of the convex face from its centre to the middle of the longer side, mm
    double wedgeSize = 1.5;   ///< Tablet: mean wedge length, mm (depth ~ 0.2 of it)
    double wedgeDensity = 0.15; ///< Tablet: wedges per mm^2 (of the area inside the margin)
    double wedgeMargin = 1.0; ///< Tablet: wedge-free band along the border, mm
    double noise = 0.002;     ///< Tablet/Terrain: amplitude of smooth scanner-like noise (wavelength 5 spacings), mm
    std::uint64_t seed = 1;
    /// Scan-like sampling (the surface stays the same; where and how densely it is sampled
    /// changes), for meshes like those scanners and meshers make:
    /// - anisotropy: lattice cells this many times longer along x than along y (triangles
    ///   of aspect ~ anisotropy), at the same mean density;
    /// - densityVariation: the densest part has this many times the vertex density of the
    ///   sparsest, varying smoothly across the surface (a sine warp of x and of y, dense in
    ///   the middle, sparse at the border);
    /// - roughness: white scanner noise, every top vertex moved in z by a seeded uniform
    ///   value in [-roughness, roughness], mm (then z differs from heightFieldValue()).
    double anisotropy = 1.0;
    double densityVariation = 1.0;
    double roughness = 0.0;
};
/// @throw InvalidInputError if a size is not positive and finite, a closed slab's
///        thickness does not reach below the lowest top point, or the mesh would exceed
///        200 million vertices.
TriMesh makeHeightField(const HeightFieldOptions& options);

/// Writes the open height field of @p options to a binary PLY, byte for byte what writePly
/// writes for makeHeightField(options), without ever holding the mesh: the lattice is
/// generated and written a band of rows at a time (memory ~ a few MB whatever the size),
/// for meshes larger than memory, e.g. a 50M-vertex terrain. Points are float unless
/// @p plyOptions forces double. Returns the vertex and triangle counts.
/// @throw InvalidInputError as makeHeightField, for a closed slab or an ascii file, and if
///        float points would lose more than 1e-7 of the size (force double then);
///        IOError if the file cannot be written (nothing is left behind).
struct StreamedMeshCounts {
    std::size_t vertices = 0, triangles = 0;
};
StreamedMeshCounts writeHeightFieldPly(const HeightFieldOptions& options, const std::string& path,
                                       const WritePlyOptions& plyOptions);

/// The analytic height of the surface makeHeightField samples (without the lattice jitter),
/// for tests that need the true surface. makeHeightField sets z = heightFieldValue(x, y)
/// exactly (bit for bit) at every top vertex. Defined for any (x, y), also outside the
/// rectangle.
///   - Plane: 0.
///   - Terrain: sum of bumps a (1 - r^2 / R^2)^4 (a Gaussian of sigma ~ R / 3 within 3 %,
///     compactly supported), sigma = hillWidth x [0.6, 1.4], a uniform in [-relief, relief],
///     0.75 / (pi hillWidth^2) bumps per mm^2 over the rectangle grown by 4.2 hillWidth,
///     plus noise.
///   - Tablet: -c ((x - w/2)^2 + (y - h/2)^2) with c = sag / (max(w, h) / 2)^2 (0 at the
///     centre), minus the wedge pits, plus noise. A wedge has length L = wedgeSize x
///     [0.6, 1.4], a random direction, a head edge 0.35 - 0.5 L wide, and its deepest point
///     (0.2 L deep) on the axis, 0.2 - 0.3 L from the head edge towards the tail: the pit is the triangular
///     pyramid over the outline triangle (the max of its three faces), and the surface the
///     min of the face and the pits, creases rounded over min(spacing, 0.1 mm) so the
///     lattice resolves them. Wedges (with their rounding) stay out of the wedgeMargin band;
///     their layout depends on the seed and the sizes only, not on the spacing.
///   - noise: amplitude x seeded value noise (C2, in [-1, 1]) of wavelength 5 spacings.
/// @note The seeded hill / wedge layout is built on first use of some options (~10 us) and
///       kept for the last four option sets per thread, so point-by-point evaluation is cheap.
/// @throw InvalidInputError for the same invalid sizes as makeHeightField.
double heightFieldValue(const HeightFieldOptions& options, double x, double y);

/// A generated DEM (digital elevation model): the height field of `surface` sampled at the
/// centres of a regular grid of cells `surface.spacing` apart (the grid covers surface.width
/// × surface.height), lifted by baseHeight, with its north-west corner at (west, north) in
/// the coordinate system `crs`, rows running south, and `nodataPatches` seeded round patches
/// of nodata (NaN) of radius up to patchRadius (at least a cell).
struct DemSampleOptions {
    HeightFieldOptions surface;
    double west = 512000.0, north = 5498000.0, baseHeight = 300.0;  ///< UTM-like, metres
    std::string crs = "EPSG:25832";                                 ///< ETRS89 / UTM zone 32N
    std::size_t nodataPatches = 0;
    double patchRadius = 0;  ///< 0 = 2 cells
};
/// @throw InvalidInputError for invalid sizes (as makeHeightField) or an unknown crs.
Dem makeDem(const DemSampleOptions& options);

/// Scanner-like holes: removes the faces around @p count seeded vertices, each hole reaching
/// a seeded radius in [minSize, maxSize] from its centre vertex (at least the faces around the
/// centre); holes stay at least 2 maxSize + minSize apart. Vertices are kept (those inside a
/// hole then belong to no face), so indices stay valid.
struct HoleOptions {
    std::size_t count = 10;   ///< holes wanted (fewer if the surface has no room)
    double minSize = 0.05;    ///< smallest hole radius, mm
    double maxSize = 0.2;     ///< largest hole radius, mm
    std::uint64_t seed = 1;
};
struct HoleReport {
    std::size_t holes = 0, facesRemoved = 0;
};
/// @throw InvalidInputError for sizes that are not positive or minSize > maxSize.
HoleReport punchHoles(TriMesh& mesh, const HoleOptions& options);

} // namespace msii::samples

