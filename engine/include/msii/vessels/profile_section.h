#pragma once
/// @file profile_section.h
/// @brief Sections of a mesh by a plane, as potters draw them: through a vessel's axis of
/// rotation (its profile), or through any plane (a tablet's, a stone's), in the drawing's
/// own coordinates; and the profile drawing as SVG (docs/vessels.md).

#include <msii/mesh/trimesh.h>
#include <msii/vessels/axis_of_rotation.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace msii {

struct SectionLine {
    bool closed = false;  ///< the first point is not repeated at the end
    std::vector<std::array<double, 2>> points;  ///< (x, y) in the section's frame
};

/// A section: its lines in the plane's 2D frame. A point (x, y) of it is origin + x·xAxis +
/// y·yAxis in the mesh's coordinates.
struct Section {
    std::vector<SectionLine> lines;
    Vec3 origin, xAxis, yAxis, normal;  ///< the frame (unit, orthogonal; normal = xAxis × yAxis)
    double length = 0;  ///< of all lines
    double yMin = 0, yMax = 0, xMin = 0, xMax = 0;  ///< the lines' extent
};

/// The profile: the section by the plane through the axis and @p through (not on the axis).
/// x is the distance from the axis, positive on the side of @p through; y the height along
/// the axis from the object's lowest point.
/// @throw InvalidInputError if @p through lies on the axis, or the plane misses the mesh.
Section axisSection(const TriMesh& mesh, const AxisOfRotation& axis, const Vec3& through);

/// The point a profile's plane goes through by default: for a piece lying to one side of
/// its axis (a sherd), its centroid, so that the section runs through its middle; else
/// (the centroid near the axis) the point one unit away along the world axis x, y or z most
/// across the axis.
Vec3 defaultThrough(const TriMesh& mesh, const AxisOfRotation& axis);

/// The section by any plane through @p point with normal @p normal: x along the plane's
/// direction closest to the world's x (its y, if the plane is across x), y along normal × x,
/// both from the lowest point of the section.
/// @throw InvalidInputError for a zero normal, or a plane that misses the mesh.
Section planeSection(const TriMesh& mesh, const Vec3& point, const Vec3& normal);

struct ProfileDrawingOptions {
    double scale = 1.0;  ///< drawing units (mm) per mesh unit: 1 is 1:1 for mm meshes, 0.5 is 1:2
    std::string units = "mm";  ///< the mesh's units, for the labels
    std::optional<double> axisX;  ///< draw the axis (dash-dot) at this x (0 for axisSection)
    std::optional<double> rimDiameter;  ///< draw and label it at the top
    std::string title;  ///< a line of text under the drawing; may be empty
};

/// The drawing as SVG: the section's lines (closed ones filled, as a cut wall is drawn), the
/// axis as a dash-dot line, the rim diameter as a dimension line, a scale bar, at a stated
/// scale (its width and height in mm, so that it prints at that scale). Atomic.
/// @throw IOError if the file cannot be written.
void writeProfileSvg(const std::string& path, const Section& section, const ProfileDrawingOptions& options);

}  // namespace msii
