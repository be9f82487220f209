/// @file components.cpp
/// @brief Connected components of a thresholded per-vertex function (union-find).
///
/// Memory-lean: a parent array (4 bytes per vertex) and a rank array (1 byte) besides the
/// output labels, no adjacency lists. The selection is kept in the parent array itself
/// (kNone = not selected). Components are numbered in the order of their smallest vertex,
/// which is also the tie-break of the area ordering. Everything runs in index order on one
/// thread, so the result cannot depend on the thread count (the union-find pass over a
/// million-vertex mesh takes a few tens of milliseconds).

#include <msii/segmentation/components.h>

#include <msii/core/errors.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

namespace msii {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// Disjoint sets over the selected vertices (unselected ones hold kNone): union by rank
/// with path halving, O(α(n)) amortised per operation, 5 bytes per vertex.
class UnionFind {
public:
    explicit UnionFind(std::vector<std::uint32_t>& parent) : mParent(parent), mRank(parent.size(), 0) {}

    bool selected(std::uint32_t v) const { return mParent[v] != kNone; }

    std::uint32_t find(std::uint32_t v)
    {
        while (mParent[v] != v) {
            mParent[v] = mParent[mParent[v]];
            v = mParent[v];
        }
        return v;
    }

    /// Merges the sets of two selected vertices.
    void unite(std::uint32_t a, std::uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (mRank[a] < mRank[b]) std::swap(a, b);
        mParent[b] = a;
        if (mRank[a] == mRank[b]) ++mRank[a];
    }

private:
    std::vector<std::uint32_t>& mParent;
    std::vector<std::uint8_t> mRank;  ///< < 32: a rank-r root has at least 2^r vertices
};

/// Per-component sums while the components are still numbered by their roots.
struct Accumulator {
    std::size_t vertices = 0;
    double area = 0;
    Vec3 weighted;   ///< Σ cell · p
    Vec3 positions;  ///< Σ p (centroid of components without area)
    Vec3 boxMin{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                std::numeric_limits<double>::infinity()};
    Vec3 boxMax{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                -std::numeric_limits<double>::infinity()};
};

void validate(const TriMesh& mesh, const std::vector<float>& f, const ComponentOptions& options)
{
    if (f.size() != mesh.numVertices())
        throw InvalidInputError("components: the function has " + std::to_string(f.size()) +
                                " values but the mesh has " + std::to_string(mesh.numVertices()) +
                                " vertices.");
    if (std::isnan(options.threshold)) throw InvalidInputError("components: the threshold is NaN.");
    if (std::isnan(options.minArea)) throw InvalidInputError("components: the minimum area is NaN.");
    if (mesh.numVertices() >= std::size_t(kNone))
        throw InvalidInputError("components: the mesh has too many vertices (at most 2^32 - 2).");
}

} // namespace

ComponentResult findComponents(const TriMesh& mesh, const std::vector<float>& f,
                               const ComponentOptions& options)
{
    validate(mesh, f, options);
    const std::size_t n = mesh.numVertices();

    // Selection: parent[v] = v for selected vertices, kNone otherwise (NaN fails both tests).
    std::vector<std::uint32_t> parent(n, kNone);
    for (std::size_t v = 0; v < n; ++v) {
        const double value = f[v];
        const bool pass = options.below ? value <= options.threshold : value >= options.threshold;
        if (pass) parent[v] = std::uint32_t(v);
    }

    ComponentResult result;
    result.label.assign(n, 0);
    std::uint32_t count = 0;
    {
        // Union over every triangle edge with both ends selected.
        UnionFind sets(parent);
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Triangle& tri = mesh.triangles[t];
            for (int k = 0; k < 3; ++k) {
                if (tri[k] >= n)
                    throw InvalidInputError("components: triangle " + std::to_string(t) +
                                            " has a vertex index out of range.");
            }
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
                if (sets.selected(a) && sets.selected(b)) sets.unite(a, b);
            }
        }

        // Number the components in the order of their smallest vertex index: the first
        // vertex met of a set numbers it (parked at the root until the root is met).
        for (std::size_t v = 0; v < n; ++v) {
            if (!sets.selected(std::uint32_t(v))) continue;
            const std::uint32_t root = sets.find(std::uint32_t(v));
            if (result.label[root] == 0) result.label[root] = ++count;
            result.label[v] = result.label[root];
        }
    }
    std::vector<std::uint32_t>().swap(parent);

    // Sizes, boxes, then barycentric cells (a third of each incident triangle's area).
    std::vector<Accumulator> acc(count);
    for (std::size_t v = 0; v < n; ++v) {
        const std::uint32_t c = result.label[v];
        if (c == 0) continue;
        Accumulator& a = acc[c - 1];
        const Vec3& p = mesh.points[v];
        ++a.vertices;
        a.positions += p;
        for (int i = 0; i < 3; ++i) {
            a.boxMin[i] = std::min(a.boxMin[i], p[i]);
            a.boxMax[i] = std::max(a.boxMax[i], p[i]);
        }
    }
    for (const Triangle& tri : mesh.triangles) {
        const std::uint32_t c0 = result.label[tri[0]], c1 = result.label[tri[1]],
                            c2 = result.label[tri[2]];
        if ((c0 | c1 | c2) == 0) continue;
        const Vec3& p0 = mesh.points[tri[0]];
        const Vec3& p1 = mesh.points[tri[1]];
        const Vec3& p2 = mesh.points[tri[2]];
        double cell = norm(cross(p1 - p0, p2 - p0)) / 6.0;
        if (!std::isfinite(cell)) cell = 0;  // non-finite coordinates: no area
        const std::uint32_t corners[3] = {c0, c1, c2};
        for (int k = 0; k < 3; ++k) {
            if (corners[k] == 0) continue;
            Accumulator& a = acc[corners[k] - 1];
            a.area += cell;
            a.weighted += mesh.points[tri[k]] * cell;
        }
    }

    // Order by decreasing area, ties by root (the component number), then filter.
    std::vector<std::uint32_t> order(count);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return acc[a].area > acc[b].area; });
    std::vector<std::uint32_t> newLabel(count, 0);
    for (const std::uint32_t id : order) {
        const Accumulator& a = acc[id];
        if (a.vertices < options.minVertices || a.area < options.minArea) {
            ++result.droppedComponents;
            continue;
        }
        Component comp;
        comp.label = std::uint32_t(result.components.size() + 1);
        comp.vertices = a.vertices;
        comp.area = a.area;
        comp.centroid = a.area > 0 ? a.weighted / a.area : a.positions / double(a.vertices);
        comp.boxMin = a.boxMin;
        comp.boxMax = a.boxMax;
        newLabel[id] = comp.label;
        result.components.push_back(comp);
    }
    for (std::uint32_t& label : result.label) {
        if (label != 0) label = newLabel[label - 1];
    }
    return result;
}

} // namespace msii
