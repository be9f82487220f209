#include <msii/featuremap/feature_map.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/io/atomic_file.h>
#include <msii/featuremap/half_floats.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfVecAttribute.h>
#include <OpenEXR/ImfFloatVectorAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <Iex.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <set>

namespace msii {
namespace {

namespace fs = std::filesystem;

/// OpenEXR's output stream on an AtomicFile: written front to back, except the table of
/// chunk offsets, which OpenEXR fills in at the end (AtomicFile::writeAt).
class AtomicFileStream : public Imf::OStream {
public:
    explicit AtomicFileStream(AtomicFile& file) : Imf::OStream(file.temporaryPath().c_str()), mFile(file) {}

    void write(const char c[], int n) override
    {
        try {
            const std::uint64_t end = mFile.position(), bytes = std::uint64_t(std::max(n, 0));
            if (mPosition > end) throw Iex::IoExc("cannot seek beyond the end of the data written");
            const std::uint64_t before = std::min(bytes, end - mPosition);  // overwrites
            if (before > 0) mFile.writeAt(mPosition, c, std::size_t(before));
            if (bytes > before) mFile.write(c + before, std::size_t(bytes - before));
            mPosition += bytes;
        } catch (const IOError& e) {
            if (mError.empty()) mError = e.what();
            throw Iex::IoExc(e.what());
        }
    }
    /// The first write error, also one OpenEXR swallowed (its destructor writes the table of
    /// chunk offsets and ignores failures); empty if none.
    const std::string& error() const { return mError; }
    std::uint64_t tellp() override { return mPosition; }
    void seekp(std::uint64_t pos) override { mPosition = pos; }

private:
    AtomicFile& mFile;
    std::uint64_t mPosition = 0;
    std::string mError;
};

constexpr int kRowsPerChunk = 64;
/// Pixels per block of the band fill (writeFeatureMap).
constexpr int kBlockPixels = 64;

Imf::Compression toImf(ExrCompression c)
{
    switch (c) {
    case ExrCompression::None: return Imf::NO_COMPRESSION;
    case ExrCompression::Rle: return Imf::RLE_COMPRESSION;
    case ExrCompression::Zips: return Imf::ZIPS_COMPRESSION;
    case ExrCompression::Zip: return Imf::ZIP_COMPRESSION;
    case ExrCompression::Piz: return Imf::PIZ_COMPRESSION;
    }
    return Imf::ZIP_COMPRESSION;
}

Imath::V3d v3(const Vec3& v) { return Imath::V3d(v.x, v.y, v.z); }
Vec3 vec(const Imath::V3d& v) { return Vec3(v.x, v.y, v.z); }

/// @throw InvalidInputError for a property without one value per vertex, with an empty,
/// reserved or repeated name, or a zip level outside 1 to 9.
void validateMapInputs(const TriMesh& mesh, const std::vector<VertexProperty>& properties,
                       const FeatureMapOptions& options)
{
    static const std::set<std::string> reserved{"height", "normal.x", "normal.y", "normal.z", "mask"};
    std::set<std::string> seen;
    for (const VertexProperty& p : properties) {
        if (p.values.size() != mesh.numVertices())
            throw InvalidInputError("property '" + p.name + "' does not have one value per vertex");
        if (p.name.empty() || reserved.count(p.name) || !seen.insert(p.name).second)
            throw InvalidInputError("property name '" + p.name + "' is empty, reserved or repeated");
    }
    if (options.zipLevel < 1 || options.zipLevel > 9) throw InvalidInputError("the zip level must be 1 to 9");
}

/// Per-vertex values, vertex-major (normal x/y/z in the map frame, or in the mesh's frame
/// without one, then the properties), so that a pixel reads three contiguous rows.
std::vector<float> vertexTable(const TriMesh& mesh, const MapFrame* frame, const std::vector<VertexProperty>& properties)
{
    const std::size_t nv = mesh.numVertices(), numValues = 3 + properties.size();
    std::vector<float> table(nv * numValues);
    MapFrame world;
    world.axisU = {1, 0, 0}, world.axisV = {0, 1, 0}, world.normal = {0, 0, 1};
    const std::array<std::vector<float>, 3> n = vertexNormalsInFrame(mesh, frame ? *frame : world);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            float* row = table.data() + i * numValues;
            for (int c = 0; c < 3; ++c) row[c] = n[std::size_t(c)][i];
            for (std::size_t q = 0; q < properties.size(); ++q) row[3 + q] = properties[q].values[i];
        }
    });
    return table;
}

