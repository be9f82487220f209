#pragma once
/// @file mesh_check.h
/// @brief Finds what makes a mesh unusable or dubious: non-finite coordinates, faces with
/// repeated or out-of-range indices, zero-area faces, duplicate faces, non-manifold edges,
/// inconsistent orientation, and borders (open meshes). Optionally repairs what can be
/// repaired without guessing (drops degenerate and duplicate faces, and the faces around
/// non-manifold edges, which leaves a small hole that is then treated as a border).

#include <msii/mesh/trimesh.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace msii {

struct MeshCheckOptions {
    /// A face whose area is below this fraction of the squared median edge length counts
    /// as degenerate (0-area slivers and needles), besides faces with repeated indices.
    double degenerateAreaRatio = 1e-12;
};

/// Edge counts (non-manifold, inconsistent, border), `closed` and unreferenced vertices are
/// computed over the faces that are neither degenerate nor duplicate, i.e. they describe the
/// mesh as removeBadFaces() leaves it (so one bad face is not reported several times).
struct MeshCheckResult {
    std::size_t numNonFinitePoints = 0;    ///< vertices with NaN or infinite coordinates
    std::size_t numDegenerateFaces = 0;    ///< repeated index or (near) zero area
    std::size_t numDuplicateFaces = 0;     ///< same vertex set as an earlier face (any order)
    std::size_t numNonManifoldEdges = 0;   ///< undirected edges shared by more than two faces
    std::size_t numInconsistentEdges = 0;  ///< edges whose two faces traverse them the same way
    std::size_t numBorderEdges = 0;        ///< edges of exactly one face
    std::size_t numUnreferencedVertices = 0;
    bool closed = false;                   ///< no border edges (and at least one face)
    /// Border edges as vertex index pairs (for distances to the border, masks).
    std::vector<std::array<std::uint32_t, 2>> borderEdges;
    /// Indices of degenerate faces, then of duplicate faces (later copies), for repair.
    std::vector<std::size_t> degenerateFaces, duplicateFaces;

    /// Problems that make the mesh unusable as it is: non-finite points, degenerate or
    /// duplicate faces, non-manifold edges. Empty if none; otherwise one sentence.
    std::string firstProblem() const;
};

/// Analyses @p mesh (parallel with TBB; the result does not depend on the thread count).
/// @throw InvalidInputError for meshes of more than 2^31 vertices or 2^32 edges.
MeshCheckResult checkMesh(const TriMesh& mesh, const MeshCheckOptions& options = {});

/// Removes the faces listed in check.degenerateFaces and check.duplicateFaces; returns how
/// many were removed. Vertices are kept (indices stay valid for per-vertex outputs).
std::size_t removeBadFaces(TriMesh& mesh, const MeshCheckResult& check);

/// Removes every face that has an edge shared by more than two faces; returns how many were
/// removed. Vertices are kept. Use after removeBadFaces() (duplicates also make such edges).
std::size_t removeNonManifoldFaces(TriMesh& mesh);

} // namespace msii
