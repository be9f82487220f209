#include "band_raster.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

namespace msii::detail {

namespace {

using Leaf = openvdb::FloatTree::LeafNodeType;
using MaskLeaf = openvdb::MaskTree::LeafNodeType;
constexpr int kLog2 = Leaf::LOG2DIM;  // 8³ blocks, as OpenVDB's leaf nodes
constexpr int kDim = Leaf::DIM;
constexpr std::int64_t kKeyBias = std::int64_t(1) << 20;  // block coordinates fit 21 bits

std::uint64_t blockKey(int bx, int by, int bz)
{
    return std::uint64_t(bx + kKeyBias) << 42 | std::uint64_t(by + kKeyBias) << 21 |
           std::uint64_t(bz + kKeyBias);
}

openvdb::Coord blockOrigin(std::uint64_t key)
{
    const std::uint64_t m = (std::uint64_t(1) << 21) - 1;
    return openvdb::Coord(int(std::int64_t(key >> 42 & m) - kKeyBias) << kLog2,
                          int(std::int64_t(key >> 21 & m) - kKeyBias) << kLog2,
                          int(std::int64_t(key & m) - kKeyBias) << kLog2);
}

/// Voxel index range (inclusive) whose centres may lie within the band of triangle f.
struct VoxelRange {
    std::array<int, 3> lo, hi;
};

/// The voxels whose centres may lie within the band of each triangle, as indices relative to
/// options.originIndex.
std::vector<VoxelRange> triangleVoxelRanges(const TriMesh& mesh, const BandOptions& options)
{
    const double h = options.voxelSize, w = options.halfWidth;
    const std::array<std::int64_t, 3>& o = options.originIndex;
    const std::size_t nf = mesh.numTriangles();
    std::vector<VoxelRange> ranges(nf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
            const auto& t = mesh.triangles[f];
            for (int a = 0; a < 3; ++a) {
                const double p0 = mesh.points[t[0]][a], p1 = mesh.points[t[1]][a],
                             p2 = mesh.points[t[2]][a];
                ranges[f].lo[a] = int(std::int64_t(std::ceil(std::min({p0, p1, p2}) / h - w)) - o[std::size_t(a)]);
                ranges[f].hi[a] = int(std::int64_t(std::floor(std::max({p0, p1, p2}) / h + w)) - o[std::size_t(a)]);
            }
        }
    });
    return ranges;
}

/// The triangles each block's voxels may be close to: (block key, triangle) pairs sorted by
/// block and then triangle, block b's run being pairs[blockFirst[b] .. blockFirst[b + 1]).
struct BlockTriangles {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;
    std::vector<std::size_t> blockFirst;
    std::size_t numBlocks() const { return blockFirst.size() - 1; }
};

BlockTriangles blockTriangles(const std::vector<VoxelRange>& ranges)
{
    const std::size_t nf = ranges.size();
    std::vector<std::size_t> first(nf + 1, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
            const VoxelRange& v = ranges[f];
            std::size_t n = 1;
            for (int a = 0; a < 3; ++a) n *= std::size_t((v.hi[a] >> kLog2) - (v.lo[a] >> kLog2) + 1);
            first[f + 1] = n;
        }
    });
    for (std::size_t f = 0; f < nf; ++f) first[f + 1] += first[f];
    BlockTriangles blocks;
    auto& pairs = blocks.pairs;
    pairs.resize(first[nf]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
            const VoxelRange& v = ranges[f];
            std::size_t k = first[f];
            for (int bx = v.lo[0] >> kLog2; bx <= v.hi[0] >> kLog2; ++bx)
                for (int by = v.lo[1] >> kLog2; by <= v.hi[1] >> kLog2; ++by)
                    for (int bz = v.lo[2] >> kLog2; bz <= v.hi[2] >> kLog2; ++bz)
                        pairs[k++] = {blockKey(bx, by, bz), std::uint32_t(f)};
        }
    });
    first = {};
    tbb::parallel_sort(pairs.begin(), pairs.end());
    for (std::size_t i = 0; i < pairs.size(); ++i)
        if (i == 0 || pairs[i].first != pairs[i - 1].first) blocks.blockFirst.push_back(i);
    blocks.blockFirst.push_back(pairs.size());
    return blocks;
}

/// Per voxel of a block, the closest point found so far.
using Best = std::array<MeshDistance::Closest, Leaf::SIZE>;

/// The band's voxels block by block: the closest triangle of every voxel, then the signed
/// distance.
class BlockRasterizer {
public:
    BlockRasterizer(const TriMesh& mesh, const MeshDistance& distance, const std::vector<VoxelRange>& ranges,
                    const BlockTriangles& blocks, const BandOptions& options)
        : mMesh(mesh), mDistance(distance), mRanges(ranges), mBlocks(blocks), mOrigin(options.originIndex),
          mH(options.voxelSize), mReach(options.halfWidth * options.voxelSize)
    {
    }

