#pragma once
/// @file read_ply.h
/// @brief msii's own PLY reader (see read_mesh.h for why it is not OpenMesh's).

#include <msii/io/read_mesh.h>

namespace msii {

/// Reads a PLY file: `vertex` (x, y, z in any numeric type; other scalar properties kept
/// with options.keepVertexProperties, list properties kept with options.keepVertexLists,
/// else skipped), `face` (`vertex_indices` or `vertex_index`, any list/count types;
/// polygons fan-triangulated) and `tristrips`
/// (`vertex_indices`, -1 restarts a strip, alternating winding), unknown elements skipped.
/// @throw IOError, InvalidInputError as readMesh().
ReadMeshResult readPly(const std::string& path, const ReadMeshOptions& options = {});

} // namespace msii
