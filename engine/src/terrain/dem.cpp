#include <msii/terrain/dem.h>

#include "raster_backend.h"

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <iomanip>
#include <sstream>

namespace msii {

namespace {

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

} // namespace

std::string utmCrsFor(double longitude, double latitude)
{
    const double lon = std::remainder(longitude, 360.0);  // [-180, 180]
    const int zone = std::clamp(int(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
    return "EPSG:" + std::to_string((latitude >= 0 ? 32600 : 32700) + zone);
}

double shortestCellStep(const RasterGeoreference& grid)
{
    const auto [width, height] = cellSides(grid);
    return std::min(width, height);
}

struct DemSource::Impl {
    detail::DemDataset* dataset = nullptr;  // the raster library's
    detail::DemBand heights;
    ~Impl()
    {
        if (dataset != nullptr) detail::rasterBackend().closeDem(dataset);
    }
};

DemSource::DemSource(const std::string& path, const DemReadOptions& options) : mImpl(std::make_unique<Impl>())
{
    mImpl->dataset = detail::rasterBackend().openDem(path, options, mInfo, mImpl->heights);
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
    detail::rasterBackend().readHeights(*mImpl->dataset, col0, row0, cols, rows, dem.heights.data());
    const float nan = std::numeric_limits<float>::quiet_NaN();
    // GDAL's scale and offset give the heights; nodata is compared before scaling.
    const detail::DemBand& band = mImpl->heights;
    const float nodata = float(band.nodata);
    // In parallel (a window has millions of cells): nodata to NaN, scaling, and whether any
    // height is implausible (rare: those are then taken one by one, in the cells' order).
    const double metresPerUnit = g.metresPerUnit;
    std::atomic<bool> implausible{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, dem.heights.size(), 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          bool seen = false;
                          for (std::size_t c = range.begin(); c < range.end(); ++c) {
                              float& h = dem.heights[c];
                              if (!std::isfinite(h) || (band.hasNodata && h == nodata)) h = nan;
                              else if (band.scaled) h = float(double(h) * band.scale + band.offset);
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

std::string crsWkt(const std::string& definition) { return detail::rasterBackend().crsWkt(definition); }

RasterRegion regionOfPart(const std::string& mosaic, const std::string& part)
{
    return detail::rasterBackend().regionOfPart(mosaic, part);
}

bool isRasterFile(const std::string& path) { return detail::rasterBackend().isRasterFile(path); }

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
