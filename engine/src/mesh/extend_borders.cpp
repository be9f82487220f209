#include <msii/mesh/extend_borders.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace msii {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

/// The share of the mirrored height the continuation takes: halfway between the tangent
/// plane (which drops the curvature across the border) and the full mirror image (which
/// also repeats features near the border, a wedge or a ditch, that the surface beyond need
/// not have). Chosen on the cut test (docs/method.md, Values up to the border).
constexpr double kMirrorShare = 0.5;

/// Items (faces, edges) binned to cubes of one size, looked up over the 27 cubes around a
/// point, in a fixed order (so that sums over them do not depend on the mesh's numbering
/// beyond the order of items within a cube).
class CubeBins {
public:
    explicit CubeBins(double size) : mSize(size) {}

    void add(const Vec3& lo, const Vec3& hi, std::uint32_t item)
    {
        const auto a = cube(lo), b = cube(hi);
        for (auto x = a[0]; x <= b[0]; ++x)
            for (auto y = a[1]; y <= b[1]; ++y)
                for (auto z = a[2]; z <= b[2]; ++z) mBins[key({x, y, z})].push_back(item);
    }
    /// Calls @p f(item) for the items in the 27 cubes around @p p (an item in several cubes
    /// may come several times).
    template <class F>
    void around(const Vec3& p, F&& f) const
    {
        const auto c = cube(p);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = mBins.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
                    if (it == mBins.end()) continue;
                    for (std::uint32_t item : it->second) f(item);
                }
    }

    /// Calls @p f(item) for the items in the cubes that a ball of @p radius about @p p touches.
    template <class F>
    void within(const Vec3& p, double radius, F&& f) const
    {
        const auto lo = cube(p - Vec3{radius, radius, radius}), hi = cube(p + Vec3{radius, radius, radius});
        for (auto x = lo[0]; x <= hi[0]; ++x)
            for (auto y = lo[1]; y <= hi[1]; ++y)
                for (auto z = lo[2]; z <= hi[2]; ++z) {
                    const auto it = mBins.find(key({x, y, z}));
                    if (it == mBins.end()) continue;
                    for (std::uint32_t item : it->second) f(item);
                }
    }

private:
    std::array<std::int64_t, 3> cube(const Vec3& p) const
    {
        return {std::int64_t(std::floor(p.x / mSize)), std::int64_t(std::floor(p.y / mSize)),
                std::int64_t(std::floor(p.z / mSize))};
    }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c)
    {
        return std::uint64_t(c[0] & 0x1FFFFF) << 42 | std::uint64_t(c[1] & 0x1FFFFF) << 21 | std::uint64_t(c[2] & 0x1FFFFF);
    }

    double mSize;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> mBins;
};

/// A border edge from -> to, in the direction of its one face, whose normal it keeps.
struct BorderEdge {
    std::uint32_t from, to;
    Vec3 faceNormal;  // unit
};

/// The border edges of @p mesh, cut edges left out, in the order of their faces. An edge
/// a -> b is a border if no face has b -> a: looked up among b's outgoing edges, which are
/// grouped by vertex (counting sort) rather than sorted, for meshes of millions of faces.
std::vector<BorderEdge> borderEdgesOf(const TriMesh& mesh, const std::vector<char>& onCut)
{
    std::vector<std::uint32_t> first(mesh.numVertices() + 1, 0);
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++first[t[k] + 1];
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) first[v + 1] += first[v];
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1), targets(first.back());
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) targets[next[t[k]]++] = t[(k + 1) % 3];
    const auto has = [&](std::uint32_t a, std::uint32_t b) {
        return std::find(targets.begin() + first[a], targets.begin() + first[a + 1], b) != targets.begin() + first[a + 1];
    };
    std::vector<BorderEdge> edges;
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = t[k], b = t[(k + 1) % 3];
            if (has(b, a)) continue;
            if (!onCut.empty() && onCut[a] && onCut[b]) continue;
            const Vec3 n = cross(mesh.points[t[1]] - mesh.points[t[0]], mesh.points[t[2]] - mesh.points[t[0]]);
            edges.push_back({a, b, normalized(n)});
        }
    return edges;
}

