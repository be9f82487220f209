#include <msii/io/gigamesh_files.h>

#include <msii/core/errors.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/write_ply.h>
#include <msii/io/read_ply.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <utility>

namespace msii {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One msii value (V/|B_r| or P/(π r²)) in GigaMesh's convention. In double, 2x − 1 is
/// exact for every float x ≥ 2^-30, so fromGigaMesh() gives x back bit for bit.
double toGigaMesh(float x, GigaMeshInvariant invariant)
{
    return invariant == GigaMeshInvariant::Volume ? 2.0 * double(x) - 1.0 : double(x);
}

float fromGigaMesh(double g, GigaMeshInvariant invariant)
{
    return invariant == GigaMeshInvariant::Volume ? float((g + 1.0) * 0.5) : float(g);
}

void checkRows(const GigaMeshRows& rows, const std::string& where)
{
    if (rows.values.size() != rows.numVertices * rows.numValues)
        throw InvalidInputError("GigaMesh rows hold " + std::to_string(rows.values.size()) + " values for " +
                                std::to_string(rows.numVertices) + " vertices of " +
                                std::to_string(rows.numValues) + where);
}

std::string invariantText(GigaMeshInvariant invariant)
{
    if (invariant == GigaMeshInvariant::Volume)
        return "V (volume), written as 2*V/|B_r| - 1: flat 0, concave > 0, convex < 0";
    return "P (surface patch area), written as P/(pi r^2): flat 1";
}

/// Shortest decimal that reads back to exactly @p value (std::to_chars); `nan` for any NaN.
void appendNumber(std::string& out, double value)
{
    if (std::isnan(value)) {
        out += "nan";
        return;
    }
    char text[64];
    const auto result = std::to_chars(text, text + sizeof(text), value);
    out.append(text, result.ptr);
}

std::string numberText(double value)
{
    std::string text;
    appendNumber(text, value);
    return text;
}

std::string oneLine(std::string text)
{
    std::replace(text.begin(), text.end(), '\n', ' ');
    std::replace(text.begin(), text.end(), '\r', ' ');
    return text;
}

bool endsWithNoCase(const std::string& text, const std::string& suffix)
{
    if (text.size() < suffix.size()) return false;
    const auto lower = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
    return std::equal(suffix.begin(), suffix.end(), text.end() - std::ptrdiff_t(suffix.size()),
                      [&](char a, char b) { return lower(a) == lower(b); });
}

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

/// Splits @p line at whitespace into [begin, end) tokens.
void tokenize(const std::string& line, std::vector<std::pair<const char*, const char*>>& tokens)
{
    tokens.clear();
    const char* p = line.data();
    const char* const end = p + line.size();
    while (true) {
        while (p < end && isSpace(*p)) ++p;
        if (p == end) return;
        const char* begin = p;
        while (p < end && !isSpace(*p)) ++p;
        tokens.emplace_back(begin, p);
    }
}

/// Parses a whole token as a double ("nan", "-nan", "inf", "1e-3", "+0.5" ...).
bool parseDouble(const char* begin, const char* end, double& value)
{
    // from_chars takes no '+'; a sign after it ("+-1") stays an error.
    const bool plus = *begin == '+' && end - begin > 1 && begin[1] != '-' && begin[1] != '+';
    const char* first = plus ? begin + 1 : begin;
    const auto result = std::from_chars(first, end, value);
    if (result.ptr != end) return false;
    if (result.ec == std::errc::result_out_of_range) {
        // 1e400 or 1e-400: from_chars leaves the value untouched; strtod gives the IEEE
        // result (infinity or zero), as the writer would expect.
        value = std::strtod(std::string(first, end).c_str(), nullptr);
    } else if (result.ec != std::errc()) {
        return false;
    }
    return true;
}

bool parseIndex(const char* begin, const char* end, std::uint64_t& index)
{
    const char* first = (*begin == '+' && end - begin > 1) ? begin + 1 : begin;
    const auto result = std::from_chars(first, end, index);
    return result.ec == std::errc() && result.ptr == end;
}

/// "1 value", "3 values".
std::string countText(std::size_t count, const char* noun)
{
    return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

std::string tokenText(const char* begin, const char* end)
{
    return std::string(begin, std::min<std::size_t>(std::size_t(end - begin), 40));
}

} // namespace

GigaMeshRows toGigaMeshRows(const std::vector<std::vector<float>>& columns, GigaMeshInvariant invariant)
{
    if (columns.empty()) throw InvalidInputError("there are no feature columns to convert to GigaMesh rows.");
    GigaMeshRows rows;
    rows.numVertices = columns[0].size();
    rows.numValues = columns.size();
    for (std::size_t j = 1; j < columns.size(); ++j)
        if (columns[j].size() != rows.numVertices)
            throw InvalidInputError("feature column " + std::to_string(j + 1) + " has " +
                                    std::to_string(columns[j].size()) + " values but column 1 has " +
                                    std::to_string(rows.numVertices) + ".");
    const std::size_t n = rows.numValues;
    rows.values.resize(rows.numVertices * n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.numVertices, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t v = range.begin(); v != range.end(); ++v)
                              for (std::size_t j = 0; j < n; ++j)  // largest radius first
                                  rows.values[v * n + (n - 1 - j)] = toGigaMesh(columns[j][v], invariant);
                      });
    return rows;
}

