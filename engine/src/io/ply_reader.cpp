#include <msii/io/read_ply.h>

#include <msii/core/errors.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "ply_reader.cpp decodes binary PLY assuming a little-endian host");

namespace msii {

namespace {

// ---------------------------------------------------------------------------------------
// The file, mapped read-only into memory (so a multi-GB scan costs no extra copy).

class MappedFile {
public:
    explicit MappedFile(const std::string& path)
    {
        mFd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (mFd < 0)
            throw IOError("cannot open '" + path + "': " + std::strerror(errno) + ".");
        struct stat st {};
        if (::fstat(mFd, &st) != 0) fail(path, errno);
        if (S_ISDIR(st.st_mode)) {
            ::close(mFd);
            throw IOError("cannot read '" + path + "': it is a folder.");
        }
        mSize = std::size_t(st.st_size);
        if (mSize == 0) return;
        if (S_ISREG(st.st_mode)) {
            void* map = ::mmap(nullptr, mSize, PROT_READ, MAP_PRIVATE, mFd, 0);
            if (map != MAP_FAILED) {
                ::madvise(map, mSize, MADV_SEQUENTIAL);
                mMap = map;
                mData = static_cast<const char*>(map);
                return;
            }
        }
        // Not mappable (special file, exotic file system): read it into memory instead.
        mCopy.resize(mSize);
        std::size_t done = 0;
        while (done < mSize) {
            const ssize_t got = ::read(mFd, mCopy.data() + done, mSize - done);
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) fail(path, errno);
            if (got == 0) break;
            done += std::size_t(got);
        }
        mSize = done;
        mData = mCopy.data();
    }
    ~MappedFile()
    {
        if (mMap) ::munmap(mMap, mSize);
        if (mFd >= 0) ::close(mFd);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    const char* data() const { return mData; }
    std::size_t size() const { return mSize; }

private:
    [[noreturn]] void fail(const std::string& path, int code)
    {
        if (mFd >= 0) ::close(mFd);
        mFd = -1;
        throw IOError("cannot read '" + path + "': " + std::strerror(code) + ".");
    }

    int mFd = -1;
    void* mMap = nullptr;
    const char* mData = nullptr;
    std::size_t mSize = 0;
    std::vector<char> mCopy;
};

// ---------------------------------------------------------------------------------------
// Header

enum class PlyType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::size_t typeSize(PlyType type)
{
    switch (type) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
    }
    return 0;
}

bool parseType(const std::string& name, PlyType& type)
{
    static const std::pair<const char*, PlyType> names[] = {
        {"char", PlyType::Int8},       {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},     {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},   {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},     {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},   {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64},
    };
    for (const auto& [text, value] : names) {
        if (name == text) {
            type = value;
            return true;
        }
    }
    return false;
}

struct PlyProperty {
    std::string name;
    bool isList = false;
    PlyType countType = PlyType::UInt8;  ///< lists only
    PlyType type = PlyType::Float32;     ///< scalar type, or type of the list items
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;