/// Which faces of @p mesh come within @p reach of a border vertex (by their bounding boxes,
/// on a grid of reach / 4): only those can enter a fitted plane or a mirrored height, so only
/// those are binned, and a large surface with a short border costs little.
std::vector<char> facesNearBorders(const TriMesh& mesh, const std::vector<BorderEdge>& edges, double reach)
{
    const double g = reach / 4.0;
    const auto cell = [&](const Vec3& p) {
        return std::array<std::int64_t, 3>{std::int64_t(std::floor(p.x / g)), std::int64_t(std::floor(p.y / g)),
                                           std::int64_t(std::floor(p.z / g))};
    };
    const auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
        return std::uint64_t(x & 0x1FFFFF) << 42 | std::uint64_t(y & 0x1FFFFF) << 21 | std::uint64_t(z & 0x1FFFFF);
    };
    std::unordered_set<std::uint64_t> borderCells, near;
    for (const BorderEdge& e : edges)
        for (const std::uint32_t v : {e.from, e.to}) {
            const auto c = cell(mesh.points[v]);
            borderCells.insert(key(c[0], c[1], c[2]));
        }
    // A point within reach of a border vertex is at most 4 cells from the vertex's cell.
    for (const std::uint64_t k : borderCells) {
        const auto unpack = [](std::uint64_t v) { return std::int64_t(v & 0x1FFFFF); };
        const std::int64_t x = unpack(k >> 42), y = unpack(k >> 21), z = unpack(k);
        for (std::int64_t dx = -4; dx <= 4; ++dx)
            for (std::int64_t dy = -4; dy <= 4; ++dy)
                for (std::int64_t dz = -4; dz <= 4; ++dz) near.insert(key(x + dx, y + dy, z + dz));
    }
    std::vector<char> kept(mesh.numTriangles(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.numTriangles()), [&](const auto& range) {
        for (std::size_t f = range.begin(); f < range.end(); ++f) {
            const Triangle& t = mesh.triangles[f];
            const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
            const auto lo = cell({std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})});
            const auto hi = cell({std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})});
            bool found = false;
            for (auto x = lo[0]; x <= hi[0] && !found; ++x)
                for (auto y = lo[1]; y <= hi[1] && !found; ++y)
                    for (auto z = lo[2]; z <= hi[2] && !found; ++z) found = near.count(key(x, y, z)) > 0;
            kept[f] = found;
        }
    });
    return kept;
}

/// Border runs: loops, or runs that end at a cut (or at a vertex where borders meet, which
/// preparation does not leave), as lists of edge indices in order.
std::vector<std::vector<std::uint32_t>> chainsOf(const std::vector<BorderEdge>& edges)
{
    std::unordered_map<std::uint32_t, std::uint32_t> outOf, intoCount;
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        if (!outOf.emplace(edges[e].from, e).second) outOf[edges[e].from] = kNone;  // pinched: no successor
        ++intoCount[edges[e].to];
    }
    const auto next = [&](std::uint32_t e) {
        const auto it = outOf.find(edges[e].to);
        return it == outOf.end() || intoCount[edges[e].to] != 1 ? kNone : it->second;
    };
    std::vector<char> used(edges.size(), 0);
    std::vector<std::vector<std::uint32_t>> chains;
    const auto follow = [&](std::uint32_t e) {
        std::vector<std::uint32_t> chain;
        while (e != kNone && !used[e]) {
            used[e] = 1;
            chain.push_back(e);
            e = next(e);
        }
        chains.push_back(std::move(chain));
    };
    // Runs first, from edges nothing leads into; then the loops.
    std::vector<char> hasPredecessor(edges.size(), 0);
    for (std::uint32_t e = 0; e < edges.size(); ++e)
        if (const std::uint32_t n = next(e); n != kNone) hasPredecessor[n] = 1;
    for (std::uint32_t e = 0; e < edges.size(); ++e)
        if (!hasPredecessor[e] && !used[e]) follow(e);
    for (std::uint32_t e = 0; e < edges.size(); ++e)
        if (!used[e]) follow(e);
    return chains;
}