/// A header of @p width × @p height pixels with the channels @p names and what every map
/// states: units, source, parameters and radii.
Imf::Header baseHeader(int width, int height, const FeatureMapOptions& options, const std::vector<std::string>& names)
{
    const Imf::PixelType type = options.half ? Imf::HALF : Imf::FLOAT;
    Imf::Header header(width, height);
    header.compression() = toImf(options.compression);
    header.zipCompressionLevel() = options.zipLevel;
    for (const std::string& name : names) header.channels().insert(name, Imf::Channel(type));
    header.insert("msii:units", Imf::StringAttribute(options.units));
    header.insert("msii:source", Imf::StringAttribute(options.source));
    header.insert("msii:parameters", Imf::StringAttribute(options.parameters));
    std::vector<float> radii(options.radii.begin(), options.radii.end());
    header.insert("msii:radii", Imf::FloatVectorAttribute(radii));
    return header;
}

/// The header of the map: its channels (@p names), the frame that places a pixel in space,
/// and where the values came from.
Imf::Header mapHeader(const MapFrame& frame, const FeatureMapOptions& options, const std::vector<std::string>& names)
{
    Imf::Header header = baseHeader(frame.width, frame.height, options, names);
    header.insert("msii:pixelSize", Imf::DoubleAttribute(frame.pixelSize));
    header.insert("msii:origin", Imf::V3dAttribute(v3(frame.origin)));
    header.insert("msii:axisU", Imf::V3dAttribute(v3(frame.axisU)));
    header.insert("msii:axisV", Imf::V3dAttribute(v3(frame.axisV)));
    header.insert("msii:normal", Imf::V3dAttribute(v3(frame.normal)));
    header.insert("msii:minU", Imf::DoubleAttribute(frame.minU));
    header.insert("msii:maxV", Imf::DoubleAttribute(frame.maxV));
    header.insert("msii:view", Imf::StringAttribute(mapViewName(frame)));
    Imf::addComments(header, "msii feature map: pixel (x, y) centre at u = minU + (x + 0.5) pixelSize, "
                             "v = maxV - (y + 0.5) pixelSize; point = origin + u axisU + v axisV + "
                             "height normal; NaN = background (see mask)");
    return header;
}

/// A band of kRowsPerChunk rows of the map, one plane per channel in the order height,
/// normal.x/y/z, mask, then the properties, filled from the pixel hits and the vertex table.
class MapBand {
public:
    /// @p width: of the map; @p numValues: per vertex in @p table. With @p views (a sheet of
    /// several views), the table's normals are in the mesh's frame and each pixel turns its
    /// normal into its view's frame: @p rotations[view] holds that frame's axes u, v, n.
    MapBand(const TriMesh& mesh, const PixelHits& hits, const std::vector<float>& table, std::size_t numValues,
            int width, std::size_t numChannels, bool half, const std::vector<std::int8_t>* views = nullptr,
            const std::vector<std::array<float, 9>>* rotations = nullptr)
        : mMesh(mesh), mHits(hits), mTable(table), mNumValues(numValues), mNumChannels(numChannels),
          mWidth(width), mChunkPixels(std::size_t(width) * kRowsPerChunk), mHalf(half), mViews(views),
          mRotations(rotations), mBand(numChannels * mChunkPixels)
    {
        if (half) mBandHalf.resize(numChannels * mChunkPixels);
    }

