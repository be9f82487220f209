#pragma once
/// @file isolines.h
/// @brief Isolines of a per-vertex function on the mesh (f linear on each triangle), chained
/// into polylines, and their projection to 2D for SVG outlines.

#include <msii/mesh/trimesh.h>

#include <array>
#include <string>
#include <vector>

namespace msii {

struct Polyline {
    double level = 0;
    bool closed = false;      ///< the first point is not repeated at the end
    std::vector<Vec3> points; ///< on the mesh, one per crossed edge (in order along the line)
};

/// The isolines f = level for each level: per triangle the segment between the edge crossings
/// (linear interpolation), joined through shared edges into maximal polylines. A vertex with
/// f exactly equal to the level is treated as f + tiny (symbolic perturbation), so lines never
/// pass through vertices and each crossing is on one edge. Triangles with a NaN value are
/// skipped (lines end there). Deterministic order: by level, then by smallest edge index.
/// @throw InvalidInputError if f has the wrong size or a level is not finite.
std::vector<Polyline> computeIsolines(const TriMesh& mesh, const std::vector<float>& f,
                                      const std::vector<double>& levels);

/// @p count levels evenly spaced strictly inside [lo, hi] (lo + k·(hi − lo)/(count + 1)).
std::vector<double> evenLevels(double lo, double hi, int count);

struct Polyline2 {
    double level = 0;
    bool closed = false;
    std::vector<std::array<double, 2>> points;  ///< map coordinates (mesh units), y up
};

struct SvgOptions {
    double minX = 0, minY = 0, width = 1, height = 1;  ///< the drawing area in map coordinates (mesh units)
    std::string units = "mm";   ///< SVG width/height are given in these units (mm, cm, in, px) when recognised
    double strokeWidth = 0;     ///< in mesh units; <= 0: width / 1000
};

/// Writes one <path> per polyline (M … L … [Z]), coordinates in mesh units with y flipped so the
/// picture is upright, a viewBox of the drawing area, each path carrying data-level="…". Atomic.
/// @throw IOError if the file cannot be written.
void writeSvg(const std::string& path, const std::vector<Polyline2>& lines, const SvgOptions& options);

} // namespace msii
