#pragma once
/// @file generators.h
/// @brief Deterministic, seedable sample meshes for tests, the demo and the benchmark.
/// Every generator triangulates irregularly, like a scanner: vertices are jittered off a
/// regular lattice and the diagonals are chosen at random, with the given mean vertex
/// spacing. The same options (including the seed) give the same mesh on every machine.
/// Units are millimetres by convention. Orientation: triangles are counter-clockwise seen
/// from outside the solid, so normals point out of the material.

#include <msii/mesh/trimesh.h>

#include <cstdint>

namespace msii::samples {

/// Closed sphere of the given radius (all vertices exactly on it), built from a subdivided
/// icosahedron whose vertices are jittered along the sphere. cavity = true flips the
/// orientation: the solid is then everything outside the sphere (the wall of a spherical
/// cavity), so the closed forms of the concave case apply.
struct SphereOptions {
    double radius = 10.0;     ///< mm
    double spacing = 0.2;     ///< mean edge length, mm
    bool cavity = false;
    Vec3 center{};            ///< mm
    std::uint64_t seed = 1;
};
TriMesh makeSphere(const SphereOptions& options);

/// Closed axis-aligned cube [0, side]^3 with irregular triangulation of each face; the 8
/// corners are vertices, edge vertices lie exactly on the edges.
struct CubeOptions {
    double side = 10.0;       ///< mm
    double spacing = 0.25;    ///< mean edge length, mm
    std::uint64_t seed = 1;
};
TriMesh makeCube(const CubeOptions& options);

/// A height field z = h(x, y) over [0, width] x [0, height], as an open patch (normals up,
/// so the solid is below) or as a closed slab (the same top surface, a flat bottom at
/// z = -thickness and side walls). In the slab the top vertices come first, in the same
/// order and at the same positions as in the open patch of the same options.
enum class HeightFieldKind {
    Plane,    ///< h = 0
    Terrain,  ///< smooth random hills (sum of seeded Gaussian bumps), amplitude ~ relief
    Tablet,   ///< gently curved clay surface with wedge-shaped stylus impressions + noise
};
struct HeightFieldOptions {
    HeightFieldKind kind = HeightFieldKind::Tablet;
    double width = 20.0;      ///< mm, along x
    double height = 15.0;     ///< mm, along y
    double spacing = 0.1;     ///< mean edge length, mm
    bool closed = false;      ///< closed slab instead of an open patch
    double thickness = 5.0;   ///< slab thickness below z = 0, mm
    double relief = 1.0;      ///< Terrain: hill amplitude, mm
    double wedgeSize = 1.5;   ///< Tablet: mean wedge length, mm (depth ~ 0.2 of it)
    double wedgeDensity = 0.15; ///< Tablet: wedges per mm^2
    double noise = 0.002;     ///< Tablet/Terrain: amplitude of smooth scanner-like noise, mm
    std::uint64_t seed = 1;
};
TriMesh makeHeightField(const HeightFieldOptions& options);

/// The analytic height of the surface makeHeightField samples (without the lattice jitter),
/// for tests that need the true surface.
double heightFieldValue(const HeightFieldOptions& options, double x, double y);

} // namespace msii::samples
