#pragma once
/// @file vessels.h
/// @brief Generated vessels, sherds and cylinder seals with known answers, for the tests of
/// the axis of rotation, the profile sections and the unrolled decoration: the true axis,
/// the true generating profile, the rim diameter and the marks come with each mesh.
///
/// Construction: a profile loop in the (r, z) half-plane revolved about the z axis. For a
/// vessel it runs from the bottom centre (0, 0) out along the base's underside, round the
/// foot's corner, up the outer wall, over a rounded lip (a half circle of diameter `wall`),
/// down the inner wall, round the inner corner of the base and back along the base's top to
/// (0, base). The outer wall is a graph r(z); the inner wall is the outer one offset by
/// `wall` along the profile's inward normal, so the wall is equally thick everywhere. The
/// loop is sampled by arc length at about `spacing` (each point moved by up to a quarter of
/// a step along the loop, so it stays on the true profile); each sample becomes a ring of
/// about 2πr / spacing vertices (at least 8) at jittered angles from a random phase, exactly
/// on the revolved profile; consecutive rings with different counts are zipped together by
/// advancing along their two sorted angle lists, which keeps the triangles irregular like a
/// scanner's; the two poles (r = 0) are single vertices with a fan. The vertex count is
/// about area / spacing² (the rings are a spacing apart and their vertices a spacing apart).
///
/// @note Marks are round pits of depth d·(1 − ρ²/R²)² pressed into the outer wall along the
/// surface normal, ρ the distance from the mark's centre measured on the surface (along the
/// profile and around the ring), R the mark's radius. Roughness moves every vertex along the
/// surface's normal by a seeded uniform amount in [−roughness, roughness]; marks and noise
/// are applied before the pose, so a posed object is the unposed one moved rigidly.
///
/// @note Determinism. The same options give the same mesh bit for bit on one machine,
/// whatever the thread count (counter-based randomness as in generators.h, every vertex and
/// triangle computed from its own indices). Unlike generators.h these shapes use sin, cos
/// and atan2, so other machines or standard libraries may differ in the last bits.
///
/// Units are mm. Before the pose the axis is the z axis through the origin, the base's
/// bottom at z = 0, the rim at z = height; angles θ are radians about +z from +x.

#include <msii/mesh/trimesh.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace msii::samples {

enum class VesselShape { Cylinder, Cone, Vase };
/// "cylinder", "cone", "vase".
const char* vesselShapeName(VesselShape shape);

/// Where a mark goes, before the pose.
struct VesselMarkPlace {
    double theta = 0;   ///< radians about +z from +x
    double height = 0;  ///< z of the mark's centre, mm
};

struct VesselOptions {
    VesselShape shape = VesselShape::Vase;
    double height = 120;    ///< base bottom to rim top, mm
    /// Outer radius, mm: the cylinder's; the cone's at the base; the vase's widest (its belly,
    /// at 0.35 of the wall's height).
    double radius = 50;
    double topRadius = 35;  ///< the cone's outer radius where the outer wall meets the lip, mm (ignored otherwise)
    double wall = 5;        ///< wall thickness, measured along the profile's normal, mm
    double base = 6;        ///< base thickness, mm
    /// The marks' places; empty: markCount marks spread over the outer wall by the seed
    /// (every 360° / markCount around, at heights in a shuffled order).
    std::vector<VesselMarkPlace> marks;
    std::size_t markCount = 8;  ///< marks placed by the seed when `marks` is empty (0: none)
    double markRadius = 2.0;    ///< mm, measured on the surface
    double markDepth = 0.6;     ///< depth of a mark's centre, mm (0: no marks at all)
    double spacing = 0.6;       ///< mean vertex spacing, mm (~area / spacing² vertices)
    double roughness = 0.0;     ///< white noise along the normal, up to this, mm
    std::uint64_t seed = 1;
    /// 0: as built; otherwise a seeded rotation (uniform over all rotations) followed by a
    /// translation of up to 1000 mm (uniform in the ball).
    std::uint64_t poseSeed = 0;
};

/// A mark as made, posed with the object.
struct VesselMark {
    Vec3 centre;  ///< on the surface before the mark was pressed in
    Vec3 normal;  ///< the surface's outward unit normal there
    double theta = 0, height = 0;  ///< its place before the pose (VesselMarkPlace)
    double radius = 0, depth = 0;
};

