#pragma once
// What `msii metric` and `msii smooth` share: reading a feature PLY (and GigaMesh .mat
// files) with all its vertex properties, and writing the result next to it.
#include <msii/mesh/trimesh.h>
#include <msii/terrain/raster_output.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace msii::tools {

/// Where a feature mesh read from a raster came from: enough to write results back onto
/// the raster's grid (writeFeatureRaster).
struct FeatureRaster {
    RasterGeoreference grid;
    std::vector<std::uint32_t> vertexOfCell;  ///< per cell, its vertex, or DemMesh::kNoVertex
    std::string radii;                        ///< MSII_RADII of msii compute's GeoTIFF, if stated
    std::string heightsFile;                  ///< the DEM file the heights were read from; empty if a band of the input
};

struct FeatureMesh {
    TriMesh mesh;
    std::vector<VertexProperty> properties;  ///< every scalar vertex property of the input
    std::vector<std::string> comments;       ///< for the output header
    double cellSize = 0;                     ///< rasters: the distance between cell centres
    std::optional<FeatureRaster> raster;     ///< set for a raster input
    std::vector<std::string> warnings;       ///< what reading it changed (a raster's implausible heights)
};

/// Prints @p warnings as "msii: warning: INPUT: …" lines, unless @p quiet.
void printWarnings(const std::string& input, const std::vector<std::string>& warnings, bool quiet);

/// A georeferenced raster (a DEM, or the GeoTIFF msii compute writes for one) read for the
/// feature commands: its bands with nodata as NaN, and its heights: the band named
/// "height", the only band, or (with @p needHeights) the DEM the GeoTIFF names
/// (MSII_INPUT) when it lies on the same grid; empty if none is found.
struct RasterInput {
    RasterImage raster;
    std::vector<float> heights;
    std::string units;        ///< the coordinate system's unit, "m" for metres
    std::size_t heightBand = 0;  ///< the band holding the heights; bands.size() if none does (they come from MSII_INPUT)
    std::string heightsFile;  ///< the DEM file the heights come from; empty if a band named "height"
    std::vector<std::string> warnings;  ///< e.g. implausible heights taken as nodata
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

/// Writes @p bands, properties of @p in (read from a raster), as float32 bands on the
/// raster's grid (NaN where a cell has no vertex) to the GeoTIFF @p path, atomically, with
/// @p description and the input's metadata that other commands read (MSII_RADII; MSII_INPUT,
/// the DEM, relative to @p path's folder).
void writeFeatureRaster(const std::string& path, const FeatureMesh& in, const std::vector<const VertexProperty*>& bands,
                        const std::string& description);

/// The output's extension of a command that writes a feature mesh: ".tif" for a raster
/// input unless @p output is a PLY, else ".ply".
std::string featureOutputExtension(const std::string& input, const std::string& output);

/// --output, else <input folder>/<input stem>.<suffix><extension>; checks that it may be
/// written and has the extension.
std::string outputPath(const std::string& input, const std::string& output, const std::string& suffix,
                       bool overwrite, const std::string& extension = ".ply");

} // namespace msii::tools