std::vector<std::vector<float>> fromGigaMeshRows(const GigaMeshRows& rows, GigaMeshInvariant invariant)
{
    checkRows(rows, "; they cannot be converted to feature columns.");
    const std::size_t n = rows.numValues;
    std::vector<std::vector<float>> columns(n, std::vector<float>(rows.numVertices));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.numVertices, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t v = range.begin(); v != range.end(); ++v)
                              for (std::size_t j = 0; j < n; ++j)
                                  columns[j][v] = fromGigaMesh(rows.values[v * n + (n - 1 - j)], invariant);
                      });
    return columns;
}

std::vector<std::string> gigaMeshMatHeader(const GigaMeshMatInfo& info)
{
    std::vector<std::string> lines;
    lines.push_back(std::string("msii ") + versionString() +
                    ": multi-scale integral invariants in the layout of GigaMesh's gigamesh-featurevectors");
    lines.push_back("input: " + info.inputFile);
    lines.push_back("invariant: " + invariantText(info.invariant));
    lines.push_back("largest radius R: " + numberText(info.largestRadius));
    lines.push_back("scales N: " + std::to_string(info.radii.size()));
    std::string radii = "radii, in the order of the columns (largest first):";
    for (auto r = info.radii.rbegin(); r != info.radii.rend(); ++r) {
        radii += ' ';
        appendNumber(radii, *r);
    }
    lines.push_back(radii);
    for (const std::string& note : info.notes) lines.push_back(note);
    lines.push_back("columns: vertex index (from 0), then one value per radius; "
                    "nan = masked (the ball reaches a mesh border)");
    return lines;
}

void writeGigaMeshMat(const std::string& path, const std::vector<std::string>& headerLines,
                      const GigaMeshRows& rows)
{
    const std::string where = "; cannot write '" + path + "'.";
    checkRows(rows, where);
    if (rows.numValues == 0 && rows.numVertices > 0)
        throw InvalidInputError("GigaMesh rows have no values per vertex" + where);
    checkWritable(path);

    std::string header;
    for (const std::string& line : headerLines) header += line.empty() ? "#\n" : "# " + oneLine(line) + "\n";
    AtomicFile file(path);
    file.write(header);

    // Rows are formatted in parallel, a batch of chunks at a time, and written in order.
    constexpr std::size_t kChunkRows = std::size_t(1) << 14;
    constexpr std::size_t kChunksPerBatch = 16;
    const std::size_t numChunks = (rows.numVertices + kChunkRows - 1) / kChunkRows;
    std::vector<std::string> buffers(std::min(numChunks, kChunksPerBatch));
    for (std::size_t first = 0; first < numChunks; first += kChunksPerBatch) {
        const std::size_t last = std::min(numChunks, first + kChunksPerBatch);
        tbb::parallel_for(first, last, [&](std::size_t c) {
            std::string& buffer = buffers[c - first];
            buffer.clear();
            const std::size_t end = std::min(rows.numVertices, (c + 1) * kChunkRows);
            for (std::size_t v = c * kChunkRows; v < end; ++v) {
                char index[24];
                buffer.append(index, std::to_chars(index, index + sizeof(index), v).ptr);
                const double* row = rows.row(v);
                for (std::size_t k = 0; k < rows.numValues; ++k) {
                    buffer += ' ';
                    appendNumber(buffer, row[k]);
                }
                buffer += '\n';
            }
        });
        for (std::size_t c = first; c < last; ++c) file.write(buffers[c - first]);
    }
    file.commit();
}

