#pragma once
// Private to the engine: GDAL's part of msii/terrain/dem.h and msii/terrain/raster_output.h
// (reading rasters, writing them, coordinate systems). It lives in the library that holds
// GDAL (libmsii_raster), which libmsii loads on first use (rasterBackend), so that a run on
// a mesh does not load GDAL; the Python wheel, with the engine linked into it, has it built
// in.
#include <msii/terrain/dem.h>
#include <msii/terrain/raster_output.h>

#include <string>
#include <vector>

namespace msii::detail {

/// An open height raster (DemSource's) and a raster being written (RasterPieceWriter's),
/// defined in the raster library.
struct DemDataset;
struct PieceDataset;

/// How a height raster's band stores its heights: a value meaning nodata (compared before
/// scaling), and GDAL's scale and offset, which give the heights (e.g. centimetres in Int16
/// with a scale of 0.01).
struct DemBand {
    double nodata = 0, scale = 1, offset = 0;
    bool hasNodata = false, scaled = false;
};

struct RasterBackend {
    DemDataset* (*openDem)(const std::string& path, const DemReadOptions& options, Dem& info, DemBand& heights);
    /// The band's values in cells [col0, col0 + cols) × [row0, row0 + rows), row-major, as stored.
    void (*readHeights)(const DemDataset& dataset, int col0, int row0, int cols, int rows, float* heights);
    void (*closeDem)(DemDataset* dataset);
    PieceDataset* (*openPieces)(const std::string& path, const RasterGeoreference& grid,
                                const std::vector<std::string>& bandNames, const RasterOutputOptions& options);
    void (*writePiece)(PieceDataset& dataset, int band, int col0, int row0, int cols, int rows, const float* values);
    void (*commitPieces)(PieceDataset& dataset);
    void (*closePieces)(PieceDataset* dataset);
    void (*joinRasterParts)(const std::vector<std::string>& parts, const std::string& output);
    RasterImage (*readRaster)(const std::string& path);
    std::string (*crsWkt)(const std::string& definition);
    RasterRegion (*regionOfPart)(const std::string& mosaic, const std::string& part);
    bool (*isRasterFile)(const std::string& path);
};

/// In the raster library: the functions of the table.
DemDataset* openDemHere(const std::string& path, const DemReadOptions& options, Dem& info, DemBand& heights);
void readHeightsHere(const DemDataset& dataset, int col0, int row0, int cols, int rows, float* heights);
void closeDemHere(DemDataset* dataset);
PieceDataset* openPiecesHere(const std::string& path, const RasterGeoreference& grid,
                             const std::vector<std::string>& bandNames, const RasterOutputOptions& options);
void writePieceHere(PieceDataset& dataset, int band, int col0, int row0, int cols, int rows, const float* values);
void commitPiecesHere(PieceDataset& dataset);
void closePiecesHere(PieceDataset* dataset);
void joinRasterPartsHere(const std::vector<std::string>& parts, const std::string& output);
RasterImage readRasterHere(const std::string& path);
std::string crsWktHere(const std::string& definition);
RasterRegion regionOfPartHere(const std::string& mosaic, const std::string& part);
bool isRasterFileHere(const std::string& path);

/// The raster library's functions, loaded on the first call.
/// @throw IOError if the library cannot be loaded (named, with where it was looked for).
const RasterBackend& rasterBackend();

} // namespace msii::detail

/// The raster library's entry point: its functions.
extern "C" const msii::detail::RasterBackend* msii_raster_backend();
