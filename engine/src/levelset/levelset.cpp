#include "levelset_impl.h"
#include "tile_sides.h"
#include "mesh_distance.h"

#include <msii/core/errors.h>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

LevelSet::LevelSet() = default;
LevelSet::LevelSet(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
LevelSet::~LevelSet() = default;
LevelSet::LevelSet(LevelSet&&) noexcept = default;
LevelSet& LevelSet::operator=(LevelSet&&) noexcept = default;

const LevelSetInfo& LevelSet::info() const { return mImpl->info; }

double LevelSet::signedDistance(const Vec3& world) const
{
    const openvdb::Vec3d xyz = mImpl->grid->transform().worldToIndex(
        openvdb::Vec3d(world.x, world.y, world.z));
    return openvdb::tools::BoxSampler::sample(mImpl->grid->tree(), xyz);
}

LevelSet buildLevelSet(const TriMesh& mesh, const LevelSetOptions& options, Progress* progress)
{
    initializeOpenVdb();
    const double h = options.voxelSize;
    if (!(h > 0) || !std::isfinite(h))
        throw InvalidInputError("the voxel size must be a positive number");
    if (!(options.halfWidth >= 2))
        throw InvalidInputError("the narrow band must be at least 2 voxels wide");
    if (mesh.empty()) throw InvalidInputError("the mesh is empty");

    Vec3 lo = mesh.points.front(), hi = lo;
    for (const auto& p : mesh.points)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
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
    const auto snap = [&](double c) { return 512.0 * h * (std::round(c / (512.0 * h)) - 4.0); };
    const openvdb::Vec3d shift(snap(centre.x), snap(centre.y), snap(centre.z));
    transform->postTranslate(shift);
    std::vector<openvdb::Vec3s> indexPoints(mesh.numVertices());
    std::vector<openvdb::Vec3I> triangles(mesh.numTriangles());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.numVertices()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3& p = mesh.points[i];
            indexPoints[i] = openvdb::Vec3s(transform->worldToIndex(openvdb::Vec3d(p.x, p.y, p.z)));
        }
    });
    for (std::size_t f = 0; f < mesh.numTriangles(); ++f) {
        const auto& t = mesh.triangles[f];
        triangles[f] = openvdb::Vec3I(t[0], t[1], t[2]);
    }

    // Unsigned distances with the closest triangle of every band voxel; signs follow below.
    openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(
        indexPoints, triangles);
    openvdb::Int32Grid closest;
    const float band = float(options.halfWidth);
    openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        adapter, *transform, band, band, openvdb::tools::UNSIGNED_DISTANCE_FIELD, &closest);
    indexPoints.clear();
    indexPoints.shrink_to_fit();
    triangles.clear();
    triangles.shrink_to_fit();
    if (progress) progress->advance();

    // OpenVDB's distances beyond the first voxel come from a neighbour's triangle and can be
    // off by a good part of a voxel: make every band voxel exact, and signed by the
    // pseudo-normal of its closest feature.
    auto distance = std::make_shared<detail::MeshDistance>(mesh);
    auto guessed = std::make_shared<openvdb::MaskTree>();
    std::mutex guessMutex;
    openvdb::tree::ValueAccessor<openvdb::MaskTree, false> guessAcc(*guessed);
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(grid->tree());
    leaves.foreach([&](openvdb::FloatTree::LeafNodeType& leaf, std::size_t) {
        auto indexAcc = closest.getConstAccessor();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            const std::int32_t f = indexAcc.getValue(ijk);
            if (f < 0 || std::size_t(f) >= mesh.numTriangles()) continue;
            const openvdb::Vec3d w = transform->indexToWorld(ijk);
            std::uint32_t face = std::uint32_t(f);
            bool beyondBorder = false;
            it.setValue(float(
                distance->signedDistance(Vec3(w.x(), w.y(), w.z()), -1, face, &beyondBorder)));
            // Beyond an open border the side is a guess: such voxels are remembered, so that
            // fillTileSides() does not spread their side (results there are masked anyway).
            if (beyondBorder) {
                std::lock_guard<std::mutex> lock(guessMutex);
                guessAcc.setValueOn(ijk);
            }
        }
    });
    if (progress) progress->advance();
    openvdb::tools::signedFloodFill(grid->tree());
    {
        // The flood fill's sides are right for leaves; tiles near the mesh get theirs from
        // the band (detail::fillTileSides), which also holds for open, tilted sheets.
        openvdb::CoordBBox box(
            openvdb::Coord::floor(transform->worldToIndex(openvdb::Vec3d(lo.x, lo.y, lo.z))),
            openvdb::Coord::ceil(transform->worldToIndex(openvdb::Vec3d(hi.x, hi.y, hi.z))));
        box.expand(kSidePadding);
        detail::fillTileSides(grid->tree(), box, grid->background(), -grid->background(),
                              guessed.get());
    }
    if (progress) progress->advance();
    if (progress) progress->end();

    auto impl = std::make_unique<LevelSet::Impl>();
    impl->grid = grid;
    impl->distance = distance;
    impl->guessedSide = guessed;
    impl->info.voxelSize = h;
    impl->info.halfWidth = options.halfWidth;
    impl->info.activeVoxels = grid->activeVoxelCount();
    impl->info.memoryBytes = grid->memUsage();
    return LevelSet(std::move(impl));
}

} // namespace msii