/// A generated object with its known answers.
struct Vessel {
    TriMesh mesh;  ///< closed, triangles facing outward, genus 0 (one piece, no holes)
    std::vector<VesselMark> marks;  ///< those on the object (for a sherd: whose centre lies on the piece)
    /// The true axis after the pose: axisPoint is the posed origin (the vessel's base bottom
    /// centre, also for a sherd), axisDirection the posed +z (from the base towards the rim).
    Vec3 axisPoint, axisDirection{0, 0, 1};
    /// Outer diameter at the top of the rim, where the outer wall meets the lip (2 r at the
    /// lip's start); 0 where there is no rim (a sherd without rim, a seal).
    double rimDiameter = 0;
    /// Extent along the axis from the object's lowest point to its highest, of the true
    /// surface (without marks and noise): a vessel's or a seal's height; a sherd's measured
    /// on its break faces.
    double height = 0;
    /// The true generating profiles in the (r, z) half-plane before the pose, as fine
    /// polylines whose points lie on the true curves and whose chords stray less than
    /// kVesselProfileTolerance from them. outerProfile runs from the bottom centre (0, 0)
    /// along the base's underside and up the outer wall to the lip's start; innerProfile
    /// from the base's top centre (0, base) up the inner wall to the lip's end. For a sherd
    /// they are those of the vessel it broke from. A seal's outerProfile is its whole
    /// outline, from (0, 0) to (0, height); it has no innerProfile.
    std::vector<std::array<double, 2>> outerProfile, innerProfile;
    /// The whole profile loop as revolved: base underside, outer wall, lip, inner wall,
    /// base top, from (0, 0) to (0, base) (a seal's: its outline); the axis closes it. Every
    /// vertex of an unmarked, noiseless vessel or seal lies on it after the revolution, and
    /// every section of the object through its axis.
    std::vector<std::array<double, 2>> section;
};

/// Largest distance of a true profile curve from its polyline (the chords' sagitta), mm.
inline constexpr double kVesselProfileTolerance = 1e-4;

/// @throw InvalidInputError for sizes that are not positive and finite, a wall too thick
///        for the profile (thicker than a third of the narrowest radius, than the profile's
///        radius of curvature, or leaving no room inside), a base thicker than a third of
///        the height, marks as deep as half the wall or that do not fit on the outer wall, a
///        spacing coarser than half the wall (the lip, a half circle of diameter `wall`,
///        would get no rings), or a mesh of more than 200 million vertices.
Vessel makeVessel(const VesselOptions& options);

/// The true outer radius at height z before the marks, from the base's underside (the
/// foot's rounding included) to where the outer wall meets the lip; NaN outside that range.
/// Only the shape's options count (not the spacing, marks, noise or pose).
/// @throw InvalidInputError for an invalid shape, as makeVessel.
double vesselOuterRadius(const VesselOptions& options, double z);

struct SherdOptions {
    VesselOptions vessel;  ///< the vessel it broke from (its marks too: those inside the piece are pressed in)
    double angle = 75;     ///< degrees of the circumference the piece covers (up to 180)
    double fromHeight = 40, toHeight = 80;  ///< z range of the piece's outer wall, mm (the breaks wander about them)
    bool rim = false;      ///< the piece reaches the rim: its top is the real rounded lip (toHeight ignored)
    double theta0 = 0;     ///< radians about +z where the piece starts (its first break, before the jag)
};

/// A closed piece of the vessel's wall: the outer and inner wall over [θ0, θ0 + angle] ×
/// [fromHeight, toHeight] (the outer wall's z), closed by four break faces joining outer and
/// inner surface, or with the lip on top when rim is true. The breaks are irregular, a
/// little jagged and not planar, like real fractures: each wanders by up to 1.5 mm plus a
/// quarter of the wall about its nominal place (smooth noise at wavelengths of 15 and 4 mm)
/// and leans through the wall. Marks that the piece holds are pressed in, the wall under
/// them giving way evenly down to the inner wall, so that a break through a mark shows its
/// dent. Its outer and inner faces lie exactly on the vessel's true surfaces; they are
/// sampled in rows of about α r / spacing vertices a spacing apart like the vessel's
/// rings (the end breaks are jittered lattices with random diagonals), so the vertex count
/// is about area / spacing² too.
/// @throw InvalidInputError as makeVessel, for an angle outside (0, 180] or too small for
///        the breaks' wander at that radius, or a height range that is too small or does not
///        lie on the wall (above the base's inner corner and below the lip, with room for the
///        breaks' wander).
Vessel makeSherd(const SherdOptions& options);

struct SealOptions {
    double radius = 12.5;  ///< mm (a 25 mm seal)
    double height = 35;    ///< mm
    /// The marks' places; empty: markCount marks spread around and along the side.
    std::vector<VesselMarkPlace> marks;
    std::size_t markCount = 10;
    double markRadius = 1.0, markDepth = 0.4;  ///< mm (depth 0: no marks)
    double spacing = 0.15, roughness = 0.0;    ///< mm
    std::uint64_t seed = 1, poseSeed = 0;      ///< as VesselOptions
};

/// A cylinder seal: a solid cylinder (flat ends, edges rounded by 5 % of the radius) with
/// marks engraved in its side.
/// @throw InvalidInputError for invalid sizes or marks that do not fit on the side.
Vessel makeCylinderSeal(const SealOptions& options);

} // namespace msii::samples
