#include "gdal_support.h"
#include "raster_backend.h"

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>

#include <cpl_string.h>
#include <gdal_utils.h>
#include <ogr_spatialref.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace msii::detail {

namespace {

/// Rasters whose bands take at most this many bytes are assembled in memory before the COG
/// is written from them; larger ones in a file next to the output (a DEM's windows are
/// written as they finish, and the whole raster need not fit in memory).
constexpr double kRasterInMemoryBytes = 256.0 * 1024 * 1024;

CPLStringList cogCreationOptions(bool scaled16)
{
    // Cloud-Optimized GeoTIFF: 512-cell tiles, all cores. Floats: DEFLATE with the
    // floating-point predictor, overviews down to a tile (AUTO). Scaled integers: ZSTD with
    // the horizontal predictor and no overviews: on a DEM's default bands 0.28 of the float
    // file's size, against 0.36 with overviews (which a GIS builds when it needs them, and
    // which a mosaic of tiles does not use). ZSTD at level 3 (zstd's own default): 7 % larger
    // than GDAL's default level 9 in a quarter of the time, which on a DEM's default bands
    // was a third of the whole run (docs/terrain.md, Output size).
    CPLStringList o;
    o.SetNameValue("COMPRESS", scaled16 ? "ZSTD" : "DEFLATE");
    if (scaled16) o.SetNameValue("LEVEL", "3");
    o.SetNameValue("PREDICTOR", "YES");
    o.SetNameValue("BLOCKSIZE", "512");
    o.SetNameValue("OVERVIEWS", scaled16 ? "NONE" : "AUTO");
    o.SetNameValue("NUM_THREADS", "ALL_CPUS");
    o.SetNameValue("BIGTIFF", "IF_SAFER");
    return o;
}

} // namespace

/// A raster being written (RasterPieceWriter's).
struct PieceDataset {
    std::string path;
    RasterOutputOptions options;
    std::unique_ptr<AtomicFile> intermediate, target;
    GdalDataset dataset;
    int width = 0, height = 0;
};

PieceDataset* openPiecesHere(const std::string& path, const RasterGeoreference& grid,
                             const std::vector<std::string>& bandNames, const RasterOutputOptions& options)
{
    initGdal();
    if (bandNames.empty()) throw InvalidInputError("no band to write");
    auto pieces = std::make_unique<PieceDataset>();
    PieceDataset& m = *pieces;
    m.path = path;
    m.options = options;
    m.width = grid.width;
    m.height = grid.height;
    // The intermediate: in memory where it is small, else a file tiled like the COG,
    // uncompressed (written once, read once by the COG driver; compressing it too costs more
    // time than the disk does).
    const GDALDataType type = options.scaled16 ? GDT_UInt16 : GDT_Float32;
    const double bytes = double(grid.width) * double(grid.height) * double(bandNames.size()) * GDALGetDataTypeSizeBytes(type);
    CPLStringList o;
    GDALDriver* driver = nullptr;
    std::string intermediatePath;
    if (bytes <= kRasterInMemoryBytes) {
        driver = GetGDALDriverManager()->GetDriverByName("MEM");
        if (!driver) throw IOError("GDAL lacks its MEM driver");
    } else {
        driver = GetGDALDriverManager()->GetDriverByName("GTiff");
        if (!driver) throw IOError("GDAL lacks its GTiff driver");
        m.intermediate = std::make_unique<AtomicFile>(path + ".part.tif");
        intermediatePath = m.intermediate->temporaryPath();
        o.SetNameValue("TILED", "YES");
        o.SetNameValue("BLOCKXSIZE", "512");
        o.SetNameValue("BLOCKYSIZE", "512");
        o.SetNameValue("BIGTIFF", "IF_SAFER");
        o.SetNameValue("INTERLEAVE", "BAND");
    }
    CPLErrorReset();
    m.dataset.reset(driver->Create(intermediatePath.c_str(), grid.width, grid.height, int(bandNames.size()), type, o.List()));
    if (!m.dataset) throw IOError("cannot write '" + path + "': " + lastGdalError("write error"));
    std::array<double, 6> transform = grid.transform;
    m.dataset->SetGeoTransform(transform.data());
    if (!grid.crsWkt.empty()) m.dataset->SetProjection(grid.crsWkt.c_str());
    if (!options.description.empty()) m.dataset->SetMetadataItem("TIFFTAG_IMAGEDESCRIPTION", options.description.c_str());
    for (const auto& [key, value] : options.metadata) m.dataset->SetMetadataItem(key.c_str(), value.c_str());
    for (std::size_t k = 0; k < bandNames.size(); ++k) {
        GDALRasterBand* band = m.dataset->GetRasterBand(int(k) + 1);
        band->SetDescription(bandNames[k].c_str());
        if (options.scaled16) {
            band->SetNoDataValue(kScaled16Nodata);
            band->SetScale(kScaled16Step);
            band->SetOffset(0.0);
        } else {
            band->SetNoDataValue(options.nodata);
        }
    }
    return pieces.release();
}

