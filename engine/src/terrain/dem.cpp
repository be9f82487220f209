#include <msii/terrain/dem.h>

#include "gdal_support.h"

#include <msii/core/errors.h>

#include <cpl_error.h>
#include <cpl_string.h>
#include <ogr_spatialref.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <sstream>
#include <memory>
#include <mutex>
#include <optional>

namespace msii {

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

} // namespace detail

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

std::string utmCrsFor(double longitude, double latitude)
{
    const double lon = std::remainder(longitude, 360.0);  // [-180, 180]
    const int zone = std::clamp(int(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
    return "EPSG:" + std::to_string((latitude >= 0 ? 32600 : 32700) + zone);
}

std::string crsWkt(const std::string& definition)
{
    detail::initGdal();
    OGRSpatialReference srs;
    char* wkt = nullptr;
    if (srs.SetFromUserInput(definition.c_str()) != OGRERR_NONE || srs.exportToWkt(&wkt) != OGRERR_NONE || !wkt)
        throw InvalidInputError("'" + definition + "' is not a coordinate system GDAL knows (e.g. EPSG:25832)");
    std::string out(wkt);
    CPLFree(wkt);
    return out;
}

double shortestCellStep(const RasterGeoreference& grid)
{
    const std::array<double, 6>& t = grid.transform;
    return std::min(std::hypot(t[1], t[4]), std::hypot(t[2], t[5]));
}

RasterRegion regionOfPart(const std::string& mosaic, const std::string& part)
{
    namespace fs = std::filesystem;
    detail::GdalDataset whole = detail::openRaster(mosaic);
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
    detail::GdalDataset tile = detail::openRaster(found);
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

bool isRasterFile(const std::string& path)
{
    detail::initGdal();
    CPLErrorReset();
    detail::GdalDataset ds(GDALDataset::FromHandle(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY,
                                                              nullptr, nullptr, nullptr)));
    return ds != nullptr && ds->GetRasterCount() > 0;
}

struct DemSource::Impl {
    std::string path;
    detail::GdalDataset dataset;
    double nodata = 0;
    bool hasNodata = false;
};

DemSource::DemSource(const std::string& path, const DemReadOptions& options) : mImpl(std::make_unique<Impl>())
{
    mImpl->path = path;
    detail::GdalDataset& mDataset = mImpl->dataset;
    mDataset = detail::openRaster(path);
    GDALDataset& ds = *mDataset;
    const std::string name = fileName(path);
    mInfo.bandsInFile = ds.GetRasterCount();
    if (mInfo.bandsInFile < 1) throw InvalidInputError(name + " has no raster band");
    if (options.band == 0 && mInfo.bandsInFile > 1)
        throw InvalidInputError(name + " has " + std::to_string(mInfo.bandsInFile) +
                                " bands; choose the height band (1 to " + std::to_string(mInfo.bandsInFile) + ")");
    mInfo.band = options.band == 0 ? 1 : options.band;
    if (mInfo.band < 1 || mInfo.band > mInfo.bandsInFile)
        throw InvalidInputError(name + " has no band " + std::to_string(mInfo.band) + " (it has " +
                                std::to_string(mInfo.bandsInFile) + ")");

    RasterGeoreference& g = mInfo.georeference;
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
    detail::describeCrs(*srs, g);
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
    int hasNodata = 0;
    mImpl->nodata = ds.GetRasterBand(mInfo.band)->GetNoDataValue(&hasNodata);
    mImpl->hasNodata = hasNodata != 0;
}

DemSource::~DemSource() = default;

Dem DemSource::read(int col0, int row0, int cols, int rows) const
{
    const RasterGeoreference& whole = mInfo.georeference;
    if (col0 < 0 || row0 < 0 || cols < 1 || rows < 1 || col0 + cols > whole.width || row0 + rows > whole.height)
        throw InvalidInputError("the window lies outside the raster");
    Dem dem;
    dem.band = mInfo.band;
    dem.bandsInFile = mInfo.bandsInFile;
    RasterGeoreference& g = dem.georeference;
    g = whole;
    g.width = cols;
    g.height = rows;
    const std::array<double, 6>& t = whole.transform;
    g.transform[0] = t[0] + col0 * t[1] + row0 * t[2];
    g.transform[3] = t[3] + col0 * t[4] + row0 * t[5];
    dem.heights.resize(std::size_t(cols) * std::size_t(rows));
    CPLErrorReset();
    if (mImpl->dataset->GetRasterBand(mInfo.band)->RasterIO(GF_Read, col0, row0, cols, rows, dem.heights.data(), cols, rows,
                                                      GDT_Float32, 0, 0, nullptr) != CE_None)
 throw IOError("cannot read the heights of '" + mImpl->path + "': " + detail::lastGdalError("read error"));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float nodata = float(mImpl->nodata);
    // Heights stored as scaled integers (e.g. centimetres in Int16 with a scale of 0.01):
    // GDAL's scale and offset give metres; nodata is compared before scaling.
    int hasScale = 0, hasOffset = 0;
    GDALRasterBand* band = mImpl->dataset->GetRasterBand(mInfo.band);
    const double scale = band->GetScale(&hasScale), offset = band->GetOffset(&hasOffset);
    const bool scaled = (hasScale && scale != 1.0) || (hasOffset && offset != 0.0);
    // In parallel (a window has millions of cells): nodata to NaN, scaling, and whether any
    // height is implausible (rare: those are then taken one by one, in the cells' order).
    const bool hasNodata = mImpl->hasNodata;
    const double metresPerUnit = g.metresPerUnit;
    std::atomic<bool> implausible{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, dem.heights.size(), 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          bool seen = false;
                          for (std::size_t c = range.begin(); c < range.end(); ++c) {
                              float& h = dem.heights[c];
                              if (!std::isfinite(h) || (hasNodata && h == nodata)) h = nan;
                              else if (scaled) h = float(double(h) * scale + offset);
                              seen = seen || (!std::isnan(h) && isImplausibleHeight(h, metresPerUnit));
                          }
                          if (seen) implausible = true;
                      });
    if (implausible) dem.undeclared = implausibleHeightsToNaN(dem.heights, metresPerUnit);
    dem.numValid = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, dem.heights.size(), 1 << 16), std::size_t(0),
        [&](const tbb::blocked_range<std::size_t>& range, std::size_t n) {
            for (std::size_t c = range.begin(); c < range.end(); ++c) n += !std::isnan(dem.heights[c]);
            return n;
        },
        std::plus<std::size_t>());
    return dem;
}

