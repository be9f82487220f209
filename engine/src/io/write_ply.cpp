#include <msii/io/write_ply.h>

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>
#include <msii/mesh/mesh_stats.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "write_ply.cpp writes binary_little_endian by copying memory: little-endian hosts only");

namespace msii {

namespace {

/// Records per chunk: each chunk is formatted independently (in parallel), then chunks are
/// written in order, a batch at a time so the memory held stays bounded; the next batch is
/// formatted while one is written.
constexpr std::size_t kChunkRecords = std::size_t(1) << 15;
constexpr std::size_t kChunksPerBatch = 8;

using Buffer = std::vector<char>;

/// Calls fill(begin, end, buffer) for consecutive ranges of [0, count) in parallel and
/// writes the buffers to @p file in range order (so the output does not depend on threads).
template <class Fill>
void writeInChunks(AtomicFile& file, std::size_t count, const Fill& fill)
{
    const std::size_t numChunks = (count + kChunkRecords - 1) / kChunkRecords;
    const std::size_t numBatches = (numChunks + kChunksPerBatch - 1) / kChunksPerBatch;
    if (numBatches == 0) return;
    std::array<std::vector<Buffer>, 2> buffers;  // batch b in buffers[b % 2]
    const auto format = [&](std::size_t batch) {
        const std::size_t first = batch * kChunksPerBatch, last = std::min(numChunks, first + kChunksPerBatch);
        std::vector<Buffer>& set = buffers[batch % 2];
        set.resize(last - first);
        tbb::parallel_for(first, last, [&](std::size_t c) {
            Buffer& buffer = set[c - first];
            buffer.clear();
            fill(c * kChunkRecords, std::min(count, (c + 1) * kChunkRecords), buffer);
        });
    };
    format(0);
    for (std::size_t batch = 0; batch < numBatches; ++batch) {
        tbb::task_group next;
        if (batch + 1 < numBatches) next.run([&format, batch] { format(batch + 1); });
        try {
            for (const Buffer& buffer : buffers[batch % 2]) file.write(buffer.data(), buffer.size());
        } catch (...) {
            next.wait();  // the task uses the buffers: let it finish before they go
            throw;
        }
        next.wait();
    }
}

template <class T>
inline char* put(char* out, T value)
{
    std::memcpy(out, &value, sizeof(T));
    return out + sizeof(T);
}

/// Appends the shortest decimal text that reads back to exactly @p value, then @p sep.
template <class T>
inline void appendNumber(Buffer& buffer, T value, char sep)
{
    char text[64];
    const auto result = std::to_chars(text, text + sizeof(text) - 1, value);
    *result.ptr = sep;
    buffer.insert(buffer.end(), text, result.ptr + 1);
}

/// True if storing the points as float would move a coordinate by more than 1e-7 of the
/// bounding box diagonal (e.g. scans in map coordinates with large offsets).
bool needsDoublePoints(const std::vector<Vec3>& points)
{
    const double tolerance = 1e-7 * boundingBox(points).diagonal();
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, points.size(), 1 << 14), false,
        [&](const tbb::blocked_range<std::size_t>& r, bool lossy) {
            for (std::size_t i = r.begin(); i != r.end() && !lossy; ++i) {
                for (int k = 0; k < 3; ++k) {
                    const double c = points[i][k];
                    // NaN compares false and stays NaN in float; out-of-range values become
                    // infinite in float and so count as lossy.
                    if (std::abs(double(float(c)) - c) > tolerance) lossy = true;
                }
            }
            return lossy;
        },
        [](bool a, bool b) { return a || b; });
}

std::string oneLine(std::string text)
{
    std::replace(text.begin(), text.end(), '\n', ' ');
    std::replace(text.begin(), text.end(), '\r', ' ');
    return text;
}

bool isPlyName(const std::string& name)
{
    if (name.empty()) return false;
    return std::none_of(name.begin(), name.end(),
                        [](unsigned char c) { return c <= ' ' || c >= 127; });
}

