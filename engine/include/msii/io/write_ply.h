#pragma once
/// @file write_ply.h
/// @brief Writes a mesh with per-vertex float properties as PLY (binary little endian by
/// default), atomically (io/atomic_file.h).

#include <msii/mesh/trimesh.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace msii {

struct WritePlyOptions {
    bool binary = true;                  ///< binary_little_endian, else ascii
    /// Write x, y, z as double: automatic when float would lose more than 1e-7 relative to
    /// the bounding box (large offsets, e.g. terrain in map coordinates), or forced here.
    bool forceDoublePoints = false;
    std::vector<std::string> comments;   ///< "comment ..." header lines
    /// Put before every scalar vertex property's name (not x, y, z, not the list), e.g.
    /// "scalar_": CloudCompare's command line loads a PLY's vertex properties as scalar
    /// fields only when they are named `scalar_<name>`.
    std::string propertyPrefix;
    /// Optional per-vertex list property `property list uchar float <listName>` written
    /// after the scalar properties: listValues holds numVertices() * listLength floats.
    std::string listName;
    int listLength = 0;
    std::vector<float> listValues;
};

/// Vertices as x, y, z (float or double, see options), then each property of @p properties in
/// order (float, or int where VertexProperty::integer; NaN becomes 0 there), then the optional list; faces as `property list uchar int vertex_indices`.
/// @throw IOError if the file cannot be written; InvalidInputError if a property has the
///        wrong number of values.
void writePly(const std::string& path, const TriMesh& mesh,
              const std::vector<VertexProperty>& properties, const WritePlyOptions& options = {});

/// The header writePly writes for a mesh of @p numVertices and @p numFaces with float
/// properties @p propertyNames (int where @p integer says so; empty: all float) and options'
/// list, x, y, z as double if @p doublePoints; for writers that stream a mesh they never hold
/// (e.g. generated samples).
std::string plyHeader(std::size_t numVertices, std::size_t numFaces, const std::vector<std::string>& propertyNames,
                      const WritePlyOptions& options, bool doublePoints, const std::vector<bool>& integer = {});

/// A vertex property of a PLY written in pieces.
struct PlyColumn {
    std::string name;
    bool integer = false;  ///< written as int
    /// Written for the vertices no piece gave (e.g. `quality`, which is never NaN, gives 0).
    float missing = std::numeric_limits<float>::quiet_NaN();
};

/// Bytes of one binary face record (`property list uchar int vertex_indices` of a triangle).
constexpr std::size_t kPlyFaceBytes = 1 + 3 * sizeof(std::int32_t);

/// The binary (little endian) face records of @p count triangles, as writePly writes them,
/// into @p bytes (resized to count · kPlyFaceBytes).
void formatPlyFaces(const Triangle* triangles, std::size_t count, std::vector<char>& bytes);

/// A binary PLY written in pieces, for results larger than memory (the tiled compute): the
/// header and the faces are written at once, the vertex records as their values arrive, in
/// any order, straight to their place in the file. Vertices never given get each column's
/// `missing` value. The
/// file is byte for byte what writePly writes for the same mesh and values (binary, no list
/// property) and appears only on commit(). Holds one bit per vertex, not the values.
class PlyPieceWriter {
public:
    /// @throw IOError if the file cannot be created; InvalidInputError as writePly.
    PlyPieceWriter(const std::string& path, const TriMesh& mesh, const std::vector<PlyColumn>& columns,
                   const WritePlyOptions& options = {});
    ~PlyPieceWriter();
    PlyPieceWriter(const PlyPieceWriter&) = delete;
    PlyPieceWriter& operator=(const PlyPieceWriter&) = delete;

    /// Writes the records of @p vertices (each given once over all calls; ascending order
    /// writes fastest): property k of vertices[i] is columns[k][i].
    /// @throw InvalidInputError for a vertex out of range or a wrong number of columns.
    void write(const std::vector<std::uint32_t>& vertices, const std::vector<const float*>& columns);
    /// Fills the vertices not written with the columns' `missing` values, then renames onto
    /// the target. @throw IOError
    void commit();

private:
    struct State;
    std::unique_ptr<State> mState;
};

} // namespace msii
