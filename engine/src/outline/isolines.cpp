/// @file isolines.cpp
/// @brief Marching triangles with a symbolic perturbation, chaining through shared edges,
/// and SVG output.
///
/// Scan: the triangles are cut into blocks of a fixed size; per block one task lists, in
/// triangle order, the segments of every level the triangle crosses (a sorted level list
/// and the triangle's value range give those levels directly, so many levels cost one pass).
/// A vertex is "above" a level when f >= level: a value equal to the level counts as
/// level + tiny, so a triangle is crossed exactly when min f < level <= max f, and then on
/// exactly two edges. Each segment is oriented with the higher values on its left (seen
/// from the side the triangle's counter-clockwise order faces): it runs from the edge where
/// the triangle's boundary goes from above to below to the edge where it goes back.
///
/// Chaining (per level, levels in parallel): a segment has two ends ("halves", 2s = the end
/// it starts from, 2s + 1 = the end it goes to), each on an undirected edge (key: min and
/// max vertex index). A hash table keyed by the edge groups the ends: an edge with exactly
/// two ends links them, an edge with one end (mesh border, NaN triangle) or with three or
/// more (non-manifold) ends the line there. Open lines are walked from their free ends, the
/// remaining segments form closed lines. Segments store only their two edge keys; the
/// points are interpolated while walking, once per crossed edge.
///
/// Canonical form, whatever the thread count or the triangle order: an open line runs along
/// its segments' orientation (higher values on the left) when the mesh orientation is
/// consistent along it, otherwise it starts at the end with the smaller edge key; a closed
/// line starts at its crossing with the smallest edge key and runs the same way. Lines of a
/// level are sorted by their smallest edge key (ties, only at non-manifold edges, by the
/// segment order).
///
/// Interpolation runs from the edge's smaller vertex, whichever triangle asks; the parameter
/// is kept within [kEdgeMargin, 1 − kEdgeMargin] so that the crossings around a vertex at
/// the level stay distinct points (the geometric image of the perturbation).
///
/// Values that are not finite (NaN, ±inf) are treated alike: their triangles are skipped.

#include <msii/outline/isolines.h>

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace msii {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
/// Crossings stay this fraction of the edge length away from the edge's vertices.
constexpr double kEdgeMargin = 1e-6;
/// Triangles per scan task (a fixed number, so the segment order never depends on threads).
constexpr std::size_t kBlockTriangles = 1 << 14;

using EdgeKey = std::uint64_t;

EdgeKey edgeKey(std::uint32_t a, std::uint32_t b)
{
    return a < b ? (EdgeKey(a) << 32) | b : (EdgeKey(b) << 32) | a;
}

/// A piece of isoline inside one triangle, as its two crossed edges: it runs from edge[0]
/// to edge[1] with the higher values on its left. The points are computed when chaining.
struct Segment {
    EdgeKey edge[2] = {0, 0};
};

/// A segment as the scan finds it, with the index of its level in the sorted levels.
struct LevelSegment {
    Segment segment;
    std::uint32_t level = 0;
};

/// One end of a segment on its edge; ordered by edge, then end (the line order).
struct EdgeEnd {
    EdgeKey key = 0;
    std::uint32_t half = 0;
    bool operator<(const EdgeEnd& o) const { return key != o.key ? key < o.key : half < o.half; }
};

/// The point where f crosses @p level on the edge @p key: interpolated from its smaller
/// vertex, so both triangles of the edge would get the same bits.
Vec3 crossing(const TriMesh& mesh, const std::vector<float>& f, EdgeKey key, double level)
{
    const auto a = std::uint32_t(key >> 32), b = std::uint32_t(key & 0xffffffffu);
    const double fa = f[a], fb = f[b];
    double t = (level - fa) / (fb - fa);
    t = std::clamp(t, kEdgeMargin, 1.0 - kEdgeMargin);
    const Vec3& pa = mesh.points[a];
    const Vec3& pb = mesh.points[b];
    return pa + (pb - pa) * t;
}

/// Segments of the triangles [begin, end), in triangle order, each triangle's levels in
/// ascending order. Sets @p badIndex for out-of-range vertex indices.
void scanBlock(const TriMesh& mesh, const std::vector<float>& f, const std::vector<double>& levels,
               std::size_t begin, std::size_t end, std::vector<LevelSegment>& out,
               std::atomic<bool>& badIndex)
{
    const std::size_t n = mesh.numVertices();
    for (std::size_t t = begin; t < end; ++t) {
        const Triangle& tri = mesh.triangles[t];
        if (tri[0] >= n || tri[1] >= n || tri[2] >= n) {
            badIndex = true;
            return;
        }
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;  // degenerate
        const double v[3] = {f[tri[0]], f[tri[1]], f[tri[2]]};
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) continue;
        const double lo = std::min({v[0], v[1], v[2]}), hi = std::max({v[0], v[1], v[2]});
        // Crossed levels: lo < level <= hi.
        auto it = std::upper_bound(levels.begin(), levels.end(), lo);
        for (; it != levels.end() && *it <= hi; ++it) {
            const double level = *it;
            LevelSegment seg;
            seg.level = std::uint32_t(it - levels.begin());
            for (int k = 0; k < 3; ++k) {
                const bool above = v[k] >= level, nextAbove = v[(k + 1) % 3] >= level;
                if (above == nextAbove) continue;
                const int side = above ? 0 : 1;  // above -> below: the segment starts here
                seg.segment.edge[side] = edgeKey(tri[k], tri[(k + 1) % 3]);
            }
            out.push_back(seg);
        }
    }
}

