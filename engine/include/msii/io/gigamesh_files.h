#pragma once
/// @file gigamesh_files.h
/// @brief Feature vectors in the files of GigaMesh's `gigamesh-featurevectors`, both ways:
/// ASCII `.mat` tables and a PLY with a per-vertex `feature_vector` list, so results can be
/// compared with GigaMesh's and features computed by GigaMesh can be used by msii.
///
/// Conventions (docs/method.md, GigaMesh conventions), and how msii maps onto them:
/// - GigaMesh writes V and P only, radii **largest first**: element i is at r·(1 − i/N),
///   i = 0..N−1. msii stores columns radius ascending (r_j = j·R/N, j = 1..N), so element i
///   of a GigaMesh row is msii column N−1−i.
/// - V is written as 2·V/|B_r| − 1 (flat 0, concave > 0, convex < 0: the orientation of
///   msii's V/|B_r| is kept); P as P/(π r²), the same as msii (flat 1).
/// - NaN (msii: masked, the ball reaches a mesh border) stays NaN and is written `nan`.
/// - Rows hold doubles so that the conversion 2x − 1 and back is exact: a float column
///   survives columns → rows → `.mat` → rows → columns bit for bit (values printed as the
///   shortest decimal that reads back to the same double). Exceptions: V fractions below
///   2^-30 (where 2x − 1 needs more than 53 bits; none occur on a surface) and the PLY,
///   whose list holds floats (GigaMesh's layout), so V read back from a PLY can differ by
///   one rounding of 2x − 1 to float (≤ 3e-8 absolute).
///
/// `.mat` layout (what GigaMesh writes; msii writes the same): lines starting with `#` are
/// comments (msii writes its parameters there), then one line per vertex: the vertex index
/// (0-based), then the N values, separated by spaces.
///
/// File names: `<name>_r<R, 2 decimals>_n<log2 N>_v<precision>.volume.mat` for V and
/// `.surface.mat` for P, as GigaMesh (`tablet_r1.00_n4_v256.volume.mat`: R = 1, N = 16,
/// raster 256). GigaMesh only knows N = 2^n. **Decision** for other N (msii allows any
/// N ≤ 256): `_N<N>` (capital N and the count itself, e.g. `_N12`), never a rounded
/// exponent, so that two runs with different N cannot overwrite each other and no file
/// claims a GigaMesh scale count it does not have; N is also recorded in the header.
/// GigaMesh's `_v` is its height-raster size; msii passes whatever the caller calls
/// precision (its `--precision`), recorded as given.
///
/// PLY: GigaMesh writes `property list uint8 float feature_vector` after `quality`. msii
/// writes the same layout with the count type spelled `uchar`: the same 1-byte type, the
/// spelling of the original PLY specification that every PLY reader knows (GigaMesh's
/// reader, MeshLab, CloudCompare, Open3D, plyfile; some older readers know no `uint8`).
/// Note: for meshes far from the origin (map coordinates) io/write_ply.h stores x, y, z as
/// `double`, a type name GigaMesh's reader does not know (it knows `float64`).
/// **quality** = the largest element of the feature vector, as GigaMesh's
/// `funcVertFeatureVecMax()` (Vertex::getFeatureVecMax: the maximum value over the
/// elements, not the element of the largest radius); NaN elements are ignored, and a vector
/// of NaN only gives NaN (GigaMesh: −infinity). GigaMeshQuality::LargestRadius gives the
/// element of the largest radius instead (msii's own `quality`).

#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace msii {

/// The two invariants GigaMesh's feature-vector files hold.
enum class GigaMeshInvariant {
    Volume,  ///< V, `.volume.mat`, values 2·V/|B_r| − 1
    Patch,   ///< P, `.surface.mat`, values P/(π r²)
};

/// Per-vertex feature vectors in GigaMesh's convention, row-major: the values of vertex v
/// are values[v·numValues … (v+1)·numValues − 1], largest radius first.
struct GigaMeshRows {
    std::size_t numVertices = 0;
    std::size_t numValues = 0;     ///< elements per vertex (N radii)
    std::vector<double> values;    ///< numVertices·numValues values, NaN = masked

    const double* row(std::size_t vertex) const { return values.data() + vertex * numValues; }
};

/// msii columns ([j][vertex], radius ascending, V/|B_r| or P/(π r²)) to GigaMesh rows
/// (largest radius first; V as 2x − 1, P unchanged).
/// @throw InvalidInputError if there are no columns or they differ in length.
GigaMeshRows toGigaMeshRows(const std::vector<std::vector<float>>& columns, GigaMeshInvariant invariant);

