#pragma once
/// @file levelset.h
/// @brief The mesh as a narrow-band signed distance field (OpenVDB), the first stage of the
/// V and S computation (docs/method.md, Level set). OpenVDB types stay behind this header
/// (pimpl) so that including it is cheap; engine code that needs the grid includes
/// src/levelset/levelset_impl.h. That code, and V and S on the level set, live in a library
/// of their own (libmsii_levelset, next to libmsii), which libmsii loads when a level set is
/// first built: a program that never builds one (a DEM on the height field, a picture, a
/// metric) does not load OpenVDB, which takes 40 ms or more of every start.
///
/// Sign convention: negative inside the solid, positive outside. The solid is what the
/// triangles' normals point away from (counter-clockwise seen from outside):
/// - closed mesh: the enclosed volume, or its complement if the normals point inwards (the
///   wall of a cavity);
/// - open mesh (one-sided scan, terrain): the side behind the oriented surface, as far as
///   it is defined; beyond the border the sign is unreliable, so results whose ball reaches
///   the border are masked (invariants/volume_sphere.h).
/// How: every voxel centre closer than halfWidth voxels to the mesh gets its exact distance
/// to the closest triangle (triangles binned to 8³ blocks, src/levelset/band_raster.h) and
/// the sign of that triangle's closest feature's angle-weighted pseudo-normal (Baerentzen &
/// Aanaes), exact for consistently oriented meshes. Off the band, voxels of the band's leaf
/// nodes take the side of their nearest band voxel, and the space around the mesh takes the
/// side of the band's faces, breadth first over 8³ blocks (src/levelset/tile_sides.h). Near
/// the mesh both take the place of OpenVDB's axis-scanning flood fill (which assumes a closed
/// surface and fails next to open borders and tilted open sheets); it still fills the tiles
/// farther away.

#include <msii/core/run_context.h>
#include <msii/mesh/trimesh.h>

#include <memory>

namespace msii {

struct LevelSetOptions {
    double voxelSize = 0;   ///< voxel edge length in mesh units; must be > 0
    double halfWidth = 3;   ///< half width of the narrow band, in voxels (>= 2)
};

struct LevelSetInfo {
    double voxelSize = 0;          ///< as requested
    double halfWidth = 0;          ///< in voxels
    std::size_t activeVoxels = 0;  ///< voxels of the narrow band
    std::size_t memoryBytes = 0;   ///< grid memory
};

class LevelSet {
public:
    struct Impl;
    /// Deletes an Impl in the library where its type is complete (libmsii_levelset).
    struct ImplDeleter {
        void operator()(Impl* impl) const;
    };

    explicit LevelSet(std::unique_ptr<Impl, ImplDeleter> impl);
    ~LevelSet();
    LevelSet(LevelSet&&) noexcept;
    LevelSet& operator=(LevelSet&&) noexcept;

    const LevelSetInfo& info() const;
    /// Signed distance at a world position (trilinear). Beyond the band the magnitude is
    /// clamped to the band half width; the sign stays meaningful.
    double signedDistance(const Vec3& world) const;

private:
    /// The OpenVDB grids, for the engine's own sources (src/levelset/levelset_impl.h).
    friend const Impl& levelSetImpl(const LevelSet& levelSet);

    std::unique_ptr<Impl, ImplDeleter> mImpl;
};

/// Builds the narrow-band signed distance field of @p mesh.
/// @pre @p mesh outlives the returned LevelSet (it answers exact distance queries off the
///      band from the mesh itself).
/// @pre the mesh passed checkMesh() (finite points, no degenerate faces) and is
///      consistently oriented.
/// @throw InvalidInputError for a non-positive voxel size, a half width below 2, an empty
///        mesh, or a grid that would be absurdly large (more than 2^20 voxels along an axis).
LevelSet buildLevelSet(const TriMesh& mesh, const LevelSetOptions& options,
                       RunContext* context = nullptr);

} // namespace msii