/// Partner of each segment end (2s + side): the other end on the same edge if exactly two
/// ends share the edge, kNone otherwise (border, NaN neighbour, non-manifold edge). An open
/// addressing table keyed by the edge finds the pairs in O(m); the result does not depend
/// on the table's layout.
std::vector<std::uint32_t> pairEnds(const std::vector<Segment>& segs)
{
    constexpr std::uint32_t kShared = kNone - 1;  // an edge with three or more ends
    constexpr EdgeKey kEmpty = std::numeric_limits<EdgeKey>::max();  // no edge has this key (a < b)
    struct Slot {
        EdgeKey key;
        std::uint32_t first;  ///< the first end seen on the edge, or kShared
    };
    const std::size_t ends = 2 * segs.size();
    std::size_t size = 16;
    while (size < 2 * ends) size *= 2;  // load <= 1/2
    int shift = 64;
    for (std::size_t s = size; s > 1; s >>= 1) --shift;
    std::vector<Slot> table(size, Slot{kEmpty, kNone});
    std::vector<std::uint32_t> partner(ends, kNone);
    for (std::uint32_t h = 0; h < ends; ++h) {
        const EdgeKey key = segs[h >> 1].edge[h & 1];
        std::size_t i = std::size_t((key * 0x9E3779B97F4A7C15ull) >> shift);
        while (table[i].key != kEmpty && table[i].key != key) i = (i + 1) & (size - 1);
        Slot& slot = table[i];
        if (slot.key == kEmpty) {
            slot = Slot{key, h};  // first end on this edge
        } else if (slot.first == kShared) {
            partner[h] = kShared;  // fourth or later end
        } else if (partner[slot.first] == kNone) {
            partner[slot.first] = h;  // second end: a pair (for now)
            partner[h] = slot.first;
        } else {
            partner[partner[slot.first]] = kShared;  // third end: non-manifold, no pairs
            partner[slot.first] = kShared;
            partner[h] = kShared;
            slot.first = kShared;
        }
    }
    for (std::uint32_t& p : partner) {
        if (p == kShared) p = kNone;
    }
    return partner;
}

/// A finished line with its sort key (the smallest edge end it touches).
struct KeyedLine {
    EdgeEnd first;
    Polyline line;
};