/// The checks of every PLY written: vertex count, property names, the list, face indices.
void validate(const std::string& path, const TriMesh& mesh, const std::vector<std::string>& names,
              const WritePlyOptions& options)
{
    const std::size_t n = mesh.numVertices();
    const std::string where = "; cannot write '" + path + "'.";
    if (n > std::size_t(std::numeric_limits<std::int32_t>::max()))
        throw InvalidInputError("the mesh has too many vertices for PLY int indices" + where);
    for (const std::string& name : names)
        if (!isPlyName(name))
            throw InvalidInputError("the vertex property name '" + name + "' is empty or contains spaces" + where);
    if (options.listLength < 0 || options.listLength > 255)
        throw InvalidInputError("the list property length " + std::to_string(options.listLength) +
                                " is outside 0..255" + where);
    if (options.listLength > 0) {
        if (!isPlyName(options.listName))
            throw InvalidInputError("the list property name '" + options.listName +
                                    "' is empty or contains spaces" + where);
        if (options.listValues.size() != n * std::size_t(options.listLength))
            throw InvalidInputError("the list property '" + options.listName + "' has " +
                                    std::to_string(options.listValues.size()) + " values for " +
                                    std::to_string(n) + " vertices of " +
                                    std::to_string(options.listLength) + where);
    }
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (std::uint32_t v : mesh.triangles[f])
            if (v >= n)
                throw InvalidInputError("triangle " + std::to_string(f) + " refers to vertex " +
                                        std::to_string(v) + " but the mesh has only " +
                                        std::to_string(n) + " vertices" + where);
}

/// An integer property's value as written: NaN (no value) becomes 0.
inline std::int32_t wholeNumber(float v)
{
    return std::isnan(v) ? 0 : std::int32_t(std::lround(v));
}

char* putPoint(char* out, const Vec3& p, bool doublePoints)
{
    if (doublePoints) {
        out = put(out, p.x);
        out = put(out, p.y);
        return put(out, p.z);
    }
    out = put(out, float(p.x));
    out = put(out, float(p.y));
    return put(out, float(p.z));
}

} // namespace

void writePly(const std::string& path, const TriMesh& mesh,
              const std::vector<VertexProperty>& properties, const WritePlyOptions& options)
{
    std::vector<std::string> names;
    std::vector<bool> integer;
    for (const VertexProperty& property : properties) {
        names.push_back(property.name);
        integer.push_back(property.integer);
        if (property.values.size() != mesh.numVertices())
            throw InvalidInputError("the vertex property '" + property.name + "' has " +
                                    std::to_string(property.values.size()) + " values for " +
                                    std::to_string(mesh.numVertices()) + " vertices; cannot write '" + path + "'.");
    }
    validate(path, mesh, names, options);
    checkWritable(path);

    const std::size_t numVertices = mesh.numVertices();
    const std::size_t numFaces = mesh.numTriangles();
    const bool hasList = options.listLength > 0;
    const std::size_t listLength = hasList ? std::size_t(options.listLength) : 0;
    const bool doublePoints = options.forceDoublePoints || needsDoublePoints(mesh.points);
    const std::string header = plyHeader(mesh.numVertices(), mesh.numTriangles(), names, options, doublePoints, integer);

    // Outputs of many MB are written past the page cache (AtomicFile::Mode::Large).
    const std::size_t approximateBytes =
        numVertices * (3 * sizeof(double) + (properties.size() + listLength) * sizeof(float)) + numFaces * 13;
    AtomicFile file(path, approximateBytes >= kLargeFileBytes ? AtomicFile::Mode::Large : AtomicFile::Mode::Buffered);
    file.write(header);

    const Vec3* points = mesh.points.data();
    const float* list = options.listValues.data();
    if (options.binary) {
        const std::size_t vertexBytes = (doublePoints ? 3 * sizeof(double) : 3 * sizeof(float)) +
                                        properties.size() * sizeof(float) +
                                        (hasList ? 1 + listLength * sizeof(float) : 0);
        writeInChunks(file, numVertices, [&](std::size_t begin, std::size_t end, Buffer& buffer) {
            buffer.resize((end - begin) * vertexBytes);
            char* out = buffer.data();
            for (std::size_t v = begin; v < end; ++v) {
                out = putPoint(out, points[v], doublePoints);
                for (const VertexProperty& property : properties)
                    out = property.integer ? put(out, wholeNumber(property.values[v])) : put(out, property.values[v]);
                if (hasList) {
                    *out++ = char(std::uint8_t(listLength));
                    std::memcpy(out, list + v * listLength, listLength * sizeof(float));
                    out += listLength * sizeof(float);
                }
            }
        });
        writeInChunks(file, numFaces, [&](std::size_t begin, std::size_t end, Buffer& buffer) {
            formatPlyFaces(mesh.triangles.data() + begin, end - begin, buffer);
        });
    } else {
        writeInChunks(file, numVertices, [&](std::size_t begin, std::size_t end, Buffer& buffer) {
            buffer.reserve((end - begin) * (40 + 12 * (properties.size() + listLength)));
            for (std::size_t v = begin; v < end; ++v) {
                const Vec3& p = points[v];
                const bool last = properties.empty() && !hasList;
                for (int k = 0; k < 3; ++k) {
                    const char sep = (k == 2 && last) ? '\n' : ' ';
                    if (doublePoints) appendNumber(buffer, p[k], sep);
                    else appendNumber(buffer, float(p[k]), sep);
                }
                for (std::size_t i = 0; i < properties.size(); ++i) {
                    const char sep = (i + 1 == properties.size() && !hasList) ? '\n' : ' ';
                    if (properties[i].integer) appendNumber(buffer, wholeNumber(properties[i].values[v]), sep);
                    else appendNumber(buffer, properties[i].values[v], sep);
                }
                if (hasList) {
                    appendNumber(buffer, int(listLength), ' ');  // listLength > 0 here
                    for (std::size_t i = 0; i < listLength; ++i)
                        appendNumber(buffer, list[v * listLength + i], i + 1 == listLength ? '\n' : ' ');
                }
            }
        });
        writeInChunks(file, numFaces, [&](std::size_t begin, std::size_t end, Buffer& buffer) {
            buffer.reserve((end - begin) * 32);
            for (std::size_t f = begin; f < end; ++f) {
                const Triangle& t = mesh.triangles[f];
                buffer.push_back('3');
                buffer.push_back(' ');
                appendNumber(buffer, t[0], ' ');
                appendNumber(buffer, t[1], ' ');
                appendNumber(buffer, t[2], '\n');
            }
        });
    }
    file.commit();
}

