#pragma once
/// @file gdal_support.h
/// @brief What the engine's GDAL sources share: registration once, GDAL's own messages kept
/// off stderr (they become the engine's one-sentence errors), datasets closed by RAII.

#include <msii/terrain/dem.h>

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <memory>
#include <string>

namespace msii::detail {

/// Registers GDAL's drivers once and sends GDAL's messages to CPLGetLastErrorMsg() only.
void initGdal();

struct GdalClose {
    void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using GdalDataset = std::unique_ptr<GDALDataset, GdalClose>;

/// Fills @p g's coordinate system fields (WKT, name, EPSG code, linear unit) from @p srs.
void describeCrs(const OGRSpatialReference& srs, RasterGeoreference& g);

/// GDAL's last error message, or @p otherwise if it has none.
std::string lastGdalError(const std::string& otherwise);

/// @p path opened read-only as a raster.
/// @throw IOError "cannot open … no such file", or "cannot read … as a raster: <GDAL's reason>".
GdalDataset openRaster(const std::string& path);

} // namespace msii::detail
