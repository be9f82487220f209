#pragma once
/// @file unroll.h
/// @brief A surface laid onto the plane around its axis of rotation: the rollout of the
/// decoration of a vessel, a column or a cylinder seal (docs/vessels.md). A cylinder unrolls
/// to x = R·θ, y = height; a cone to its exact development, in which lengths on the cone are
/// kept; z is the relief, the offset from the fitted surface. Vertex i of the rollout is
/// vertex i of the input, so every vertex property carries over; the triangles that cross the
/// seam get copies of their vertices on the far side, appended after the input's; triangles
/// at the axis (a base), which have no place in a rollout, are left out.

#include <msii/mesh/trimesh.h>
#include <msii/vessels/axis_of_rotation.h>

#include <cstdint>
#include <optional>
#include <vector>

namespace msii {

enum class UnrollShape { Cylinder, Cone };

struct UnrollOptions {
    UnrollShape shape = UnrollShape::Cylinder;
    /// The seam runs along the surface's line through this point. Default: the middle of the
    /// widest span of angles (at least 5°) where the surface has no vertex, so that a sherd or
    /// a partial scan is not cut; where the surface goes all round, the line at the axis
    /// frame's angle 0 (AxisFrame::e1).
    std::optional<Vec3> cutThrough;
    /// Lay out the impression instead: what the surface leaves when rolled over clay, the
    /// rollout mirrored left to right with its relief inverted.
    bool impression = false;
};

struct Unrolled {
    TriMesh mesh;  ///< the rollout: x, y in the plane, z the relief (towards the viewer)
    std::vector<std::uint32_t> copyOf;  ///< for each vertex appended at the seam, the input vertex it copies
    /// Triangles at the axis (spanning more than an eighth of a turn: a base, a lid), left out.
    std::size_t trianglesLeftOut = 0;
    UnrollShape shape = UnrollShape::Cylinder;
    double radius = 0;  ///< the cylinder's
    double apexHeight = 0;  ///< the cone's apex along the axis from the axis point
    double halfAngle = 0;  ///< the cone's, radians
    double seamAngle = 0;  ///< the seam's angle in the axis frame (AxisFrame::angle)
    Vec3 seamPoint;  ///< where the seam meets the fitted surface, at the object's mid-height
    /// Length distortion over the fitted surface: of the edges with both ends within 1 % of
    /// the radius of it, the largest |unrolled length / length − 1| and its 99th percentile.
    double maxDistortion = 0, distortion99 = 0;
    std::size_t edgesMeasured = 0;
};

/// @throw InvalidInputError for a cone without slope (use a cylinder), a seam point on the
/// axis, or nothing left to unroll (every triangle at the axis).
Unrolled unrollSurface(const TriMesh& mesh, const AxisOfRotation& axis, const UnrollOptions& options = {});

}  // namespace msii