/// The unit normal of the plane the surface has around @p p: the area-weighted normals of
/// the faces whose centroid is within @p radius (exact for a plane), or @p fallback.
Vec3 fittedNormal(const TriMesh& mesh, const CubeBins& faces, const Vec3& p, double radius, const Vec3& fallback)
{
    Vec3 sum{0, 0, 0};
    const double r2 = radius * radius;
    faces.around(p, [&](std::uint32_t f) {
        const Triangle& t = mesh.triangles[f];
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        if (squaredNorm((a + b + c) / 3.0 - p) <= r2) sum = sum + cross(b - a, c - a);
    });
    const double len = norm(sum);
    return len > 0 && std::isfinite(len) ? sum / len : fallback;
}

/// Where the line @p from + λ·@p direction meets triangle @p t (Möller–Trumbore), if it does.
std::optional<double> lineHit(const TriMesh& mesh, const Triangle& t, const Vec3& from, const Vec3& direction)
{
    const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
    const Vec3 e1 = b - a, e2 = c - a, q = cross(direction, e2);
    const double det = dot(e1, q);
    if (!(std::abs(det) > 1e-300)) return std::nullopt;
    const Vec3 s = from - a;
    const double u = dot(s, q) / det;
    if (u < 0 || u > 1) return std::nullopt;
    const Vec3 r = cross(s, e1);
    const double v = dot(direction, r) / det;
    if (v < 0 || u + v > 1) return std::nullopt;
    return dot(e2, r) / det;
}

/// The height of the surface above @p at along the unit @p normal: the hit of the line
/// through @p at nearest to it, within ±@p limit, searched outwards cube by cube.
std::optional<double> heightAt(const TriMesh& mesh, const CubeBins& faces, double cube, const Vec3& at,
                               const Vec3& normal, double limit)
{
    std::optional<double> best;
    for (int k = 0; double(k - 1) * cube <= limit; ++k) {
        for (const double side : {1.0, -1.0}) {
            if (k == 0 && side < 0) continue;
            faces.around(at + normal * (side * k * cube), [&](std::uint32_t f) {
                const std::optional<double> h = lineHit(mesh, mesh.triangles[f], at, normal);
                if (h && std::abs(*h) <= limit && (!best || std::abs(*h) < std::abs(*best))) best = h;
            });
        }
        // Every hit nearer than (k + 1) cubes lies in the cubes searched so far.
        if (best && std::abs(*best) <= double(k + 1) * cube) return best;
    }
    return best;
}

/// One column of the skirt: its positions ring by ring, from the border vertex out.
struct Column {
    std::uint32_t vertex = kNone;  // the border vertex
    std::vector<Vec3> at;          // ring k's position (at[0]: the border vertex)
    int rings = 0;                 // rings kept (0: only the border vertex)
    std::uint32_t firstNew = kNone;
};

/// A border run in order: its vertices (vertex k starts edge k), their arc length along it.
struct Chain {
    std::vector<std::uint32_t> edges, vertices;
    std::vector<double> arc;  // per vertex; arc.back() + closing edge = total for a loop
    bool loop = false;
    double total = 0;
    /// Distance along the chain between vertices at arc lengths @p a and @p b.
    double between(double a, double b) const
    {
        const double d = std::abs(a - b);
        return loop ? std::min(d, total - d) : d;
    }
};

Chain chainOf(const TriMesh& mesh, const std::vector<BorderEdge>& edges, std::vector<std::uint32_t> list)
{
    Chain c;
    c.loop = edges[list.back()].to == edges[list.front()].from;
    for (std::uint32_t e : list) c.vertices.push_back(edges[e].from);
    if (!c.loop) c.vertices.push_back(edges[list.back()].to);
    c.edges = std::move(list);
    c.arc.assign(c.vertices.size(), 0.0);
    for (std::size_t k = 1; k < c.vertices.size(); ++k)
        c.arc[k] = c.arc[k - 1] + norm(mesh.points[c.vertices[k]] - mesh.points[c.vertices[k - 1]]);
    c.total = c.arc.back() + (c.loop ? norm(mesh.points[c.vertices.front()] - mesh.points[c.vertices.back()]) : 0.0);
    return c;
}