void closePiecesHere(PieceDataset* pieces) { delete pieces; }

void writePieceHere(PieceDataset& m, int band, int col0, int row0, int cols, int rows, const float* values)
{
    if (!m.dataset) throw IOError("the raster '" + m.path + "' is closed");
    if (m.options.scaled16) {
        std::vector<std::uint16_t> raw(std::size_t(cols) * std::size_t(rows));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, raw.size(), 1 << 16), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t k = range.begin(); k < range.end(); ++k) {
                if (std::isnan(values[k])) {
                    raw[k] = std::uint16_t(kScaled16Nodata);
                    continue;
                }
                // The nearest step, halves away from 0 (std::lround's rule, inline: a call per
                // value was a few percent of a DEM's run), within [0, nodata).
                const double x = std::clamp(double(values[k]) / kScaled16Step, 0.0, double(kScaled16Nodata - 1));
                const long whole = long(x);
                raw[k] = std::uint16_t(whole + (x - double(whole) >= 0.5 ? 1 : 0));
            }
        });
        if (m.dataset->GetRasterBand(band + 1)->RasterIO(GF_Write, col0, row0, cols, rows, raw.data(), cols, rows,
                                                         GDT_UInt16, 0, 0, nullptr) != CE_None)
            throw IOError("cannot write '" + m.path + "': " + lastGdalError("write error"));
        return;
    }
    std::vector<float> copy;
    if (!std::isnan(m.options.nodata)) {
        copy.assign(values, values + std::size_t(cols) * std::size_t(rows));
        for (float& v : copy)
            if (std::isnan(v)) v = float(m.options.nodata);
        values = copy.data();
    }
    if (m.dataset->GetRasterBand(band + 1)->RasterIO(GF_Write, col0, row0, cols, rows, const_cast<float*>(values), cols,
                                                     rows, GDT_Float32, 0, 0, nullptr) != CE_None)
        throw IOError("cannot write '" + m.path + "': " + lastGdalError("write error"));
}

void commitPiecesHere(PieceDataset& m)
{
    GDALDriver* cog = GetGDALDriverManager()->GetDriverByName("COG");
    if (!cog) throw IOError("GDAL lacks its COG driver");
    m.dataset->FlushCache();
    m.target = std::make_unique<AtomicFile>(m.path);
    const CPLStringList o = cogCreationOptions(m.options.scaled16);
    CPLErrorReset();
    GdalDataset written(
        cog->CreateCopy(m.target->temporaryPath().c_str(), m.dataset.get(), FALSE, o.List(), nullptr, nullptr));
    if (!written) throw IOError("cannot write '" + m.path + "': " + lastGdalError("write error"));
    written.reset();
    m.dataset.reset();
    m.target->commit();
    m.intermediate.reset();  // removes the intermediate file
}