    /// Rows @p r of the band that starts at row @p y0 of the map.
    void fillRows(int y0, const tbb::blocked_range<int>& r)
    {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        const std::size_t numValues = mNumValues, chunkPixels = mChunkPixels;
        const int width = mWidth;
        // Per row, blocks of kBlockPixels: the values of a block's pixels are interpolated
        // pixel by pixel from the rows of the vertex table (contiguous), then stored
        // channel by channel (contiguous): a pixel's 70 values are not scattered over 70
        // planes one at a time.
        std::vector<float> value(std::size_t(kBlockPixels) * numValues);
        std::array<bool, kBlockPixels> hit{};
        for (int y = r.begin(); y < r.end(); ++y)
            for (int x0 = 0; x0 < width; x0 += kBlockPixels) {
                const int count = std::min(kBlockPixels, width - x0);
                const std::size_t k0 = mHits.index(x0, y0 + y);
                const std::size_t at = std::size_t(y) * std::size_t(width) + std::size_t(x0);
                for (int x = 0; x < count; ++x) {
                    const std::size_t k = k0 + std::size_t(x);
                    const std::uint32_t t = mHits.triangle[k];
                    mBand[at + std::size_t(x)] = mHits.depth[k];
                    mBand[4 * chunkPixels + at + std::size_t(x)] = t != PixelHits::kNone ? 1.0f : 0.0f;
                    hit[std::size_t(x)] = t != PixelHits::kNone;
                    if (t == PixelHits::kNone) continue;
                    // Linear interpolation over the triangle (barycentric weights).
                    const Triangle& tri = mMesh.triangles[t];
                    const float w1 = mHits.b1[k], w2 = mHits.b2[k], w0 = 1.0f - w1 - w2;
                    const float* r0 = mTable.data() + std::size_t(tri[0]) * numValues;
                    const float* r1 = mTable.data() + std::size_t(tri[1]) * numValues;
                    const float* r2 = mTable.data() + std::size_t(tri[2]) * numValues;
                    float* v = value.data() + std::size_t(x) * numValues;
                    for (std::size_t q = 0; q < numValues; ++q) v[q] = w0 * r0[q] + w1 * r1[q] + w2 * r2[q];
                    if (mViews) {
                        const std::array<float, 9>& R = (*mRotations)[std::size_t((*mViews)[k])];
                        const float x = v[0], y = v[1], z = v[2];
                        for (int c = 0; c < 3; ++c) v[c] = R[3 * c] * x + R[3 * c + 1] * y + R[3 * c + 2] * z;
                    }
                    const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                    for (int c = 0; c < 3; ++c) v[c] = len > 0 ? v[c] / len : nan;
                }
                // Channel c of the band holds value q = c − 2 (c >= 5) or c − 1 (normals).
                for (std::size_t q = 0; q < numValues; ++q) {
                    float* out = mBand.data() + (q < 3 ? 1 + q : 2 + q) * chunkPixels + at;
                    const float* v = value.data() + q;
                    for (int x = 0; x < count; ++x) out[x] = hit[std::size_t(x)] ? v[std::size_t(x) * numValues] : nan;
                }
            }
        // --half: the rows just filled, while they are in the cache.
        if (mHalf)
            for (std::size_t c = 0; c < mNumChannels; ++c) {
                const std::size_t from = c * chunkPixels + std::size_t(r.begin()) * std::size_t(width);
                floatsToHalf(mBand.data() + from, mBandHalf.data() + from, std::size_t(r.size()) * std::size_t(width));
            }
    }

    /// The band as OpenEXR's slices of the channels @p names, for the rows from @p y0.
    Imf::FrameBuffer frameBuffer(const std::vector<std::string>& names, int y0)
    {
        const int width = mWidth;
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < mNumChannels; ++c) {
            // Slices address pixel (x, y) as base + x·xStride + y·yStride: shift by y0 rows.
            if (mHalf) {
                half* h = reinterpret_cast<half*>(mBandHalf.data() + c * mChunkPixels);
                char* base = reinterpret_cast<char*>(h) - std::ptrdiff_t(y0) * width * std::ptrdiff_t(sizeof(half));
                fb.insert(names[c], Imf::Slice(Imf::HALF, base, sizeof(half), sizeof(half) * std::size_t(width)));
            } else {
                char* base = reinterpret_cast<char*>(mBand.data() + c * mChunkPixels) -
                             std::ptrdiff_t(y0) * width * std::ptrdiff_t(sizeof(float));
                fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * std::size_t(width)));
            }
        }
        return fb;
    }

private:
    const TriMesh& mMesh;
    const PixelHits& mHits;
    const std::vector<float>& mTable;
    const std::size_t mNumValues, mNumChannels;
    const int mWidth;
    const std::size_t mChunkPixels;
    const bool mHalf;
    const std::vector<std::int8_t>* mViews;
    const std::vector<std::array<float, 9>>* mRotations;
    std::vector<float> mBand;
    std::vector<std::uint16_t> mBandHalf;  // half bits when mHalf
};

} // namespace

ExrCompression parseExrCompression(const std::string& name)
{
    if (name == "none") return ExrCompression::None;
    if (name == "rle") return ExrCompression::Rle;
    if (name == "zips") return ExrCompression::Zips;
    if (name == "zip") return ExrCompression::Zip;
    if (name == "piz") return ExrCompression::Piz;
    throw InvalidInputError("unknown EXR compression '" + name + "' (use zip, zips, piz, rle or none; all lossless)");
}

