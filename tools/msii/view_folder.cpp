#include "view_folder.h"

#include <msii/core/errors.h>
#include <msii/core/version.h>
#include <msii/render/colormap.h>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <signal.h>
#include <unistd.h>

namespace msii::tools {

namespace fs = std::filesystem;

namespace {

/// Entries of each colour map in data.json: at t = i/255, as msii render's colorAt gives
/// them; the page interpolates between them, within one 8-bit level of colorAt.
constexpr int kColorMapEntries = 256;

void checkCancel(const ViewFolderOptions& options)
{
    if (options.cancel && options.cancel->load()) throw Interrupted();
}

std::string hexColors(ColorMapKind kind)
{
    static const char* digits = "0123456789abcdef";
    std::string hex;
    for (int i = 0; i < kColorMapEntries; ++i) {
        const Rgb8 c = colorAt(kind, double(i) / (kColorMapEntries - 1));
        for (int k = 0; k < 3; ++k) {
            hex += digits[c[k] >> 4];
            hex += digits[c[k] & 15];
        }
    }
    return hex;
}

/// A section of data.bin and its entry in data.json.
struct Section {
    std::string name;
    std::string type;  ///< float32, uint32, uint16, int8
    std::size_t count = 0;
    SectionEncoding encoding;
    std::string bytes;  ///< compressed
};

template <class T>
Section makeSection(const std::string& name, const std::string& type, const std::vector<T>& values,
                    const SectionEncoding& encoding)
{
    return {name, type, values.size(), encoding, encodeSection(values.data(), values.size(), sizeof(T), encoding)};
}

nlohmann::ordered_json array3(const std::array<double, 3>& a) { return nlohmann::ordered_json::array({a[0], a[1], a[2]}); }

/// The 1st and 99th percentile of the finite values (msii render's default range); [0, 1] if there are none.
std::array<double, 2> defaultRange(const std::vector<float>& values)
{
    try {
        const ValueRange r = percentileRange(values, 1, 99);
        return {r.lo, r.hi};
    } catch (const InvalidInputError&) {
        return {0, 1};
    }
}

bool isFeatureColumn(const std::string& name)
{
    return name.size() >= 4 && name[1] == '_' && std::string("VSPL").find(name[0]) != std::string::npos &&
           std::all_of(name.begin() + 2, name.end(), [](unsigned char c) { return std::isdigit(c); });
}

/// Removes temporary folders of @p folder left by runs that were killed (their process is gone).
void removeStaleTemporaries(const fs::path& folder)
{
    const fs::path parent = folder.parent_path().empty() ? fs::path(".") : folder.parent_path();
    const std::string prefix = "." + folder.filename().string() + ".tmp-";
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind(prefix, 0) != 0) continue;
        const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
        if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
    }
}

/// The hidden temporary folder beside @p folder, removed unless released.
class TemporaryFolder {
public:
    explicit TemporaryFolder(const fs::path& folder)
    {
        static int counter = 0;
        const fs::path parent = folder.parent_path().empty() ? fs::path(".") : folder.parent_path();
        mPath = parent / ("." + folder.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                          std::to_string(counter++));
        std::error_code ec;
        fs::create_directory(mPath, ec);
        if (ec) throw IOError("cannot write '" + folder.string() + "': " + ec.message());
    }
    ~TemporaryFolder()
    {
        std::error_code ec;
        if (!mReleased) fs::remove_all(mPath, ec);
    }
    TemporaryFolder(const TemporaryFolder&) = delete;
    TemporaryFolder& operator=(const TemporaryFolder&) = delete;
    const fs::path& path() const { return mPath; }
    void release() { mReleased = true; }

private:
    fs::path mPath;
    bool mReleased = false;
};

void writeFile(const fs::path& path, const std::string& bytes)
{
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.close();
    if (!out) throw IOError("cannot write '" + path.string() + "' (disk full?)");
}

