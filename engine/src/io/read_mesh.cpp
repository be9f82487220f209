#include <msii/io/read_mesh.h>

#include <msii/core/errors.h>
#include <msii/io/read_ply.h>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/Options.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cmath>
#include <limits>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <sstream>
#include <streambuf>
#include <string_view>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace msii {

namespace {

using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

/// Collects what an OpenMesh reader delivers, as it comes: no topology is built, so faces
/// that OpenMesh's own mesh kernel would refuse (non-manifold, duplicate) are kept for
/// mesh_check to report. Polygons are fan-triangulated.
class RawImporter final : public OpenMesh::IO::BaseImporter {
public:
    std::vector<Vec3> points;
    std::vector<Triangle> triangles;
    std::size_t numPolygons = 0;
    /// First face index outside the vertex array, if any (reported after reading, since
    /// throwing through OpenMesh's reader would skip its clean-up).
    bool badIndex = false;
    long long badIndexValue = 0;
    std::size_t badIndexFace = 0;

    VertexHandle add_vertex(const OpenMesh::Vec3f& p) override { return addPoint({p[0], p[1], p[2]}); }
    VertexHandle add_vertex(const OpenMesh::Vec3d& p) override { return addPoint({p[0], p[1], p[2]}); }
    VertexHandle add_vertex() override { return addPoint({}); }
    void set_point(VertexHandle v, const OpenMesh::Vec3f& p) override
    {
        if (v.is_valid() && std::size_t(v.idx()) < points.size()) points[std::size_t(v.idx())] = {p[0], p[1], p[2]};
    }

    FaceHandle add_face(const VHandles& vertices) override
    {
        const std::size_t face = numPolygons++;
        for (const VertexHandle& v : vertices) {
            if (v.idx() < 0 || std::size_t(v.idx()) >= points.size()) {
                if (!badIndex) {
                    badIndex = true;
                    badIndexValue = v.idx();
                    badIndexFace = face;
                }
                return FaceHandle(int(face));
            }
        }
        for (std::size_t i = 2; i < vertices.size(); ++i)
            triangles.push_back({std::uint32_t(vertices[0].idx()), std::uint32_t(vertices[i - 1].idx()),
                                 std::uint32_t(vertices[i].idx())});
        return FaceHandle(int(face));
    }

    size_t n_vertices() const override { return points.size(); }
    size_t n_faces() const override { return numPolygons; }
    size_t n_edges() const override { return 0; }
    void reserve(unsigned int nV, unsigned int /*nE*/, unsigned int nF) override
    {
        points.reserve(nV);
        triangles.reserve(nF);
    }