/// The columns of @p chain, one per vertex, grown ring by ring. The tangent plane fitted
/// around the border carries the column out: each step goes along the outward directions of
/// the border edges, put into the plane whose normal is the average of the normals fitted at
/// the border vertices (over ρ = @p radius each), both averaged along the chain with
/// triangular weights over ρ + s/2 (s the ring's distance); the averages widen outwards, so
/// that columns from a jagged border run nearly parallel instead of crossing. Off the plane,
/// the surface's own height above it is mirrored through b: the ring at x = b + s·t (in the
/// plane) rises by kMirrorShare times the surface's height above the plane at 2b − x, so that
/// curvature and features partly go on past the border; where the mirror point has no
/// surface under it (within ±s), the last height found holds. The heights are averaged across
/// columns like the directions. On a plane every ring stays in it.
std::vector<Column> columnsOf(const TriMesh& mesh, const std::vector<BorderEdge>& edges, const Chain& chain,
                              const CubeBins& faces, const CubeBins& fineFaces, double cube, double radius,
                              const std::vector<double>& rings)
{
    const std::size_t n = chain.vertices.size(), m = chain.edges.size();
    std::vector<Vec3> outward(n, Vec3{0, 0, 0});
    for (std::size_t k = 0; k < m; ++k) {
        const BorderEdge& e = edges[chain.edges[k]];
        // Away from the face, in its plane: the edge turned by the face's normal.
        const Vec3 away = normalized(cross(mesh.points[e.to] - mesh.points[e.from], e.faceNormal));
        outward[k] = outward[k] + away;
        outward[(k + 1) % n] = outward[(k + 1) % n] + away;
    }
    std::vector<Vec3> fitted(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& range) {
        for (std::size_t k = range.begin(); k < range.end(); ++k)
            fitted[k] = fittedNormal(mesh, faces, mesh.points[chain.vertices[k]], radius, Vec3{0, 0, 0});
    });
    // Pass 1, per column: the neighbours along the chain, the plane and direction of each
    // ring, the in-plane path and the mirrored heights.
    std::vector<Column> columns(n);
    std::vector<std::vector<std::pair<std::size_t, double>>> nearOf(n);
    std::vector<std::vector<Vec3>> normals(n);
    std::vector<std::vector<double>> heights(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& range) {
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
            Column& col = columns[k];
            col.vertex = chain.vertices[k];
            const Vec3& p = mesh.points[col.vertex];
            const Vec3 own = normalized(outward[k] - fitted[k] * dot(outward[k], fitted[k]));
            // The neighbours along the chain, nearest first on each side, with their distance.
            std::vector<std::pair<std::size_t, double>>& near = nearOf[k];
            near.push_back({k, 0.0});
            const double widest = radius + 0.5 * rings.back();
            for (std::size_t s = 1; s < n && (chain.loop || s <= k); ++s) {
                const double d = chain.between(chain.arc[(k + n - s) % n], chain.arc[k]);
                if (d > widest || (chain.loop && 2 * s > n)) break;
                near.push_back({(k + n - s) % n, d});
            }
            for (std::size_t s = 1; s < n && (chain.loop || k + s < n); ++s) {
                const double d = chain.between(chain.arc[(k + s) % n], chain.arc[k]);
                if (d > widest || (chain.loop && 2 * s >= n)) break;
                near.push_back({(k + s) % n, d});
            }
            col.at.assign(rings.size(), p);
            normals[k].assign(rings.size(), fitted[k]);
            heights[k].assign(rings.size(), 0.0);
            Vec3 inPlane = p;
            double height = 0;
            for (std::size_t r = 1; r < rings.size(); ++r) {
                // The outward directions and the fitted normals, averaged alike: neighbouring
                // columns keep nearly the same plane, so the skirt does not fan out in height.
                const double h = radius + 0.5 * rings[r - 1];
                Vec3 sum{0, 0, 0}, normalSum{0, 0, 0};
                for (const auto& [j, d] : near)
                    if (d < h) {
                        sum = sum + outward[j] * (1.0 - d / h);
                        normalSum = normalSum + fitted[j] * (1.0 - d / h);
                    }
                const double normalLength = norm(normalSum);
                const Vec3 normal = normalLength > 0 && std::isfinite(normalLength) ? normalSum / normalLength : fitted[k];
                Vec3 t = sum - normal * dot(sum, normal);
                const double len = norm(t);
                t = len > 1e-9 * norm(sum) && std::isfinite(len) ? t / len : own;
                inPlane = inPlane + t * (rings[r] - rings[r - 1]);
                if (squaredNorm(normal) > 0.5)
                    if (const std::optional<double> found =
                            heightAt(mesh, fineFaces, cube, p * 2.0 - inPlane, normal, rings[r]))
                        height = *found;
                col.at[r] = inPlane;
                normals[k][r] = normal;
                heights[k][r] = height;
            }
        }
    });
    // Pass 2: the heights averaged across columns with the same weights (a jagged border
    // mirrors each column about a slightly different point; averaging keeps the skirt from
    // turning that into a sawtooth), kMirrorShare of them off the plane.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& range) {
        for (std::size_t k = range.begin(); k < range.end(); ++k)
            for (std::size_t r = 1; r < rings.size(); ++r) {
                const double h = radius + 0.5 * rings[r - 1];
                double sum = 0, weights = 0;
                for (const auto& [j, d] : nearOf[k])
                    if (d < h) sum += heights[j][r] * (1.0 - d / h), weights += 1.0 - d / h;
                columns[k].at[r] = columns[k].at[r] + normals[k][r] * (kMirrorShare * sum / weights);
            }
    });
    return columns;
}

