#include <msii/mesh/prepare_mesh.h>

#include "blocks.h"
#include "mesh_topology.h"

#include <msii/core/errors.h>
#include <msii/mesh/mesh_check.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

namespace msii {

namespace {

using detail::findRoot;
using detail::forEachBlock;
using detail::numBlocks;
using detail::unite;
constexpr std::uint32_t kNone = PrepareMeshResult::kNoVertex;

std::string plural(std::size_t n, const char* one, const char* many)
{
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

/// Bit pattern of a point, for exact equality of positions (0.0 and -0.0 are one position).
std::array<std::uint64_t, 3> bitsOf(const Vec3& p)
{
    std::array<std::uint64_t, 3> b{};
    for (int k = 0; k < 3; ++k) {
        const double c = p[k] == 0.0 ? 0.0 : p[k];
        std::memcpy(&b[std::size_t(k)], &c, sizeof c);
    }
    return b;
}

/// For each vertex the smallest-index vertex at exactly the same position (itself if none).
std::vector<std::uint32_t> samePositionRepresentatives(const std::vector<Vec3>& points, std::size_t& numMerged)
{
    const std::size_t n = points.size();
    // Sort (hash, index) pairs, then compare positions within runs of equal hashes.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(n);
    forEachBlock(n, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v) {
            const auto b = bitsOf(points[v]);
            std::uint64_t h = b[0] * 0x9E3779B97F4A7C15ull;
            h = (h ^ (h >> 29) ^ b[1]) * 0xBF58476D1CE4E5B9ull;
            h = (h ^ (h >> 31) ^ b[2]) * 0x94D049BB133111EBull;
            keys[v] = {h ^ (h >> 32), std::uint32_t(v)};
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    std::vector<std::uint32_t> rep(n);
    std::iota(rep.begin(), rep.end(), 0u);
    numMerged = 0;
    for (std::size_t i = 0; i < n;) {
        std::size_t j = i + 1;
        while (j < n && keys[j].first == keys[i].first) ++j;
        // Within the run (ascending indices), each vertex joins the first equal one.
        for (std::size_t a = i; a < j; ++a) {
            const std::uint32_t va = keys[a].second;
            if (rep[va] != va) continue;
            for (std::size_t b = a + 1; b < j; ++b) {
                const std::uint32_t vb = keys[b].second;
                if (rep[vb] == vb && bitsOf(points[va]) == bitsOf(points[vb])) {
                    rep[vb] = va;
                    ++numMerged;
                }
            }
        }
        i = j;
    }
    return rep;
}

/// Splits every vertex whose faces form more than one fan (faces joined through edges at
/// the vertex): the fan of its first face keeps the vertex, each other fan gets a copy
/// appended to the points. Returns the number of vertices split.
std::size_t splitNonManifoldVertices(TriMesh& mesh)
{
    const detail::VertexTriangles inc = detail::vertexTriangles(mesh);
    const std::size_t nv = mesh.numVertices();
    // Per vertex, the fan (0 = first) of each incident face, where there is more than one.
    struct Split {
        std::uint32_t vertex;
        std::vector<std::uint32_t> faces, fans;
        std::uint32_t numFans;
    };
    std::vector<std::vector<Split>> blocks(numBlocks(nv));
    forEachBlock(nv, [&](std::size_t b, std::size_t begin, std::size_t end) {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> others;  // (other vertex, local face)
        std::vector<std::uint32_t> parent;
        for (std::size_t v = begin; v < end; ++v) {
            const std::uint32_t first = inc.offsets[v], count = inc.offsets[v + 1] - first;
            if (count < 2) continue;
            others.clear();
            for (std::uint32_t k = 0; k < count; ++k)
                for (std::uint32_t w : mesh.triangles[inc.triangles[first + k]])
                    if (w != v) others.emplace_back(w, k);
            std::sort(others.begin(), others.end());
            parent.resize(count);
            std::iota(parent.begin(), parent.end(), 0u);
            for (std::size_t i = 1; i < others.size(); ++i)
                if (others[i].first == others[i - 1].first) unite(parent, others[i].second, others[i - 1].second);
            // Nearly every vertex has one fan: count the roots before numbering the fans.
            std::uint32_t numFans = 0;
            for (std::uint32_t k = 0; k < count; ++k) numFans += findRoot(parent, k) == k;
            if (numFans < 2) continue;
            // Every face points to a smaller face of its fan (unite keeps the smaller root,
            // path halving only shortens), so fans number in the order of their first faces.
            std::vector<std::uint32_t> fans(count);
            for (std::uint32_t k = 0, next = 0; k < count; ++k) fans[k] = parent[k] == k ? next++ : fans[parent[k]];
            Split s{std::uint32_t(v), {}, std::move(fans), numFans};
            s.faces.assign(inc.triangles.begin() + first, inc.triangles.begin() + first + count);
            blocks[b].push_back(std::move(s));
        }
    });
    std::size_t numSplit = 0;
    for (const auto& block : blocks)
        for (const Split& s : block) {
            const std::uint32_t base = std::uint32_t(mesh.points.size());
            for (std::uint32_t c = 1; c < s.numFans; ++c) mesh.points.push_back(mesh.points[s.vertex]);
            for (std::size_t k = 0; k < s.faces.size(); ++k)
                if (s.fans[k] > 0)
                    for (std::uint32_t& w : mesh.triangles[s.faces[k]])
                        if (w == s.vertex) w = base + s.fans[k] - 1;
            ++numSplit;
        }
    return numSplit;
}

/// Re-orients each edge-connected part coherently, keeping the orientation of the majority
/// of its faces (so one flipped face is turned, not the rest). Returns the faces turned.
std::size_t orientCoherently(TriMesh& mesh)
{
    const std::size_t nf = mesh.numTriangles();
    // Half-edges keyed by their undirected edge; the direction bit says whether the face
    // runs from the smaller vertex to the larger.
    struct HalfEdge {
        std::uint64_t key;
        std::uint32_t face;
        bool forward;
        bool operator<(const HalfEdge& o) const { return key < o.key || (key == o.key && face < o.face); }
    };
    std::vector<HalfEdge> halfEdges(3 * nf);
    forEachBlock(nf, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f < end; ++f)
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = mesh.triangles[f][std::size_t(k)], b = mesh.triangles[f][std::size_t((k + 1) % 3)];
                halfEdges[3 * f + std::size_t(k)] = {std::uint64_t(std::min(a, b)) << 32 | std::max(a, b),
                                                     std::uint32_t(f), a < b};
            }
    });
    tbb::parallel_sort(halfEdges.begin(), halfEdges.end());
    // Neighbours across manifold edges, and whether they disagree.
    std::vector<std::array<std::uint32_t, 3>> neighbour(nf, {kNone, kNone, kNone});
    std::vector<std::array<bool, 3>> disagrees(nf, {false, false, false});
    std::vector<std::uint8_t> slots(nf, 0);
    for (std::size_t i = 0; i + 1 < halfEdges.size(); ++i) {
        const HalfEdge &a = halfEdges[i], &b = halfEdges[i + 1];
        if (a.key != b.key || (i + 2 < halfEdges.size() && halfEdges[i + 2].key == a.key)) continue;
        if (i > 0 && halfEdges[i - 1].key == a.key) continue;
        if (slots[a.face] < 3 && slots[b.face] < 3) {
            neighbour[a.face][slots[a.face]] = b.face, disagrees[a.face][slots[a.face]++] = a.forward == b.forward;
            neighbour[b.face][slots[b.face]] = a.face, disagrees[b.face][slots[b.face]++] = a.forward == b.forward;
        }
    }
    // Breadth-first over each part: flip[f] relative to the part's first face.
    std::vector<std::int8_t> flip(nf, -1);
    std::vector<std::uint32_t> queue, part;
    std::size_t turned = 0;
    for (std::size_t seed = 0; seed < nf; ++seed) {
        if (flip[seed] >= 0) continue;
        part.clear();
        queue.assign(1, std::uint32_t(seed));
        flip[seed] = 0;
        std::size_t flipped = 0;
        for (std::size_t q = 0; q < queue.size(); ++q) {
            const std::uint32_t f = queue[q];
            part.push_back(f);
            flipped += std::size_t(flip[f]);
            for (int k = 0; k < slots[f]; ++k) {
                const std::uint32_t g = neighbour[f][std::size_t(k)];
                if (flip[g] >= 0) continue;  // a non-orientable part keeps its first choice
                flip[g] = std::int8_t(flip[f] ^ std::int8_t(disagrees[f][std::size_t(k)]));
                queue.push_back(g);
            }
        }
        const std::int8_t turn = 2 * flipped > part.size() ? 0 : 1;  // the side to turn: the minority
        for (std::uint32_t f : part)
            if (flip[f] == turn) {
                std::swap(mesh.triangles[f][1], mesh.triangles[f][2]);
                ++turned;
            }
    }
    return turned;
}

/// Turns closed parts (vertex-connected, no border edge) whose signed volume is negative
/// inside out, so that every closed part faces outward. Returns the parts turned.
std::size_t turnClosedPartsOutward(TriMesh& mesh, const MeshCheckResult& check, std::size_t& facesTurned)
{
    const std::vector<std::uint32_t> root = detail::vertexParts(mesh);
    std::unordered_set<std::uint32_t> open;
    for (const auto& e : check.borderEdges) open.insert(root[e[0]]);
    // Signed volume relative to each part's first vertex (small numbers far from the origin).
    std::unordered_map<std::uint32_t, double> volume;
    for (const Triangle& t : mesh.triangles) {
        const std::uint32_t r = root[t[0]];
        if (open.count(r)) continue;
        const Vec3& o = mesh.points[r];
        const Vec3 a = mesh.points[t[0]] - o, b = mesh.points[t[1]] - o, c = mesh.points[t[2]] - o;
        volume[r] += dot(a, cross(b, c));
    }
    std::size_t turned = 0;
    facesTurned = 0;
    for (const auto& [r, v] : volume)
        if (v < 0) ++turned;
    if (turned == 0) return 0;
    for (Triangle& t : mesh.triangles) {
        const auto it = volume.find(root[t[0]]);
        if (it != volume.end() && it->second < 0) {
            std::swap(t[1], t[2]);
            ++facesTurned;
        }
    }
    return turned;
}

/// The sum of the weights @p w of the @p n points (x, y, z) within √r2 of @p p: the whole
/// loop vectorised where the processor has AVX2 (integer sums, so every variant gives the
/// same sum; no fused multiply-adds in any, so every variant tests the same distances).
__attribute__((target_clones("avx2", "default"))) std::int64_t weightWithin(
    const double* __restrict x, const double* __restrict y, const double* __restrict z,
    const std::int64_t* __restrict w, std::size_t n, const Vec3& p, double r2)
{
    const double qx = p.x, qy = p.y, qz = p.z;
    std::int64_t sum = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double ex = x[i] - qx, ey = y[i] - qy, ez = z[i] - qz;
        const std::int64_t wi = w[i];  // read whatever the test, so that the loop has no branch
        sum += ex * ex + ey * ey + ez * ez <= r2 ? wi : 0;
    }
    return sum;
}

} // namespace