namespace {

/// The channels' names in the band buffer's order: height, normal.x/y/z, mask, then the
/// properties.
std::vector<std::string> channelNames(const std::vector<VertexProperty>& properties)
{
    std::vector<std::string> names{"height", "normal.x", "normal.y", "normal.z", "mask"};
    for (const VertexProperty& p : properties) names.push_back(p.name);
    return names;
}

/// Writes the map's pixels band by band to @p path, atomically; returns the seconds taken.
double writeBands(const std::string& path, const Imf::Header& header, const std::vector<std::string>& names,
                  MapBand& band, int height, const FeatureMapOptions& options, RunContext* progress)
{
    Stopwatch stage;
    const int width = header.dataWindow().max.x - header.dataWindow().min.x + 1;
    const std::size_t nc = names.size();
    // OpenEXR writes through AtomicFile (a temporary file renamed on commit), which writes
    // past the page cache where it can (AtomicFile::Mode::Large).
    const std::size_t rawBytes = std::size_t(width) * std::size_t(height) * nc * (options.half ? 2 : 4);
    AtomicFile temp(path, rawBytes >= kLargeFileBytes ? AtomicFile::Mode::Large : AtomicFile::Mode::Buffered);
    AtomicFileStream stream(temp);
    try {
        // As many threads as TBB may use here (msii -j limits it).
        Imf::setGlobalThreadCount(int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)));
        Imf::OutputFile file(stream, header);
        const int numChunks = (height + kRowsPerChunk - 1) / kRowsPerChunk;
        if (progress) progress->start("writing the feature map", std::size_t(numChunks));
        for (int y0 = 0; y0 < height; y0 += kRowsPerChunk) {
            const int rows = std::min(kRowsPerChunk, height - y0);
            tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const auto& r) { band.fillRows(y0, r); });
            file.setFrameBuffer(band.frameBuffer(names, y0));
            file.writePixels(rows);
            if (progress) progress->advance();
        }
        if (progress) progress->end();
    } catch (const Iex::BaseExc& e) {
        // A failed write of the file says why itself (e.g. "No space left on device").
        if (!stream.error().empty()) throw IOError(stream.error());
        throw IOError("cannot write " + path + ": " + e.what());
    }
    if (!stream.error().empty()) throw IOError(stream.error());
    temp.commit();
    return stage.seconds();
}

std::vector<std::string> writtenChannels(const Imf::Header& header)
{
    std::vector<std::string> names;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) names.push_back(it.name());
    return names;
}

} // namespace

FeatureMapInfo writeFeatureMap(const std::string& path, const TriMesh& mesh, const MapFrame& frame,
                               const std::vector<VertexProperty>& properties,
                               const FeatureMapOptions& options, RunContext* progress)
{
    validateMapInputs(mesh, properties, options);

    FeatureMapInfo info;
    Stopwatch stage;
    const PixelHits hits = rasterize(mesh, frame, progress);
    info.coveredPixels = hits.covered;
    const std::size_t numValues = 3 + properties.size();
    const std::vector<float> table = vertexTable(mesh, &frame, properties);
    info.rasterSeconds = stage.seconds();

    const std::vector<std::string> names = channelNames(properties);
    const Imf::Header header = mapHeader(frame, options, names);
    MapBand band(mesh, hits, table, numValues, frame.width, names.size(), options.half);
    info.writeSeconds = writeBands(path, header, names, band, frame.height, options, progress);
    info.channels = writtenChannels(header);
    return info;
}

FeatureMapInfo writeFeatureSheet(const std::string& path, const TriMesh& mesh, const FeatureSheet& sheet,
                                 const std::vector<VertexProperty>& properties, const FeatureMapOptions& options,
                                 RunContext* progress)
{
    validateMapInputs(mesh, properties, options);
    if (!sheet.hits || !sheet.view || sheet.view->size() != sheet.hits->triangle.size())
        throw InvalidInputError("the sheet's pixels and their views do not match");
    FeatureMapInfo info;
    Stopwatch stage;
    const PixelHits& hits = *sheet.hits;
    info.coveredPixels = hits.covered;
    const std::vector<float> table = vertexTable(mesh, nullptr, properties);
    std::vector<std::array<float, 9>> rotations;
    for (const MapFrame& f : sheet.frames)
        rotations.push_back({float(f.axisU.x), float(f.axisU.y), float(f.axisU.z), float(f.axisV.x),
                             float(f.axisV.y), float(f.axisV.z), float(f.normal.x), float(f.normal.y),
                             float(f.normal.z)});
    for (std::size_t k = 0; k < hits.triangle.size(); ++k)
        if (hits.triangle[k] != PixelHits::kNone && !(std::size_t((*sheet.view)[k]) < rotations.size()))
            throw InvalidInputError("a pixel of the sheet sees the mesh outside every view");
    info.rasterSeconds = stage.seconds();

    const std::vector<std::string> names = channelNames(properties);
    Imf::Header header = baseHeader(hits.width, hits.height, options, names);
    header.insert("msii:pixelSize", Imf::DoubleAttribute(sheet.pixelSize));
    for (const auto& [name, value] : sheet.attributes) header.insert(name, Imf::StringAttribute(value));
    Imf::addComments(header, "msii feature sheet: several orthographic views on one image; msii:views gives each "
                             "view's box and its matrix from the mesh's coordinates to [column, row, depth]; "
                             "NaN = background (see mask)");
    MapBand band(mesh, hits, table, 3 + properties.size(), hits.width, names.size(), options.half, sheet.view,
                 &rotations);
    info.writeSeconds = writeBands(path, header, names, band, hits.height, options, progress);
    info.channels = writtenChannels(header);
    return info;
}