/// data.json without its sections.
nlohmann::ordered_json describe(const ViewInput& input)
{
    nlohmann::ordered_json h;
    h["format"] = "msii-view 1";
    h["generator"] = std::string("msii ") + versionString() + " view";
    h["source"] = input.source;
    h["kind"] = input.mesh ? "mesh" : "raster";
    h["units"] = input.units.empty() ? "mm" : input.units;
    h["comments"] = input.comments;
    h["radii"] = input.radii;
    h["radius"] = input.radii.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(input.radii.back());
    h["scales"] = input.radii.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(input.radii.size());
    if (input.mesh) {
        const ViewMesh& m = *input.mesh;
        h["items"] = m.positions.size() / 3;
        h["mesh"] = {{"vertices", m.positions.size() / 3},
                     {"triangles", m.triangles.size() / 3},
                     {"center", array3(m.center)},
                     {"bbox_min", array3(m.bboxMin)},
                     {"bbox_max", array3(m.bboxMax)},
                     {"view", {{"right", array3(m.right)}, {"up", array3(m.up)}, {"normal", array3(m.normal)}}}};
    } else {
        const ViewRaster& r = *input.raster;
        h["items"] = std::size_t(r.width) * std::size_t(r.height);
        h["raster"] = {{"width", r.width},         {"height", r.height},
                       {"transform", r.transform}, {"crs", r.crs},
                       {"cell", {r.cellX, r.cellY}}, {"heights", !r.heights.empty()}};
    }
    // msii render's light (render/shading.h): the azimuth is the direction the light travels,
    // counter-clockwise from +x in the picture; 315° comes from the top left.
    h["shading"] = {{"azimuth", 315}, {"elevation", 45}, {"ambient", 0.15}, {"strength", 0.6}};
    h["missing_code"] = kViewMissingCode;
    for (ColorMapKind k : {ColorMapKind::Viridis, ColorMapKind::Cividis, ColorMapKind::Gray, ColorMapKind::CoolWarm})
        h["colormaps"][colorMapName(k)] = hexColors(k);
    return h;
}

} // namespace

QuantizedColumn quantizeColumn(const std::vector<float>& values, bool integer)
{
    QuantizedColumn q;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    bool whole = true;
    for (float v : values) {
        if (!std::isfinite(v)) continue;
        lo = std::min(lo, double(v));
        hi = std::max(hi, double(v));
        whole = whole && std::floor(v) == v;
    }
    q.codes.resize(values.size(), kViewMissingCode);
    if (!(lo <= hi)) {  // no finite value
        q.missing = values.size();
        return q;
    }
    q.lo = lo, q.min = lo, q.max = hi;
    constexpr double kLevels = kViewMissingCode - 1;  // codes 0 … 65534
    if (integer && whole && hi - lo <= kLevels) {
        q.step = 1, q.exact = true;
    } else if (hi > lo) {
        // A power of two, and lo a multiple of it: every decoded value lo + code·step is then
        // exact in double, and all columns share one grid, so values equal in the file stay
        // equal (msii metric tests feature vectors for constancy) and the flat surface's 0.5
        // and 1 are exact. The price: a step up to twice (max − min)/65534. Two levels spare
        // for lo rounded down and max rounded up.
        q.step = std::exp2(std::ceil(std::log2((hi - lo) / (kLevels - 2))));
        q.lo = std::floor(lo / q.step) * q.step;
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
        const float v = values[i];
        if (!std::isfinite(v)) {
            ++q.missing;
            continue;
        }
        const double code = q.step > 0 ? std::round((double(v) - q.lo) / q.step) : 0.0;
        q.codes[i] = std::uint16_t(std::clamp(code, 0.0, kLevels));
    }
    return q;
}

std::string encodeSection(const void* data, std::size_t count, std::size_t elementBytes, const SectionEncoding& encoding)
{
    const auto* in = static_cast<const unsigned char*>(data);
    const std::size_t size = count * elementBytes;
    std::string raw(size, '\0');
    if (encoding.delta && elementBytes > 1) {
        // Little-endian integers minus their predecessor, modulo 2^(8·elementBytes), byte by
        // byte with borrow: the same for 2 and 4 bytes, no aliasing of the input.
        std::vector<unsigned char> previous(elementBytes, 0);
        for (std::size_t i = 0; i < count; ++i) {
            int borrow = 0;
            for (std::size_t b = 0; b < elementBytes; ++b) {
                const int d = int(in[i * elementBytes + b]) - int(previous[b]) - borrow;
                borrow = d < 0;
                raw[i * elementBytes + b] = char(d & 0xff);
            }
            std::memcpy(previous.data(), in + i * elementBytes, elementBytes);
        }
    } else {
        std::memcpy(raw.data(), in, size);
    }
    if (encoding.planes && elementBytes > 1) {
        std::string planes(size, '\0');
        for (std::size_t i = 0; i < count; ++i)
            for (std::size_t b = 0; b < elementBytes; ++b) planes[b * count + i] = raw[i * elementBytes + b];
        raw.swap(planes);
    }
    uLongf bound = compressBound(uLong(size));
    std::string out(bound, '\0');
    const int status = compress2(reinterpret_cast<Bytef*>(out.data()), &bound,
                                 reinterpret_cast<const Bytef*>(raw.data()), uLong(size), encoding.level);
    if (status != Z_OK) throw IOError("zlib could not compress a section of " + std::to_string(size) + " bytes");
    out.resize(bound);
    return out;
}

