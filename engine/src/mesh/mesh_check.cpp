#include <msii/mesh/mesh_check.h>

#include "blocks.h"

#include <msii/core/errors.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace msii {

namespace {

using detail::forEachBlock;
using detail::numBlocks;

enum FaceStatus : std::uint8_t { kGood = 0, kDegenerate = 1, kDuplicate = 2 };

/// Runs body(first, last) on consecutive vertex ranges, one per thread, in parallel. Each
/// range is written by one body only, so per-vertex arrays need no atomics (which, on the
/// random access patterns of large scans, cost more than the work itself).
template <class Body>
void forEachVertexRange(std::size_t numVertices, const Body& body)
{
    // At most 8 ranges: every range reads all faces, so more would only add reading.
    const std::size_t parts = std::size_t(std::clamp(tbb::this_task_arena::max_concurrency(), 1, 8));
    tbb::parallel_for(std::size_t(0), parts,
                      [&](std::size_t p) { body(numVertices * p / parts, numVertices * (p + 1) / parts); });
}

/// Groups items by a vertex with a counting sort (linear time; a comparison sort of all
/// half-edges costs several times more on large scans): afterwards
/// entries[offsets[v] .. offsets[v + 1]) are the items filed under vertex v, in face order
/// whatever the number of threads. @p emit(f, add) calls add(vertex, entry) for each item
/// of face f; it runs twice per face and vertex range.
template <class Entry, class Emit>
void groupByVertex(std::size_t numVertices, std::size_t numFaces, const Emit& emit,
                   std::vector<std::uint32_t>& offsets, std::vector<Entry>& entries)
{
    offsets.assign(numVertices + 1, 0);
    forEachVertexRange(numVertices, [&](std::size_t first, std::size_t last) {
        for (std::size_t f = 0; f < numFaces; ++f)
            emit(f, [&](std::uint32_t v, const Entry&) {
                if (v >= first && v < last) ++offsets[v];
            });
    });
    std::uint64_t total = 0;
    for (std::size_t v = 0; v < numVertices; ++v) {
        const std::uint64_t count = offsets[v];
        offsets[v] = std::uint32_t(total);
        total += count;
    }
    if (total > std::numeric_limits<std::uint32_t>::max())
        throw InvalidInputError("the mesh has too many faces for the mesh check (more than 2^32 edges).");
    entries.resize(std::size_t(total));
    forEachVertexRange(numVertices, [&](std::size_t first, std::size_t last) {
        for (std::size_t f = 0; f < numFaces; ++f)
            emit(f, [&](std::uint32_t v, const Entry& entry) {
                if (v >= first && v < last) entries[offsets[v]++] = entry;
            });
    });
    // offsets[v] now holds the end of group v, i.e. the start of group v + 1.
    for (std::size_t v = numVertices; v > 0; --v) offsets[v] = offsets[v - 1];
    offsets[0] = 0;
}

/// The other two vertices of a face and its index, grouped under the face's smallest vertex.
struct FaceRest {
    std::uint32_t b, c, face;
    bool operator<(const FaceRest& o) const { return std::tie(b, c, face) < std::tie(o.b, o.c, o.face); }
};

/// Per-block results, combined in block order so they do not depend on scheduling.
struct EdgeBlock {
    std::size_t inconsistent = 0, nonManifold = 0;
    std::vector<std::array<std::uint32_t, 2>> border;
    std::vector<std::size_t> duplicates;
};

std::string plural(std::size_t n, const char* one, const char* many)
{
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

/// Vertices with NaN or infinite coordinates.
std::size_t countNonFinitePoints(const std::vector<Vec3>& points)
{
    const std::size_t numVertices = points.size();
    std::vector<std::size_t> counts(numBlocks(numVertices), 0);
    forEachBlock(numVertices, [&](std::size_t b, std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v)
            if (!isFinite(points[v])) ++counts[b];
    });
    std::size_t total = 0;
    for (std::size_t count : counts) total += count;
    return total;
}

/// Degenerate faces: invalid or repeated index, or an area that is negligible against the
/// mesh resolution (the median edge length of the other faces). Faces touching non-finite
/// points have no meaningful area and are left to the non-finite count. Marks them kDegenerate
/// in @p status and lists them in @p result.
void findDegenerateFaces(const TriMesh& mesh, const MeshCheckOptions& options, std::vector<std::uint8_t>& status,
                         MeshCheckResult& result)
{
    const auto& points = mesh.points;
    const auto& triangles = mesh.triangles;
    const std::size_t numVertices = points.size();
    const std::size_t numFaces = triangles.size();
    // One pass over the faces gathers edge lengths and areas (the random access to points
    // is the expensive part on large scans).
    std::vector<double> squaredEdges(3 * numFaces), areas(numFaces);
    forEachBlock(numFaces, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f < end; ++f) {
            const Triangle& t = triangles[f];
            double* squared = &squaredEdges[3 * f];
            squared[0] = squared[1] = squared[2] = -1.0;
            areas[f] = std::numeric_limits<double>::quiet_NaN();
            if (t[0] >= numVertices || t[1] >= numVertices || t[2] >= numVertices || t[0] == t[1] ||
                t[1] == t[2] || t[0] == t[2]) {
                status[f] = kDegenerate;
                continue;
            }
            const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
            if (!isFinite(a) || !isFinite(b) || !isFinite(c)) continue;
            squared[0] = squaredNorm(b - a);
            squared[1] = squaredNorm(c - b);
            squared[2] = squaredNorm(a - c);
            areas[f] = 0.5 * norm(cross(b - a, c - a));
        }
    });
    squaredEdges.erase(std::remove(squaredEdges.begin(), squaredEdges.end(), -1.0), squaredEdges.end());
    double medianSquared = 0;
    if (!squaredEdges.empty()) {
        const auto middle = squaredEdges.begin() + std::ptrdiff_t(squaredEdges.size() / 2);
        std::nth_element(squaredEdges.begin(), middle, squaredEdges.end());
        medianSquared = *middle;
    }
    const double minArea = options.degenerateAreaRatio * medianSquared;
    forEachBlock(numFaces, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f < end; ++f)
            if (areas[f] < minArea || areas[f] == 0) status[f] = kDegenerate;  // NaN: neither
    });
    for (std::size_t f = 0; f < numFaces; ++f)
        if (status[f] == kDegenerate) result.degenerateFaces.push_back(f);
    result.numDegenerateFaces = result.degenerateFaces.size();
}