    bool hasLists() const
    {
        return std::any_of(properties.begin(), properties.end(), [](const PlyProperty& p) { return p.isList; });
    }
    /// Smallest possible size of one record in bytes (binary) or in tokens (ascii).
    std::size_t minRecordBytes(bool binary) const
    {
        std::size_t bytes = 0;
        for (const PlyProperty& p : properties)
            bytes += binary ? typeSize(p.isList ? p.countType : p.type) : 1;
        return bytes;
    }
    int findProperty(const std::string& name) const
    {
        for (std::size_t i = 0; i < properties.size(); ++i)
            if (properties[i].name == name) return int(i);
        return -1;
    }
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    std::size_t dataOffset = 0;  ///< first byte after the end_header line
    std::vector<std::string> comments;
};

PlyHeader parseHeader(const std::string& path, const char* data, std::size_t size)
{
    const auto invalid = [&](const std::string& what) {
        return InvalidInputError("the PLY header of '" + path + "' " + what + ".");
    };
    PlyHeader header;
    bool haveFormat = false;
    std::size_t pos = 0, lineNumber = 0;
    while (true) {
        if (pos >= size) {
            if (lineNumber == 0) throw InvalidInputError("'" + path + "' is empty.");
            throw invalid("has no end_header line (the file is truncated or not a PLY file)");
        }
        const char* lineStart = data + pos;
        const char* newline = static_cast<const char*>(std::memchr(lineStart, '\n', size - pos));
        const std::size_t lineLength = newline ? std::size_t(newline - lineStart) : size - pos;
        pos += lineLength + 1;
        std::string line(lineStart, lineLength);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        ++lineNumber;

        if (lineNumber == 1) {
            if (line != "ply")
                throw InvalidInputError("'" + path + "' is not a PLY file (it does not start with 'ply').");
            continue;
        }
        // Guard against binary garbage after a "ply" line being read as an endless header.
        if (lineNumber > 100000) throw invalid("has no end_header line within 100000 lines");

        std::istringstream words(line);
        std::string keyword;
        if (!(words >> keyword)) continue;  // blank line
        if (keyword == "comment") {
            std::string text;
            std::getline(words >> std::ws, text);
            header.comments.push_back(text);
            continue;
        }
        if (keyword == "obj_info") continue;
        if (keyword == "end_header") {
            if (!newline) throw invalid("ends without a newline after end_header");
            break;
        }
        if (keyword == "format") {
            std::string format, version;
            words >> format >> version;
            if (format == "ascii") header.format = PlyFormat::Ascii;
            else if (format == "binary_little_endian") header.format = PlyFormat::BinaryLittleEndian;
            else if (format == "binary_big_endian") header.format = PlyFormat::BinaryBigEndian;
            else throw invalid("has an unknown format '" + format + "'");
            haveFormat = true;
        } else if (keyword == "element") {
            PlyElement element;
            std::string count;
            if (!(words >> element.name >> count)) throw invalid("has an incomplete line '" + line + "'");
            const auto parsed = std::from_chars(count.data(), count.data() + count.size(), element.count);
            if (parsed.ec != std::errc() || parsed.ptr != count.data() + count.size())
                throw invalid("has an invalid element count in '" + line + "'");
            header.elements.push_back(std::move(element));
        } else if (keyword == "property") {
            if (header.elements.empty()) throw invalid("declares a property before any element");
            PlyProperty property;
            std::string type;
            if (!(words >> type)) throw invalid("has an incomplete line '" + line + "'");
            if (type == "list") {
                std::string countType, itemType;
                if (!(words >> countType >> itemType >> property.name))
                    throw invalid("has an incomplete line '" + line + "'");
                if (!parseType(countType, property.countType) || !parseType(itemType, property.type))
                    throw invalid("has an unknown type in '" + line + "'");
                if (property.countType == PlyType::Float32 || property.countType == PlyType::Float64)
                    throw invalid("has a floating-point list count in '" + line + "'");
                property.isList = true;
            } else {
                if (!(words >> property.name)) throw invalid("has an incomplete line '" + line + "'");
                if (!parseType(type, property.type)) throw invalid("has an unknown type in '" + line + "'");
            }
            header.elements.back().properties.push_back(std::move(property));
        } else {
            throw invalid("has an unknown line '" + line + "'");
        }
    }
    if (!haveFormat) throw invalid("has no format line");
    header.dataOffset = pos;
    return header;
}

// ---------------------------------------------------------------------------------------
// Value sources: the same element readers run over binary (either byte order) and ascii
// data through these, resolved at compile time (no per-value virtual call).

/// Where a source is, for error messages.
struct ReadContext {
    const std::string* path = nullptr;
    const PlyElement* element = nullptr;
    std::uint64_t record = 0;