void formatPlyFaces(const Triangle* triangles, std::size_t count, std::vector<char>& bytes)
{
    bytes.resize(count * kPlyFaceBytes);
    char* out = bytes.data();
    for (std::size_t f = 0; f < count; ++f) {
        *out++ = 3;
        for (std::uint32_t v : triangles[f]) out = put(out, std::int32_t(v));
    }
}

std::string plyHeader(std::size_t numVertices, std::size_t numFaces, const std::vector<std::string>& propertyNames,
                      const WritePlyOptions& options, bool doublePoints, const std::vector<bool>& integer)
{
    const char* pointType = doublePoints ? "double" : "float";
    std::string header = "ply\nformat ";
    header += options.binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
    for (const std::string& comment : options.comments) header += "comment " + oneLine(comment) + "\n";
    header += "element vertex " + std::to_string(numVertices) + "\n";
    for (const char* axis : {"x", "y", "z"}) header += std::string("property ") + pointType + " " + axis + "\n";
    for (std::size_t k = 0; k < propertyNames.size(); ++k)
        header += std::string(k < integer.size() && integer[k] ? "property int " : "property float ") +
                  options.propertyPrefix + propertyNames[k] + "\n";
    if (options.listLength > 0) header += "property list uchar float " + options.listName + "\n";
    header += "element face " + std::to_string(numFaces) + "\n";
    header += "property list uchar int vertex_indices\nend_header\n";
    return header;
}

// ---------------------------------------------------------------------------------------
// PlyPieceWriter

struct PlyPieceWriter::State {
    const TriMesh& mesh;
    AtomicFile file;
    std::size_t recordBytes = 0;
    std::vector<PlyColumn> columns;
    std::uint64_t vertexOffset = 0;  // where the first vertex record starts
    bool doublePoints = false;
    std::vector<bool> written;
    State(const std::string& path, const TriMesh& m) : mesh(m), file(path) {}