/// The fill triangles cut into pieces much smaller than R, each piece's area at its
/// centroid, summed over the ball of radius R of each vertex.
std::vector<float> fillShare(const TriMesh& mesh, std::size_t firstFill, double radius, std::size_t count)
{
    struct Piece {
        Vec3 at;
        double area;
    };
    const auto cellOf = [&](const Vec3& p) {
        return std::array<std::int64_t, 3>{std::int64_t(std::floor(p.x / radius)), std::int64_t(std::floor(p.y / radius)),
                                           std::int64_t(std::floor(p.z / radius))};
    };
    const auto keyOf = [](const std::array<std::int64_t, 3>& c) {
        return std::uint64_t(c[0] & 0x1FFFFF) << 42 | std::uint64_t(c[1] & 0x1FFFFF) << 21 | std::uint64_t(c[2] & 0x1FFFFF);
    };
    const std::size_t wanted = count > 0 ? std::min(count, mesh.numVertices()) : mesh.numVertices();
    // The cells (of side R) next to a vertex asked for: a piece outside them is farther than R
    // from all of them and adds nothing. Left out, the pieces of fill far from the vertices
    // (a continuation that rises kilometres past a spiky DEM's edge) take no memory.
    std::unordered_set<std::uint64_t> near;
    for (std::size_t v = 0; v < wanted; ++v) {
        const auto c = cellOf(mesh.points[v]);
        if (!near.insert(keyOf(c) | (std::uint64_t(1) << 63)).second) continue;  // its block is in already
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) near.insert(keyOf({c[0] + dx, c[1] + dy, c[2] + dz}));
    }
    std::vector<Piece> pieces;
    const double pieceSize = radius / 16.0;
    for (std::size_t f = firstFill; f < mesh.numTriangles(); ++f) {
        const Triangle& t = mesh.triangles[f];
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const double longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
        const int m = std::clamp(int(std::ceil(longest / pieceSize)), 1, 64);
        const double area = 0.5 * norm(cross(b - a, c - a)) / double(m * m);
        // The m² sub-triangles of the regular subdivision, by their centroids.
        const Vec3 u = (b - a) / double(m), w = (c - a) / double(m);
        for (int i = 0; i < m; ++i)
            for (int j = 0; i + j < m; ++j) {
                const Vec3 first = a + u * (i + 1.0 / 3) + w * (j + 1.0 / 3);
                if (near.count(keyOf(cellOf(first)))) pieces.push_back({first, area});
                if (i + j + 1 >= m) continue;
                const Vec3 second = a + u * (i + 2.0 / 3) + w * (j + 2.0 / 3);
                if (near.count(keyOf(cellOf(second)))) pieces.push_back({second, area});
            }
    }
    // The pieces by cell, each cell's pieces together (in piece order) and coordinate by
    // coordinate, so that a vertex's test of a cell's pieces is one vectorised loop.
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> byCell;
    for (std::size_t i = 0; i < pieces.size(); ++i) byCell[keyOf(cellOf(pieces[i].at))].push_back(std::uint32_t(i));
    struct CellPieces {
        std::array<std::int64_t, 3> cell;
        Vec3 lo, hi;  // the box of its pieces
        std::size_t begin, end;
    };
    std::unordered_map<std::uint64_t, CellPieces> cells;
    std::vector<double> px, py, pz;
    std::vector<std::int64_t> weight;
    // Areas in whole units of 2^-40 πR², summed as integers: the sum is exact whatever its
    // order (a vertex's sum does not depend on how the pieces are grouped, and tiles give
    // the untiled run's shares bit for bit), and rounding a piece to the unit changes a
    // share by at most 2^-41 per piece, far below a float's step.
    const double unit = std::ldexp(M_PI * radius * radius, -40);
    for (const auto& [key, list] : byCell) {
        CellPieces& c = cells[key];
        c.cell = cellOf(pieces[list.front()].at);
        c.lo = c.hi = pieces[list.front()].at;
        c.begin = px.size();
        for (std::uint32_t i : list) {
            for (int a = 0; a < 3; ++a)
                c.lo[a] = std::min(c.lo[a], pieces[i].at[a]), c.hi[a] = std::max(c.hi[a], pieces[i].at[a]);
            px.push_back(pieces[i].at.x);
            py.push_back(pieces[i].at.y);
            pz.push_back(pieces[i].at.z);
            weight.push_back(std::int64_t(std::llround(pieces[i].area / unit)));
        }
        c.end = px.size();
    }
    // The cells next to a piece: a vertex in none of them is farther than R from every
    // piece, and most vertices of a large surface with small holes are.
    std::unordered_set<std::uint64_t> reached;
    for (const auto& [key, c] : cells)
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) reached.insert(keyOf({c.cell[0] + dx, c.cell[1] + dy, c.cell[2] + dz}));
    const double r2 = radius * radius;
    // A cell is skipped where the box of its pieces, widened by a millionth of R against
    // rounding, is farther than R from the vertex. (The box, not the cell's bounds: cells
    // 2^21 apart share a key, and their pieces one list.)
    const double slack = 1e-6 * radius;
    std::vector<float> share(mesh.numVertices(), 0.0f);
    forEachBlock(wanted, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v) {
            const Vec3& p = mesh.points[v];
            const auto c = cellOf(p);
            if (!reached.count(keyOf(c))) continue;
            std::int64_t sum = 0;
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const auto it = cells.find(keyOf({c[0] + dx, c[1] + dy, c[2] + dz}));
                        if (it == cells.end()) continue;
                        const CellPieces& cp = it->second;
                        double gap2 = 0;
                        for (int a = 0; a < 3; ++a) {
                            const double lo = cp.lo[a] - slack, hi = cp.hi[a] + slack, q = p[a];
                            const double gap = q < lo ? lo - q : q > hi ? q - hi : 0.0;
                            gap2 += gap * gap;
                        }
                        if (gap2 > r2) continue;
                        sum += weightWithin(px.data() + cp.begin, py.data() + cp.begin, pz.data() + cp.begin,
                                            weight.data() + cp.begin, cp.end - cp.begin, p, r2);
                    }
            share[v] = float(std::min(1.0, double(sum) * 0x1p-40));
        }
    });
    return share;
}

