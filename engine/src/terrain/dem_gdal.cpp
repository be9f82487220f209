#include "gdal_support.h"
#include "raster_backend.h"

#include <msii/core/errors.h>

#include <cpl_error.h>
#include <cpl_string.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <memory>
#include <mutex>
#include <optional>

namespace msii {

namespace {

/// The longest side of a cell at most this many times its shortest (openDemHere).
constexpr double kMaxCellAspect = 20;

} // namespace

namespace detail {

void initGdal()
{
    static std::once_flag once;
    std::call_once(once, [] {
        GDALAllRegister();
        CPLSetErrorHandler(CPLQuietErrorHandler);
        // GDAL's block cache holds written blocks until they are flushed, by default up to
        // 5 % of the machine's memory; a window's computation needs the memory more.
        if (!CPLGetConfigOption("GDAL_CACHEMAX", nullptr)) GDALSetCacheMax64(GIntBig(256) << 20);
    });
}

void describeCrs(const OGRSpatialReference& srs, RasterGeoreference& g)
{
    char* wkt = nullptr;
    if (srs.exportToWkt(&wkt) == OGRERR_NONE && wkt) g.crsWkt = wkt;
    CPLFree(wkt);
    if (const char* n = srs.GetName()) g.crsName = n;
    if (const char* code = srs.GetAuthorityCode(nullptr)) g.epsg = code;
    const char* unit = nullptr;
    const double metres = srs.GetLinearUnits(&unit);
    if (unit) g.units = unit;
    if (metres > 0 && std::isfinite(metres)) g.metresPerUnit = metres;
}

std::string lastGdalError(const std::string& otherwise)
{
    const char* msg = CPLGetLastErrorMsg();
    return msg && *msg ? std::string(msg) : otherwise;
}

GdalDataset openRaster(const std::string& path)
{
    initGdal();
    if (!std::filesystem::exists(path)) throw IOError("cannot open '" + path + "': no such file");
    CPLErrorReset();
    // NUM_THREADS: GeoTIFF tiles are decompressed on every core (GDAL ≥ 3.6; other drivers
    // ignore it).
    const char* const options[] = {"NUM_THREADS=ALL_CPUS", nullptr};
    GdalDataset ds(GDALDataset::FromHandle(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, options, nullptr)));
    if (!ds) throw IOError("cannot read '" + path + "' as a raster: " + lastGdalError("not a format GDAL reads"));
    return ds;
}

namespace {

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

/// The raster's centre in longitude and latitude (degrees), if its coordinate system can say.
std::optional<std::array<double, 2>> centreInDegrees(GDALDataset& ds, const OGRSpatialReference& srs)
{
    std::array<double, 6> t{};
    if (ds.GetGeoTransform(t.data()) != CE_None) return std::nullopt;
    const double col = 0.5 * ds.GetRasterXSize(), row = 0.5 * ds.GetRasterYSize();
    double x = t[0] + col * t[1] + row * t[2], y = t[3] + col * t[4] + row * t[5];
    OGRSpatialReference wgs84;
    wgs84.importFromEPSG(4326);
    wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // longitude first
    OGRSpatialReference from(srs);
    from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);   // as the geotransform is
    std::unique_ptr<OGRCoordinateTransformation> to(OGRCreateCoordinateTransformation(&from, &wgs84));
    if (!to || !to->Transform(1, &x, &y) || !std::isfinite(x) || !std::isfinite(y) || std::abs(y) > 90) return std::nullopt;
    return std::array<double, 2>{x, y};
}

} // namespace

/// An open height raster (DemSource's).
struct DemDataset {
    std::string path;
    GdalDataset dataset;
    int band = 1;
};

