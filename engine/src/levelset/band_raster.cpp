#include "band_raster.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
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

/// At most this many candidate triangles per voxel; a voxel with more (a vertex of higher
/// valence at its closest point) takes all of its block's triangles instead.
constexpr int kMaxCandidates = 16;

/// Per voxel of a block: the least approximate squared distance so far, the triangles whose
/// approximate squared distance is within the tolerance of it (ascending face index), and
/// in the end the closest point.
struct Scratch {
    struct Candidate {
        double approx;
        std::uint32_t face;
    };
    alignas(64) std::array<double, Leaf::SIZE> least;
    std::array<std::uint8_t, Leaf::SIZE> count;  // kMaxCandidates + 1: too many
    std::array<std::array<Candidate, kMaxCandidates>, Leaf::SIZE> candidates;
    std::array<MeshDistance::Closest, Leaf::SIZE> best;
};

/// A row of a block's voxels along z, as vector lanes.
using Lanes = double __attribute__((vector_size(kDim * sizeof(double))));
using Mask = std::int64_t __attribute__((vector_size(kDim * sizeof(double))));

/// One triangle against the voxels of a block within its range.
struct PairScan {
    Vec3 a, b, c;
    std::array<int, 3> lo, hi;  // in the block, inclusive
    std::array<double, 3> g;    // the block's first voxel, global index
    double h = 0;
    double tolerance = 0;
    double reach2 = 0;  // the band's half width, squared
    std::uint32_t face = 0;
};

