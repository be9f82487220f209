#pragma once
/// @file dem.h
/// @brief Digital elevation models (DEMs): single-band height rasters read through GDAL
/// (GeoTIFF, ESRI ASCII grid, VRT mosaics and whatever else GDAL reads), as a triangle
/// mesh the computation takes, and per-cell results written back as georeferenced rasters
/// (terrain/raster_output.h). GDAL stays behind this header (docs/terrain.md).

#include <msii/mesh/trimesh.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace msii {

/// Where a raster's cells are and what its heights mean: what a result raster copies from
/// its input.
struct RasterGeoreference {
    int width = 0, height = 0;  ///< cells (columns, rows)
    /// GDAL's affine geotransform: cell (col, row)'s corner is at
    /// x = t[0] + col·t[1] + row·t[2], y = t[3] + col·t[4] + row·t[5].
    std::array<double, 6> transform{0, 1, 0, 0, 0, -1};
    std::string crsWkt;       ///< the coordinate system, as WKT
    std::string crsName;      ///< e.g. "ETRS89 / UTM zone 32N"
    std::string epsg;         ///< e.g. "25832", empty if none is known
    std::string units;        ///< the coordinate system's linear unit, e.g. "metre"
    double metresPerUnit = 1; ///< that unit in metres
};

struct DemReadOptions {
    int band = 0;  ///< 1-based band to read; 0 = the only band (several are an error)
};

/// Heights no terrain has, read as nodata where the raster declares none for them
/// (docs/terrain.md, "Nodata that is not declared"): the float extremes (|h| ≥ 1e30, e.g.
/// −3.4028235e38, which many tools write), the usual sentinels −9999, −99999, −32767 and
/// −32768, and heights beyond ±12,000 m (Everest is 8,849 m, the deepest sea −10,935 m).
/// Each height is judged alone, so every window of a raster judges its cells alike.
bool isImplausibleHeight(double height, double metresPerUnit);

/// Cells of a read window whose heights were implausible (isImplausibleHeight) and are now
/// nodata; empty if none.
struct UndeclaredNodata {
    std::vector<float> values;          ///< the distinct heights found (at most 255)
    std::vector<std::uint8_t> valueOf;  ///< per cell: 0, or 1 + the index of its value
    bool empty() const { return values.empty(); }
    /// Adds cell @p c's height to @p cellsPerValue if it was one of them.
    void count(std::size_t c, std::map<float, std::size_t>& cellsPerValue) const
    {
        if (!valueOf.empty() && valueOf[c] != 0) ++cellsPerValue[values[valueOf[c] - 1u]];
    }
    /// The cells of each height, over all cells.
    std::map<float, std::size_t> cellsPerValue() const;
};

/// Replaces implausible heights in @p heights by NaN; which were replaced.
UndeclaredNodata implausibleHeightsToNaN(std::vector<float>& heights, double metresPerUnit);

/// @p cellsPerValue (height → cells) with the most cells first.
std::vector<std::pair<float, std::size_t>> mostCellsFirst(const std::map<float, std::size_t>& cellsPerValue);

/// One sentence on @p cellsPerValue (height → cells), the most cells first: "100 cells hold
/// -9999 and 12 hold -3.40282347e+38, heights no terrain has, and the raster declares no
/// nodata value for them: taken as nodata".
std::string describeUndeclaredNodata(const std::map<float, std::size_t>& cellsPerValue);

struct Dem {
    RasterGeoreference georeference;
    std::vector<float> heights;  ///< row-major, row 0 at the top; NaN where nodata
    std::size_t numValid = 0;    ///< cells with a height
    int band = 1;                ///< the band read
    int bandsInFile = 1;
    UndeclaredNodata undeclared; ///< implausible heights taken as nodata
};

/// A height raster opened once and read in windows (for rasters larger than memory).
class DemSource {
public:
    /// Opens @p path and checks it as readDem does (except for the heights).
    DemSource(const std::string& path, const DemReadOptions& options = {});
    ~DemSource();
    DemSource(const DemSource&) = delete;
    DemSource& operator=(const DemSource&) = delete;

    /// The whole raster's grid, band and band count (no heights).
    const Dem& info() const { return mInfo; }
    /// The cells [col0, col0 + cols) × [row0, row0 + rows) as a Dem of their own (its
    /// geotransform moved to the window's corner). @throw IOError
    Dem read(int col0, int row0, int cols, int rows) const;

private:
    struct Impl;  // the GDAL dataset, in libmsii_raster (src/terrain/raster_backend.h)
    std::unique_ptr<Impl> mImpl;
    Dem mInfo;
};

/// Reads a height raster.
/// @throw IOError if GDAL cannot open or read the file; InvalidInputError, with one
/// sentence, if it has no coordinate system, a geographic one (degrees: the sentence names
/// `gdalwarp -t_srs` as the fix), several bands without options.band, a band that does not
/// exist, a rotated geotransform, or no cell with a height.
Dem readDem(const std::string& path, const DemReadOptions& options = {});

/// A coordinate system as WKT, from anything GDAL understands ("EPSG:25832", a WKT or
/// PROJ string). @throw InvalidInputError if GDAL does not.
std::string crsWkt(const std::string& definition);

/// The WGS 84 / UTM coordinate system of the zone holding (@p longitude, @p latitude), in
/// degrees: "EPSG:326zz" north of the equator, "EPSG:327zz" south (zones of 6°, without the
/// exceptions around Norway and Svalbard). For the hint to a DEM in degrees.
std::string utmCrsFor(double longitude, double latitude);

/// The sides of @p grid's cells on the ground: along a row and down a column (its cells may
/// be rectangular or rotated). Inline: the raster library checks them too.
inline std::array<double, 2> cellSides(const RasterGeoreference& grid)
{
    const std::array<double, 6>& t = grid.transform;
    return {std::hypot(t[1], t[4]), std::hypot(t[2], t[5])};
}

/// The shortest step between neighbouring cell centres of @p grid on the ground (its cells
/// may be rectangular or rotated).
double shortestCellStep(const RasterGeoreference& grid);

/// Cells [col, col + cols) × [row, row + rows) of a raster; cols = 0: all of it.
struct RasterRegion {
    int col = 0, row = 0, cols = 0, rows = 0;
};

/// Where the raster @p part (one source tile of the mosaic @p mosaic, e.g. a VRT; a path, a
/// path relative to the mosaic's folder, or the file name or stem of one of its files) lies
/// in the mosaic's grid.
/// @throw InvalidInputError if it is none of the mosaic's files, or its cells are not the
///        mosaic's (another size or rotation, or not on its grid); IOError if unreadable.
RasterRegion regionOfPart(const std::string& mosaic, const std::string& part);

/// True if GDAL can open @p path as a raster (not a mesh format msii reads itself).
bool isRasterFile(const std::string& path);

/// A DEM as a triangle mesh: a vertex at each cell centre with a height (z = height), two
/// triangles per square of four such centres, split along the same diagonal everywhere, and
/// oriented so that their normals point up (+z): the solid is the ground below. Squares with
/// a nodata corner are left out, so nodata cells become holes (mesh preparation fills the
/// small ones; the large ones and the raster's edge are borders).
struct DemMesh {
    TriMesh mesh;
    /// Per cell (row-major), its vertex, or kNoVertex for nodata cells.
    std::vector<std::uint32_t> vertexOfCell;
    static constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();
};
DemMesh demToMesh(const Dem& dem);

/// A per-vertex column of a DemMesh back on the raster's cells (NaN for nodata cells).
std::vector<float> toCells(const DemMesh& dm, const std::vector<float>& perVertex);

} // namespace msii