DemDataset* openDemHere(const std::string& path, const DemReadOptions& options, Dem& info, DemBand& heights)
{
    auto source = std::make_unique<DemDataset>();
    source->path = path;
    source->dataset = openRaster(path);
    GDALDataset& ds = *source->dataset;
    const std::string name = fileName(path);
    info.bandsInFile = ds.GetRasterCount();
    if (info.bandsInFile < 1) throw InvalidInputError(name + " has no raster band");
    if (options.band == 0 && info.bandsInFile > 1)
        throw InvalidInputError(name + " has " + std::to_string(info.bandsInFile) +
                                " bands; choose the height band (1 to " + std::to_string(info.bandsInFile) + ")");
    info.band = options.band == 0 ? 1 : options.band;
    if (info.band < 1 || info.band > info.bandsInFile)
        throw InvalidInputError(name + " has no band " + std::to_string(info.band) + " (it has " +
                                std::to_string(info.bandsInFile) + ")");

    RasterGeoreference& g = info.georeference;
    g.width = ds.GetRasterXSize();
    g.height = ds.GetRasterYSize();
    if (ds.GetGeoTransform(g.transform.data()) != CE_None)
        throw InvalidInputError(name + " has no georeferencing (no geotransform): msii needs the cells' positions");
    const OGRSpatialReference* srs = ds.GetSpatialRef();
    if (!srs || srs->IsEmpty()) {
        // gdal_translate writes a GeoTIFF with the system whatever the format (gdal_edit.py
        // only adds an .aux.xml, which GDAL ignores for some, e.g. ESRI ASCII grids). Which
        // system is the data's to say: the hint names none that could mislabel it.
        const std::string stem = std::filesystem::path(path).stem().string();
        throw InvalidInputError(name + " has no coordinate system; assign the one its coordinates are in (the data's " +
                                "documentation gives its EPSG code), e.g. gdal_translate -a_srs EPSG:<code> " + name +
                                " " + stem + "_crs.tif");
    }
    if (srs->IsGeographic()) {
        const std::string stem = std::filesystem::path(path).stem().string();
        const std::optional<std::array<double, 2>> centre = centreInDegrees(ds, *srs);
        const std::string target = centre ? utmCrsFor((*centre)[0], (*centre)[1]) : "EPSG:<UTM zone of the data>";
        throw InvalidInputError(name + " is in geographic coordinates (degrees), whose cells are not square on the ground; " +
                                "reproject it to a projected system first, e.g. to the UTM zone of its centre: gdalwarp " +
                                "-t_srs " + target + " -r bilinear " + name + " " + stem + "_utm.tif");
    }
    describeCrs(*srs, g);
    // Cells beyond 10^12 units from the origin are in no coordinate system of the Earth; double
    // precision could not tell the cells there apart either.
    const std::array<double, 6>& t = g.transform;
    for (const double corner : {t[0], t[3], t[0] + g.width * t[1] + g.height * t[2], t[3] + g.width * t[4] + g.height * t[5]})
        if (!std::isfinite(corner) || std::abs(corner) > 1e12) {
            std::ostringstream where;
            where << corner;
            throw InvalidInputError(name + " has broken georeferencing: its cells reach the coordinate " + where.str() +
                                    ", beyond any coordinate system of the Earth");
        }
    const double det = g.transform[1] * g.transform[5] - g.transform[2] * g.transform[4];
    if (!(std::abs(det) > 0) || !std::isfinite(det)) throw InvalidInputError(name + " has a degenerate geotransform");
    // Elevation models have square cells, or nearly (1 × 2 at most in practice); cells many
    // times longer one way are a broken pixel size, and the height field's quadrature, fine
    // enough for the shorter side, would cut the longer one into that many more pieces.
    const auto [cellWidth, cellHeight] = cellSides(g);
    if (std::max(cellWidth, cellHeight) > kMaxCellAspect * std::min(cellWidth, cellHeight)) {
        std::ostringstream msg;
        msg << name << " has cells of " << cellWidth << " × " << cellHeight
            << ", far longer one way than the other: no elevation model has such cells, so its pixel size is "
            << "likely broken (gdalinfo shows it); if the cells are right, resample them to squares, e.g. gdalwarp -tr "
            << std::min(cellWidth, cellHeight) << ' ' << std::min(cellWidth, cellHeight) << " -r bilinear " << name << ' '
            << std::filesystem::path(path).stem().string() << "_square.tif";
        throw InvalidInputError(msg.str());
    }
    GDALRasterBand* band = ds.GetRasterBand(info.band);
    int hasNodata = 0, hasScale = 0, hasOffset = 0;
    heights.nodata = band->GetNoDataValue(&hasNodata);
    heights.hasNodata = hasNodata != 0;
    const double scale = band->GetScale(&hasScale), offset = band->GetOffset(&hasOffset);
    heights.scaled = (hasScale && scale != 1.0) || (hasOffset && offset != 0.0);
    if (heights.scaled) heights.scale = scale, heights.offset = offset;
    source->band = info.band;
    return source.release();
}