/// Duplicate faces: same vertex set as an earlier non-degenerate face. Faces are grouped
/// under their smallest vertex; each small group is then sorted. Marks them kDuplicate in
/// @p status and lists them in @p result; @p offsets is scratch for the grouping.
void findDuplicateFaces(const TriMesh& mesh, std::vector<std::uint8_t>& status, std::vector<std::uint32_t>& offsets,
                        MeshCheckResult& result)
{
    const auto& triangles = mesh.triangles;
    const std::size_t numVertices = mesh.points.size();
    const std::size_t numFaces = triangles.size();
    std::vector<FaceRest> rests;
    groupByVertex<FaceRest>(
        numVertices, numFaces,
        [&](std::size_t f, const auto& add) {
            if (status[f] != kGood) return;
            std::array<std::uint32_t, 3> v = triangles[f];
            std::sort(v.begin(), v.end());
            add(v[0], FaceRest{v[1], v[2], std::uint32_t(f)});
        },
        offsets, rests);
    std::vector<EdgeBlock> blocks(numBlocks(numVertices));
    forEachBlock(numVertices, [&](std::size_t b, std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v) {
            const auto first = rests.begin() + offsets[v], last = rests.begin() + offsets[v + 1];
            if (last - first < 2) continue;
            std::sort(first, last);
            for (auto it = first + 1; it != last; ++it)
                if (it->b == (it - 1)->b && it->c == (it - 1)->c) blocks[b].duplicates.push_back(it->face);
        }
    });
    for (const EdgeBlock& block : blocks)
        result.duplicateFaces.insert(result.duplicateFaces.end(), block.duplicates.begin(), block.duplicates.end());
    std::sort(result.duplicateFaces.begin(), result.duplicateFaces.end());
    for (std::size_t f : result.duplicateFaces) status[f] = kDuplicate;
    result.numDuplicateFaces = result.duplicateFaces.size();
}

/// Edges of the faces still kGood, i.e. of the mesh as removeBadFaces() leaves it: border,
/// inconsistently oriented and non-manifold edges, and whether the mesh is closed. Each
/// half-edge is filed under its smaller vertex as (larger vertex << 1 | direction), where
/// direction is 1 if the face runs from the larger to the smaller vertex. @p offsets is
/// scratch for the grouping.
void checkEdges(const TriMesh& mesh, const std::vector<std::uint8_t>& status, std::vector<std::uint32_t>& offsets,
                MeshCheckResult& result)
{
    const auto& triangles = mesh.triangles;
    const std::size_t numVertices = mesh.points.size();
    const std::size_t numFaces = triangles.size();
    std::vector<std::uint32_t> halfedges;
    groupByVertex<std::uint32_t>(
        numVertices, numFaces,
        [&](std::size_t f, const auto& add) {
            if (status[f] != kGood) return;
            const Triangle& t = triangles[f];
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t from = t[k], to = t[(k + 1) % 3];
                add(std::min(from, to), (std::max(from, to) << 1) | (from > to ? 1u : 0u));
            }
        },
        offsets, halfedges);
    const std::size_t numGoodFaces = halfedges.size() / 3;
    std::vector<EdgeBlock> blocks(numBlocks(numVertices));
    forEachBlock(numVertices, [&](std::size_t b, std::size_t begin, std::size_t end) {
        EdgeBlock& block = blocks[b];
        for (std::size_t v = begin; v < end; ++v) {
            const auto first = halfedges.begin() + offsets[v], last = halfedges.begin() + offsets[v + 1];
            std::sort(first, last);
            for (auto it = first; it != last;) {
                auto next = it + 1;
                while (next != last && (*next >> 1) == (*it >> 1)) ++next;
                const auto count = next - it;
                if (count == 1) {
                    const std::uint32_t lo = std::uint32_t(v), hi = *it >> 1;
                    if (*it & 1) block.border.push_back({hi, lo});
                    else block.border.push_back({lo, hi});
                } else if (count == 2) {
                    // Consistently oriented neighbours run along a shared edge in
                    // opposite directions.
                    if ((*it & 1) == (*(it + 1) & 1)) ++block.inconsistent;
                } else {
                    ++block.nonManifold;
                }
                it = next;
            }
        }
    });
    for (const EdgeBlock& block : blocks) {
        result.numInconsistentEdges += block.inconsistent;
        result.numNonManifoldEdges += block.nonManifold;
        result.borderEdges.insert(result.borderEdges.end(), block.border.begin(), block.border.end());
    }
    result.numBorderEdges = result.borderEdges.size();
    result.closed = numGoodFaces > 0 && result.numBorderEdges == 0;
}