/// Ring distances from the border: steps of @p step, growing by 15 % of the distance once
/// that is larger (far rings are coarser), until @p width is passed.
std::vector<double> ringDistances(double step, double width)
{
    std::vector<double> s{0.0};
    while (s.back() < width) s.push_back(s.back() + std::max(step, 0.15 * s.back()));
    return s;
}

/// Where each border edge is: its chain and the arc length of its start along it.
struct EdgePlace {
    std::uint32_t chain = kNone;
    double arc = 0;
};

/// Stops each column at its first ring that is markedly nearer (0.85) to another border
/// than to its own border vertex: skirts from the two sides of a gap, or from a concave
/// bend, end about where they meet instead of overlapping. The border within @p radius + s
/// along the column's own chain is its own (its direction was averaged over it).
std::size_t trimColumns(const TriMesh& mesh, const std::vector<BorderEdge>& edges, const std::vector<EdgePlace>& places,
                        const CubeBins& edgeBins, const std::vector<double>& rings, std::uint32_t chainId,
                        const Chain& chain, double radius, std::vector<Column>& columns)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, columns.size()), [&](const auto& range) {
        for (std::size_t c = range.begin(); c < range.end(); ++c) {
            Column& col = columns[c];
            int kept = 0;
            for (std::size_t k = 1; k < rings.size(); ++k) {
                const Vec3& v = col.at[k];
                const double limit2 = 0.85 * 0.85 * rings[k] * rings[k];
                bool nearer = false;
                edgeBins.within(v, 0.85 * rings[k], [&](std::uint32_t e) {
                    if (nearer) return;
                    if (places[e].chain == chainId && chain.between(places[e].arc, chain.arc[c]) <= radius + rings[k]) return;
                    nearer = pointSegmentDistance2(v, mesh.points[edges[e].from], mesh.points[edges[e].to]) < limit2;
                });
                if (nearer) break;
                kept = int(k);
            }
            col.rings = kept;
        }
    });
    std::size_t trimmed = 0;
    for (const Column& col : columns) trimmed += std::size_t(col.rings + 1 < int(rings.size()));
    return trimmed;
}

