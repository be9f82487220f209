#pragma once
/// @file sheet_orientation.h
/// @brief How an object lies on a figure sheet: the direction from it towards a
/// viewer of its obverse (front) and the direction that is up on the obverse
/// (docs/figures.md, "Orientation"). The default follows the surface's
/// area-weighted principal axes:
///   - the obverse looks along the axis of least extent, and the longest axis
///   is vertical;
///   - front: an open scan faces its viewer (the side its vector area points
///   to, when that
///     holds most of its projected area); a closed object shows the flatter of
///     its two large sides as the obverse (the side whose height along the axis
///     varies less: a tablet's reverse is the more convex one);
///   - up: the side of the longest axis towards which the surface's third
///   moment along it
///     leans (its longer tail of area);
///   - where those measures are equal to rounding (a symmetric object), the
///   sign that makes
///     the axis's largest component positive, which depends on the pose.
/// Each rule depends on the surface alone, so the same object in another pose
/// lies the same way on the sheet (up to the last case). Given directions
/// override the rules.

#include <msii/mesh/trimesh.h>

#include <optional>
#include <string>

namespace msii {

struct SheetOrientationOptions {
    /// From the object towards a viewer of the obverse; any length > 0.
    std::optional<Vec3> front;
    /// Up on the obverse; any length > 0; its part along front is dropped, so it
    /// needs a part across it.
    std::optional<Vec3> up;
};

struct SheetOrientation {
    Vec3 front, up;  ///< unit and orthogonal
    /// How each was chosen: "given", "the scan's side", "the flatter side", "third moment",
    /// "sign convention".
    std::string frontRule, upRule;
    /// The surface's area-weighted centroid: the origin of the sheet's views.
    Vec3 centre;
    /// Closed: the surface's vector area is at most 1 % of its area (a closed surface's is
    /// zero; a few small holes keep it small); every side of it is there to see.
    bool closed = false;
    /// Right on the obverse: up × front (so that right, up and front are
    /// right-handed).
    Vec3 right() const { return cross(up, front); }
};

/// @throw InvalidInputError for a given direction of zero length or not finite,
/// front parallel to up, or a mesh without area.
SheetOrientation orientSheet(const TriMesh& mesh, const SheetOrientationOptions& options = {});

}  // namespace msii