FeatureMapImage readFeatureMap(const std::string& path, const std::vector<std::string>& only)
{
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw IOError("cannot read " + path + ": no such file");
    FeatureMapImage image;
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        image.width = dw.max.x - dw.min.x + 1;
        image.height = dw.max.y - dw.min.y + 1;
        const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
        Imf::FrameBuffer fb;
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
            image.channelNames.push_back(it.name());
            if (!only.empty() && std::find(only.begin(), only.end(), std::string(it.name())) == only.end()) continue;
            std::vector<float>& data = image.channels[it.name()];
            data.assign(n, 0.0f);
            char* base = reinterpret_cast<char*>(data.data()) -
                         (std::ptrdiff_t(dw.min.x) + std::ptrdiff_t(dw.min.y) * image.width) * std::ptrdiff_t(sizeof(float));
            fb.insert(it.name(), Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * std::size_t(image.width)));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);

        const auto* ps = header.findTypedAttribute<Imf::DoubleAttribute>("msii:pixelSize");
        const auto* o = header.findTypedAttribute<Imf::V3dAttribute>("msii:origin");
        const auto* u = header.findTypedAttribute<Imf::V3dAttribute>("msii:axisU");
        const auto* v = header.findTypedAttribute<Imf::V3dAttribute>("msii:axisV");
        const auto* w = header.findTypedAttribute<Imf::V3dAttribute>("msii:normal");
        const auto* minU = header.findTypedAttribute<Imf::DoubleAttribute>("msii:minU");
        const auto* maxV = header.findTypedAttribute<Imf::DoubleAttribute>("msii:maxV");
        if (ps) image.frame.pixelSize = ps->value();
        if (const auto* a = header.findTypedAttribute<Imf::StringAttribute>("msii:views")) image.views = a->value();
        if (ps && o && u && v && w && minU && maxV) {
            image.hasFrame = true;
            image.frame.pixelSize = ps->value();
            image.frame.origin = vec(o->value());
            image.frame.axisU = vec(u->value());
            image.frame.axisV = vec(v->value());
            image.frame.normal = vec(w->value());
            image.frame.minU = minU->value();
            image.frame.maxV = maxV->value();
            image.frame.width = image.width;
            image.frame.height = image.height;
        }
        if (const auto* a = header.findTypedAttribute<Imf::StringAttribute>("msii:view")) {
            // Written by mapViewName: "best-fit plane", "+x" ... or "direction X,Y,Z".
            const std::string& name = a->value();
            if (name.rfind("direction", 0) == 0) {
                image.frame.view = MapView::Direction;
            } else if (name != "best-fit plane") {
                MapFrameOptions parsed;
                try {
                    parseMapView(name, parsed);
                    image.frame.view = parsed.view;
                } catch (const InvalidInputError&) {
                }
            }
        }
        if (const auto* a = header.findTypedAttribute<Imf::StringAttribute>("msii:units")) image.units = a->value();
        if (const auto* a = header.findTypedAttribute<Imf::StringAttribute>("msii:source")) image.source = a->value();
        if (const auto* a = header.findTypedAttribute<Imf::StringAttribute>("msii:parameters")) image.parameters = a->value();
        if (const auto* a = header.findTypedAttribute<Imf::FloatVectorAttribute>("msii:radii"))
            image.radii.assign(a->value().begin(), a->value().end());
    } catch (const Iex::BaseExc& e) {
        throw IOError("cannot read " + path + ": " + e.what());
    }
    return image;
}

} // namespace msii