namespace {

/// The repairs prepareMesh makes, recorded as they are made; with repair off, the first
/// problem that would need one refuses the mesh instead.
class RepairLog {
public:
    RepairLog(bool repair, std::vector<Diagnostic>& changes) : mRepair(repair), mChanges(changes) {}

    /// Records a repair of @p count things (@p done says what was done).
    /// @throw InvalidInputError naming @p problem if repair is off.
    void record(const char* kind, std::size_t count, const std::string& problem, const std::string& done) const
    {
        if (!mRepair) throw InvalidInputError("the mesh has " + problem + ", and repair is off");
        mChanges.push_back({kind, count, {}, done});
    }

private:
    bool mRepair;
    std::vector<Diagnostic>& mChanges;
};

struct SpikeFaces {
    std::size_t faces = 0;  ///< left out
    double extent = 0;      ///< the diagonal of the central 98 %
};

/// Leaves out of @p triangles the faces of spike vertices: vertices whose shortest edge is
/// longer than kSpikeEdgeFactor times the diagonal of the box of the central 98 % of the
/// vertices in faces (the 1st and 99th percentiles on each axis, at least five vertices off
/// each end; from at most a million vertices at even steps), and longer than kSpikeNeighbourFactor times the shortest edge of each of
/// their neighbours. The second test keeps coarse parts of a surface (a plane of a few
/// long triangles beside a fine scan): their vertices' neighbours have long edges too.
SpikeFaces leaveOutSpikeFaces(const std::vector<Vec3>& points, std::vector<Triangle>& triangles)
{
    SpikeFaces out;
    if (triangles.empty()) return out;
    // The vertices in faces, each once, at most a million at even steps.
    std::vector<char> used(points.size(), 0);
    std::size_t numUsed = 0;
    for (const Triangle& t : triangles)
        for (std::uint32_t v : t)
            if (v < points.size() && !used[v]) used[v] = 1, ++numUsed;  // others: refused by the index check
    if (numUsed < 4) return out;
    const std::size_t step = std::max<std::size_t>(1, numUsed / 1000000);
    std::array<std::vector<double>, 3> axis;
    for (std::size_t v = 0, k = 0; v < points.size(); ++v)
        if (used[v] && k++ % step == 0)
            for (int a = 0; a < 3; ++a) axis[std::size_t(a)].push_back(points[v][a]);
    std::array<double, 3> lo{}, hi{};
    for (std::size_t a = 0; a < 3; ++a) {
        std::vector<double>& x = axis[a];
        // At least five vertices off each end (a quarter of a tiny mesh's), so that a small
        // mesh's few spikes are outside too.
        const std::size_t trim = std::min(std::max<std::size_t>(5, x.size() / 100), (x.size() - 1) / 4);
        const std::size_t i = trim, j = x.size() - 1 - trim;
        std::nth_element(x.begin(), x.begin() + std::ptrdiff_t(i), x.end());
        lo[a] = x[i];
        std::nth_element(x.begin(), x.begin() + std::ptrdiff_t(j), x.end());
        hi[a] = x[j];
    }
    out.extent = norm(Vec3(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
    if (!(out.extent > 0)) return out;
    const auto valid = [&](const Triangle& t) { return t[0] < points.size() && t[1] < points.size() && t[2] < points.size(); };
    // Each vertex's shortest edge, then the longest of its neighbours' shortest edges.
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> shortest(points.size(), inf);
    for (const Triangle& t : triangles) {
        if (!valid(t)) continue;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
            const double len = norm(points[a] - points[b]);
            shortest[a] = std::min(shortest[a], len), shortest[b] = std::min(shortest[b], len);
        }
    }
    const double farEdge = kSpikeEdgeFactor * out.extent;
    std::vector<double> neighbours(points.size(), 0.0);
    for (const Triangle& t : triangles) {
        if (!valid(t)) continue;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
            if (shortest[a] > farEdge) neighbours[a] = std::max(neighbours[a], shortest[b]);
            if (shortest[b] > farEdge) neighbours[b] = std::max(neighbours[b], shortest[a]);
        }
    }
    const auto spikeVertex = [&](std::uint32_t v) {
        return shortest[v] > farEdge && shortest[v] > kSpikeNeighbourFactor * neighbours[v];
    };
    const std::size_t before = triangles.size();
    triangles.erase(std::remove_if(triangles.begin(), triangles.end(),
                                   [&](const Triangle& t) {
                                       return valid(t) && (spikeVertex(t[0]) || spikeVertex(t[1]) || spikeVertex(t[2]));
                                   }),
                    triangles.end());
    out.faces = before - triangles.size();
    return out;
}

/// Step 1: refuses what cannot be repaired (no vertices or faces, too many vertices,
/// non-finite coordinates, face indices out of range).
void refuseUnrepairable(const TriMesh& input)
{
    if (input.points.empty()) throw InvalidInputError("the mesh has no vertices");
    if (input.triangles.empty()) throw InvalidInputError("the mesh has no faces");
    const std::size_t n = input.numVertices();
    if (n >= std::size_t(kNone)) throw InvalidInputError("the mesh has more than 2^32 - 1 vertices");
    std::size_t nonFinite = 0, first = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (!isFinite(input.points[i]) && nonFinite++ == 0) first = i;
    if (nonFinite > 0)
        throw InvalidInputError("the mesh has " + plural(nonFinite, "vertex", "vertices") +
                                " with NaN or infinite coordinates (the first is vertex " + std::to_string(first) +
                                ", counting from 0)");
    for (std::size_t f = 0; f < input.numTriangles(); ++f)
        for (std::uint32_t v : input.triangles[f])
            if (v >= n)
                throw InvalidInputError("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                                        " but the mesh has only " + plural(n, "vertex", "vertices"));
}

/// Step 2: vertices at the same position become one; @p triangles (the input's) then refer
/// to the first of them. Returns that vertex for each input vertex (itself if none).
std::vector<std::uint32_t> mergeSamePositions(const std::vector<Vec3>& points, std::vector<Triangle>& triangles,
                                              const RepairLog& log)
{
    std::size_t numMerged = 0;
    std::vector<std::uint32_t> rep = samePositionRepresentatives(points, numMerged);
    if (numMerged > 0) {
        for (Triangle& t : triangles)
            for (std::uint32_t& v : t) v = rep[v];
        log.record("duplicate_vertices_merged", numMerged,
                   plural(numMerged, "vertex", "vertices") + " at exactly the position of another",
                   "merged " + plural(numMerged, "vertex", "vertices") +
                       " with another at exactly the same position (texture seams, triangle soups)");
    }
    return rep;
}

/// Steps 3 and 4: removes the faces that make no surface (degenerate, duplicate, around
/// non-manifold edges). Returns the check of the faces after step 3.
MeshCheckResult removeFacesWithoutSurface(TriMesh& work, const RepairLog& log)
{
    MeshCheckResult check = checkMesh(work);
    if (check.numDegenerateFaces > 0 || check.numDuplicateFaces > 0) {
        const std::size_t degenerate = check.numDegenerateFaces, duplicate = check.numDuplicateFaces;
        if (degenerate > 0)
            log.record("degenerate_faces_removed", degenerate,
                       plural(degenerate, "degenerate face", "degenerate faces") + " (a repeated vertex, or no area)",
                       "removed " + plural(degenerate, "degenerate face", "degenerate faces") +
                           " (a repeated vertex, or no area)");
        if (duplicate > 0)
            log.record("duplicate_faces_removed", duplicate,
                       plural(duplicate, "duplicate face", "duplicate faces") + " (the same vertices as an earlier face)",
                       "removed " + plural(duplicate, "duplicate face", "duplicate faces") +
                           " (the same vertices as an earlier face)");
        removeBadFaces(work, check);
        if (work.triangles.empty()) throw InvalidInputError("the mesh has no faces with an area");
        check = checkMesh(work);
    }
    if (check.numNonManifoldEdges > 0) {
        const std::size_t edges = check.numNonManifoldEdges;
        const std::size_t removed = removeNonManifoldFaces(work);
        log.record("non_manifold_faces_removed", removed,
                   plural(edges, "non-manifold edge", "non-manifold edges") + " (edges of more than two faces)",
                   "removed the " + plural(removed, "face", "faces") + " around " +
                       plural(edges, "non-manifold edge", "non-manifold edges") +
                       " (edges of more than two faces); the hole they leave is treated as any other");
        if (work.triangles.empty()) throw InvalidInputError("the mesh has no faces left around its non-manifold edges");
    }
    return check;
}

/// The prepared mesh of @p triangles (indices of the input's @p points): only vertices in
/// some face take part, in input order; fills result.mesh, preparedOf (through @p rep, the
/// merged vertex of each input vertex) and numIsolatedVertices.
void keepVerticesInFaces(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles,
                         const std::vector<std::uint32_t>& rep, PrepareMeshResult& result)
{
    const std::size_t n = points.size();
    std::vector<std::uint32_t> index(n, kNone);
    for (const Triangle& t : triangles)
        for (std::uint32_t v : t) index[v] = 0;
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < n; ++v)
        if (index[v] == 0) {
            index[v] = next++;
            result.mesh.points.push_back(points[v]);
        }
    result.mesh.triangles.resize(triangles.size());
    for (std::size_t f = 0; f < triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) result.mesh.triangles[f][std::size_t(k)] = index[triangles[f][std::size_t(k)]];
    result.preparedOf.resize(n);
    for (std::size_t v = 0; v < n; ++v) result.preparedOf[v] = index[rep[v]];
    result.numIsolatedVertices = std::size_t(std::count(result.preparedOf.begin(), result.preparedOf.end(), kNone));
}

/// Step 6: each part oriented coherently, closed parts facing outward. @p check is the
/// check of @p mesh as it comes, and afterwards as it leaves.
void orientParts(TriMesh& mesh, MeshCheckResult& check, const RepairLog& log)
{
    if (check.numInconsistentEdges > 0) {
        const std::size_t turned = orientCoherently(mesh);
        log.record("faces_reoriented", turned,
                   plural(check.numInconsistentEdges, "edge", "edges") + " whose two faces disagree in orientation",
                   "re-oriented " + plural(turned, "face", "faces") + " to agree with their neighbours");
        check = checkMesh(mesh);
    }
    std::size_t facesTurned = 0;
    if (const std::size_t parts = turnClosedPartsOutward(mesh, check, facesTurned); parts > 0) {
        log.record("closed_parts_turned_outward", parts,
                   plural(parts, "closed part", "closed parts") + " facing inward (negative volume)",
                   "turned " + plural(parts, "closed part", "closed parts") + " (" +
                       plural(facesTurned, "face", "faces") + ") that faced inward, so that they face outward");
        check = checkMesh(mesh);
    }
}

/// Step 7: holes filled for the computation only (result.holes, firstFillTriangle, the
/// changes), and the share of fill near each vertex (filledShare) when a radius is given.
void fillHolesForComputation(const MeshCheckResult& check, const PrepareMeshOptions& options,
                             PrepareMeshResult& result)
{
    TriMesh& mesh = result.mesh;
    result.firstFillTriangle = mesh.numTriangles();
    if (options.maxHolePerimeter > 0 && !check.closed) {
        FillHolesOptions fo;
        fo.maxPerimeter = options.maxHolePerimeter;
        result.holes = fillHoles(mesh, check.borderEdges, fo);
        if (result.holes.numFilled > 0) {
            std::ostringstream msg;
            msg.precision(3);
            msg << "filled " << plural(result.holes.numFilled, "hole", "holes") << " for the computation (the longest "
                << result.holes.largestPerimeter << " around, " << result.holes.areaAdded
                << " of area added); values near them rest partly on the filled surface (filled_share)";
            result.changes.push_back({"holes_filled",
                                      result.holes.numFilled,
                                      {{"largest_perimeter", result.holes.largestPerimeter},
                                       {"area_added", result.holes.areaAdded}},
                                      msg.str()});
        }
        if (result.holes.numFailed > 0)
            result.changes.push_back({"holes_not_filled", result.holes.numFailed, {},
                                      "could not fill " + plural(result.holes.numFailed, "hole", "holes") +
                                          "; their rims stay borders of the surface (continued past them, or masked, as chosen)"});
    }
    if (options.radius > 0)
        result.filledShare = result.holes.numFilled > 0 ? fillShare(mesh, result.firstFillTriangle, options.radius)
                                                        : std::vector<float>(mesh.numVertices(), 0.0f);
}

} // namespace

