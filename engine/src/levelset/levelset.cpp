#include "levelset_impl.h"
#include "levelset_backend.h"
#include "tile_sides.h"
#include "band_raster.h"

#include <msii/core/errors.h>
#include <msii/mesh/mesh_stats.h>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <cmath>
#include <mutex>
#include <sstream>

namespace msii {

namespace {

/// Voxels around the mesh's bounding box whose tiles get their side from the band.
constexpr int kSidePadding = 24;

void initializeOpenVdb()
{
    static std::once_flag flag;
    std::call_once(flag, [] { openvdb::initialize(); });
}

} // namespace

namespace {

double signedDistanceOf(const LevelSet::Impl& impl, const Vec3& world)
{
    const openvdb::Vec3d xyz = impl.grid->transform().worldToIndex(openvdb::Vec3d(world.x, world.y, world.z));
    return openvdb::tools::BoxSampler::sample(impl.grid->tree(), xyz);
}

} // namespace

LevelSet detail::buildLevelSetHere(const TriMesh& mesh, const LevelSetOptions& options, RunContext* progress)
{
    initializeOpenVdb();
    const double h = options.voxelSize;
    if (!(h > 0) || !std::isfinite(h))
        throw InvalidInputError("the voxel size must be a positive number");
    if (!(options.halfWidth >= 2))
        throw InvalidInputError("the narrow band must be at least 2 voxels wide");
    if (mesh.empty()) throw InvalidInputError("the mesh is empty");

    const BoundingBox box = boundingBox(mesh.points);
    const Vec3 &lo = box.min, &hi = box.max;
    for (int a = 0; a < 3; ++a) {
        if ((hi[a] - lo[a]) / h > double(1 << 20)) {
            std::ostringstream msg;
            msg << "the voxel size " << h << " is too small for a mesh of this extent";
            throw InvalidInputError(msg.str());
        }
    }

    if (progress) progress->start("level set", 3);
    // Index space is shifted so that the mesh sits in the middle of one of OpenVDB's root
    // children (4096^3 voxels): then the signed flood fill gives every voxel near the mesh
    // its side, with no reliance on the root background. The shift is a multiple of 512
    // voxels, so every level of the occupancy pyramid (cells of 2^l voxels) lies on the same
    // world-aligned lattice whatever the mesh's extent: a part of a mesh (a tile, an open
    // patch of a closed slab) gives the same values as the whole.
    auto transform = openvdb::math::Transform::createLinearTransform(h);
    const Vec3 centre = (lo + hi) * 0.5;
    // The shift in voxels is an integer, kept exact: positions are computed from the global
    // index (index + shift) · h, identical for any part of the mesh.
    const auto snap = [&](double c) { return std::int64_t(512.0 * (std::round(c / (512.0 * h)) - 4.0)); };
    const std::array<std::int64_t, 3> shiftIndex{snap(centre.x), snap(centre.y), snap(centre.z)};
    const openvdb::Vec3d shift(double(shiftIndex[0]) * h, double(shiftIndex[1]) * h, double(shiftIndex[2]) * h);
    transform->postTranslate(shift);
    auto distance = std::make_shared<detail::MeshDistance>(mesh);
    if (progress) progress->advance();

    // Exact signed distances in the band; the sides of the space off it follow below.
    detail::BandOptions bandOptions;
    bandOptions.voxelSize = h;
    bandOptions.originIndex = shiftIndex;
    bandOptions.halfWidth = options.halfWidth;
    detail::Band band = detail::rasterizeBand(mesh, *distance, bandOptions);
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(band.distance);
    grid->setTransform(transform);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    const std::shared_ptr<const openvdb::MaskTree> guessed = band.guessedSide;
    if (progress) progress->advance();
    // Sides off the band: inside leaves from the nearest band voxel, then OpenVDB's flood
    // fill for the tiles (not for leaves: see detail::fillLeafSides), then the tiles near the
    // mesh again from the band.
    detail::fillLeafSides(grid->tree(), grid->background());
    openvdb::tools::signedFloodFill(grid->tree(), /*threaded=*/true, /*grainSize=*/1,
                                    /*minLevel=*/1);
    {
        // The flood fill's tile sides assume a closed surface; near the mesh they come from
        // the band instead (detail::fillTileSides), which also holds for open, tilted sheets.
        openvdb::CoordBBox sideBox(
            openvdb::Coord::floor(transform->worldToIndex(openvdb::Vec3d(lo.x, lo.y, lo.z))),
            openvdb::Coord::ceil(transform->worldToIndex(openvdb::Vec3d(hi.x, hi.y, hi.z))));
        sideBox.expand(kSidePadding);
        detail::fillTileSides(grid->tree(), sideBox, grid->background(), -grid->background(),
                              guessed.get());
    }
    if (progress) progress->advance();
    if (progress) progress->end();

    auto impl = std::make_unique<LevelSet::Impl>();
    impl->grid = grid;
    impl->shiftIndex = shiftIndex;
    impl->distance = distance;
    impl->guessedSide = guessed;
    impl->info.voxelSize = h;
    impl->info.halfWidth = options.halfWidth;
    impl->info.activeVoxels = grid->activeVoxelCount();
    impl->info.memoryBytes = grid->memUsage();
    return LevelSet(std::unique_ptr<LevelSet::Impl, LevelSet::ImplDeleter>(impl.release()));
}

} // namespace msii

extern "C" const msii::detail::LevelSetBackend* msii_levelset_backend()
{
    static const msii::detail::LevelSetBackend backend{
        &msii::detail::buildLevelSetHere,
        &msii::detail::computeVolumeSphereHere,
        [](msii::LevelSet::Impl* impl) { delete impl; },
        [](const msii::LevelSet::Impl& impl) -> const msii::LevelSetInfo& { return impl.info; },
        &msii::signedDistanceOf,
    };
    return &backend;
}
