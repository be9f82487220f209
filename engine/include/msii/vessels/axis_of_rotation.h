#pragma once
/// @file axis_of_rotation.h
/// @brief The axis of rotation of a surface of revolution (a whole vessel, a sherd, a
/// cylinder seal), fitted robustly, with the shape class that fits best and, for a vessel,
/// its rim diameter (docs/vessels.md). In two steps:
///   1. the surface's normal lines meet the axis of a surface of revolution, so the axis is
///      the line that the normal lines meet best: a linear line complex fitted to them in
///      Plücker coordinates (Pottmann and Randrup's method), by least squares reweighted so
///      that decoration, handles and break faces, whose normals miss the axis, lose weight;
///   2. refined on the profile: the axis that makes the points' distance from it the
///      smoothest function of their height along it, per side of the wall (Gauss–Newton on
///      the four parameters of a line, the profile re-estimated in bins every step, robust
///      weights again).

#include <msii/mesh/trimesh.h>

#include <optional>
#include <string>

namespace msii {

enum class RevolutionShape { Cylinder, Cone, General };
/// "cylinder", "cone", "surface of revolution".
const char* revolutionShapeName(RevolutionShape shape);

struct AxisFitOptions {
    int lineIterations = 8;  ///< reweighted fits of the normal lines
    int profileIterations = 12;  ///< Gauss–Newton steps on the profile
    /// Refuse the fit (not a surface of revolution) when the surface's RMS distance from the
    /// fitted surface of revolution exceeds this share of its mean radius.
    double notRevolution = 0.02;
    /// Refuse (too little of a surface of revolution to tell its axis) when the axis's
    /// direction is uncertain by more than this many degrees.
    double uncertainDegrees = 5.0;
};

struct AxisOfRotation {
    Vec3 point;  ///< on the axis, at the object's lowest point along it
    Vec3 direction;  ///< unit; from the base towards the open end where one is told apart
    RevolutionShape shape = RevolutionShape::General;
    double residual = 0;  ///< RMS distance of the fitting surface from the surface of revolution, mesh units
    double inlierShare = 0;  ///< share of the surface's area that fits it
    double meanRadius = 0;  ///< of the outer wall
    double height = 0;  ///< the object's extent along the axis
    double directionUncertainty = 0;  ///< degrees, from the fit's curvature
    /// The outer wall's best cylinder radius, and best cone r = coneRadius0 + coneSlope·h (h
    /// along the axis from `point`).
    double cylinderRadius = 0, coneRadius0 = 0, coneSlope = 0;
    /// Their RMS misfit to the outer wall, mesh units.
    double cylinderMisfit = 0, coneMisfit = 0;
    /// The outer diameter at the top of the rim: where the outer wall meets the lip of an
    /// open end that is level all round (a whole vessel) or along the piece (a rim sherd).
    std::optional<double> rimDiameter;
};

/// @throw InvalidInputError in one sentence when the surface is not a surface of revolution
/// or its axis cannot be told: a plane (every normal line is an axis), a sphere (every line
/// through its centre), too little of one (the direction uncertain by more than
/// options.uncertainDegrees), or a surface that does not fit one (options.notRevolution).
AxisOfRotation fitAxisOfRotation(const TriMesh& mesh, const AxisFitOptions& options = {});

/// Cylindrical coordinates about an axis: h along it from its point, r from it, and the unit
/// radial direction.
struct AxisFrame {
    Vec3 point, direction;
    Vec3 e1, e2;  ///< unit, completing a right-handed frame (e1 × e2 = direction)
    AxisFrame(const Vec3& point, const Vec3& direction);
    double height(const Vec3& p) const { return dot(p - point, direction); }
    double radius(const Vec3& p) const;
    double angle(const Vec3& p) const;  ///< radians in (−π, π], from e1 towards e2
};

}  // namespace msii