void joinRasterPartsHere(const std::vector<std::string>& parts, const std::string& output)
{
    if (parts.empty()) throw InvalidInputError("no raster to join");
    const auto bandNames = [](GDALDataset& ds) {
        std::vector<std::string> names;
        for (int k = 1; k <= ds.GetRasterCount(); ++k) names.push_back(ds.GetRasterBand(k)->GetDescription());
        return names;
    };
    GdalDataset first = openRaster(parts.front());
    const std::vector<std::string> names = bandNames(*first);
    for (const std::string& part : parts)
        if (bandNames(*openRaster(part)) != names)
            throw InvalidInputError(part + " has other bands than " + parts.front() + ": not parts of one computation");
    AtomicFile target(output);
    std::vector<const char*> sources;
    for (const std::string& part : parts) sources.push_back(part.c_str());
    GDALBuildVRTOptions* options = GDALBuildVRTOptionsNew(nullptr, nullptr);
    int usageError = 0;
    CPLErrorReset();
    GdalDataset vrt(GDALDataset::FromHandle(GDALBuildVRT(target.temporaryPath().c_str(), int(sources.size()),
                                                                 nullptr, sources.data(), options, &usageError)));
    GDALBuildVRTOptionsFree(options);
    if (!vrt) throw IOError("cannot join the parts into '" + output + "': " + lastGdalError("gdalbuildvrt failed"));
    for (int k = 1; k <= first->GetRasterCount(); ++k) {
        GDALRasterBand* from = first->GetRasterBand(k);
        GDALRasterBand* to = vrt->GetRasterBand(k);
        to->SetDescription(from->GetDescription());
        int has = 0;
        const double scale = from->GetScale(&has), offset = from->GetOffset();
        if (has) to->SetScale(scale), to->SetOffset(offset);
        const double nodata = from->GetNoDataValue(&has);
        if (has) to->SetNoDataValue(nodata);
    }
    if (char** md = first->GetMetadata(); md) vrt->SetMetadata(md);
    vrt.reset();  // writes the VRT
    target.commit();
}

RasterImage readRasterHere(const std::string& path)
{
    GdalDataset ds = openRaster(path);
    RasterImage image;
    RasterGeoreference& g = image.georeference;
    g.width = ds->GetRasterXSize();
    g.height = ds->GetRasterYSize();
    ds->GetGeoTransform(g.transform.data());
    if (const OGRSpatialReference* srs = ds->GetSpatialRef(); srs && !srs->IsEmpty()) describeCrs(*srs, g);
    if (char** md = ds->GetMetadata(); md)
        for (int k = 0; md[k]; ++k) {
            const std::string item = md[k];
            const std::size_t eq = item.find('=');
            if (eq != std::string::npos) image.metadata.emplace_back(item.substr(0, eq), item.substr(eq + 1));
        }
    for (int k = 1; k <= ds->GetRasterCount(); ++k) {
        GDALRasterBand* band = ds->GetRasterBand(k);
        RasterBand b;
        b.name = band->GetDescription();
        b.values.resize(std::size_t(g.width) * std::size_t(g.height));
        if (band->RasterIO(GF_Read, 0, 0, g.width, g.height, b.values.data(), g.width, g.height, GDT_Float32, 0, 0,
                           nullptr) != CE_None)
            throw IOError("cannot read band " + std::to_string(k) + " of '" + path + "'");
        int has = 0;
        double nodata = band->GetNoDataValue(&has);
        int hasScale = 0, hasOffset = 0;
        const double scale = band->GetScale(&hasScale), offset = band->GetOffset(&hasOffset);
        if ((hasScale && scale != 1.0) || (hasOffset && offset != 0.0)) {
            // Stored as scaled integers (e.g. msii's scaled16): the values, nodata as NaN.
            for (float& v : b.values)
                v = has && double(v) == nodata ? std::numeric_limits<float>::quiet_NaN()
                                               : float(double(v) * scale + offset);
            nodata = std::numeric_limits<double>::quiet_NaN();
        }
        if (k == 1) image.hasNodata = has != 0, image.nodata = nodata;
        image.bands.push_back(std::move(b));
    }
    return image;
}

} // namespace msii::detail

extern "C" const msii::detail::RasterBackend* msii_raster_backend()
{
    using namespace msii::detail;
    static const RasterBackend backend{
        &openDemHere,   &readHeightsHere,         &closeDemHere,   &openPiecesHere, &writePieceHere,   &commitPiecesHere,
        &closePiecesHere, &joinRasterPartsHere, &readRasterHere, &crsWktHere,     &regionOfPartHere, &isRasterFileHere,
    };
    return &backend;
}