    [[noreturn]] void endOfFile() const
    {
        throw InvalidInputError("unexpected end of file in '" + *path + "' while reading element '" +
                                element->name + "' (record " + std::to_string(record + 1) + " of " +
                                std::to_string(element->count) + ").");
    }
    [[noreturn]] void negativeCount(std::int64_t count) const
    {
        throw InvalidInputError("'" + *path + "' has a negative list length " + std::to_string(count) +
                                " in element '" + element->name + "' (record " + std::to_string(record + 1) +
                                ").");
    }
    [[noreturn]] void badNumber(const char* begin, const char* end) const
    {
        std::string token(begin, std::min<std::size_t>(std::size_t(end - begin), 40));
        throw InvalidInputError("'" + *path + "' has an invalid number '" + token + "' in element '" +
                                element->name + "' (record " + std::to_string(record + 1) + ").");
    }
};

template <bool Swap>
class BinarySource {
public:
    BinarySource(const char* begin, const char* end, ReadContext& context)
        : mPos(begin), mEnd(end), mContext(context)
    {
    }

    double readDouble(PlyType type) { return loadChecked<double>(type); }
    float readFloat(PlyType type) { return loadChecked<float>(type); }
    std::int64_t readInt(PlyType type) { return loadChecked<std::int64_t>(type); }
    /// A list length; one that the rest of the file cannot hold is an unexpected end of
    /// file (and is refused before anything is allocated for it).
    std::size_t readCount(PlyType countType, PlyType itemType)
    {
        const std::int64_t count = readInt(countType);
        if (count < 0) mContext.negativeCount(count);
        if (std::uint64_t(count) > remaining() / typeSize(itemType)) mContext.endOfFile();
        return std::size_t(count);
    }
    void skip(PlyType type) { skipBytes(typeSize(type)); }
    void skipBytes(std::size_t bytes)
    {
        if (std::size_t(mEnd - mPos) < bytes) mContext.endOfFile();
        mPos += bytes;
    }
    ReadContext& context() { return mContext; }
    std::size_t remaining() const { return std::size_t(mEnd - mPos); }
    const char* position() const { return mPos; }
    void advance(std::size_t bytes) { mPos += bytes; }

    template <class T>
    static T load(const char* p)
    {
        T value;
        if constexpr (Swap && sizeof(T) > 1) {
            char bytes[sizeof(T)];
            for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = p[sizeof(T) - 1 - i];
            std::memcpy(&value, bytes, sizeof(T));
        } else {
            std::memcpy(&value, p, sizeof(T));
        }
        return value;
    }

    template <class Out>
    static Out convert(const char* p, PlyType type)
    {
        switch (type) {
        case PlyType::Int8: return Out(load<std::int8_t>(p));
        case PlyType::UInt8: return Out(load<std::uint8_t>(p));
        case PlyType::Int16: return Out(load<std::int16_t>(p));
        case PlyType::UInt16: return Out(load<std::uint16_t>(p));
        case PlyType::Int32: return Out(load<std::int32_t>(p));
        case PlyType::UInt32: return Out(load<std::uint32_t>(p));
        case PlyType::Float32: return convertFloat<Out>(load<float>(p));
        case PlyType::Float64: return convertFloat<Out>(load<double>(p));
        }
        return Out();
    }

private:
    template <class Out, class In>
    static Out convertFloat(In value)
    {
        if constexpr (std::is_integral_v<Out>) {
            // Float-typed indices are unusual; anything that is not a sensible integer maps
            // to an out-of-range index and is reported as such.
            if (!(value > -1e18 && value < 1e18)) return std::numeric_limits<Out>::min();
        }
        return Out(value);
    }

    template <class Out>
    Out loadChecked(PlyType type)
    {
        const std::size_t bytes = typeSize(type);
        if (std::size_t(mEnd - mPos) < bytes) mContext.endOfFile();
        const Out value = convert<Out>(mPos, type);
        mPos += bytes;
        return value;
    }

    const char* mPos;
    const char* mEnd;
    ReadContext& mContext;
};

class AsciiSource {
public:
    AsciiSource(const char* begin, const char* end, ReadContext& context)
        : mPos(begin), mEnd(end), mContext(context)
    {
    }