bool isImplausibleHeight(double h, double metresPerUnit)
{
    return std::abs(h) >= 1e30 || h == -9999.0 || h == -99999.0 || h == -32767.0 || h == -32768.0 ||
           std::abs(h * metresPerUnit) > 12000.0;
}

UndeclaredNodata implausibleHeightsToNaN(std::vector<float>& heights, double metresPerUnit)
{
    UndeclaredNodata found;
    for (std::size_t c = 0; c < heights.size(); ++c) {
        const float h = heights[c];
        if (std::isnan(h) || !isImplausibleHeight(h, metresPerUnit)) continue;
        if (found.valueOf.empty()) found.valueOf.assign(heights.size(), 0);
        auto it = std::find(found.values.begin(), found.values.end(), h);
        if (it == found.values.end()) {
            if (found.values.size() < 255) it = found.values.insert(found.values.end(), h);
            else it = found.values.end() - 1;  // beyond 255 distinct values: counted with the last
        }
        found.valueOf[c] = std::uint8_t(1 + (it - found.values.begin()));
        heights[c] = std::numeric_limits<float>::quiet_NaN();
    }
    return found;
}

std::map<float, std::size_t> UndeclaredNodata::cellsPerValue() const
{
    std::map<float, std::size_t> out;
    for (std::size_t c = 0; c < valueOf.size(); ++c) count(c, out);
    return out;
}

