// The one source file that includes CGAL (its headers compile slowly, and its Polygon Mesh
// Processing is GPL-3.0+, which is why msii is).
#include <msii/mesh/fill_holes.h>

#include "mesh_topology.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

namespace msii {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

/// Rings of triangles around a hole handed to CGAL with it: fairing (bi-Laplacian, tangent
/// continuity) reads the rim and the ring beyond it; a third ring keeps the local mesh's own
/// cut border away from both.
constexpr int kRings = 3;

/// Refinement density of a filled hole relative to its rim (see fillLoop).
constexpr double kDensity = 3.0;

/// A border loop, as vertices in the direction of their faces' edges.
struct Loop {
    std::vector<std::uint32_t> vertices;
    double perimeter = 0;
    std::uint32_t component = 0;
};

/// What filling one hole gives: new points, and triangles whose indices are mesh vertices
/// (>= 0) or new points (-1 - k).
struct Patch {
    bool ok = false;
    std::vector<Vec3> points;
    std::vector<std::array<std::int64_t, 3>> triangles;
    double area = 0;
};

/// Traces the loops of the border edges (each border vertex of a vertex-manifold mesh starts
/// exactly one border edge). Loops come in the order of their smallest start vertex.
std::vector<Loop> traceLoops(const TriMesh& mesh, std::vector<std::array<std::uint32_t, 2>> edges)
{
    std::sort(edges.begin(), edges.end());
    std::vector<char> used(edges.size(), 0);
    std::vector<Loop> loops;
    const auto startingAt = [&](std::uint32_t v) -> std::ptrdiff_t {
        const auto it = std::lower_bound(edges.begin(), edges.end(), std::array<std::uint32_t, 2>{v, 0});
        if (it == edges.end() || (*it)[0] != v) return -1;
        return it - edges.begin();
    };
    for (std::size_t first = 0; first < edges.size(); ++first) {
        if (used[first]) continue;
        Loop loop;
        std::ptrdiff_t e = std::ptrdiff_t(first);
        bool closed = false;
        while (e >= 0 && !used[std::size_t(e)]) {
            used[std::size_t(e)] = 1;
            const auto& edge = edges[std::size_t(e)];
            loop.vertices.push_back(edge[0]);
            loop.perimeter += norm(mesh.points[edge[1]] - mesh.points[edge[0]]);
            e = startingAt(edge[1]);
            closed = e == std::ptrdiff_t(first);
        }
        if (closed) loops.push_back(std::move(loop));
    }
    return loops;
}

/// Fills one loop on a local copy of the triangles within kRings of it.
Patch fillLoop(const TriMesh& mesh, const detail::VertexTriangles& around, const Loop& loop)
{
    Patch patch;
    // The local triangles, ring by ring, in mesh order.
    std::unordered_set<std::uint32_t> faceSet;
    std::vector<std::uint32_t> frontier = loop.vertices;
    std::unordered_set<std::uint32_t> seen(frontier.begin(), frontier.end());
    for (int ring = 0; ring < kRings; ++ring) {
        std::vector<std::uint32_t> next;
        for (std::uint32_t v : frontier)
            for (std::uint32_t k = around.offsets[v]; k < around.offsets[v + 1]; ++k) {
                const std::uint32_t f = around.triangles[k];
                if (!faceSet.insert(f).second) continue;
                for (std::uint32_t w : mesh.triangles[f])
                    if (seen.insert(w).second) next.push_back(w);
            }
        frontier.swap(next);
    }
    std::vector<std::uint32_t> faces(faceSet.begin(), faceSet.end());
    std::sort(faces.begin(), faces.end());

    // Local coordinates around the loop's first vertex: scans in map coordinates keep
    // their precision.
    const Vec3 origin = mesh.points[loop.vertices.front()];
    SurfaceMesh sm;
    std::unordered_map<std::uint32_t, SurfaceMesh::Vertex_index> local;
    std::vector<std::uint32_t> global;
    const auto vertexOf = [&](std::uint32_t v) {
        const auto [it, fresh] = local.emplace(v, SurfaceMesh::Vertex_index());
        if (fresh) {
            const Vec3 p = mesh.points[v] - origin;
            it->second = sm.add_vertex(Kernel::Point_3(p.x, p.y, p.z));
            global.push_back(v);
        }
        return it->second;
    };
    for (std::uint32_t f : faces) {
        const Triangle& t = mesh.triangles[f];
        const auto a = vertexOf(t[0]), b = vertexOf(t[1]), c = vertexOf(t[2]);
        sm.add_face(a, b, c);  // a face the local cut would make non-manifold is left out
    }
    // The loop runs along its faces' edges a -> b; the hole's border halfedge is b -> a.
    const auto [h, found] = CGAL::halfedge(local.at(loop.vertices[1 % loop.vertices.size()]),
                                           local.at(loop.vertices[0]), sm);
    if (!found || !sm.is_border(h)) return patch;

    std::vector<SurfaceMesh::Face_index> newFaces;
    std::vector<SurfaceMesh::Vertex_index> newVertices;
    namespace PMP = CGAL::Polygon_mesh_processing;
    try {
        // Fairing may fail (a singular system): the refined triangulation is kept then.
        // Refined about twice as densely as the rim (CGAL's default factor is sqrt 2): a
        // pin-hole then gets inner vertices, which fairing moves onto the surface the rim's
        // curvature continues (e.g. down into a wedge's pit); without them a small hole stays
        // a flat lid, and fairing has nothing to move.
        const auto refine = CGAL::parameters::density_control_factor(kDensity);
        PMP::triangulate_refine_and_fair_hole(sm, h, std::back_inserter(newFaces), std::back_inserter(newVertices), refine);
        // Delaunay triangulations find nothing for some degenerate loops (a slit, a loop
        // folded onto itself); the exhaustive search of the best triangulation still does.
        if (newFaces.empty())
            PMP::triangulate_refine_and_fair_hole(sm, h, std::back_inserter(newFaces), std::back_inserter(newVertices),
                                                  refine.use_delaunay_triangulation(false)
                                                      .use_2d_constrained_delaunay_triangulation(false));
    } catch (const std::exception&) {
        return patch;
    }
    if (newFaces.empty()) return patch;

    const std::size_t numOld = global.size();
    for (std::size_t k = numOld; k < sm.number_of_vertices(); ++k) {
        const auto& p = sm.point(SurfaceMesh::Vertex_index(std::uint32_t(k)));
        patch.points.push_back(Vec3(p.x(), p.y(), p.z()) + origin);
    }
    const auto indexOf = [&](SurfaceMesh::Vertex_index v) -> std::int64_t {
        const std::size_t k = std::size_t(v);
        return k < numOld ? std::int64_t(global[k]) : -1 - std::int64_t(k - numOld);
    };
    const auto pointOf = [&](std::int64_t i) { return i >= 0 ? mesh.points[std::size_t(i)] : patch.points[std::size_t(-1 - i)]; };
    for (const auto f : newFaces) {
        std::array<std::int64_t, 3> tri{};
        int k = 0;
        for (const auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
            if (k == 3) return Patch{};
            tri[std::size_t(k++)] = indexOf(v);
        }
        if (k != 3) return Patch{};
        patch.triangles.push_back(tri);
        patch.area += 0.5 * norm(cross(pointOf(tri[1]) - pointOf(tri[0]), pointOf(tri[2]) - pointOf(tri[0])));
    }
    patch.ok = true;
    return patch;
}

} // namespace