/// The approximate squared distances from the voxels of a triangle's range to it, kept as
/// candidates where they come within the tolerance of a voxel's least so far.
///
/// The formulation is branch-free, so that a row of 8 voxels is one pass of vector lanes: to
/// the triangle's plane where a voxel projects inside it (all three edge tests positive),
/// else to the nearest of its three edges, each as |p − u|² − t (2 (p − u)·e − t |e|²) with t
/// the clamped projection onto the edge. It differs from MeshDistance::closestOnFace's value
/// by rounding only, well within the tolerance; the candidates then get that exact value.
/// Its vector width does not change the result: every candidate's distance is recomputed
/// exactly, in order.
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"))) void scanPair(const PairScan& s,
                                                                                              Scratch& scratch)
{
    const Vec3 e0 = s.b - s.a, e1 = s.c - s.b, e2 = s.a - s.c;
    const Vec3 n = cross(e0, s.c - s.a);
    const double nn = dot(n, n);
    // A degenerate triangle has no inside: the edge tests (strict) never all pass.
    const bool flat = !(nn > 0) || !std::isfinite(nn);
    const Vec3 m0 = flat ? Vec3() : cross(n, e0), m1 = flat ? Vec3() : cross(n, e1),
               m2 = flat ? Vec3() : cross(n, e2);
    const double planeScale = flat ? 0.0 : 1.0 / nn;
    const double l0 = dot(e0, e0), l1 = dot(e1, e1), l2 = dot(e2, e2);
    const double i0 = l0 > 0 ? 1.0 / l0 : 0.0, i1 = l1 > 0 ? 1.0 / l1 : 0.0, i2 = l2 > 0 ? 1.0 / l2 : 0.0;
    const double h = s.h, tolerance = s.tolerance;
    const int zlo = s.lo[2], zhi = s.hi[2];
    // Rows whose plane distance is beyond this have no voxel within reach.
    const double farPlane2 = s.reach2 + tolerance;
    Lanes az, bz, cz, valid;
    for (int z = 0; z < kDim; ++z) {
        const double pz = h * (s.g[2] + z);
        az[z] = pz - s.a.z;
        bz[z] = pz - s.b.z;
        cz[z] = pz - s.c.z;
        valid[z] = z >= zlo && z <= zhi ? 0.0 : std::numeric_limits<double>::infinity();
    }
    const Lanes zero = Lanes{} * 0.0, one = zero + 1.0;
    for (int x = s.lo[0]; x <= s.hi[0]; ++x) {
        const double px = h * (s.g[0] + x);
        const double ax = px - s.a.x, bx = px - s.b.x, cx = px - s.c.x;
        for (int y = s.lo[1]; y <= s.hi[1]; ++y) {
            const double py = h * (s.g[1] + y);
            const double ay = py - s.a.y, by = py - s.b.y, cy = py - s.c.y;
            const int row = (x << 2 * kLog2) | (y << kLog2);
            // The row's ends both beyond the band on one side of the plane: so is the row
            // (the distance to a triangle is at least that to its plane).
            const double planeLo = (n.x * ax + n.y * ay) + n.z * az[zlo], planeHi = (n.x * ax + n.y * ay) + n.z * az[zhi];
            if ((planeLo > 0) == (planeHi > 0) &&
                std::min(planeLo * planeLo, planeHi * planeHi) * planeScale > farPlane2)
                continue;
            const Lanes s0 = (m0.x * ax + m0.y * ay) + m0.z * az, s1 = (m1.x * bx + m1.y * by) + m1.z * bz,
                        s2 = (m2.x * cx + m2.y * cy) + m2.z * cz;
            const Lanes plane = (n.x * ax + n.y * ay) + n.z * az;
            const Lanes d0 = (e0.x * ax + e0.y * ay) + e0.z * az, d1 = (e1.x * bx + e1.y * by) + e1.z * bz,
                        d2 = (e2.x * cx + e2.y * cy) + e2.z * cz;
            // The projections onto the edges, clamped to [0, 1] (written out: a vector
            // passed to a function would change its calling convention between the clones).
            Lanes t0 = d0 * i0, t1 = d1 * i1, t2 = d2 * i2;
            t0 = t0 > zero ? t0 : zero;
            t1 = t1 > zero ? t1 : zero;
            t2 = t2 > zero ? t2 : zero;
            t0 = t0 < one ? t0 : one;
            t1 = t1 < one ? t1 : one;
            t2 = t2 < one ? t2 : one;
            const Lanes r0 = ((ax * ax + ay * ay) + az * az) - t0 * (2.0 * d0 - t0 * l0);
            const Lanes r1 = ((bx * bx + by * by) + bz * bz) - t1 * (2.0 * d1 - t1 * l1);
            const Lanes r2 = ((cx * cx + cy * cy) + cz * cz) - t2 * (2.0 * d2 - t2 * l2);
            const Lanes r01 = r0 < r1 ? r0 : r1;
            const Lanes edge = r01 < r2 ? r01 : r2;
            const Mask inside = (s0 > zero) & (s1 > zero) & (s2 > zero);
            const Lanes approx = (inside ? plane * plane * planeScale : edge) + valid;
            Lanes leastRow;
            std::memcpy(&leastRow, &scratch.least[std::size_t(row)], sizeof leastRow);
            const Mask isNear = approx <= leastRow + tolerance;
            // The lanes' bits, gathered by halves.
            Mask bits = isNear & Mask{1, 2, 4, 8, 16, 32, 64, 128};
            bits |= __builtin_shuffle(bits, Mask{4, 5, 6, 7, 0, 1, 2, 3});
            bits |= __builtin_shuffle(bits, Mask{2, 3, 0, 1, 6, 7, 4, 5});
            bits |= __builtin_shuffle(bits, Mask{1, 0, 3, 2, 5, 4, 7, 6});
            unsigned near = unsigned(bits[0]);
            for (; near; near &= near - 1) {
                const int z = __builtin_ctz(near);
                const std::size_t o = std::size_t(row + z);
                const double d = approx[z];
                double& least = scratch.least[o];
                std::uint8_t& count = scratch.count[o];
                if (d < least - tolerance) {  // every earlier candidate is now too far
                    least = d;
                    scratch.candidates[o][0] = {d, s.face};
                    count = 1;
                    continue;
                }
                least = std::min(least, d);
                if (count < kMaxCandidates) scratch.candidates[o][count] = {d, s.face};
                if (count <= kMaxCandidates) ++count;
            }
        }
    }
}

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
    /// @p scratch is scratch.
    void rasterize(std::size_t b, Scratch& scratch, std::unique_ptr<Leaf>& leaf, std::unique_ptr<MaskLeaf>& mask) const
    {
        const openvdb::Coord origin = blockOrigin(mBlocks.pairs[mBlocks.blockFirst[b]].first);
        // The block's first voxel as a global index (whole numbers, exact in double).
        const std::array<double, 3> g{double(mOrigin[0] + origin.x()), double(mOrigin[1] + origin.y()),
                                      double(mOrigin[2] + origin.z())};
        findClosest(b, origin, g, scratch);
        // Filled in locals: @p leaf and @p mask lie next to other threads' blocks.
        std::unique_ptr<Leaf> blockLeaf;
        std::unique_ptr<MaskLeaf> blockMask;
        signedDistances(scratch.best, origin, g, blockLeaf, blockMask);
        leaf = std::move(blockLeaf);
        mask = std::move(blockMask);
    }