    /// Writes the records of vertices[first, last) (consecutive runs in one call each).
    template <class Value>
    void writeRecords(const std::vector<std::uint32_t>& vertices, const Value& value)
    {
        constexpr std::size_t kBufferBytes = std::size_t(8) << 20;
        Buffer buffer;
        std::size_t i = 0;
        while (i < vertices.size()) {
            // A run of consecutive vertices, at most a buffer long.
            std::size_t end = i + 1;
            while (end < vertices.size() && vertices[end] == vertices[end - 1] + 1 &&
                   (end - i + 1) * recordBytes <= kBufferBytes)
                ++end;
            buffer.resize((end - i) * recordBytes);
            char* out = buffer.data();
            for (std::size_t k = i; k < end; ++k) {
                out = putPoint(out, mesh.points[vertices[k]], doublePoints);
                for (std::size_t c = 0; c < columns.size(); ++c) {
                    const float v = value(c, k);
                    out = columns[c].integer ? put(out, wholeNumber(v)) : put(out, v);
                }
            }
            file.writeAt(vertexOffset + std::uint64_t(vertices[i]) * recordBytes, buffer.data(), buffer.size());
            i = end;
        }
    }
};

PlyPieceWriter::PlyPieceWriter(const std::string& path, const TriMesh& mesh, const std::vector<PlyColumn>& columns,
                               const WritePlyOptions& options)
{
    std::vector<std::string> propertyNames;
    std::vector<bool> integer;
    for (const PlyColumn& c : columns) {
        propertyNames.push_back(c.name);
        integer.push_back(c.integer);
    }
    if (!options.binary || options.listLength > 0)
        throw InvalidInputError("a PLY written in pieces is binary and has no list property; cannot write '" + path + "'.");
    validate(path, mesh, propertyNames, options);
    checkWritable(path);
    mState = std::make_unique<State>(path, mesh);
    State& s = *mState;
    s.columns = columns;
    s.doublePoints = options.forceDoublePoints || needsDoublePoints(mesh.points);
    s.recordBytes = (s.doublePoints ? 3 * sizeof(double) : 3 * sizeof(float)) + columns.size() * sizeof(float);
    static_assert(sizeof(std::int32_t) == sizeof(float), "int and float properties take the same room");
    const std::string header =
        plyHeader(mesh.numVertices(), mesh.numTriangles(), propertyNames, options, s.doublePoints, integer);
    s.file.write(header);
    s.vertexOffset = header.size();
    s.written.assign(mesh.numVertices(), false);
    // The faces now, after the room left for the vertex records.
    std::uint64_t at = s.vertexOffset + std::uint64_t(mesh.numVertices()) * s.recordBytes;
    constexpr std::size_t kFaces = std::size_t(1) << 18;
    Buffer buffer;
    for (std::size_t f = 0; f < mesh.numTriangles(); f += kFaces) {
        formatPlyFaces(mesh.triangles.data() + f, std::min(mesh.numTriangles() - f, kFaces), buffer);
        s.file.writeAt(at, buffer.data(), buffer.size());
        at += buffer.size();
    }
}

PlyPieceWriter::~PlyPieceWriter() = default;

void PlyPieceWriter::write(const std::vector<std::uint32_t>& vertices, const std::vector<const float*>& columns)
{
    State& s = *mState;
    if (columns.size() != s.columns.size())
        throw InvalidInputError("PlyPieceWriter: " + std::to_string(columns.size()) + " columns for " +
                                std::to_string(s.columns.size()) + " properties.");
    for (std::uint32_t v : vertices) {
        if (v >= s.written.size())
            throw InvalidInputError("PlyPieceWriter: vertex " + std::to_string(v) + " out of range.");
        s.written[v] = true;
    }
    s.writeRecords(vertices, [&](std::size_t c, std::size_t k) { return columns[c][k]; });
}

void PlyPieceWriter::commit()
{
    State& s = *mState;
    std::vector<std::uint32_t> missing;
    for (std::size_t v = 0; v < s.written.size(); ++v)
        if (!s.written[v]) missing.push_back(std::uint32_t(v));
    s.writeRecords(missing, [&](std::size_t c, std::size_t) { return s.columns[c].missing; });
    s.file.commit();
}

} // namespace msii