std::string gigaMeshMatFileName(const std::string& name, double largestRadius, int scales, int precision,
                                GigaMeshInvariant invariant)
{
    if (!(largestRadius > 0) || !std::isfinite(largestRadius))
        throw InvalidInputError("the largest radius must be positive and finite for a GigaMesh file name (got " +
                                numberText(largestRadius) + ").");
    if (scales < 1)
        throw InvalidInputError("the number of scales must be at least 1 for a GigaMesh file name (got " +
                                std::to_string(scales) + ").");
    // "%.2f" as GigaMesh's sprintf, without depending on the C locale.
    std::array<char, 400> radius{};
    const auto printed = std::to_chars(radius.data(), radius.data() + radius.size(), largestRadius,
                                       std::chars_format::fixed, 2);
    std::string fileName = name + "_r" + std::string(radius.data(), printed.ptr);
    if ((scales & (scales - 1)) == 0) {
        int exponent = 0;
        while ((1 << exponent) < scales) ++exponent;
        fileName += "_n" + std::to_string(exponent);
    } else {
        fileName += "_N" + std::to_string(scales);  // no GigaMesh exponent exists: see the header
    }
    fileName += "_v" + std::to_string(precision);
    fileName += invariant == GigaMeshInvariant::Volume ? ".volume.mat" : ".surface.mat";
    return fileName;
}

std::optional<GigaMeshInvariant> gigaMeshInvariantOfFileName(const std::string& path)
{
    if (endsWithNoCase(path, ".volume.mat")) return GigaMeshInvariant::Volume;
    if (endsWithNoCase(path, ".surface.mat")) return GigaMeshInvariant::Patch;
    return std::nullopt;
}

GigaMeshRows readGigaMeshMat(const std::string& path, std::size_t expectedVertexCount)
{
    std::error_code error;
    if (std::filesystem::is_directory(path, error))
        throw IOError("cannot read '" + path + "': it is a folder.");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IOError("cannot open '" + path + "': " + std::strerror(errno) + ".");

    const auto fail = [&](std::size_t lineNumber, const std::string& what) {
        return InvalidInputError("'" + path + "' line " + std::to_string(lineNumber) + ": " + what + ".");
    };

    GigaMeshRows rows;
    rows.numVertices = expectedVertexCount;
    std::vector<std::size_t> lineOfVertex(expectedVertexCount, 0);  // 0 = no row yet
    std::size_t firstRowLine = 0, numRows = 0, lineNumber = 0;
    std::string line;
    std::vector<std::pair<const char*, const char*>> tokens;
    std::vector<double> values;
    while (std::getline(in, line)) {
        ++lineNumber;
        tokenize(line, tokens);
        if (tokens.empty() || *tokens[0].first == '#') continue;

        std::uint64_t index = 0;
        if (!parseIndex(tokens[0].first, tokens[0].second, index))
            throw fail(lineNumber, "the vertex index '" + tokenText(tokens[0].first, tokens[0].second) +
                                       "' is not a whole number from 0");
        if (index >= expectedVertexCount)
            throw fail(lineNumber, "the vertex index " + std::to_string(index) +
                                       " is out of range (the mesh has " + std::to_string(expectedVertexCount) +
                                       " vertices, indices from 0)");
        if (lineOfVertex[index] != 0)
            throw fail(lineNumber, "vertex index " + std::to_string(index) +
                                       " appears a second time (first on line " +
                                       std::to_string(lineOfVertex[index]) + ")");
        lineOfVertex[index] = lineNumber;

        values.resize(tokens.size() - 1);
        for (std::size_t k = 1; k < tokens.size(); ++k)
            if (!parseDouble(tokens[k].first, tokens[k].second, values[k - 1]))
                throw fail(lineNumber, "value " + std::to_string(k) + " '" +
                                           tokenText(tokens[k].first, tokens[k].second) + "' is not a number");
        if (values.empty()) throw fail(lineNumber, "vertex index " + std::to_string(index) + " has no values");
        if (numRows == 0) {
            firstRowLine = lineNumber;
            rows.numValues = values.size();
            rows.values.assign(expectedVertexCount * rows.numValues, kNaN);
        } else if (values.size() != rows.numValues) {
            throw fail(lineNumber, "the row has " + countText(values.size(), "value") +
                                       " after the vertex index but the first row (line " +
                                       std::to_string(firstRowLine) + ") has " + std::to_string(rows.numValues));
        }
        std::copy(values.begin(), values.end(), rows.values.begin() + std::ptrdiff_t(index * rows.numValues));
        ++numRows;
    }
    if (in.bad()) throw IOError("cannot read '" + path + "': " + std::strerror(errno) + ".");
    if (numRows == 0 && expectedVertexCount > 0)
        throw InvalidInputError("'" + path + "' has no rows of values in its " + std::to_string(lineNumber) +
                                " lines, for a mesh of " + std::to_string(expectedVertexCount) + " vertices.");
    if (numRows < expectedVertexCount) {
        const std::size_t missing = std::size_t(
            std::find(lineOfVertex.begin(), lineOfVertex.end(), std::size_t(0)) - lineOfVertex.begin());
        throw InvalidInputError("'" + path + "' ends at line " + std::to_string(lineNumber) + " with " +
                                std::to_string(numRows) + " rows of values for a mesh of " +
                                std::to_string(expectedVertexCount) + " vertices (none for vertex " +
                                std::to_string(missing) + ").");
    }
    return rows;
}

