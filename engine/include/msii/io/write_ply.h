#pragma once
/// @file write_ply.h
/// @brief Writes a mesh with per-vertex float properties as PLY (binary little endian by
/// default), atomically (io/atomic_file.h).

#include <msii/mesh/trimesh.h>

#include <string>
#include <vector>

namespace msii {

struct WritePlyOptions {
    bool binary = true;                  ///< binary_little_endian, else ascii
    /// Write x, y, z as double: automatic when float would lose more than 1e-7 relative to
    /// the bounding box (large offsets, e.g. terrain in map coordinates), or forced here.
    bool forceDoublePoints = false;
    std::vector<std::string> comments;   ///< "comment ..." header lines
    /// Optional per-vertex list property `property list uchar float <listName>` written
    /// after the scalar properties: listValues holds numVertices() * listLength floats.
    std::string listName;
    int listLength = 0;
    std::vector<float> listValues;
};

/// Vertices as x, y, z (float or double, see options), then each property of @p properties (float) in order, then
/// the optional list; faces as `property list uchar int vertex_indices`.
/// @throw IOError if the file cannot be written; InvalidInputError if a property has the
///        wrong number of values.
void writePly(const std::string& path, const TriMesh& mesh,
              const std::vector<VertexProperty>& properties, const WritePlyOptions& options = {});

} // namespace msii
