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

} // namespace

Band rasterizeBand(const TriMesh& mesh, const MeshDistance& distance, const BandOptions& options)
{
    const double h = options.voxelSize, w = options.halfWidth;
    const double reach = w * h, reach2 = reach * reach;
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

    // (block, triangle) pairs, sorted by block and then triangle.
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
    std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(first[nf]);
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
    std::vector<std::size_t> blockFirst;
    for (std::size_t i = 0; i < pairs.size(); ++i)
        if (i == 0 || pairs[i].first != pairs[i - 1].first) blockFirst.push_back(i);
    blockFirst.push_back(pairs.size());
    const std::size_t numBlocks = blockFirst.size() - 1;

    // Blocks: the closest triangle of every voxel, then the signed distance.
    std::vector<std::unique_ptr<Leaf>> leaves(numBlocks);
    std::vector<std::unique_ptr<MaskLeaf>> guessed(numBlocks);
    using Best = std::array<MeshDistance::Closest, Leaf::SIZE>;
    tbb::enumerable_thread_specific<std::unique_ptr<Best>> scratch(
        [] { return std::make_unique<Best>(); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numBlocks), [&](const auto& r) {
        Best& best = *scratch.local();
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            const openvdb::Coord origin = blockOrigin(pairs[blockFirst[b]].first);
            // The block's first voxel as a global index (whole numbers, exact in double).
            const double gx = double(o[0] + origin.x()), gy = double(o[1] + origin.y()), gz = double(o[2] + origin.z());
            for (auto& c : best) {
                c.squaredDistance = reach2;
                c.face = std::uint32_t(-1);
            }
            for (std::size_t i = blockFirst[b]; i < blockFirst[b + 1]; ++i) {
                const std::uint32_t f = pairs[i].second;
                const VoxelRange& v = ranges[f];
                const Vec3& a = mesh.points[mesh.triangles[f][0]];
                const Vec3& n = distance.faceNormal(f);
                const MeshDistance::BoundingSphere& sphere = distance.boundingSphere(f);
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
                            const MeshDistance::Closest c = distance.closestOnFace(p, f);
                            if (c.squaredDistance < current.squaredDistance) current = c;
                        }
            }
            std::unique_ptr<Leaf> leaf;
            std::unique_ptr<MaskLeaf> mask;
            for (int offset = 0; offset < int(Leaf::SIZE); ++offset) {
                const MeshDistance::Closest& c = best[std::size_t(offset)];
                if (c.face == std::uint32_t(-1)) continue;
                const openvdb::Coord local = Leaf::offsetToLocalCoord(offset);
                const Vec3 p(h * (gx + local.x()), h * (gy + local.y()), h * (gz + local.z()));
                bool beyondBorder = false;
                const double d = distance.signedFromClosest(p, c, &beyondBorder);
                if (!leaf) leaf = std::make_unique<Leaf>(origin, float(reach), false);
                leaf->setValueOn(openvdb::Index(offset), float(d));
                if (beyondBorder) {
                    if (!mask) mask = std::make_unique<MaskLeaf>(origin, false);
                    mask->setValueOn(openvdb::Index(offset));
                }
            }
            leaves[b] = std::move(leaf);
            guessed[b] = std::move(mask);
        }
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
