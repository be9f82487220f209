#pragma once
/// @file view_folder.h
/// @brief The folder that `msii view` writes: the page and three.js, and the mesh (or the
/// raster) with its features in `data.bin`, described by `data.json` (docs/view.md).
///
/// Values are stored as 16-bit codes per column over the column's finite range, in steps
/// of a power of two at most (max − min)/32766, so a value is within half a step of the
/// float it came from; code 65535 marks NaN. Every section of data.bin is a zlib stream that the browser inflates itself
/// (DecompressionStream), after its bytes were split into planes and, for codes and
/// indices, replaced by the differences between neighbours: both make the slowly varying
/// part of the numbers repeat, which deflate then removes.
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace msii::tools {

/// The code of a missing value (NaN in a feature file, nodata in a raster).
constexpr std::uint16_t kViewMissingCode = 65535;

/// One column of per-item values: a vertex property of a mesh, or a band of a raster (one
/// value per cell, row-major from the top row).
struct ViewColumn {
    std::string name;
    const std::vector<float>* values = nullptr;
    bool integer = false;  ///< whole numbers (labels, counts): stored exactly where their range fits
};

/// A column as 16-bit codes: value = lo + code · step for code < kViewMissingCode.
struct QuantizedColumn {
    double lo = 0;    ///< a multiple of step at or below the smallest finite value (0 if there is none)
    /// The smallest power of two with (max − min)/step ≤ 65532 (so at most 2·(max − min)/65532);
    /// 1 for whole numbers whose range fits; 0 for a constant column.
    double step = 0;
    double min = std::numeric_limits<double>::quiet_NaN();  ///< of the finite values
    double max = std::numeric_limits<double>::quiet_NaN();
    std::size_t missing = 0;  ///< values coded kViewMissingCode (NaN and infinities)
    bool exact = false;       ///< whole numbers coded one to one
    std::vector<std::uint16_t> codes;
    /// The largest difference between a value and its decoded code: step/2, 0 where exact.
    double maxError() const { return exact ? 0 : step / 2; }
};

/// Codes of @p values over their finite range [min, max] on a grid of power-of-two steps
/// (decoded exactly in double; equal values keep equal codes' values); NaN and ±∞ get
/// kViewMissingCode. Whole numbers (@p integer) whose range is at most 65,534 get step 1
/// and are exact.
QuantizedColumn quantizeColumn(const std::vector<float>& values, bool integer = false);

/// How a section of data.bin is stored before deflate.
struct SectionEncoding {
    bool planes = true;  ///< byte k of every element together, k = 0 … size − 1 (little-endian)
    bool delta = false;  ///< integers only: each element minus the one before, modulo 2^bits
    int level = 6;       ///< zlib's compression level, 1 (fast) … 9 (small)
};

/// @p count elements of @p elementBytes bytes each, transformed as @p encoding says and
/// compressed as one zlib stream (RFC 1950), which the page inflates.
/// @throw IOError if zlib fails.
std::string encodeSection(const void* data, std::size_t count, std::size_t elementBytes, const SectionEncoding& encoding);

/// The inverse of encodeSection (for tests and for reading a folder back).
/// @throw InvalidInputError if @p compressed is not a zlib stream of @p count elements.
std::vector<unsigned char> decodeSection(const std::string& compressed, std::size_t count, std::size_t elementBytes,
                                         const SectionEncoding& encoding);

/// A mesh for the page: positions relative to the centre of its bounding box (float is
/// then exact enough for georeferenced scans too), unit normals as signed bytes.
struct ViewMesh {
    std::vector<float> positions;          ///< x, y, z per vertex, minus `center`
    std::vector<std::int8_t> normals;      ///< x, y, z per vertex, · 127
    std::vector<std::uint32_t> triangles;  ///< three vertex indices per triangle
    std::array<double, 3> center{}, bboxMin{}, bboxMax{};
    /// The frame of msii render's default picture (the best-fit plane): the page's first view.
    std::array<double, 3> right{1, 0, 0}, up{0, 1, 0}, normal{0, 0, 1};
};

/// A raster for the page: a grid of cells, row-major from the top row.
struct ViewRaster {
    int width = 0, height = 0;
    std::array<double, 6> transform{};  ///< GDAL's geotransform
    std::string crs;                    ///< e.g. "EPSG:25832", or the coordinate system's name
    double cellX = 1, cellY = 1;        ///< the cells' sides (positive), in `units`
    std::vector<float> heights;         ///< per cell, NaN for nodata; empty when unknown (no hillshade)
};

/// What the page shows: exactly one of mesh and raster, and the columns of its items.
struct ViewInput {
    std::string source;                 ///< the input's file name: the page's title
    std::string units;                  ///< of lengths and radii ("mm", "m")
    std::vector<double> radii;          ///< r_j = j·R/N, radius ascending; empty when not recorded
    std::vector<std::string> comments;  ///< the input's provenance (PLY comments, raster description)
    std::optional<ViewMesh> mesh;
    std::optional<ViewRaster> raster;
    std::vector<ViewColumn> columns;
};

struct ViewFolderOptions {
    std::string assets;      ///< the page and three.js (share/msii/view), copied into the folder
    bool overwrite = false;  ///< replace an existing folder
    int level = 6;           ///< zlib's compression level of data.bin
    /// Set (by a signal handler) to stop early: the temporary folder is removed and
    /// writeViewFolder throws Interrupted.
    const std::atomic<bool>* cancel = nullptr;
};

/// Thrown when ViewFolderOptions::cancel was set.
struct Interrupted : std::runtime_error {
    Interrupted() : std::runtime_error("interrupted") {}
};

struct ViewFolderResult {
    std::uint64_t folderBytes = 0;  ///< every file of the folder
    std::uint64_t dataBytes = 0;    ///< data.bin
    std::size_t columns = 0;
    double largestError = 0;        ///< the largest maxError() of the feature columns (V_, S_, P_, L_)
};

/// Writes @p folder: the files of options.assets, data.json and data.bin. They are written
/// into a hidden temporary folder beside it, renamed onto @p folder when complete (an
/// existing one is replaced only with options.overwrite), and removed on failure.
/// @throw IOError if @p folder exists without overwrite, or cannot be written;
///        InvalidInputError if the input has no columns or the assets are incomplete.
ViewFolderResult writeViewFolder(const ViewInput& input, const std::string& folder, const ViewFolderOptions& options);

/// The files of the page that options.assets must hold, relative to it.
const std::vector<std::string>& viewAssetFiles();

/// Where the page's files are: @p executable's folder/../share/msii/view (the build tree and
/// an installed prefix alike, see tools/CMakeLists.txt), or the folder MSII_VIEW_ASSETS names.
/// @throw InvalidInputError naming what is missing and how to get it.
std::string findViewAssets(const std::string& executable);

} // namespace msii::tools