/// Vertices no face still kGood uses.
std::size_t countUnreferencedVertices(const TriMesh& mesh, const std::vector<std::uint8_t>& status)
{
    const std::size_t numVertices = mesh.points.size();
    const std::size_t numFaces = mesh.triangles.size();
    std::vector<std::uint8_t> used(numVertices, 0);
    forEachVertexRange(numVertices, [&](std::size_t first, std::size_t last) {
        for (std::size_t f = 0; f < numFaces; ++f)
            if (status[f] == kGood)
                for (std::uint32_t v : mesh.triangles[f])
                    if (v >= first && v < last) used[v] = 1;
    });
    return std::size_t(std::count(used.begin(), used.end(), 0));
}

} // namespace

std::string MeshCheckResult::firstProblem() const
{
    if (numNonFinitePoints > 0)
        return "the mesh has " + plural(numNonFinitePoints, "vertex", "vertices") +
               " with NaN or infinite coordinates";
    if (numDegenerateFaces > 0)
        return "the mesh has " + plural(numDegenerateFaces, "degenerate face", "degenerate faces") +
               " (repeated or invalid vertex indices, or zero area)";
    if (numDuplicateFaces > 0)
        return "the mesh has " + plural(numDuplicateFaces, "duplicate face", "duplicate faces") +
               " (same vertices as an earlier face)";
    if (numNonManifoldEdges > 0)
        return "the mesh has " + plural(numNonManifoldEdges, "non-manifold edge", "non-manifold edges") +
               " (shared by more than two faces)";
    return {};
}

MeshCheckResult checkMesh(const TriMesh& mesh, const MeshCheckOptions& options)
{
    const std::size_t numVertices = mesh.points.size();
    if (numVertices > (std::size_t(1) << 31))
        throw InvalidInputError("the mesh has " + std::to_string(numVertices) +
                                " vertices; mesh checks support at most 2^31.");
    MeshCheckResult result;
    result.numNonFinitePoints = countNonFinitePoints(mesh.points);
    // Each step looks only at the faces the steps before left kGood.
    std::vector<std::uint8_t> status(mesh.triangles.size(), kGood);
    findDegenerateFaces(mesh, options, status, result);
    std::vector<std::uint32_t> offsets;  // one allocation for both groupings
    findDuplicateFaces(mesh, status, offsets, result);
    checkEdges(mesh, status, offsets, result);
    result.numUnreferencedVertices = countUnreferencedVertices(mesh, status);
    return result;
}

std::size_t removeBadFaces(TriMesh& mesh, const MeshCheckResult& check)
{
    std::vector<std::uint8_t> remove(mesh.triangles.size(), 0);
    for (const auto* list : {&check.degenerateFaces, &check.duplicateFaces})
        for (std::size_t f : *list)
            if (f < remove.size()) remove[f] = 1;
    std::size_t kept = 0;
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        if (!remove[f]) mesh.triangles[kept++] = mesh.triangles[f];
    const std::size_t removed = mesh.triangles.size() - kept;
    mesh.triangles.resize(kept);
    return removed;
}

std::size_t removeNonManifoldFaces(TriMesh& mesh)
{
    // Undirected edges (smaller << 32 | larger) with their face counts; sorted, so the
    // result does not depend on hashing or threads.
    const std::size_t nf = mesh.triangles.size();
    std::vector<std::uint64_t> edges;
    edges.reserve(3 * nf);
    const auto key = [](std::uint32_t a, std::uint32_t b) {
        return std::uint64_t(std::min(a, b)) << 32 | std::uint64_t(std::max(a, b));
    };
    for (const Triangle& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) edges.push_back(key(t[k], t[(k + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    std::vector<std::uint64_t> shared;  // edges of more than two faces
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i + 1;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i > 2) shared.push_back(edges[i]);
        i = j;
    }
    if (shared.empty()) return 0;
    std::size_t kept = 0;
    for (std::size_t f = 0; f < nf; ++f) {
        const Triangle t = mesh.triangles[f];
        bool bad = false;
        for (int k = 0; k < 3 && !bad; ++k)
            bad = std::binary_search(shared.begin(), shared.end(), key(t[k], t[(k + 1) % 3]));
        if (!bad) mesh.triangles[kept++] = t;
    }
    mesh.triangles.resize(kept);
    return nf - kept;
}

} // namespace msii