    // Everything else (attributes, half-edge construction) is of no use here.
    HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
    FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
    void set_face_texindex(FaceHandle, int) override {}
    void set_halfedge(VertexHandle, HalfedgeHandle) override {}
    void set_normal(VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_normal(VertexHandle, const OpenMesh::Vec3d&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec4f&) override {}
    void set_texcoord(VertexHandle, const OpenMesh::Vec2f&) override {}
    void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_next(HalfedgeHandle, HalfedgeHandle) override {}
    void set_face(HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(HalfedgeHandle, const OpenMesh::Vec2f&) override {}
    void set_texcoord(VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_texcoord(HalfedgeHandle, const OpenMesh::Vec3f&) override {}
    void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3f&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4f&) override {}
    void set_status(OpenMesh::EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3f&) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3d&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3f&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4f&) override {}
    void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void add_texture_information(int, std::string) override {}

private:
    VertexHandle addPoint(const Vec3& p)
    {
        points.push_back(p);
        return VertexHandle(int(points.size() - 1));
    }
};

/// A stream buffer that swallows everything.
class NullBuffer : public std::streambuf {
protected:
    int overflow(int c) override { return traits_type::not_eof(c); }
    std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

/// Silences OpenMesh's diagnostics while it reads, so the user sees only msii's message:
/// its omerr/omout/omlog streams, and std::cerr/std::clog/std::cout, which some of its
/// readers use directly (e.g. the OBJ reader's material warnings). Restores all on exit.
/// @note Output of other threads to these streams is lost meanwhile; reading is a short,
///       single-threaded stage at the start of a run.
class QuietOpenMesh {
public:
    QuietOpenMesh()
    {
        mWasEnabled[0] = ::omerr().is_enabled();
        mWasEnabled[1] = ::omout().is_enabled();
        mWasEnabled[2] = ::omlog().is_enabled();
        ::omerr().disable();
        ::omout().disable();
        ::omlog().disable();
        mCerr = std::cerr.rdbuf(&mNull);
        mClog = std::clog.rdbuf(&mNull);
        mCout = std::cout.rdbuf(&mNull);
    }
    ~QuietOpenMesh()
    {
        std::cerr.rdbuf(mCerr);
        std::clog.rdbuf(mClog);
        std::cout.rdbuf(mCout);
        if (mWasEnabled[0]) ::omerr().enable();
        if (mWasEnabled[1]) ::omout().enable();
        if (mWasEnabled[2]) ::omlog().enable();
    }
    QuietOpenMesh(const QuietOpenMesh&) = delete;
    QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

private:
    NullBuffer mNull;
    std::streambuf* mCerr = nullptr;
    std::streambuf* mClog = nullptr;
    std::streambuf* mCout = nullptr;
    bool mWasEnabled[3] = {true, true, true};
};

/// OpenMesh only says "false" when it cannot open a file: find out why ourselves first.
void checkReadable(const std::string& path)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw IOError("cannot open '" + path + "': " + std::strerror(errno) + ".");
    struct stat st {};
    const bool known = ::fstat(fd, &st) == 0;
    const bool isFolder = known && S_ISDIR(st.st_mode);
    const bool isEmpty = known && S_ISREG(st.st_mode) && st.st_size == 0;
    ::close(fd);
    if (isFolder) throw IOError("cannot read '" + path + "': it is a folder.");
    if (isEmpty) throw InvalidInputError("'" + path + "' is empty.");
}

/// OpenMesh's OFF reader does not notice a file that ends early (it repeats the last values
/// read): compare the counts the header declares with the number of values present. Only a
/// lower bound is checked (3 coordinates per vertex, a count and 3 indices per face), so
/// variants with colours or normals per line pass; binary OFF is left to OpenMesh.
void checkOffComplete(const std::string& path)
{
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return;
    std::vector<std::string> head;  // the first few values
    std::uint64_t numTokens = 0;
    bool inToken = false, inComment = false;
    std::vector<char> buffer(1 << 16);
    std::size_t got;
    while ((got = std::fread(buffer.data(), 1, buffer.size(), file)) > 0) {
        for (std::size_t i = 0; i < got; ++i) {
            const char c = buffer[i];
            if (inComment) {
                inComment = c != '\n';
                continue;
            }
            const bool space = std::isspace(static_cast<unsigned char>(c)) != 0;
            if (c == '#' || space) {
                inComment = c == '#';
                inToken = false;
                continue;
            }
            if (!inToken) {
                inToken = true;
                if (++numTokens <= 6) head.emplace_back();
            }
            if (numTokens <= 6) head.back() += c;
        }
    }
    std::fclose(file);

    if (head.empty() || head[0].size() < 3 || head[0].compare(head[0].size() - 3, 3, "OFF") != 0) return;
    std::size_t pos = 1;
    std::uint64_t dimension = head[0].find('4') != std::string::npos ? 4 : 3;
    const auto number = [&](std::size_t i, std::uint64_t& value) {
        if (i >= head.size()) return false;
        const auto r = std::from_chars(head[i].data(), head[i].data() + head[i].size(), value);
        return r.ec == std::errc() && r.ptr == head[i].data() + head[i].size();
    };
    if (head[0].find('n') != std::string::npos && !number(pos++, dimension)) return;
    if (pos < head.size() && head[pos] == "BINARY") return;
    std::uint64_t numVertices = 0, numFaces = 0, numEdges = 0;
    if (!number(pos, numVertices) || !number(pos + 1, numFaces) || !number(pos + 2, numEdges)) return;
    const std::uint64_t required = pos + 3 + dimension * numVertices + 4 * numFaces;
    if (numTokens < required)
        throw InvalidInputError("unexpected end of file in '" + path + "' (it declares " +
                                std::to_string(numVertices) + (numVertices == 1 ? " vertex and " : " vertices and ") +
                                std::to_string(numFaces) + (numFaces == 1 ? " face" : " faces") +
                                " but holds only " + std::to_string(numTokens) + " values).");
}

/// OpenMesh's OBJ reader drops a vertex whose coordinates it cannot read as floats (nan,
/// inf, 1e308), so the faces after it point one vertex too far and the user reads about a
/// face index: name the vertex line instead. And it aborts on a face corner without a
/// vertex index ("/2/2"): refuse that first. Reads the `v` and `f` lines only.
void checkObjVertices(const std::string& path)
{
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return;
    std::string line;
    std::size_t lineNumber = 0, vertex = 0;
    int c = 0;
    while (c != EOF) {
        line.clear();
        while ((c = std::fgetc(file)) != EOF && c != '\n') line += char(c);
        ++lineNumber;
        if (line.size() >= 2 && line[0] == 'f' && std::isspace(static_cast<unsigned char>(line[1]))) {
            // Every corner (v, v/vt, v//vn, v/vt/vn) starts with its vertex index: OpenMesh's
            // reader aborts the program on a face whose corners have none.
            std::size_t at = 1;
            while (true) {
                at = line.find_first_not_of(" \t\r", at);
                if (at == std::string::npos) break;
                const std::size_t end = std::min(line.find_first_of(" \t\r", at), line.size());
                const std::string corner = line.substr(at, end - at);
                const std::size_t digits = corner.find_first_not_of("+-0123456789");
                if (digits == 0 || corner == "-" || corner == "+") {
                    std::fclose(file);
                    throw InvalidInputError("'" + path + "' line " + std::to_string(lineNumber) + ": the face corner '" +
                                            corner + "' has no vertex index");
                }
                if (std::strtol(corner.c_str(), nullptr, 10) == 0) {  // OBJ counts from 1 (or back from -1)
                    std::fclose(file);
                    throw InvalidInputError("'" + path + "' line " + std::to_string(lineNumber) + ": the face corner '" +
                                            corner + "' has the vertex index 0 (OBJ counts vertices from 1)");
                }
                at = end;
            }
            continue;
        }
        if (line.size() < 2 || line[0] != 'v' || !std::isspace(static_cast<unsigned char>(line[1]))) continue;
        ++vertex;
        const char* p = line.c_str() + 1;
        for (int k = 0; k < 3; ++k) {
            char* end = nullptr;
            const double x = std::strtod(p, &end);
            std::string word(p, std::size_t(end - p));
            word.erase(0, word.find_first_not_of(" \t"));
            if (end == p) break;  // fewer numbers: OpenMesh's own message
            if (!std::isfinite(x) || std::abs(x) > double(std::numeric_limits<float>::max())) {
                std::fclose(file);
                throw InvalidInputError("'" + path + "' line " + std::to_string(lineNumber) + ": vertex " +
                                        std::to_string(vertex) + " has the coordinate '" + word + "', " +
                                        (std::isfinite(x) ? "beyond the range of the OBJ reader's single-precision numbers"
                                                          : "which is not a finite number"));
            }
            p = end;
        }
    }
    std::fclose(file);
}

/// OpenMesh takes an STL for binary when its size is 84 + 50 bytes per declared triangle,
/// else for ASCII: a binary file cut short or with a damaged count is then read as text and
/// said to contain no vertices. Say what is wrong with it instead, if it is not text.
void checkBinaryStlSize(const std::string& path)
{
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return;
    unsigned char head[1024];
    const std::size_t got = std::fread(head, 1, sizeof head, file);
    std::fseek(file, 0, SEEK_END);
    const long size = std::ftell(file);
    std::fclose(file);
    if (got < 84 || size < 84) return;
    const std::uint64_t count = std::uint64_t(head[80]) | std::uint64_t(head[81]) << 8 | std::uint64_t(head[82]) << 16 |
                                std::uint64_t(head[83]) << 24;
    if (84 + 50 * count == std::uint64_t(size)) return;  // binary, and whole
    // Text has "facet" early and no zero bytes (a binary record's small numbers have many).
    const std::string text(reinterpret_cast<const char*>(head), got);
    if (text.find("facet") != std::string::npos && text.find('\0') == std::string::npos) return;
    throw InvalidInputError("'" + path + "' is a binary STL that declares " + std::to_string(count) +
                            (count == 1 ? " triangle" : " triangles") + " (" + std::to_string(84 + 50 * count) +
                            " bytes) but is " + std::to_string(size) + " bytes long: cut short or damaged.");
}

ReadMeshResult readWithOpenMesh(const std::string& path, const std::string& format)
{
    checkReadable(path);
    if (format == "obj") checkObjVertices(path);
    if (format == "stl") checkBinaryStlSize(path);
    RawImporter importer;
    bool ok = false;
    {
        // OpenMesh's reader singletons and stream switches are global state.
        static std::mutex openMeshMutex;
        const std::lock_guard<std::mutex> lock(openMeshMutex);
        const QuietOpenMesh quiet;
        OpenMesh::IO::Options options;
        ok = OpenMesh::IO::IOManager().read(path, importer, options);
    }
    if (!ok) throw InvalidInputError("'" + path + "' could not be read as " + format + " (malformed file).");
    if (format == "off") checkOffComplete(path);
    if (importer.badIndex)
        throw InvalidInputError("'" + path + "' has a vertex index " + std::to_string(importer.badIndexValue) +
                                " in face " + std::to_string(importer.badIndexFace + 1) + " but only " +
                                std::to_string(importer.points.size()) + " vertices.");
    if (importer.points.empty()) throw InvalidInputError("'" + path + "' contains no vertices.");
    if (importer.triangles.empty()) throw InvalidInputError("'" + path + "' contains no faces.");

    ReadMeshResult result;
    result.mesh.points = std::move(importer.points);
    result.mesh.triangles = std::move(importer.triangles);
    result.numPolygonsRead = importer.numPolygons;
    result.format = format;
    return result;
}

/// The next line of @p text from @p pos without its comment (from '#') and surrounding
/// blanks; false at the end of the text.
bool nextLine(const std::string& text, std::size_t& pos, std::string_view& line)
{
    if (pos >= text.size()) return false;
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    line = std::string_view(text).substr(pos, end - pos);
    pos = end + 1;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) line.remove_prefix(1);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.remove_suffix(1);
    return true;
}

/// Splits @p line into numbers (as many as parse); false if a word is not a number.
template <class T>
bool numbersOf(std::string_view line, std::vector<T>& out)
{
    out.clear();
    const char* p = line.data();
    const char* end = line.data() + line.size();
    while (p < end) {
        while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
        if (p == end) break;
        T value{};
        if (*p == '+') ++p;
        const auto r = std::from_chars(p, end, value);
        if (r.ec != std::errc() || (r.ptr < end && !std::isspace(static_cast<unsigned char>(*r.ptr)))) return false;
        out.push_back(value);
        p = r.ptr;
    }
    return true;
}

/// The first of the first @p count words of @p line that is a number out of range or not
/// finite (1e400, nan, inf), or empty if they are finite numbers or not numbers at all.
std::string_view firstNonFinite(std::string_view line, std::size_t count)
{
    for (std::size_t k = 0; k < count; ++k) {
        while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) line.remove_prefix(1);
        std::size_t n = 0;
        while (n < line.size() && !std::isspace(static_cast<unsigned char>(line[n]))) ++n;
        const std::string_view word = line.substr(0, n);
        if (word.empty()) break;
        const char* p = word.data() + (word.front() == '+' ? 1 : 0);
        double value = 0;
        const auto r = std::from_chars(p, word.data() + word.size(), value);
        if (r.ec == std::errc::result_out_of_range || (r.ec == std::errc() && !std::isfinite(value))) return word;
        line.remove_prefix(n);
    }
    return {};
}