    double readDouble(PlyType type)
    {
        if (type == PlyType::Float32) return double(parseFloating<float>());
        if (type == PlyType::Float64) return parseFloating<double>();
        return double(parseInteger());
    }
    float readFloat(PlyType type)
    {
        if (type == PlyType::Float32) return parseFloating<float>();
        if (type == PlyType::Float64) return float(parseFloating<double>());
        return float(parseInteger());
    }
    std::int64_t readInt(PlyType /*type*/) { return parseInteger(); }
    /// A list length (see BinarySource::readCount); each item takes at least 2 characters.
    std::size_t readCount(PlyType countType, PlyType /*itemType*/)
    {
        const std::int64_t count = readInt(countType);
        if (count < 0) mContext.negativeCount(count);
        if (std::uint64_t(count) > std::size_t(mEnd - mPos) / 2 + 1) mContext.endOfFile();
        return std::size_t(count);
    }
    ReadContext& context() { return mContext; }
    void skip(PlyType /*type*/)
    {
        const char* begin;
        const char* end;
        nextToken(begin, end);
    }

private:
    static bool isSpace(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\f' || c == '\v'; }

    void nextToken(const char*& begin, const char*& end)
    {
        while (mPos < mEnd && isSpace(*mPos)) ++mPos;
        if (mPos == mEnd) mContext.endOfFile();
        begin = mPos;
        while (mPos < mEnd && !isSpace(*mPos)) ++mPos;
        end = mPos;
    }

    template <class T>
    T parseFloating()
    {
        const char* begin;
        const char* end;
        nextToken(begin, end);
        const char* first = (*begin == '+' && end - begin > 1) ? begin + 1 : begin;
        T value{};
        const auto result = std::from_chars(first, end, value);
        if (result.ptr != end) mContext.badNumber(begin, end);
        if (result.ec == std::errc::result_out_of_range) {
            // from_chars leaves the value untouched for 1e400 or 1e-400; strtod gives the
            // IEEE result (infinity or zero), as a writer of such a file would expect.
            value = T(std::strtod(std::string(first, end).c_str(), nullptr));
        }
        return value;
    }

    std::int64_t parseInteger()
    {
        const char* begin;
        const char* end;
        nextToken(begin, end);
        const char* first = (*begin == '+' && end - begin > 1) ? begin + 1 : begin;
        std::int64_t value = 0;
        const auto result = std::from_chars(first, end, value);
        if (result.ec == std::errc() && result.ptr == end) return value;
        // Some writers print integer properties as "3.0".
        double real = 0;
        const auto asReal = std::from_chars(first, end, real);
        if (asReal.ec == std::errc() && asReal.ptr == end && real == std::floor(real) && std::abs(real) < 1e18)
            return std::int64_t(real);
        mContext.badNumber(begin, end);
    }

    const char* mPos;
    const char* mEnd;
    ReadContext& mContext;
};

// ---------------------------------------------------------------------------------------
// Element readers

class PlyMeshBuilder {
public:
    PlyMeshBuilder(const std::string& path, std::uint64_t numVertices, ReadMeshResult& result)
        : mPath(path), mNumVertices(numVertices), mResult(result)
    {
    }

    /// Fan-triangulates one polygon of the `face` element.
    void addPolygon(const std::int64_t* indices, std::size_t count, std::uint64_t faceNumber)
    {
        for (std::size_t i = 0; i < count; ++i) checkIndex(indices[i], "face", faceNumber);
        auto& triangles = mResult.mesh.triangles;
        for (std::size_t i = 2; i < count; ++i)
            triangles.push_back({std::uint32_t(indices[0]), std::uint32_t(indices[i - 1]), std::uint32_t(indices[i])});
    }