private:
    /// The clipped range of triangle @p f's voxels in the block at @p origin.
    void rangeIn(std::uint32_t f, const openvdb::Coord& origin, std::array<int, 3>& lo, std::array<int, 3>& hi) const
    {
        const VoxelRange& v = mRanges[f];
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::max(v.lo[k], origin[k]) - origin[k];
            hi[k] = std::min(v.hi[k], origin[k] + kDim - 1) - origin[k];
        }
    }

    /// Offers triangle @p f to voxel @p p's closest point so far, after two cheap rejections
    /// (the triangle's plane, and in it the gap to the bounding circle).
    void offer(const Vec3& p, std::uint32_t f, MeshDistance::Closest& current) const
    {
        const Vec3& a = mMesh.points[mMesh.triangles[f][0]];
        const Vec3& n = mDistance.faceNormal(f);
        const MeshDistance::BoundingSphere& sphere = mDistance.boundingSphere(f);
        const double plane = dot(p - a, n);
        const double plane2 = plane * plane;
        if (plane2 >= current.squaredDistance) return;
        const double lateral2 = squaredNorm(p - sphere.centre) - plane2;
        if (lateral2 > sphere.radius * sphere.radius) {
            const double gap = std::sqrt(lateral2) - sphere.radius;
            if (plane2 + gap * gap >= current.squaredDistance) return;
        }
        const MeshDistance::Closest c = mDistance.closestOnFace(p, f);
        if (c.squaredDistance < current.squaredDistance) current = c;
    }

    /// The closest of the block's triangles to each voxel of the block within reach (ties
    /// keep the lowest face index). The approximate distances of scanPair() pick each
    /// voxel's candidates; those are then offered in ascending face order, as all of the
    /// block's triangles would be, and the same one is closest.
    void findClosest(std::size_t b, const openvdb::Coord& origin, const std::array<double, 3>& g,
                     Scratch& scratch) const
    {
        const double h = mH, reach2 = mReach * mReach;
        const std::size_t first = mBlocks.blockFirst[b], last = mBlocks.blockFirst[b + 1];
        // The approximate and the exact squared distance differ by rounding, a few units of
        // the last place of the squares of the lengths involved (at most about
        // (3 (radius + reach))²): 1e-10 of that is far beyond it and far below the gaps
        // between distinct triangles' distances.
        double extent = 0;
        for (std::size_t i = first; i < last; ++i)
            extent = std::max(extent, mDistance.boundingSphere(mBlocks.pairs[i].second).radius);
        const double tolerance = 2e-10 * 9.0 * (extent + mReach) * (extent + mReach);
        scratch.least.fill(reach2 + tolerance);
        scratch.count.fill(0);
        PairScan scan;
        scan.g = g;
        scan.h = h;
        scan.tolerance = tolerance;
        scan.reach2 = reach2;
        for (std::size_t i = first; i < last; ++i) {
            const std::uint32_t f = mBlocks.pairs[i].second;
            const auto& t = mMesh.triangles[f];
            scan.a = mMesh.points[t[0]];
            scan.b = mMesh.points[t[1]];
            scan.c = mMesh.points[t[2]];
            scan.face = f;
            rangeIn(f, origin, scan.lo, scan.hi);
            scanPair(scan, scratch);
        }
        for (int offset = 0; offset < int(Leaf::SIZE); ++offset) {
            const std::size_t o = std::size_t(offset);
            MeshDistance::Closest& current = scratch.best[o];
            current.squaredDistance = reach2;
            current.face = std::uint32_t(-1);
            const int count = scratch.count[o];
            if (count == 0) continue;
            const int x = offset >> 2 * kLog2, y = offset >> kLog2 & (kDim - 1), z = offset & (kDim - 1);
            const Vec3 p(h * (g[0] + x), h * (g[1] + y), h * (g[2] + z));
            if (count <= kMaxCandidates) {
                const double limit = scratch.least[o] + tolerance;
                for (int k = 0; k < count; ++k)
                    if (scratch.candidates[o][std::size_t(k)].approx <= limit)
                        offer(p, scratch.candidates[o][std::size_t(k)].face, current);
                continue;
            }
            std::array<int, 3> lo, hi;  // too many candidates: every triangle in range
            for (std::size_t i = first; i < last; ++i) {
                const std::uint32_t f = mBlocks.pairs[i].second;
                rangeIn(f, origin, lo, hi);
                if (x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2])
                    offer(p, f, current);
            }
        }
    }

    /// The signed distance of every voxel with a closest triangle, and whether its side
    /// is a guess.
    void signedDistances(const std::array<MeshDistance::Closest, Leaf::SIZE>& best, const openvdb::Coord& origin, const std::array<double, 3>& g,
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
    tbb::enumerable_thread_specific<std::unique_ptr<Scratch>> scratch(
        [] { return std::make_unique<Scratch>(); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numBlocks), [&](const auto& r) {
        Scratch& blockScratch = *scratch.local();
        for (std::size_t b = r.begin(); b < r.end(); ++b) rasterizer.rasterize(b, blockScratch, leaves[b], guessed[b]);
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