/// Appends the quads between consecutive columns @p a -> @p b (the direction of their
/// border edge), as far as both reach; skips slivers.
void appendQuads(TriMesh& mesh, const Column& a, const Column& b, double& area)
{
    const auto at = [](const Column& c, int k) { return k == 0 ? c.vertex : c.firstNew + std::uint32_t(k - 1); };
    const auto add = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
        const double twice = norm(cross(mesh.points[y] - mesh.points[x], mesh.points[z] - mesh.points[x]));
        const double longest = std::max({squaredNorm(mesh.points[y] - mesh.points[x]), squaredNorm(mesh.points[z] - mesh.points[y]),
                                         squaredNorm(mesh.points[x] - mesh.points[z])});
        if (!(twice > 1e-6 * longest)) return;  // a sliver where columns meet at a sharp bend
        mesh.triangles.push_back({x, y, z});
        area += 0.5 * twice;
    };
    const int top = std::min(a.rings, b.rings);
    for (int k = 0; k < top; ++k) {
        // The face's edge runs a -> b; the skirt, on its other side, runs b -> a.
        add(at(b, k), at(a, k), at(a, k + 1));
        add(at(b, k), at(a, k + 1), at(b, k + 1));
    }
}

} // namespace

ExtendBordersResult extendBorders(TriMesh& mesh, const ExtendBordersOptions& options)
{
    ExtendBordersResult result;
    result.firstNewVertex = mesh.numVertices();
    result.firstNewTriangle = mesh.numTriangles();
    if (!(options.width > 0) || !(options.fitRadius > 0) || !(options.step > 0))
        throw InvalidInputError("the border extension needs a positive width, fit radius and step");
    if (!options.onCut.empty() && options.onCut.size() != mesh.numVertices())
        throw InvalidInputError("the cut flags must be one per vertex");
    const std::vector<BorderEdge> edges = borderEdgesOf(mesh, options.onCut);
    if (edges.empty()) return result;

    // The faces a fitted plane (within fitRadius of a border vertex) or a mirrored height
    // (a line within the last ring's distance of one, searched as far again along it) can
    // meet; binned in the order of their indices, so that sums over a cube do not depend on
    // which faces were left out.
    const std::vector<double> rings = ringDistances(options.step, options.width);
    const double cube = 2.0 * options.step;
    const std::vector<char> near = facesNearBorders(mesh, edges, std::max(options.fitRadius, 2.0 * rings.back()) + 2.0 * cube);
    CubeBins faces(options.fitRadius);
    // The faces again, in cubes of two steps, for the mirror heights.
    CubeBins fineFaces(cube);
    for (std::uint32_t f = 0; f < mesh.numTriangles(); ++f) {
        if (!near[f]) continue;
        const Triangle& t = mesh.triangles[f];
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const Vec3 centroid = (a + b + c) / 3.0;
        faces.add(centroid, centroid, f);
        fineFaces.add(Vec3{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
                      Vec3{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})}, f);
    }
    CubeBins edgeBins(std::max(4.0 * options.step, options.width / 2.0));
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        const Vec3 &a = mesh.points[edges[e].from], &b = mesh.points[edges[e].to];
        edgeBins.add(Vec3{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)},
                     Vec3{std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}, e);
    }

    std::vector<Chain> chains;
    std::vector<EdgePlace> places(edges.size());
    for (std::vector<std::uint32_t>& list : chainsOf(edges)) {
        chains.push_back(chainOf(mesh, edges, std::move(list)));
        const Chain& c = chains.back();
        for (std::size_t k = 0; k < c.edges.size(); ++k) places[c.edges[k]] = {std::uint32_t(chains.size() - 1), c.arc[k]};
    }
    for (std::uint32_t id = 0; id < chains.size(); ++id) {
        const Chain& chain = chains[id];
        std::vector<Column> columns = columnsOf(mesh, edges, chain, faces, fineFaces, cube, options.fitRadius, rings);
        result.numTrimmed += trimColumns(mesh, edges, places, edgeBins, rings, id, chain, options.fitRadius, columns);
        for (Column& col : columns) {
            col.firstNew = std::uint32_t(mesh.numVertices());
            for (int k = 1; k <= col.rings; ++k) mesh.points.push_back(col.at[std::size_t(k)]);
        }
        for (std::size_t k = 0; k + 1 < columns.size(); ++k) appendQuads(mesh, columns[k], columns[k + 1], result.areaAdded);
        if (chain.loop) appendQuads(mesh, columns.back(), columns.front(), result.areaAdded);
        ++result.numChains;
        result.numBorderVertices += columns.size();
    }
    return result;
}

} // namespace msii