std::vector<unsigned char> decodeSection(const std::string& compressed, std::size_t count, std::size_t elementBytes,
                                         const SectionEncoding& encoding)
{
    const std::size_t size = count * elementBytes;
    std::vector<unsigned char> raw(size);
    uLongf length = uLongf(size);
    const int status = uncompress(raw.data(), &length, reinterpret_cast<const Bytef*>(compressed.data()),
                                  uLong(compressed.size()));
    if (status != Z_OK || length != size)
        throw InvalidInputError("a section of the view is not a zlib stream of " + std::to_string(size) + " bytes");
    if (encoding.planes && elementBytes > 1) {
        std::vector<unsigned char> joined(size);
        for (std::size_t i = 0; i < count; ++i)
            for (std::size_t b = 0; b < elementBytes; ++b) joined[i * elementBytes + b] = raw[b * count + i];
        raw.swap(joined);
    }
    if (encoding.delta && elementBytes > 1)
        for (std::size_t i = 1; i < count; ++i) {
            int carry = 0;
            for (std::size_t b = 0; b < elementBytes; ++b) {
                const int s = int(raw[i * elementBytes + b]) + int(raw[(i - 1) * elementBytes + b]) + carry;
                carry = s > 0xff;
                raw[i * elementBytes + b] = static_cast<unsigned char>(s & 0xff);
            }
        }
    return raw;
}

const std::vector<std::string>& viewAssetFiles()
{
    static const std::vector<std::string> files{
        "index.html",
        "viewer.js",
        "viewer.css",
        "data.js",
        "metrics.js",
        "plot.js",
        "three/three.module.js",
        "three/three.core.js",
        "three/LICENSE",
        "three/addons/controls/OrbitControls.js",
        "three/addons/controls/MapControls.js",
    };
    return files;
}

std::string findViewAssets(const std::string& executable)
{
    fs::path dir;
    if (const char* env = std::getenv("MSII_VIEW_ASSETS"); env && *env) dir = env;
    else dir = fs::path(executable).parent_path() / MSII_VIEW_ASSETS_FROM_BIN;
    dir = dir.lexically_normal();
    for (const std::string& f : viewAssetFiles())
        if (!fs::is_regular_file(dir / f))
            throw InvalidInputError("the viewer's page is incomplete: '" + (dir / f).string() +
                                    "' is missing (run npm ci in the source folder, which installs three.js, then "
                                    "build msii again)");
    return dir.string();
}