/// Chains the segments of one level into polylines, in canonical form and order.
std::vector<Polyline> chainLevel(const TriMesh& mesh, const std::vector<float>& f,
                                 const std::vector<Segment>& segs, double level)
{
    const std::size_t m = segs.size();
    const auto keyOf = [&](std::uint32_t h) { return segs[h >> 1].edge[h & 1]; };
    const auto pointOf = [&](std::uint32_t h) { return crossing(mesh, f, keyOf(h), level); };
    const auto endOf = [&](std::uint32_t h) { return EdgeEnd{keyOf(h), h}; };

    const std::vector<std::uint32_t> partner = pairEnds(segs);

    std::vector<char> visited(m, 0);
    std::vector<KeyedLine> lines;
    std::vector<std::uint32_t> entries;  // per segment of the walk: the end it is entered by

    // Walks from end @p start until a free end or back to @p start, filling `entries`;
    // @p exit is the end by which the walk leaves the last segment.
    const auto walk = [&](std::uint32_t start, std::uint32_t& exit) {
        entries.clear();
        std::uint32_t cur = start;
        for (;;) {
            entries.push_back(cur);
            visited[cur >> 1] = 1;
            exit = cur ^ 1u;
            const std::uint32_t next = partner[exit];
            if (next == kNone || next == start) return;
            cur = next;
        }
    };
    const auto smallestEnd = [&]() {
        EdgeEnd best{std::numeric_limits<EdgeKey>::max(), kNone};
        for (const std::uint32_t h : entries) {
            best = std::min({best, endOf(h), endOf(h ^ 1u)});
        }
        return best;
    };
    /// Whether to start at end @p a rather than @p b: the start should be the end a
    /// segment leaves from (orientation). If both or neither are (inconsistent mesh
    /// orientation), the smaller edge, then the smaller next edge (a closed line's two ways
    /// out of its start edge), so the choice depends on the vertex indices only.
    const auto prefer = [&](std::uint32_t a, std::uint32_t b) {
        const bool aFrom = (a & 1u) == 0, bFrom = (b & 1u) == 0;
        if (aFrom != bFrom) return aFrom;
        return std::make_tuple(keyOf(a), keyOf(a ^ 1u), a) < std::make_tuple(keyOf(b), keyOf(b ^ 1u), b);
    };

    // Open lines, from their free ends.
    for (std::uint32_t h = 0; h < 2 * m; ++h) {
        if (partner[h] != kNone || visited[h >> 1]) continue;
        std::uint32_t exit = kNone;
        walk(h, exit);
        KeyedLine kl;
        kl.first = smallestEnd();
        kl.line.level = level;
        kl.line.closed = false;
        kl.line.points.reserve(entries.size() + 1);
        for (const std::uint32_t e : entries) kl.line.points.push_back(pointOf(e));
        kl.line.points.push_back(pointOf(exit));
        if (!prefer(h, exit)) std::reverse(kl.line.points.begin(), kl.line.points.end());
        lines.push_back(std::move(kl));
    }

    // Closed lines: all remaining segments.
    for (std::uint32_t s = 0; s < m; ++s) {
        if (visited[s]) continue;
        std::uint32_t exit = kNone;
        walk(2 * s, exit);
        const std::size_t k = entries.size();
        std::size_t i0 = 0;  // the entry on the smallest edge
        for (std::size_t i = 1; i < k; ++i) {
            if (keyOf(entries[i]) < keyOf(entries[i0])) i0 = i;
        }
        // Two ways to leave that edge: into entries[i0]'s segment, or back into the previous one.
        const std::uint32_t forwardStart = entries[i0];
        const std::uint32_t backwardStart = entries[(i0 + k - 1) % k] ^ 1u;
        const bool forward = prefer(forwardStart, backwardStart);
        KeyedLine kl;
        kl.first = smallestEnd();
        kl.line.level = level;
        kl.line.closed = true;
        kl.line.points.reserve(k);
        for (std::size_t j = 0; j < k; ++j) {
            const std::size_t idx = forward ? (i0 + j) % k : (i0 + k - j) % k;
            kl.line.points.push_back(pointOf(entries[idx]));
        }
        lines.push_back(std::move(kl));
    }

    std::sort(lines.begin(), lines.end(),
              [](const KeyedLine& a, const KeyedLine& b) { return a.first < b.first; });
    std::vector<Polyline> result;
    result.reserve(lines.size());
    for (KeyedLine& kl : lines) result.push_back(std::move(kl.line));
    return result;
}

/// Appends @p value; precision 0: the shortest text that reads back exactly.
void appendNumber(std::string& out, double value, int precision)
{
    if (value == 0) value = 0;  // no "-0"
    char buffer[64];
    const auto res = precision > 0
                         ? std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, precision)
                         : std::to_chars(buffer, buffer + sizeof buffer, value);
    out.append(buffer, res.ptr);
}

bool isSvgUnit(const std::string& units)
{
    static const char* const kUnits[] = {"mm", "cm", "in", "px", "pt", "pc"};
    return std::any_of(std::begin(kUnits), std::end(kUnits), [&](const char* u) { return units == u; });
}

} // namespace

