#pragma once
// What `msii metric` and `msii smooth` share: reading a feature PLY (and GigaMesh .mat
// files) with all its vertex properties, and writing the result next to it.
#include <msii/mesh/trimesh.h>
#include <msii/terrain/raster_output.h>

#include <string>
#include <vector>

namespace msii::tools {

struct FeatureMesh {
    TriMesh mesh;
    std::vector<VertexProperty> properties;  ///< every scalar vertex property of the input
    std::vector<std::string> comments;       ///< for the output header
    double cellSize = 0;                     ///< rasters: the distance between cell centres
};

/// A georeferenced raster (a DEM, or the GeoTIFF msii compute writes for one) read for the
/// feature commands: its bands with nodata as NaN, and its heights: the band named
/// "height", the only band, or (with @p needHeights) the DEM the GeoTIFF names
/// (MSII_INPUT) when it lies on the same grid; empty if none is found.
struct RasterInput {
    RasterImage raster;
    std::vector<float> heights;
    std::string units;  ///< the coordinate system's unit, "m" for metres
};
RasterInput readRasterInput(const std::string& path, bool needHeights);

/// A georeferenced raster (a DEM, or the GeoTIFF msii compute writes for one) as a feature
/// mesh: its heights triangulated at the cell centres as msii compute does (terrain/dem.h),
/// from a band named "height", the only band, or the DEM the GeoTIFF names (MSII_INPUT);
/// every other band is a vertex property of its name. Comments state its units, and its
/// radii where the GeoTIFF records them.
/// @throw InvalidInputError if no heights are found.
FeatureMesh featureMeshFromRaster(const std::string& path);

/// Reads @p input (any mesh format; PLY keeps its vertex properties; a raster through
/// featureMeshFromRaster) and replaces its V or P features by those of each GigaMesh `.mat`
/// file in @p matFiles.
FeatureMesh readFeatureMesh(const std::string& input, const std::vector<std::string>& matFiles);

/// Replaces NaN in the property `quality` (if any) by 0: viewers colour by quality without
/// checking (MeshLab 2020.09 aborts on NaN), so no msii output holds NaN there. Other
/// properties keep NaN where a value is undefined.
void qualityWithoutNaN(std::vector<VertexProperty>& properties);

/// "V_07": a feature element of invariant @p letter (V, S, P or L; 0 = any of them).
bool isFeatureName(const std::string& name, char letter = 0);

/// The index of vertex property @p name in @p in.properties.
/// @throw InvalidInputError naming the properties the input has.
std::size_t findProperty(const FeatureMesh& in, const std::string& name);

/// The properties named in a comma-separated list, in its order (indices into in.properties).
/// @throw InvalidInputError for a name the input lacks, or an empty list.
std::vector<std::size_t> findProperties(const FeatureMesh& in, const std::string& commaList);

/// Comma-separated finite numbers ("0.5,0.6"). @throw InvalidInputError naming @p option.
std::vector<double> parseNumberList(const std::string& text, const std::string& option);

/// --output, else <input folder>/<input stem>.<suffix><extension>; checks that it may be
/// written and has the extension.
std::string outputPath(const std::string& input, const std::string& output, const std::string& suffix,
                       bool overwrite, const std::string& extension = ".ply");

} // namespace msii::tools