    /// Block @p b: its leaf of distances and its mask of guessed sides (null if none);
    /// @p best is scratch.
    void rasterize(std::size_t b, Best& best, std::unique_ptr<Leaf>& leaf, std::unique_ptr<MaskLeaf>& mask) const
    {
        const openvdb::Coord origin = blockOrigin(mBlocks.pairs[mBlocks.blockFirst[b]].first);
        // The block's first voxel as a global index (whole numbers, exact in double).
        const std::array<double, 3> g{double(mOrigin[0] + origin.x()), double(mOrigin[1] + origin.y()),
                                      double(mOrigin[2] + origin.z())};
        findClosest(b, origin, g, best);
        // Filled in locals: @p leaf and @p mask lie next to other threads' blocks.
        std::unique_ptr<Leaf> blockLeaf;
        std::unique_ptr<MaskLeaf> blockMask;
        signedDistances(best, origin, g, blockLeaf, blockMask);
        leaf = std::move(blockLeaf);
        mask = std::move(blockMask);
    }

private:
    /// The closest of the block's triangles to each voxel of the block within reach.
    void findClosest(std::size_t b, const openvdb::Coord& origin, const std::array<double, 3>& g, Best& best) const
    {
        const double h = mH, reach2 = mReach * mReach;
        const double gx = g[0], gy = g[1], gz = g[2];
        for (auto& c : best) {
            c.squaredDistance = reach2;
            c.face = std::uint32_t(-1);
        }
        for (std::size_t i = mBlocks.blockFirst[b]; i < mBlocks.blockFirst[b + 1]; ++i) {
            const std::uint32_t f = mBlocks.pairs[i].second;
            const VoxelRange& v = mRanges[f];
            const Vec3& a = mMesh.points[mMesh.triangles[f][0]];
            const Vec3& n = mDistance.faceNormal(f);
            const MeshDistance::BoundingSphere& sphere = mDistance.boundingSphere(f);
            const Vec3& centre = sphere.centre;
            const double radius = sphere.radius, radius2 = radius * radius;
            std::array<int, 3> lo, hi;
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::max(v.lo[k], origin[k]) - origin[k];
                hi[k] = std::min(v.hi[k], origin[k] + kDim - 1) - origin[k];
            }
            for (int x = lo[0]; x <= hi[0]; ++x)
                for (int y = lo[1]; y <= hi[1]; ++y)
                    for (int z = lo[2]; z <= hi[2]; ++z) {
                        const Vec3 p(h * (gx + x), h * (gy + y), h * (gz + z));
                        const int offset = (x << 2 * kLog2) | (y << kLog2) | z;
                        MeshDistance::Closest& current = best[std::size_t(offset)];
                        // Lower bound of the squared distance: the distance to the
                        // plane, and in the plane, the gap to the bounding circle.
                        const double plane = dot(p - a, n);
                        const double plane2 = plane * plane;
                        if (plane2 >= current.squaredDistance) continue;
                        const double lateral2 = squaredNorm(p - centre) - plane2;
                        if (lateral2 > radius2) {
                            const double gap = std::sqrt(lateral2) - radius;
                            if (plane2 + gap * gap >= current.squaredDistance) continue;
                        }
                        const MeshDistance::Closest c = mDistance.closestOnFace(p, f);
                        if (c.squaredDistance < current.squaredDistance) current = c;
                    }
        }
    }

    /// The signed distance of every voxel with a closest triangle, and whether its side
    /// is a guess.
    void signedDistances(const Best& best, const openvdb::Coord& origin, const std::array<double, 3>& g,
                         std::unique_ptr<Leaf>& leaf, std::unique_ptr<MaskLeaf>& mask) const
    {
        const double h = mH;
        for (int offset = 0; offset < int(Leaf::SIZE); ++offset) {
            const MeshDistance::Closest& c = best[std::size_t(offset)];
            if (c.face == std::uint32_t(-1)) continue;
            const openvdb::Coord local = Leaf::offsetToLocalCoord(offset);
            const Vec3 p(h * (g[0] + local.x()), h * (g[1] + local.y()), h * (g[2] + local.z()));
            bool beyondBorder = false;
            const double d = mDistance.signedFromClosest(p, c, &beyondBorder);
            if (!leaf) leaf = std::make_unique<Leaf>(origin, float(mReach), false);
            leaf->setValueOn(openvdb::Index(offset), float(d));
            if (beyondBorder) {
                if (!mask) mask = std::make_unique<MaskLeaf>(origin, false);
                mask->setValueOn(openvdb::Index(offset));
            }
        }
    }

    const TriMesh& mMesh;
    const MeshDistance& mDistance;
    const std::vector<VoxelRange>& mRanges;
    const BlockTriangles& mBlocks;
    const std::array<std::int64_t, 3>& mOrigin;  // options.originIndex
    const double mH, mReach;                      // voxel size; half width in mesh units
};

} // namespace

Band rasterizeBand(const TriMesh& mesh, const MeshDistance& distance, const BandOptions& options)
{
    const double reach = options.halfWidth * options.voxelSize;
    const std::vector<VoxelRange> ranges = triangleVoxelRanges(mesh, options);
    const BlockTriangles blocks = blockTriangles(ranges);
    const std::size_t numBlocks = blocks.numBlocks();

    const BlockRasterizer rasterizer(mesh, distance, ranges, blocks, options);
    std::vector<std::unique_ptr<Leaf>> leaves(numBlocks);
    std::vector<std::unique_ptr<MaskLeaf>> guessed(numBlocks);
    tbb::enumerable_thread_specific<std::unique_ptr<Best>> scratch(
        [] { return std::make_unique<Best>(); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numBlocks), [&](const auto& r) {
        Best& best = *scratch.local();
        for (std::size_t b = r.begin(); b < r.end(); ++b) rasterizer.rasterize(b, best, leaves[b], guessed[b]);
    });

    Band band;
    band.distance = std::make_shared<openvdb::FloatTree>(float(reach));
    band.guessedSide = std::make_shared<openvdb::MaskTree>();
    for (auto& leaf : leaves)
        if (leaf) band.distance->addLeaf(leaf.release());
    for (auto& mask : guessed)
        if (mask) band.guessedSide->addLeaf(mask.release());
    return band;
}

} // namespace msii::detail
