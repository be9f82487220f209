#pragma once
/// @file raster_output.h
/// @brief Per-cell results as a georeferenced raster: a Cloud-Optimized GeoTIFF on the
/// input's grid (same geotransform and coordinate system), one float32 band per feature with
/// its name as the band description, NaN as nodata, tiled, compressed, with overviews, so
/// that QGIS opens and places it directly. Written to a temporary name and renamed.

#include <msii/terrain/dem.h>

#include <memory>
#include <string>
#include <vector>

namespace msii {

struct RasterBand {
    std::string name;           ///< band description, e.g. "V_16"
    std::vector<float> values;  ///< row-major, one per cell; NaN = nodata
};

/// Scaled 16-bit values (RasterOutputOptions::scaled16): raw = round(value / kScaled16Step),
/// value = raw · kScaled16Step (GDAL's scale, offset 0), raw kScaled16Nodata for NaN.
constexpr double kScaled16Step = 1.0 / 65534.0;
constexpr double kScaled16Nodata = 65535.0;

struct RasterOutputOptions {
    double nodata = std::numeric_limits<double>::quiet_NaN();  ///< the nodata value written (float32)
    /// Unsigned 16-bit integers with GDAL's scale (kScaled16Step: a resolution of 1.5e-5,
    /// values within 7.7e-6) instead of float32, ZSTD-compressed: about a third of the size.
    /// For bands of fractions in [0, 1] (V̂, Ŝ, filled_share); values outside are clamped.
    /// GDAL and QGIS apply the scale when they read; so does readRaster.
    bool scaled16 = false;
    std::string description;     ///< dataset metadata (TIFFTAG_IMAGEDESCRIPTION)
    std::vector<std::pair<std::string, std::string>> metadata;  ///< further key=value metadata
};

/// Writes @p bands on @p grid's grid to @p path as a COG (DEFLATE, 512-cell tiles,
/// overviews).
/// @throw InvalidInputError if a band's size is not width × height or there is no band;
/// IOError if the file cannot be written.
void writeRaster(const std::string& path, const RasterGeoreference& grid, const std::vector<RasterBand>& bands,
                 const RasterOutputOptions& options = {});

/// The same, filled window by window, for rasters too large to hold: the bands go to an
/// intermediate tiled GeoTIFF next to @p path (removed afterwards, also on interruption),
/// and commit() turns it into the COG at @p path.
class RasterPieceWriter {
public:
    /// @throw IOError if the folder is not writable.
    RasterPieceWriter(const std::string& path, const RasterGeoreference& grid, const std::vector<std::string>& bandNames,
                      const RasterOutputOptions& options = {});
    ~RasterPieceWriter();
    RasterPieceWriter(const RasterPieceWriter&) = delete;
    RasterPieceWriter& operator=(const RasterPieceWriter&) = delete;

    /// Writes @p values (row-major, @p cols × @p rows, NaN = nodata) into band @p band
    /// (0-based) at cell (col0, row0). @throw IOError
    void write(int band, int col0, int row0, int cols, int rows, const float* values);
    /// The COG, renamed onto the path. @throw IOError
    void commit();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

/// Joins @p parts, rasters written by msii on tiles of one grid (`msii compute --tile-of-mosaic`),
/// into the VRT mosaic @p output (written atomically, its parts referred to relative to it):
/// GDAL's gdalbuildvrt, with the parts' band names, scale and offset, nodata and metadata,
/// which gdalbuildvrt leaves out.
/// @throw InvalidInputError if the parts do not have the same bands; IOError if unreadable.
void joinRasterParts(const std::vector<std::string>& parts, const std::string& output);

/// A raster read back: its grid and every band (float), with the band descriptions as names.
struct RasterImage {
    RasterGeoreference georeference;
    std::vector<RasterBand> bands;
    bool hasNodata = false;
    double nodata = 0;
    std::vector<std::pair<std::string, std::string>> metadata;  ///< the dataset's key=value metadata
};
/// @throw IOError if GDAL cannot read it.
RasterImage readRaster(const std::string& path);

} // namespace msii