/// ASCII OFF as real files have it: comments anywhere (also right after the keyword, which
/// OpenMesh's reader takes for the end of the file), blank lines, the counts on the keyword's
/// line or the next, colours or normals after a vertex's coordinates or a face's indices
/// (COFF, NOFF, CNOFF, STOFF), homogeneous 4OFF; polygons fan-triangulated. Line by line,
/// so a file that ends early is noticed.
ReadMeshResult readOffAscii(const std::string& path, const std::string& text)
{
    std::size_t pos = 0;
    std::string_view line;
    const auto unexpectedEnd = [&](std::size_t nv, std::size_t nf, const std::string& what) {
        return InvalidInputError("unexpected end of file in '" + path + "' (it declares " + std::to_string(nv) +
                                 (nv == 1 ? " vertex and " : " vertices and ") + std::to_string(nf) +
                                 (nf == 1 ? " face" : " faces") + " but " + what + ").");
    };
    // The keyword, possibly with the counts after it.
    while (nextLine(text, pos, line) && line.empty()) {
    }
    std::string_view keyword = line.substr(0, line.find_first_of(" \t\r"));
    const bool homogeneous = keyword.find('4') != std::string_view::npos;
    if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF" || keyword.find('n') != std::string_view::npos)
        throw InvalidInputError("'" + path + "' could not be read as off (it does not start with OFF).");
    std::string_view rest = line.substr(keyword.size());
    std::vector<double> numbers;
    std::vector<long long> counts;
    while (true) {
        while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.front()))) rest.remove_prefix(1);
        if (!rest.empty()) break;
        if (!nextLine(text, pos, line)) throw InvalidInputError("'" + path + "' has no counts after OFF.");
        rest = line;
    }
    if (!numbersOf(rest, counts) || counts.size() < 2 || counts[0] < 0 || counts[1] < 0)
        throw InvalidInputError("'" + path + "' could not be read as off (the counts line is '" + std::string(rest) + "').");
    const std::size_t nv = std::size_t(counts[0]), nf = std::size_t(counts[1]);
    if (nv == 0) throw InvalidInputError("'" + path + "' contains no vertices.");
    if (nf == 0) throw InvalidInputError("'" + path + "' contains no faces.");
    if (nv > text.size() / 6 || nf > text.size() / 8)
        throw unexpectedEnd(nv, nf, "is only " + std::to_string(text.size()) + " bytes long");

    ReadMeshResult result;
    result.format = "off";
    auto& points = result.mesh.points;
    points.reserve(nv);
    while (points.size() < nv) {
        if (!nextLine(text, pos, line)) throw unexpectedEnd(nv, nf, "holds only " + std::to_string(points.size()) + " vertices");
        if (line.empty()) continue;
        if (const std::string_view word = firstNonFinite(line, homogeneous ? 4u : 3u); !word.empty())
            throw InvalidInputError("'" + path + "': vertex " + std::to_string(points.size()) + " has the coordinate '" +
                                    std::string(word) + "', which is not a finite number.");
        if (!numbersOf(line, numbers) || numbers.size() < (homogeneous ? 4u : 3u))
            throw InvalidInputError("'" + path + "': vertex " + std::to_string(points.size()) + " is not 3 numbers ('" +
                                    std::string(line) + "').");
        const double w = homogeneous ? numbers[3] : 1.0;
        points.push_back({numbers[0] / w, numbers[1] / w, numbers[2] / w});
    }
    std::vector<long long> indices;
    auto& triangles = result.mesh.triangles;
    triangles.reserve(nf);
    while (result.numPolygonsRead < nf) {
        if (!nextLine(text, pos, line))
            throw unexpectedEnd(nv, nf, "holds only " + std::to_string(result.numPolygonsRead) + " faces");
        if (line.empty()) continue;
        const std::size_t face = result.numPolygonsRead;
        // Colour values after the indices may be floats: read the indices as integers first.
        std::string_view head = line;
        if (!numbersOf(head.substr(0, head.find_first_of(" \t")), indices) || indices.size() != 1 || indices[0] < 1)
            throw InvalidInputError("'" + path + "': face " + std::to_string(face + 1) + " does not start with its vertex count ('" +
                                    std::string(line) + "').");
        const std::size_t n = std::size_t(indices[0]);
        std::vector<double> all;
        if (!numbersOf(line, all) || all.size() < n + 1)
            throw unexpectedEnd(nv, nf, "face " + std::to_string(face + 1) + " lists fewer than " + std::to_string(n) + " vertices");
        std::vector<std::uint32_t> polygon(n);
        for (std::size_t k = 0; k < n; ++k) {
            const double v = all[k + 1];
            if (!(v >= 0) || v >= double(nv) || v != std::floor(v)) {
                std::ostringstream index;  // as written: 1e30 or inf, not what a cast makes of it
                index << v;
                throw InvalidInputError("'" + path + "' has a vertex index " + index.str() + " in face " +
                                        std::to_string(face + 1) + " but only " + std::to_string(nv) + " vertices.");
            }
            polygon[k] = std::uint32_t(v);
        }
        for (std::size_t k = 2; k < n; ++k) triangles.push_back({polygon[0], polygon[k - 1], polygon[k]});
        ++result.numPolygonsRead;
    }
    if (triangles.empty()) throw InvalidInputError("'" + path + "' contains no faces.");
    return result;
}