std::vector<float> gigaMeshQuality(const GigaMeshRows& rows, GigaMeshQuality quality)
{
    checkRows(rows, "; no quality can be computed.");
    std::vector<float> result(rows.numVertices, std::numeric_limits<float>::quiet_NaN());
    if (rows.numValues == 0) return result;
    for (std::size_t v = 0; v < rows.numVertices; ++v) {
        const double* row = rows.row(v);
        if (quality == GigaMeshQuality::LargestRadius) {
            result[v] = float(row[0]);
            continue;
        }
        double largest = kNaN;
        for (std::size_t k = 0; k < rows.numValues; ++k)
            if (!std::isnan(row[k]) && !(row[k] <= largest)) largest = row[k];
        result[v] = float(largest);
    }
    return result;
}

void writeGigaMeshPly(const std::string& path, const TriMesh& mesh, const GigaMeshRows& rows,
                      const GigaMeshPlyOptions& options)
{
    const std::string where = "; cannot write '" + path + "'.";
    checkRows(rows, where);
    if (rows.numVertices != mesh.numVertices())
        throw InvalidInputError("there are feature vectors for " + std::to_string(rows.numVertices) +
                                " vertices but the mesh has " + std::to_string(mesh.numVertices()) + where);
    if (rows.numValues < 1 || rows.numValues > 255)
        throw InvalidInputError("a PLY feature_vector holds 1 to 255 values (a uchar count), not " +
                                std::to_string(rows.numValues) + where);
    WritePlyOptions plyOptions;
    plyOptions.comments = options.comments;
    plyOptions.listName = "feature_vector";
    plyOptions.listLength = int(rows.numValues);
    plyOptions.listValues.assign(rows.values.begin(), rows.values.end());  // GigaMesh stores floats
    writePly(path, mesh, {{"quality", gigaMeshQuality(rows, options.quality)}}, plyOptions);
}

GigaMeshPlyContents readGigaMeshPly(const std::string& path)
{
    ReadMeshOptions options;
    options.keepVertexProperties = true;
    options.keepVertexLists = true;
    ReadMeshResult read = readPly(path, options);

    GigaMeshPlyContents contents;
    contents.mesh = std::move(read.mesh);
    std::vector<const std::vector<float>*> elements;
    const auto find = [&](const std::string& name) -> const VertexProperty* {
        for (const VertexProperty& property : read.vertexProperties)
            if (property.name == name) return &property;
        return nullptr;
    };
    for (std::size_t k = 0;; ++k) {
        const std::string digits = std::to_string(k);
        const std::string name = "feature_vector" + std::string(digits.size() < 2 ? "_0" : "_") + digits;
        const VertexProperty* element = find(name);
        if (!element) break;
        elements.push_back(&element->values);
    }
    if (elements.empty()) throw InvalidInputError("'" + path + "' has no per-vertex feature_vector list.");
    if (const VertexProperty* quality = find("quality")) contents.quality = quality->values;

    GigaMeshRows& rows = contents.rows;
    rows.numVertices = contents.mesh.numVertices();
    rows.numValues = elements.size();
    rows.values.resize(rows.numVertices * rows.numValues);
    for (std::size_t v = 0; v < rows.numVertices; ++v)
        for (std::size_t k = 0; k < rows.numValues; ++k) rows.values[v * rows.numValues + k] = (*elements[k])[v];
    return contents;
}

} // namespace msii