std::vector<Polyline> computeIsolines(const TriMesh& mesh, const std::vector<float>& f,
                                      const std::vector<double>& levels)
{
    if (f.size() != mesh.numVertices())
        throw InvalidInputError("isolines: the function has " + std::to_string(f.size()) +
                                " values but the mesh has " + std::to_string(mesh.numVertices()) +
                                " vertices.");
    for (const double level : levels) {
        if (!std::isfinite(level)) throw InvalidInputError("isolines: a level is not finite.");
    }
    if (mesh.numTriangles() >= std::size_t(1) << 31)
        throw InvalidInputError("isolines: the mesh has too many triangles (at most 2^31 - 1).");

    std::vector<double> sorted = levels;
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    if (sorted.empty() || mesh.triangles.empty()) return {};

    // Scan: per block, the segments in triangle order.
    const std::size_t numTriangles = mesh.numTriangles();
    const std::size_t numBlocks = (numTriangles + kBlockTriangles - 1) / kBlockTriangles;
    std::vector<std::vector<LevelSegment>> blocks(numBlocks);
    std::atomic<bool> badIndex{false};
    tbb::parallel_for(std::size_t(0), numBlocks, [&](std::size_t b) {
        const std::size_t begin = b * kBlockTriangles;
        const std::size_t end = std::min(numTriangles, begin + kBlockTriangles);
        scanBlock(mesh, f, sorted, begin, end, blocks[b], badIndex);
    });
    if (badIndex) throw InvalidInputError("isolines: a triangle has a vertex index out of range.");

    // Per level, in block and triangle order.
    std::vector<std::vector<Segment>> perLevel(sorted.size());
    {
        std::vector<std::size_t> count(sorted.size(), 0);
        for (const auto& block : blocks) {
            for (const LevelSegment& s : block) ++count[s.level];
        }
        for (std::size_t l = 0; l < sorted.size(); ++l) perLevel[l].reserve(count[l]);
        for (auto& block : blocks) {
            for (const LevelSegment& s : block) perLevel[s.level].push_back(s.segment);
            std::vector<LevelSegment>().swap(block);
        }
    }

    std::vector<std::vector<Polyline>> chained(sorted.size());
    tbb::parallel_for(std::size_t(0), sorted.size(), [&](std::size_t l) {
        chained[l] = chainLevel(mesh, f, perLevel[l], sorted[l]);
        std::vector<Segment>().swap(perLevel[l]);
    });

    std::vector<Polyline> result;
    std::size_t total = 0;
    for (const auto& c : chained) total += c.size();
    result.reserve(total);
    for (auto& c : chained) {
        for (Polyline& line : c) result.push_back(std::move(line));
    }
    return result;
}

std::vector<double> evenLevels(double lo, double hi, int count)
{
    std::vector<double> levels;
    if (count <= 0) return levels;
    levels.reserve(std::size_t(count));
    for (int k = 1; k <= count; ++k) levels.push_back(lo + k * (hi - lo) / (count + 1));
    return levels;
}

void writeSvg(const std::string& path, const std::vector<Polyline2>& lines, const SvgOptions& options)
{
    if (!std::isfinite(options.minX) || !std::isfinite(options.minY) || !std::isfinite(options.width) ||
        !std::isfinite(options.height) || options.width <= 0 || options.height <= 0)
        throw InvalidInputError("svg: the drawing area must be finite with a positive width and height.");
    const double stroke = options.strokeWidth > 0 && std::isfinite(options.strokeWidth)
                              ? options.strokeWidth
                              : options.width / 1000.0;
    const std::string unit = isSvgUnit(options.units) ? options.units : std::string();
    constexpr int kDigits = 7;  // significant digits: 1e-6 of the drawing size or finer

    std::string out;
    out += "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n";
    out += "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"";
    appendNumber(out, options.width, 0);
    out += unit + "\" height=\"";
    appendNumber(out, options.height, 0);
    out += unit + "\" viewBox=\"0 0 ";
    appendNumber(out, options.width, 0);
    out += ' ';
    appendNumber(out, options.height, 0);
    out += "\">\n<g fill=\"none\" stroke=\"black\" stroke-width=\"";
    appendNumber(out, stroke, 0);
    out += "\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n";
    const double top = options.minY + options.height;
    for (const Polyline2& line : lines) {
        out += "<path data-level=\"";
        appendNumber(out, line.level, 0);
        out += "\" d=\"";
        std::size_t written = 0;
        for (const auto& p : line.points) {
            if (!std::isfinite(p[0]) || !std::isfinite(p[1])) continue;  // not drawable
            out += written == 0 ? "M" : " L";
            appendNumber(out, p[0] - options.minX, kDigits);
            out += ' ';
            appendNumber(out, top - p[1], kDigits);
            ++written;
        }
        if (line.closed && written > 1) out += " Z";
        out += "\"/>\n";
    }
    out += "</g>\n</svg>\n";
    writeTextFileAtomic(path, out);
}

} // namespace msii