ViewFolderResult writeViewFolder(const ViewInput& input, const std::string& folder, const ViewFolderOptions& options)
{
    if (input.mesh.has_value() == input.raster.has_value())
        throw InvalidInputError("a view holds a mesh or a raster");
    if (input.columns.empty()) throw InvalidInputError("there is nothing to colour by: the input has no per-vertex values");
    const fs::path target(folder);
    std::error_code ec;
    if (fs::exists(fs::symlink_status(target, ec)) && !options.overwrite)
        throw IOError("'" + folder + "' exists already (use --overwrite to replace it)");
    removeStaleTemporaries(target);

    ViewFolderResult result;
    nlohmann::ordered_json header = describe(input);

    // The geometry first, then the columns; each is an independent zlib stream.
    std::vector<Section> sections;
    if (input.mesh) {
        const ViewMesh& m = *input.mesh;
        sections.push_back(makeSection("positions", "float32", m.positions, {true, false, options.level}));
        sections.push_back(makeSection("normals", "int8", m.normals, {false, false, options.level}));
        // Differences alone: nearly as small as with byte planes (0.38 MB against 0.30 for
        // the 1.1M-vertex tablet), and quicker for the page to undo before its first frame.
        sections.push_back(makeSection("indices", "uint32", m.triangles, {false, true, options.level}));
    } else if (!input.raster->heights.empty()) {
        sections.push_back(makeSection("heights", "float32", input.raster->heights, {true, false, options.level}));
    }
    checkCancel(options);
    const std::size_t firstColumn = sections.size();
    sections.resize(firstColumn + input.columns.size());
    std::vector<nlohmann::ordered_json> columns(input.columns.size());
    tbb::parallel_for(std::size_t(0), input.columns.size(), [&](std::size_t k) {
        if (options.cancel && options.cancel->load()) return;
        const ViewColumn& c = input.columns[k];
        const QuantizedColumn q = quantizeColumn(*c.values, c.integer);
        const std::array<double, 2> range = defaultRange(*c.values);
        const std::string name = "column:" + c.name;
        sections[firstColumn + k] = makeSection(name, "uint16", q.codes, {true, true, options.level});
        columns[k] = {{"name", c.name},
                      {"section", name},
                      {"lo", q.lo},
                      {"step", q.step},
                      {"max_error", q.maxError()},
                      {"min", std::isnan(q.min) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(q.min)},
                      {"max", std::isnan(q.max) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(q.max)},
                      {"missing", q.missing},
                      {"percentiles", range},
                      {"integer", c.integer}};
    });
    checkCancel(options);
    for (std::size_t k = 0; k < input.columns.size(); ++k)
        if (isFeatureColumn(input.columns[k].name))
            result.largestError = std::max(result.largestError, columns[k]["max_error"].get<double>());
    header["columns"] = columns;
    // The column the page shows first (quality, else the first) right after the geometry:
    // the page draws as soon as those bytes have arrived, while the rest still streams in.
    const auto shownFirst = std::find_if(input.columns.begin(), input.columns.end(),
                                         [](const ViewColumn& c) { return c.name == "quality"; });
    if (shownFirst != input.columns.end())
        std::rotate(sections.begin() + std::ptrdiff_t(firstColumn),
                    sections.begin() + std::ptrdiff_t(firstColumn) + (shownFirst - input.columns.begin()),
                    sections.begin() + std::ptrdiff_t(firstColumn) + (shownFirst - input.columns.begin()) + 1);
    std::uint64_t offset = 0;
    for (const Section& s : sections) {
        header["sections"][s.name] = {{"offset", offset},     {"bytes", s.bytes.size()},     {"type", s.type},
                                      {"count", s.count},      {"planes", s.encoding.planes}, {"delta", s.encoding.delta},
                                      {"compression", "deflate"}};
        offset += s.bytes.size();
    }

    TemporaryFolder temp(target);
    for (const std::string& f : viewAssetFiles()) {
        const fs::path to = temp.path() / f;
        fs::create_directories(to.parent_path());
        fs::copy_file(fs::path(options.assets) / f, to, fs::copy_options::overwrite_existing);
    }
    writeFile(temp.path() / "data.json", header.dump(1) + "\n");
    {
        std::ofstream out(temp.path() / "data.bin", std::ios::binary);
        for (const Section& s : sections) {
            checkCancel(options);
            out.write(s.bytes.data(), std::streamsize(s.bytes.size()));
        }
        out.close();
        if (!out) throw IOError("cannot write '" + (target / "data.bin").string() + "' (disk full?)");
    }
    result.dataBytes = offset;
    result.columns = input.columns.size();
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(temp.path()))
        if (e.is_regular_file()) result.folderBytes += e.file_size();
    checkCancel(options);

    // An existing folder is moved aside first (a folder cannot be renamed over a full one).
    fs::path old;
    if (fs::exists(fs::symlink_status(target, ec))) {
        old = temp.path().parent_path() / ("." + target.filename().string() + ".old-" + std::to_string(::getpid()));
        fs::remove_all(old, ec);
        fs::rename(target, old);
    }
    try {
        fs::rename(temp.path(), target);
    } catch (const fs::filesystem_error& e) {
        if (!old.empty()) fs::rename(old, target, ec);
        throw IOError("cannot write '" + folder + "': " + e.code().message());
    }
    temp.release();
    if (!old.empty()) fs::remove_all(old, ec);
    return result;
}

} // namespace msii::tools
