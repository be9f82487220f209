#pragma once
/// @file prepare_mesh.h
/// @brief Mesh preparation, the first stage of the pipeline (docs/method.md, "Mesh
/// preparation"): makes the computation see the surface a scan means, and says what it did.
/// In order:
///   1. refuses what cannot be repaired: no faces, NaN or infinite coordinates, face indices
///      out of range;
///   2. merges vertices at the same position (STL soups, OBJ texture seams);
///   3. drops degenerate faces (repeated index, zero area) and duplicate faces;
///   4. drops the faces around non-manifold edges (the hole they leave is filled in 7);
///   5. splits non-manifold vertices (two fans meeting at a point) into one copy per fan;
///   6. re-orients each connected part coherently (flipping the fewer faces), closed parts
///      facing outward;
///   7. fills holes up to a size (mesh/fill_holes.h).
/// The input is never changed: the prepared mesh is a separate computation mesh, and every
/// result maps back to the input's vertices by index (toInputVertices), so outputs keep the
/// input's vertices and faces in the input's order.

#include <msii/core/diagnostics.h>
#include <msii/mesh/fill_holes.h>
#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace msii {

/// A vertex is the tip of a spike (PrepareMeshOptions::leaveOutSpikes) when its shortest
/// edge is longer than kSpikeEdgeFactor times the diagonal of the mesh's central 98 % (no
/// face of a surface is ten times longer than the surface is wide) and longer than
/// kSpikeNeighbourFactor times the shortest edge of each of its neighbours (a coarse part of
/// the surface has coarse neighbours).
constexpr double kSpikeEdgeFactor = 10.0;
constexpr double kSpikeNeighbourFactor = 100.0;

struct PrepareMeshOptions {
    /// Repair what steps 2-6 repair; false refuses such meshes instead (InvalidInputError).
    bool repair = true;
    /// Leave out the faces of spike tips (kSpikeEdgeFactor, kSpikeNeighbourFactor): spikes
    /// to stray points (docs/limits.md, Spikes). Their tips are left in no face (NaN), the
    /// holes they leave filled as others. Off for DEM windows, whose spikes are
    /// heights: a window's own extent must not decide what a cell is.
    bool leaveOutSpikes = true;
    /// Fill border loops up to this length (mesh units); 0 fills none.
    double maxHolePerimeter = 0;
    /// Radius of the ball for filledShare (the largest radius R); 0 = no filledShare.
    double radius = 0;
};


struct PrepareMeshResult {
    /// The mesh the computation runs on: the input's referenced vertices in input order,
    /// then copies made by splitting non-manifold vertices, then hole-filling vertices.
    TriMesh mesh;
    /// For each input vertex, its vertex in `mesh`, or kNoVertex for a vertex in no face
    /// (its values are NaN).
    std::vector<std::uint32_t> preparedOf;
    static constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();
    /// mesh.triangles[firstFillTriangle ...] are hole fill.
    std::size_t firstFillTriangle = 0;
    /// Per vertex of `mesh`: the area of fill inside the ball of radius options.radius,
    /// divided by πR² (the area a flat disc has there), capped at 1; 0 where nothing was
    /// filled. Empty if no radius was given.
    std::vector<float> filledShare;
    FillHolesResult holes;
    /// The mesh had borders before hole filling (some may be left: an open surface's, holes
    /// too large or that could not be filled).
    bool open = false;
    std::vector<Diagnostic> changes;      ///< one per kind of change made (core/diagnostics.h)
    std::size_t numIsolatedVertices = 0;  ///< input vertices in no face
};

/// Prepares @p input for the computation (see the file comment).
/// @throw InvalidInputError for input that cannot be repaired, and with options.repair
///        false for input that would need repair; one sentence each.
PrepareMeshResult prepareMesh(const TriMesh& input, const PrepareMeshOptions& options = {});

/// Per vertex of @p mesh: the area of triangles firstFill ... inside the ball of radius
/// @p radius, divided by πR² (the area a flat disc has there), at most 1 (filledShare); for
/// the first @p count vertices (0 = all), the others 0.
std::vector<float> fillShare(const TriMesh& mesh, std::size_t firstFill, double radius, std::size_t count = 0);

/// The default hole size for a largest radius R: loops of at most πR, the perimeter of a
/// disc of diameter R, i.e. holes that fit well inside the largest ball (docs/method.md,
/// Hole filling).
double defaultMaxHolePerimeter(double radius);

/// A per-vertex column of the prepared mesh mapped to the input's vertices (NaN for
/// vertices in no face).
std::vector<float> toInputVertices(const PrepareMeshResult& prepared, const std::vector<float>& column);

/// The input vertices of each prepared vertex (several where positions were merged, none
/// for hole-filling vertices and split copies): inputs[offsets[p] ... offsets[p + 1]).
struct InputVertexLists {
    std::vector<std::size_t> offsets;
    std::vector<std::uint32_t> inputs;
};
InputVertexLists inputVerticesOf(const PrepareMeshResult& prepared);

} // namespace msii