FillHolesResult fillHoles(TriMesh& mesh, const std::vector<std::array<std::uint32_t, 2>>& borderEdges,
                          const FillHolesOptions& options)
{
    FillHolesResult result;
    result.firstNewVertex = mesh.numVertices();
    result.firstNewTriangle = mesh.numTriangles();
    if (borderEdges.empty() || !(options.maxPerimeter > 0)) return result;

    std::vector<Loop> loops = traceLoops(mesh, borderEdges);
    if (loops.empty()) return result;

    // Connected parts (over shared vertices) and their areas, for the outer-border rule.
    const std::vector<std::uint32_t> part = detail::vertexParts(mesh);
    std::unordered_map<std::uint32_t, double> partArea;
    for (const Triangle& t : mesh.triangles) {
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        partArea[part[t[0]]] += 0.5 * norm(cross(b - a, c - a));
    }
    std::unordered_map<std::uint32_t, std::size_t> longest;  // part -> its longest loop
    for (std::size_t i = 0; i < loops.size(); ++i) {
        loops[i].component = part[loops[i].vertices.front()];
        const auto [it, fresh] = longest.emplace(loops[i].component, i);
        if (!fresh && loops[i].perimeter > loops[it->second].perimeter) it->second = i;
    }

    std::vector<std::size_t> chosen;
    for (std::size_t i = 0; i < loops.size(); ++i) {
        const Loop& loop = loops[i];
        if (loop.perimeter > options.maxPerimeter || loop.vertices.size() < 3) {
            ++result.numTooLarge;
            continue;
        }
        const double disc = loop.perimeter * loop.perimeter / (4.0 * M_PI);
        if (longest.at(loop.component) == i && disc > options.outerBorderAreaShare * partArea.at(loop.component)) {
            ++result.numOuterBorders;
            continue;
        }
        chosen.push_back(i);
    }
    if (chosen.empty()) return result;

    const detail::VertexTriangles around = detail::vertexTriangles(mesh);  // for the local meshes
    std::vector<Patch> patches(chosen.size());
    tbb::parallel_for(std::size_t(0), chosen.size(),
                      [&](std::size_t k) { patches[k] = fillLoop(mesh, around, loops[chosen[k]]); });

    for (std::size_t k = 0; k < chosen.size(); ++k) {
        const Patch& patch = patches[k];
        if (!patch.ok) {
            ++result.numFailed;
            continue;
        }
        const std::int64_t base = std::int64_t(mesh.points.size());
        mesh.points.insert(mesh.points.end(), patch.points.begin(), patch.points.end());
        for (const auto& tri : patch.triangles) {
            Triangle t;
            for (std::size_t c = 0; c < 3; ++c) t[c] = std::uint32_t(tri[c] >= 0 ? tri[c] : base - 1 - tri[c]);
            mesh.triangles.push_back(t);
        }
        ++result.numFilled;
        result.areaAdded += patch.area;
        result.largestPerimeter = std::max(result.largestPerimeter, loops[chosen[k]].perimeter);
    }
    return result;
}

} // namespace msii