    /// Decodes one record of a `tristrips` element: -1 starts a new strip; in each strip every
    /// second triangle is flipped so all keep the strip's orientation; triangles with a
    /// repeated index (used to stitch strips together) are skipped.
    void addStrips(const std::vector<std::int64_t>& indices, std::uint64_t stripNumber)
    {
        auto& triangles = mResult.mesh.triangles;
        std::size_t start = 0;
        for (std::size_t i = 0; i <= indices.size(); ++i) {
            if (i < indices.size() && indices[i] != -1) {
                checkIndex(indices[i], "tristrips", stripNumber);
                continue;
            }
            for (std::size_t k = start; k + 2 < i; ++k) {
                std::uint32_t a = std::uint32_t(indices[k]), b = std::uint32_t(indices[k + 1]);
                const std::uint32_t c = std::uint32_t(indices[k + 2]);
                if ((k - start) & 1) std::swap(a, b);
                if (a == b || b == c || a == c) continue;
                triangles.push_back({a, b, c});
            }
            start = i + 1;
        }
    }

private:
    void checkIndex(std::int64_t index, const char* element, std::uint64_t number) const
    {
        if (index >= 0 && std::uint64_t(index) < mNumVertices) return;
        throw InvalidInputError("'" + mPath + "' has a vertex index " + std::to_string(index) + " in " +
                                element + " " + std::to_string(number + 1) + " but only " +
                                std::to_string(mNumVertices) + " vertices.");
    }