/// The inverse of toGigaMeshRows(): columns [j][vertex], radius ascending, msii's
/// normalisation (V = (g + 1)/2), rounded to float.
/// @throw InvalidInputError if values.size() != numVertices·numValues.
std::vector<std::vector<float>> fromGigaMeshRows(const GigaMeshRows& rows, GigaMeshInvariant invariant);

/// What msii records in the `#` header of a `.mat` file.
struct GigaMeshMatInfo {
    std::string inputFile;                               ///< the mesh the features belong to
    GigaMeshInvariant invariant = GigaMeshInvariant::Volume;
    double largestRadius = 0;                            ///< R (mesh units, usually mm)
    std::vector<double> radii;                           ///< msii's radii, ascending (written largest first)
    std::vector<std::string> notes;                      ///< further header lines (e.g. precision, voxel size)
};

/// The header lines (without the leading "# ") describing @p info: program and version,
/// input, invariant and its normalisation, R, N, the radii in file order, the columns.
std::vector<std::string> gigaMeshMatHeader(const GigaMeshMatInfo& info);

/// Writes @p rows as a GigaMesh `.mat` file: each header line as "# <line>", then per vertex
/// "<index> <v1> … <vN>\n" (index 0-based; values as the shortest decimal that reads back to
/// the same double; NaN as `nan`, infinities as `inf`/`-inf`). Atomic (io/atomic_file.h).
/// @throw IOError if the file cannot be written; InvalidInputError if rows are inconsistent.
void writeGigaMeshMat(const std::string& path, const std::vector<std::string>& headerLines,
                      const GigaMeshRows& rows);

/// "<name>_r<R, 2 decimals>_n<log2 N>_v<precision>.volume.mat" (or `.surface.mat` for P);
/// `_N<N>` instead of `_n…` when N is not a power of two (see the file comment).
/// @p name may include a folder. @throw InvalidInputError if R ≤ 0 or N < 1.
std::string gigaMeshMatFileName(const std::string& name, double largestRadius, int scales, int precision,
                                GigaMeshInvariant invariant);

/// The invariant a file name stands for: `.volume.mat` → Volume, `.surface.mat` → Patch,
/// anything else → none.
std::optional<GigaMeshInvariant> gigaMeshInvariantOfFileName(const std::string& path);

/// Reads a GigaMesh `.mat` file for a mesh of @p expectedVertexCount vertices. Accepts `#`
/// comment lines, blank lines, any whitespace, CR-LF line ends, values such as `nan`,
/// `-nan`, `NaN`, `inf`, `1e-3`, `+0.5`; rows in any order (placed by their index).
/// @throw IOError if the file cannot be opened or read; InvalidInputError (one sentence with
///        the file and line number) for: a vertex index that is not a whole number, out of
///        range or repeated; a row without values or with a different number of values than
///        the first; a value that is not a number; fewer rows than vertices.
GigaMeshRows readGigaMeshMat(const std::string& path, std::size_t expectedVertexCount);

/// Which value GigaMesh-style PLY files carry as `quality`.
enum class GigaMeshQuality {
    MaxElement,     ///< the largest element (GigaMesh: funcVertFeatureVecMax), NaN ignored
    LargestRadius,  ///< the element of the largest radius (first element; msii's quality)
};

struct GigaMeshPlyOptions {
    GigaMeshQuality quality = GigaMeshQuality::MaxElement;  ///< what `quality` holds
    std::vector<std::string> comments;                      ///< "comment ..." header lines
};

/// Writes @p mesh as binary little-endian PLY in GigaMesh's layout: x, y, z, `quality`
/// (float), `property list uchar float feature_vector` (the row as floats, largest radius
/// first), faces as `property list uchar int vertex_indices`. Atomic (io/write_ply.h).
/// @throw InvalidInputError if rows do not match the mesh or N > 255 (the uchar count);
///        IOError if the file cannot be written.
void writeGigaMeshPly(const std::string& path, const TriMesh& mesh, const GigaMeshRows& rows,
                      const GigaMeshPlyOptions& options = {});

/// The per-vertex value written as `quality` by writeGigaMeshPly().
std::vector<float> gigaMeshQuality(const GigaMeshRows& rows, GigaMeshQuality quality);

struct GigaMeshPlyContents {
    TriMesh mesh;
    GigaMeshRows rows;           ///< from `feature_vector` (floats widened to double)
    std::vector<float> quality;  ///< the `quality` property; empty if the file has none
};

/// Reads a PLY with a per-vertex `feature_vector` list (GigaMesh's or writeGigaMeshPly()'s;
/// any list and count types, ascii or binary). Every vertex must have a list of the same
/// length.
/// @throw IOError / InvalidInputError as readPly(); InvalidInputError if there is no
///        `feature_vector` list.
GigaMeshPlyContents readGigaMeshPly(const std::string& path);

} // namespace msii
