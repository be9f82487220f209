#pragma once
/// @file feature_map.h
/// @brief Multichannel OpenEXR feature maps: the mesh projected orthographically onto a map
/// frame, with height, normal, quality and every feature element per pixel, and the frame in
/// the header so that a map can be put back onto the object. Reading them back.
///
/// Channels (32-bit float, or half on request; background pixels are NaN except in `mask`):
///   - `height`: height over the plane (mesh units, towards the viewer);
///   - `normal.x`, `normal.y`, `normal.z`: the interpolated unit normal in the map frame
///     (x right, y up, z towards the viewer);
///   - `mask`: 1 where the pixel sees the mesh, 0 elsewhere;
///   - one channel per given vertex property (`quality`, `V_01` …), interpolated linearly
///     over the triangle the pixel sees.
/// Header attributes (names as written): `msii:pixelSize` (double), `msii:origin`,
/// `msii:axisU`, `msii:axisV`, `msii:normal` (V3d), `msii:minU`, `msii:maxV` (double),
/// `msii:units`, `msii:view`, `msii:source`, `msii:parameters` (string), `msii:radii` (float
/// vector; empty when unknown), and the standard `comments`.

#include <msii/core/run_context.h>
#include <msii/featuremap/map_frame.h>
#include <msii/featuremap/rasterize.h>
#include <msii/mesh/trimesh.h>

#include <cstdint>
#include <map>
#include <utility>
#include <string>
#include <vector>

namespace msii {

enum class ExrCompression { None, Rle, Zips, Zip, Piz };

/// "none", "rle", "zips", "zip", "piz". @throw InvalidInputError otherwise.
ExrCompression parseExrCompression(const std::string& name);

struct FeatureMapOptions {
    bool half = false;                          ///< 16-bit half channels instead of 32-bit float
    /// All lossless. PIZ (wavelet) is the default: on feature maps it gives smaller files than
    /// ZIP (397 vs 558 MB for 2048 × 1539 × 70 floats) in a third of the time.
    ExrCompression compression = ExrCompression::Piz;
    int zipLevel = 1;                           ///< zlib level for zip/zips (1 fastest … 9 smallest)
    std::string units = "mm";
    std::string source;                         ///< input file, for the header
    std::string parameters;                     ///< msii parameters (e.g. the feature PLY's comments)
    std::vector<double> radii;                  ///< radii of the features, ascending; may be empty
};

struct FeatureMapInfo {
    std::vector<std::string> channels;  ///< as written (sorted, as OpenEXR stores them)
    std::size_t coveredPixels = 0;
    double rasterSeconds = 0, writeSeconds = 0;
};

/// Rasterises @p mesh into @p frame and writes the map to @p path, atomically (temporary file,
/// then rename), computing the channels in bands of rows so that memory stays at the pixel
/// buffers (16 bytes per pixel) plus one band.
/// @throw InvalidInputError if a property has the wrong size or a reserved or duplicate name;
/// IOError if the file cannot be written.
FeatureMapInfo writeFeatureMap(const std::string& path, const TriMesh& mesh, const MapFrame& frame,
                               const std::vector<VertexProperty>& properties,
                               const FeatureMapOptions& options, RunContext* context = nullptr);

/// Several views on one image (a figure sheet, figures/fat_cross.h): its pixel hits, each
/// pixel's view, and the views' frames (each pixel's normal is given in its view's frame).
struct FeatureSheet {
    const PixelHits* hits = nullptr;                 ///< the sheet's pixels
    const std::vector<std::int8_t>* view = nullptr;  ///< per pixel, its index into frames (−1: none)
    std::vector<MapFrame> frames;
    double pixelSize = 0;                            ///< mesh units per pixel
    /// More string attributes for the header, e.g. msii:layout and msii:views (the views'
    /// boxes and matrices as JSON).
    std::vector<std::pair<std::string, std::string>> attributes;
};

/// Writes a sheet's map to @p path as writeFeatureMap writes a map: the same channels, with
/// height along each pixel's view (towards its viewer) and normals in its view's frame; the
/// header has msii:pixelSize and the sheet's attributes instead of one frame.
/// @throw InvalidInputError as writeFeatureMap, or if the pixels and views do not match;
/// IOError if the file cannot be written.
FeatureMapInfo writeFeatureSheet(const std::string& path, const TriMesh& mesh, const FeatureSheet& sheet,
                                 const std::vector<VertexProperty>& properties, const FeatureMapOptions& options,
                                 RunContext* context = nullptr);

/// A feature map read back: every channel as float, and the frame from the header.
struct FeatureMapImage {
    int width = 0, height = 0;
    std::map<std::string, std::vector<float>> channels;  ///< row-major, row 0 at the top
    std::vector<std::string> channelNames;               ///< every channel of the file, read or not
    MapFrame frame;           ///< view, pixel size, axes and corner from the header (a sheet's: its pixel size alone)
    bool hasFrame = false;    ///< the msii attributes of one frame were present
    std::string views;        ///< a sheet's msii:views (JSON), else empty
    std::string units, source, parameters;
    std::vector<double> radii;
};

/// Reads any scanline OpenEXR file (channels converted to float): all channels, or only
/// those of @p only that the file has (the caller checks for missing ones). Files without
/// the msii attributes read with hasFrame = false.
/// @throw IOError if the file is missing or not an OpenEXR file.
FeatureMapImage readFeatureMap(const std::string& path, const std::vector<std::string>& only = {});

} // namespace msii