    const std::string& mPath;
    std::uint64_t mNumVertices;
    ReadMeshResult& mResult;
};

/// A vertex list property kept with ReadMeshOptions::keepVertexLists: every vertex's list,
/// one after the other (all of the same length, checked while reading).
struct KeptList {
    std::string name;
    std::size_t length = 0;     ///< the first vertex's list length
    std::vector<float> values;  ///< numVertices * length
};

/// The name a kept vertex property gets: without the prefix `scalar_` that CloudCompare
/// gives every scalar field it saves (and msii writes with --property-names cloudcompare),
/// unless another property of the element has that name already.
std::string keptName(const PlyElement& element, const std::string& name)
{
    static const std::string prefix = "scalar_";
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return name;
    const std::string plain = name.substr(prefix.size());
    for (const PlyProperty& other : element.properties)
        if (other.name == plain) return name;
    return plain;
}

/// What each vertex property feeds: a coordinate (0, 1, 2), a kept property (3 + index), a
/// kept list (-2 - index), or nothing (-1).
std::vector<int> vertexTargets(const PlyElement& element, const ReadMeshOptions& options,
                               std::vector<VertexProperty>& kept, std::vector<KeptList>& lists)
{
    std::vector<int> targets;
    for (const PlyProperty& property : element.properties) {
        int target = -1;
        if (!property.isList) {
            if (property.name == "x") target = 0;
            else if (property.name == "y") target = 1;
            else if (property.name == "z") target = 2;
            else if (options.keepVertexProperties) {
                target = 3 + int(kept.size());
                const bool integer = property.type != PlyType::Float32 && property.type != PlyType::Float64;
                kept.push_back({keptName(element, property.name), std::vector<float>(element.count), integer});
            }
        } else if (options.keepVertexLists) {
            target = -2 - int(lists.size());
            lists.push_back({property.name, 0, {}});
        }
        targets.push_back(target);
    }
    return targets;
}

/// Appends each kept list as properties <name>_00, <name>_01, ... (element index, zero-based).
void expandLists(std::vector<KeptList>& lists, std::size_t numVertices, std::vector<VertexProperty>& kept)
{
    for (KeptList& list : lists) {
        for (std::size_t k = 0; k < list.length; ++k) {
            const std::string digits = std::to_string(k);
            VertexProperty property{list.name + (digits.size() < 2 ? "_0" : "_") + digits,
                                    std::vector<float>(numVertices)};
            for (std::size_t v = 0; v < numVertices; ++v) property.values[v] = list.values[v * list.length + k];
            kept.push_back(std::move(property));
        }
        list.values = {};
    }
}

template <class Source>
void readVerticesGeneric(Source& source, ReadContext& context, const PlyElement& element,
                         const std::vector<int>& targets, TriMesh& mesh, std::vector<VertexProperty>& kept,
                         std::vector<KeptList>& lists)
{
    for (std::uint64_t v = 0; v < element.count; ++v) {
        context.record = v;
        Vec3& point = mesh.points[v];
        for (std::size_t i = 0; i < element.properties.size(); ++i) {
            const PlyProperty& property = element.properties[i];
            const int target = targets[i];
            if (property.isList) {
                const std::size_t n = source.readCount(property.countType, property.type);
                if (target > -2) {
                    for (std::size_t j = 0; j < n; ++j) source.skip(property.type);
                    continue;
                }
                KeptList& list = lists[std::size_t(-2 - target)];
                if (v == 0) list.length = n;
                if (n != list.length)
                    throw InvalidInputError("'" + *context.path + "' has vertex lists '" + list.name +
                                            "' of different lengths (" + std::to_string(list.length) +
                                            " values at vertex 1, " + std::to_string(n) + " at vertex " +
                                            std::to_string(v + 1) + "); msii keeps only lists of one length.");
                for (std::size_t j = 0; j < n; ++j) list.values.push_back(source.readFloat(property.type));
            } else if (target >= 3) {
                kept[std::size_t(target - 3)].values[v] = source.readFloat(property.type);
            } else if (target >= 0) {
                point[target] = source.readDouble(property.type);
            } else {
                source.skip(property.type);
            }
        }
    }
}

/// Binary vertices with scalar properties only: fixed-size records, checked once.
template <bool Swap>
void readVerticesFixed(BinarySource<Swap>& source, ReadContext& context, const PlyElement& element,
                       const std::vector<int>& targets, TriMesh& mesh, std::vector<VertexProperty>& kept)
{
    struct Field {
        std::size_t offset;
        PlyType type;
        int target;
    };
    std::vector<Field> fields;
    std::size_t recordBytes = 0;
    for (std::size_t i = 0; i < element.properties.size(); ++i) {
        if (targets[i] >= 0) fields.push_back({recordBytes, element.properties[i].type, targets[i]});
        recordBytes += typeSize(element.properties[i].type);
    }
    if (recordBytes != 0 && source.remaining() / recordBytes < element.count) {
        context.record = source.remaining() / recordBytes;
        context.endOfFile();
    }
    const char* data = source.position();
    for (std::uint64_t v = 0; v < element.count; ++v) {
        const char* record = data + v * recordBytes;
        Vec3& point = mesh.points[v];
        for (const Field& field : fields) {
            if (field.target < 3)
                point[field.target] = BinarySource<Swap>::template convert<double>(record + field.offset, field.type);
            else
                kept[std::size_t(field.target - 3)].values[v] =
                    BinarySource<Swap>::template convert<float>(record + field.offset, field.type);
        }
    }
    source.advance(recordBytes * element.count);
}

template <class Source>
void readPolygonsGeneric(Source& source, ReadContext& context, const PlyElement& element, int indexProperty,
                         bool strips, PlyMeshBuilder& builder)
{
    std::vector<std::int64_t> indices;
    for (std::uint64_t f = 0; f < element.count; ++f) {
        context.record = f;
        for (std::size_t i = 0; i < element.properties.size(); ++i) {
            const PlyProperty& property = element.properties[i];
            if (!property.isList) {
                source.skip(property.type);
                continue;
            }
            const std::size_t n = source.readCount(property.countType, property.type);
            if (int(i) != indexProperty) {
                for (std::size_t j = 0; j < n; ++j) source.skip(property.type);
                continue;
            }
            indices.resize(n);
            for (std::size_t j = 0; j < n; ++j) indices[j] = source.readInt(property.type);
        }
        if (strips) builder.addStrips(indices, f);
        else builder.addPolygon(indices.data(), indices.size(), f);
    }
}

/// The layout nearly every writer uses for faces: one `list uchar int|uint` property.
template <bool Swap>
void readFacesFast(BinarySource<Swap>& source, ReadContext& context, const PlyElement& element,
                   PlyMeshBuilder& builder, std::vector<Triangle>& triangles, std::uint64_t numVertices)
{
    const bool isSigned = element.properties[0].type == PlyType::Int32;
    const char* p = source.position();
    const char* const begin = p;
    const std::size_t available = source.remaining();
    const char* const end = p + available;
    std::int64_t indices[256];
    for (std::uint64_t f = 0; f < element.count; ++f) {
        if (p == end) {
            context.record = f;
            context.endOfFile();
        }
        const std::size_t n = std::uint8_t(*p);
        if (std::size_t(end - p - 1) < 4 * n) {
            context.record = f;
            context.endOfFile();
        }
        ++p;
        if (n == 3) {
            const std::uint32_t a = BinarySource<Swap>::template load<std::uint32_t>(p);
            const std::uint32_t b = BinarySource<Swap>::template load<std::uint32_t>(p + 4);
            const std::uint32_t c = BinarySource<Swap>::template load<std::uint32_t>(p + 8);
            // Negative int32 values become huge uint32 values, caught by the same test.
            if (a < numVertices && b < numVertices && c < numVertices) {
                triangles.push_back({a, b, c});
                p += 12;
                continue;
            }
        }
        for (std::size_t j = 0; j < n; ++j) {
            const char* q = p + 4 * j;
            indices[j] = isSigned ? std::int64_t(BinarySource<Swap>::template load<std::int32_t>(q))
                                  : std::int64_t(BinarySource<Swap>::template load<std::uint32_t>(q));
        }
        builder.addPolygon(indices, n, f);
        p += 4 * n;
    }
    source.advance(std::size_t(p - begin));
}

template <class Source>
void skipElementGeneric(Source& source, ReadContext& context, const PlyElement& element)
{
    for (std::uint64_t r = 0; r < element.count; ++r) {
        context.record = r;
        for (const PlyProperty& property : element.properties) {
            if (property.isList) {
                const std::size_t n = source.readCount(property.countType, property.type);
                for (std::size_t j = 0; j < n; ++j) source.skip(property.type);
            } else {
                source.skip(property.type);
            }
        }
    }
}

template <bool Swap>
void skipElementBinary(BinarySource<Swap>& source, ReadContext& context, const PlyElement& element)
{
    if (element.hasLists()) {
        for (std::uint64_t r = 0; r < element.count; ++r) {
            context.record = r;
            for (const PlyProperty& property : element.properties) {
                if (property.isList) {
                    const std::size_t n = source.readCount(property.countType, property.type);
                    source.skipBytes(n * typeSize(property.type));
                } else {
                    source.skip(property.type);
                }
            }
        }
        return;
    }
    const std::size_t recordBytes = element.minRecordBytes(true);
    if (recordBytes != 0 && source.remaining() / recordBytes < element.count) {
        context.record = source.remaining() / recordBytes;
        context.endOfFile();
    }
    source.advance(recordBytes * element.count);
}

int findIndexProperty(const std::string& path, const PlyElement& element)
{
    for (const char* name : {"vertex_indices", "vertex_index"}) {
        const int i = element.findProperty(name);
        if (i >= 0) {
            if (!element.properties[std::size_t(i)].isList)
                throw InvalidInputError("the '" + element.name + "' element of '" + path + "' has a property '" +
                                        name + "' that is not a list.");
            return i;
        }
    }
    throw InvalidInputError("the '" + element.name + "' element of '" + path +
                            "' has no vertex_indices list.");
}

template <class Source>
void readBody(Source& source, const std::string& path, const PlyHeader& header,
              const PlyElement& vertexElement, const ReadMeshOptions& options, ReadMeshResult& result,
              std::size_t remainingBytes)
{
    constexpr bool isBinary = !std::is_same_v<Source, AsciiSource>;
    ReadContext& context = source.context();
    TriMesh& mesh = result.mesh;
    PlyMeshBuilder builder(path, vertexElement.count, result);
    for (const PlyElement& element : header.elements) {
        context.element = &element;
        context.record = 0;
        // A header may declare absurd counts: refuse before reserving memory for them.
        const std::size_t minBytes = element.minRecordBytes(isBinary);
        if (minBytes != 0 && remainingBytes / minBytes < element.count) {
            context.record = remainingBytes / minBytes;
            context.endOfFile();
        }
        if (&element == &vertexElement) {
            mesh.points.assign(element.count, Vec3{});
            std::vector<KeptList> lists;
            const std::vector<int> targets = vertexTargets(element, options, result.vertexProperties, lists);
            if constexpr (isBinary) {
                if (!element.hasLists()) {
                    readVerticesFixed(source, context, element, targets, mesh, result.vertexProperties);
                    continue;
                }
            }
            readVerticesGeneric(source, context, element, targets, mesh, result.vertexProperties, lists);
            expandLists(lists, std::size_t(element.count), result.vertexProperties);
        } else if (element.name == "face" || element.name == "tristrips") {
            const bool strips = element.name == "tristrips";
            const int indexProperty = findIndexProperty(path, element);
            result.numPolygonsRead += element.count;
            if (!strips) mesh.triangles.reserve(mesh.triangles.size() + element.count);
            if constexpr (isBinary) {
                const PlyProperty& first = element.properties[0];
                if (!strips && element.properties.size() == 1 &&
                    first.countType == PlyType::UInt8 &&
                    (first.type == PlyType::Int32 || first.type == PlyType::UInt32)) {
                    readFacesFast(source, context, element, builder, mesh.triangles, vertexElement.count);
                    continue;
                }
            }
            readPolygonsGeneric(source, context, element, indexProperty, strips, builder);
        } else {
            if constexpr (isBinary) skipElementBinary(source, context, element);
            else skipElementGeneric(source, context, element);
        }
    }
}

} // namespace

ReadMeshResult readPly(const std::string& path, const ReadMeshOptions& options)
{
    const MappedFile file(path);
    const PlyHeader header = parseHeader(path, file.data(), file.size());

    const PlyElement* vertexElement = nullptr;
    for (const PlyElement& element : header.elements)
        if (element.name == "vertex" && !vertexElement) vertexElement = &element;
    if (!vertexElement) throw InvalidInputError("'" + path + "' has no vertex element.");
    for (const char* axis : {"x", "y", "z"}) {
        const int i = vertexElement->findProperty(axis);
        if (i < 0 || vertexElement->properties[std::size_t(i)].isList)
            throw InvalidInputError("the vertex element of '" + path + "' has no scalar property '" +
                                    axis + "'.");
    }
    if (vertexElement->count > std::numeric_limits<std::uint32_t>::max())
        throw InvalidInputError("'" + path + "' has more vertices than msii supports (2^32 - 1).");

    ReadMeshResult result;
    result.comments = header.comments;
    ReadContext context;
    context.path = &path;
    const char* begin = file.data() + header.dataOffset;
    const char* end = file.data() + file.size();
    const std::size_t remaining = file.size() - header.dataOffset;
    switch (header.format) {
    case PlyFormat::Ascii: {
        result.format = "ply-ascii";
        AsciiSource source(begin, end, context);
        readBody(source, path, header, *vertexElement, options, result, remaining);
        break;
    }
    case PlyFormat::BinaryLittleEndian: {
        result.format = "ply-binary";
        BinarySource<false> source(begin, end, context);
        readBody(source, path, header, *vertexElement, options, result, remaining);
        break;
    }
    case PlyFormat::BinaryBigEndian: {
        result.format = "ply-binary";
        BinarySource<true> source(begin, end, context);
        readBody(source, path, header, *vertexElement, options, result, remaining);
        break;
    }
    }
    if (result.mesh.points.empty()) throw InvalidInputError("'" + path + "' contains no vertices.");
    if (result.mesh.triangles.empty()) throw InvalidInputError("'" + path + "' contains no faces.");
    return result;
}

} // namespace msii