void closeDemHere(DemDataset* dataset) { delete dataset; }

void readHeightsHere(const DemDataset& source, int col0, int row0, int cols, int rows, float* heights)
{
    CPLErrorReset();
    if (source.dataset->GetRasterBand(source.band)->RasterIO(GF_Read, col0, row0, cols, rows, heights, cols, rows,
                                                             GDT_Float32, 0, 0, nullptr) != CE_None)
        throw IOError("cannot read the heights of '" + source.path + "': " + lastGdalError("read error"));
}

std::string crsWktHere(const std::string& definition)
{
    initGdal();
    OGRSpatialReference srs;
    char* wkt = nullptr;
    if (srs.SetFromUserInput(definition.c_str()) != OGRERR_NONE || srs.exportToWkt(&wkt) != OGRERR_NONE || !wkt)
        throw InvalidInputError("'" + definition + "' is not a coordinate system GDAL knows (e.g. EPSG:25832)");
    std::string out(wkt);
    CPLFree(wkt);
    return out;
}

RasterRegion regionOfPartHere(const std::string& mosaic, const std::string& part)
{
    namespace fs = std::filesystem;
    GdalDataset whole = openRaster(mosaic);
    // The part: as given, next to the mosaic, or one of the mosaic's files by name or stem.
    std::string found;
    if (fs::exists(part)) found = part;
    else if (fs::exists(fs::path(mosaic).parent_path() / part)) found = (fs::path(mosaic).parent_path() / part).string();
    else if (char** files = whole->GetFileList()) {
        for (int k = 0; files[k] && found.empty(); ++k) {
            const fs::path f(files[k]);
            if (f.filename().string() == part || f.stem().string() == part) found = files[k];
        }
        CSLDestroy(files);
    }
    if (found.empty()) throw InvalidInputError("'" + part + "' is none of the files of " + fileName(mosaic));
    GdalDataset tile = openRaster(found);
    std::array<double, 6> t{}, p{};
    if (whole->GetGeoTransform(t.data()) != CE_None || tile->GetGeoTransform(p.data()) != CE_None)
        throw InvalidInputError(fileName(found) + " or " + fileName(mosaic) + " has no georeferencing (no geotransform)");
    const double tol = 1e-6;
    const bool sameCells = t[2] == 0 && t[4] == 0 && p[2] == 0 && p[4] == 0 && std::abs(p[1] - t[1]) <= tol * std::abs(t[1]) &&
                           std::abs(p[5] - t[5]) <= tol * std::abs(t[5]);
    const double col = (p[0] - t[0]) / t[1], row = (p[3] - t[3]) / t[5];
    RasterRegion r{int(std::lround(col)), int(std::lround(row)), tile->GetRasterXSize(), tile->GetRasterYSize()};
    if (!sameCells || std::abs(col - r.col) > 1e-3 || std::abs(row - r.row) > 1e-3)
        throw InvalidInputError(fileName(found) + "'s cells are not on the grid of " + fileName(mosaic) +
                                " (another cell size, a rotation, or an offset of a fraction of a cell)");
    // Clipped to the mosaic (a VRT may take only part of a source).
    const int c1 = std::min(whole->GetRasterXSize(), r.col + r.cols), r1 = std::min(whole->GetRasterYSize(), r.row + r.rows);
    r.col = std::max(0, r.col), r.row = std::max(0, r.row), r.cols = c1 - r.col, r.rows = r1 - r.row;
    if (r.cols < 1 || r.rows < 1) throw InvalidInputError(fileName(found) + " lies outside " + fileName(mosaic));
    return r;
}

bool isRasterFileHere(const std::string& path)
{
    initGdal();
    CPLErrorReset();
    GdalDataset ds(GDALDataset::FromHandle(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY,
                                                              nullptr, nullptr, nullptr)));
    return ds != nullptr && ds->GetRasterCount() > 0;
}

} // namespace detail

} // namespace msii
