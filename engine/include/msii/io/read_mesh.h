#pragma once
/// @file read_mesh.h
/// @brief Reading triangle meshes: PLY (binary little/big endian and ascii, `face` and
/// `tristrips` elements, any extra vertex properties), OBJ, OFF and STL (ascii and binary).
/// OBJ/OFF/STL are read through OpenMesh's readers into a raw importer, so no face is
/// dropped or altered on the way (non-manifold and duplicate faces reach mesh_check; only
/// OpenMesh's OBJ and STL readers themselves drop repeated vertices of a face, and STL
/// corners are merged by position); PLY has its own reader (mesh/read_ply.h) because
/// OpenMesh's PLY reader knows no `tristrips`. Polygons are fan-triangulated. A file with
/// no vertices or no faces is an error.

#include <msii/mesh/trimesh.h>

#include <string>
#include <vector>

namespace msii {

struct ReadMeshOptions {
    /// Keep per-vertex scalar properties of a PLY file (other than x, y, z) in
    /// ReadMeshResult::vertexProperties (e.g. to carry `quality` or features on).
    bool keepVertexProperties = false;
    /// Keep per-vertex list properties of a PLY file (e.g. GigaMesh's `feature_vector`) as
    /// float properties `<name>_00`, `<name>_01`, ... (element index, zero-based), after the
    /// scalar ones. Every vertex must have a list of the same length (else InvalidInputError).
    bool keepVertexLists = false;
};

struct ReadMeshResult {
    TriMesh mesh;
    std::string format;                          ///< "ply-binary", "ply-ascii", "obj", "off", "stl"
    std::size_t numPolygonsRead = 0;             ///< faces/strips as found in the file
    std::vector<VertexProperty> vertexProperties; ///< only with keepVertexProperties/keepVertexLists
    std::vector<std::string> comments;           ///< PLY header comments (e.g. msii's parameters)
};

/// Reads a triangle mesh; the format is chosen by the file extension (case-insensitive).
/// @throw IOError if the file is missing or unreadable; InvalidInputError for an unknown
///        extension, a malformed file, or face indices out of range.
/// @note Does not judge the geometry (NaN, degenerate faces...): see mesh/mesh_check.h.
ReadMeshResult readMesh(const std::string& path, const ReadMeshOptions& options = {});

} // namespace msii