/// Whether an OFF file is binary ("OFF BINARY"): OpenMesh reads those.
bool isBinaryOff(const std::string& text)
{
    const std::size_t end = std::min(text.size(), std::size_t(256));
    return text.substr(0, end).find("BINARY") != std::string::npos;
}

/// Binary OFF (Geomview's: big-endian counts after the keyword line): counts the file cannot
/// hold are refused before OpenMesh allocates for them (a flipped byte declaring 200 million
/// vertices in a file of 75 bytes).
void checkBinaryOffCounts(const std::string& path, const std::string& text)
{
    const std::size_t line = text.find('\n', text.find("BINARY"));
    if (line == std::string::npos || line + 13 > text.size()) return;  // OpenMesh says it is malformed
    const auto bigEndian = [&](std::size_t at) {
        std::uint32_t v = 0;
        for (int k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(text[at + std::size_t(k)]);
        return v;
    };
    const std::uint64_t nv = bigEndian(line + 1), nf = bigEndian(line + 5);
    // Three floats per vertex; a count and three indices per face.
    const std::uint64_t needed = line + 13 + 12 * nv + 16 * nf;
    if (needed > text.size())
        throw InvalidInputError("unexpected end of file in '" + path + "' (it declares " + std::to_string(nv) +
                                (nv == 1 ? " vertex and " : " vertices and ") + std::to_string(nf) +
                                (nf == 1 ? " face" : " faces") + ", at least " + std::to_string(needed) +
                                " bytes, but is " + std::to_string(text.size()) + " bytes long).");
}

} // namespace

ReadMeshResult readMesh(const std::string& path, const ReadMeshOptions& options)
{
    std::string extension = std::filesystem::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (extension == ".ply") return readPly(path, options);
    if (extension == ".off") {
        checkReadable(path);
        std::string text;
        {
            std::FILE* file = std::fopen(path.c_str(), "rb");
            if (!file) throw IOError("cannot open '" + path + "': " + std::strerror(errno) + ".");
            std::vector<char> buffer(1 << 20);
            std::size_t got;
            while ((got = std::fread(buffer.data(), 1, buffer.size(), file)) > 0) text.append(buffer.data(), got);
            std::fclose(file);
        }
        if (!isBinaryOff(text)) return readOffAscii(path, text);
        checkBinaryOffCounts(path, text);
    }
    if (extension == ".obj" || extension == ".off" || extension == ".stl")
        return readWithOpenMesh(path, extension.substr(1));
    const std::string found = extension.empty() ? "it has no file extension"
                                                : "unknown file extension '" + extension + "'";
    throw InvalidInputError("cannot read '" + path + "': " + found + " (supported: .ply, .obj, .off, .stl).");
}

} // namespace msii