std::vector<std::pair<float, std::size_t>> mostCellsFirst(const std::map<float, std::size_t>& cellsPerValue)
{
    std::vector<std::pair<float, std::size_t>> out(cellsPerValue.begin(), cellsPerValue.end());
    std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
    return out;
}

std::string describeUndeclaredNodata(const std::map<float, std::size_t>& cellsPerValue)
{
    const std::vector<std::pair<float, std::size_t>> counts = mostCellsFirst(cellsPerValue);
    std::ostringstream out;
    out << std::setprecision(9);  // a float's every digit: the value to declare as nodata
    std::size_t shown = 0;
    for (const auto& [value, cells] : counts) {
        if (shown == 4) {
            out << " and other values";
            break;
        }
        out << (shown == 0 ? "" : shown + 1 == counts.size() ? " and " : ", ") << cells
            << (shown == 0 ? (cells == 1 ? " cell holds " : " cells hold ") : " hold ") << value;
        ++shown;
    }
    out << ", heights no terrain has, and the raster declares no nodata value for "
        << (counts.size() == 1 ? "it" : "them") << ": taken as nodata";
    return out.str();
}

Dem readDem(const std::string& path, const DemReadOptions& options)
{
    const DemSource source(path, options);
    const RasterGeoreference& g = source.info().georeference;
    Dem dem = source.read(0, 0, g.width, g.height);
    if (dem.numValid == 0)
        throw InvalidInputError(fileName(path) + " has no cell with a height (all nodata)");
    return dem;
}

DemMesh demToMesh(const Dem& dem)
{
    const RasterGeoreference& g = dem.georeference;
    const std::array<double, 6>& t = g.transform;
    const std::size_t w = std::size_t(g.width), h = std::size_t(g.height);
    DemMesh dm;
    dm.vertexOfCell.assign(w * h, DemMesh::kNoVertex);
    dm.mesh.points.reserve(dem.numValid);
    for (std::size_t row = 0; row < h; ++row)
        for (std::size_t col = 0; col < w; ++col) {
            const float z = dem.heights[row * w + col];
            if (std::isnan(z)) continue;
            const double c = double(col) + 0.5, r = double(row) + 0.5;
            dm.vertexOfCell[row * w + col] = std::uint32_t(dm.mesh.points.size());
            dm.mesh.points.push_back({t[0] + c * t[1] + r * t[2], t[3] + c * t[4] + r * t[5], double(z)});
        }
    // (a, c, b) in (col, row) order turns clockwise seen from +row × +col; in the world its
    // normal points up when the geotransform flips orientation (north-up rasters: rows go
    // south, det < 0), so the winding follows the determinant's sign.
    const bool flip = t[1] * t[5] - t[2] * t[4] > 0;
    const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        dm.mesh.triangles.push_back(flip ? Triangle{a, b, c} : Triangle{a, c, b});
    };
    for (std::size_t row = 0; row + 1 < h; ++row)
        for (std::size_t col = 0; col + 1 < w; ++col) {
            const std::uint32_t a = dm.vertexOfCell[row * w + col], b = dm.vertexOfCell[row * w + col + 1],
                                c = dm.vertexOfCell[(row + 1) * w + col], d = dm.vertexOfCell[(row + 1) * w + col + 1];
            if (a == DemMesh::kNoVertex || b == DemMesh::kNoVertex || c == DemMesh::kNoVertex ||
                d == DemMesh::kNoVertex)
                continue;
            add(a, b, c);  // the diagonal b–c in every square
            add(b, d, c);
        }
    return dm;
}

std::vector<float> toCells(const DemMesh& dm, const std::vector<float>& perVertex)
{
    std::vector<float> cells(dm.vertexOfCell.size(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t k = 0; k < cells.size(); ++k)
        if (dm.vertexOfCell[k] != DemMesh::kNoVertex) cells[k] = perVertex[dm.vertexOfCell[k]];
    return cells;
}

} // namespace msii