double defaultMaxHolePerimeter(double radius) { return M_PI * radius; }

PrepareMeshResult prepareMesh(const TriMesh& input, const PrepareMeshOptions& options)
{
    refuseUnrepairable(input);
    PrepareMeshResult result;
    const RepairLog log(options.repair, result.changes);

    TriMesh work;
    work.points = input.points;
    work.triangles = input.triangles;
    if (options.leaveOutSpikes)
        if (const SpikeFaces spikes = leaveOutSpikeFaces(input.points, work.triangles); spikes.faces > 0) {
            std::ostringstream done;
            done.precision(3);
            done << "left out " << plural(spikes.faces, "face", "faces") << " of spikes to stray points (vertices "
                 << "whose every edge is over " << kSpikeEdgeFactor << " times as long as the mesh's central 98 % is wide, "
                 << spikes.extent << ", and their neighbours' edges far shorter); those vertices get no values, the "
                    "holes left are filled as others";
            log.record("spike_faces_left_out", spikes.faces,
                       plural(spikes.faces, "spike face", "spike faces") + " (edges far longer than the mesh is wide)",
                       done.str());
        }
    const std::vector<std::uint32_t> rep = mergeSamePositions(input.points, work.triangles, log);
    MeshCheckResult check = removeFacesWithoutSurface(work, log);
    keepVerticesInFaces(input.points, work.triangles, rep, result);
    work = TriMesh();
    TriMesh& mesh = result.mesh;

    // 5. One copy of a vertex per fan of faces.
    if (const std::size_t split = splitNonManifoldVertices(mesh); split > 0)
        log.record("non_manifold_vertices_split", split,
                   plural(split, "non-manifold vertex", "non-manifold vertices") +
                       " (separate fans of faces meeting at one point)",
                   "split " + plural(split, "non-manifold vertex", "non-manifold vertices") +
                       " (where separate fans of faces meet at one point) into one per fan");

    // 6. The check of the faces stands for the prepared mesh if nothing changed it (a clean
    // scan: one check in all).
    if (!result.changes.empty() || result.numIsolatedVertices > 0) check = checkMesh(mesh);
    orientParts(mesh, check, log);

    fillHolesForComputation(check, options, result);
    result.open = !check.closed;  // unless every loop was filled
    if (result.numIsolatedVertices > 0)
        result.changes.push_back({"isolated_vertices", result.numIsolatedVertices, {},
                                  plural(result.numIsolatedVertices, "vertex belongs", "vertices belong") +
                                      " to no face: no values there (NaN)"});
    return result;
}

std::vector<float> toInputVertices(const PrepareMeshResult& prepared, const std::vector<float>& column)
{
    std::vector<float> out(prepared.preparedOf.size(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t v = 0; v < out.size(); ++v)
        if (prepared.preparedOf[v] != kNone && prepared.preparedOf[v] < column.size())
            out[v] = column[prepared.preparedOf[v]];
    return out;
}

InputVertexLists inputVerticesOf(const PrepareMeshResult& prepared)
{
    InputVertexLists lists;
    lists.offsets.assign(prepared.mesh.numVertices() + 1, 0);
    for (std::uint32_t p : prepared.preparedOf)
        if (p != kNone) ++lists.offsets[p + 1];
    for (std::size_t p = 0; p + 1 < lists.offsets.size(); ++p) lists.offsets[p + 1] += lists.offsets[p];
    lists.inputs.resize(lists.offsets.back());
    std::vector<std::size_t> fill(lists.offsets.begin(), lists.offsets.end() - 1);
    for (std::size_t v = 0; v < prepared.preparedOf.size(); ++v)
        if (prepared.preparedOf[v] != kNone) lists.inputs[fill[prepared.preparedOf[v]]++] = std::uint32_t(v);
    return lists;
}

} // namespace msii
