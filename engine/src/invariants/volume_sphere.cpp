#include <msii/invariants/volume_sphere.h>
#include <msii/invariants/scales.h>

#include "../levelset/levelset_backend.h"
#include "../levelset/levelset_impl.h"
#include "../levelset/tile_sides.h"
#include "cube_fraction.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>

#include <openvdb/tools/Dense.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

namespace msii {

namespace {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatTree;
using openvdb::Int32Tree;

/// Half width of the shell kernel for S = dV/dr, in voxels of the radius' level.
constexpr double kShellHalfWidth = 0.5;

// ---------------------------------------------------------------------------------------
// Levels: radius j goes to the coarsest level l (voxel h·2^l) with r_j / (h·2^l) >= k.

struct LevelPlan {
    std::vector<int> levelOf;                 // per radius
    std::vector<std::vector<int>> radiiOf;    // per level: radius indices, ascending
};

LevelPlan planLevels(const std::vector<int>& levelOf, std::size_t numRadii)
{
    if (levelOf.size() != numRadii || *std::min_element(levelOf.begin(), levelOf.end()) < 0)
        throw InvalidInputError("the grid levels do not match the radii");
    LevelPlan plan;
    plan.levelOf = levelOf;
    plan.radiiOf.resize(*std::max_element(plan.levelOf.begin(), plan.levelOf.end()) + 1);
    for (std::size_t j = 0; j < numRadii; ++j) plan.radiiOf[std::size_t(plan.levelOf[j])].push_back(int(j));
    return plan;
}

// ---------------------------------------------------------------------------------------
// Occupancy, stored as q = 1/2 - occupancy, so that the sign of q is the side, as for the
// distance (q = +1/2 outside, -1/2 inside): the level set's sides carry over, and
// detail::fillTileSides() works on both.

/// Level 0 from the signed distance field: fraction of each voxel inside the solid.
FloatTree::Ptr occupancyFromDistance(const openvdb::FloatGrid& sdf)
{
    const FloatTree& dist = sdf.tree();
    const double h = sdf.voxelSize()[0];
    auto q = std::make_shared<FloatTree>(dist);  // same topology, values replaced below

    using Leaf = FloatTree::LeafNodeType;
    openvdb::tree::LeafManager<FloatTree> leaves(*q);
    leaves.foreach([&](Leaf& leaf, std::size_t) {
        openvdb::tree::ValueAccessor<const FloatTree> acc(dist);
        // The distances of the leaf (q is a copy of dist: the same leaves) and, off it, of
        // its neighbours through the accessor.
        const Leaf& source = *dist.probeConstLeaf(leaf.origin());
        for (openvdb::Index offset = 0; offset < Leaf::SIZE; ++offset) {
            const double phi = source.getValue(offset);
            // A voxel farther than 0.95 h from the surface is wholly on one side (the cube's
            // half diagonal 0.87 h plus the largest curvature term h/12), so only voxels
            // within h need φ's neighbours, which a band of half width 2 holds exactly.
            if (!leaf.isValueOn(offset) || std::abs(phi) >= h) {
                leaf.setValueOnly(offset, phi < 0 ? -0.5f : 0.5f);
                continue;
            }
            const Coord local = Leaf::offsetToLocalCoord(offset);
            const Coord ijk = leaf.origin() + local;
            const auto at = [&](int axis, int step) {
                const int c = local[axis] + step;
                if (c < 0 || c >= int(Leaf::DIM)) {
                    Coord n = ijk;
                    n[axis] += step;
                    return double(acc.getValue(n));
                }
                const int stride = axis == 0 ? int(Leaf::DIM * Leaf::DIM) : axis == 1 ? int(Leaf::DIM) : 1;
                return double(source.getValue(openvdb::Index(int(offset) + step * stride)));
            };
            const double xp = at(0, 1), xm = at(0, -1), yp = at(1, 1), ym = at(1, -1), zp = at(2, 1),
                         zm = at(2, -1);
            const double gx = xp - xm, gy = yp - ym, gz = zp - zm;
            const double g = std::sqrt(gx * gx + gy * gy + gz * gz);
            double occupancy;
            if (g < 1e-12) {
                occupancy = phi < 0 ? 1.0 : 0.0;
            } else {
                // Mean curvature term: the surface bends away from its tangent plane by
                // h²·Δφ/24 on average over a voxel cross-section (Δφ = 2H for a distance).
                double lap = (xp + xm + yp + ym + zp + zm - 6.0 * phi) / (h * h);
                lap = std::clamp(lap, -2.0 / h, 2.0 / h);
                const double phiEff = phi + h * h * lap / 24.0;
                occupancy = detail::cubeFraction(-phiEff / h, std::abs(gx) / g,
                                                 std::abs(gy) / g, std::abs(gz) / g);
            }
            leaf.setValueOnly(offset, float(0.5 - occupancy));
        }
    });
    auto tiles = q->beginValueOff();
    tiles.setMaxDepth(FloatTree::ValueOffIter::LEAF_DEPTH - 1);  // tiles only: leaves are done
    for (; tiles; ++tiles) tiles.setValue(tiles.getValue() < 0 ? -0.5f : 0.5f);
    q->root().setBackground(0.5f, /*updateChildNodes=*/true);
    return q;
}

/// Level l+1 from level l: mean of the 2×2×2 children (exact for volume fractions). Every
/// voxel of every coarse leaf is computed from the fine tree (whose tiles carry their side),
/// so no coarse voxel's side has to be guessed; the coarse tree's tiles get theirs from the
/// finest level afterwards (copyTileSides).
FloatTree::Ptr restrictOccupancy(const FloatTree& fine)
{
    using Leaf = FloatTree::LeafNodeType;
    std::vector<Coord> origins;
    origins.reserve(fine.leafCount());
    for (auto it = fine.cbeginLeaf(); it; ++it) {
        const Coord o = it->origin();
        origins.push_back(Coord(o.x() >> 1, o.y() >> 1, o.z() >> 1) & ~(Leaf::DIM - 1));
    }
    std::sort(origins.begin(), origins.end());
    origins.erase(std::unique(origins.begin(), origins.end()), origins.end());

    std::vector<std::unique_ptr<Leaf>> leafs(origins.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size()), [&](const auto& r) {
        openvdb::tree::ValueAccessor<const FloatTree> acc(fine);
        constexpr int kHalf = int(Leaf::DIM) / 2;
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            auto leaf = std::make_unique<Leaf>(origins[i], 0.5f, /*active=*/true);
            // The coarse leaf's eighths, each the children of one fine leaf (or tile).
            for (int part = 0; part < 8; ++part) {
                const Coord corner((part & 1) * kHalf, ((part >> 1) & 1) * kHalf, (part >> 2) * kHalf);
                const Coord fineOrigin = (origins[i] + corner) << 1;
                const Leaf* source = acc.probeConstLeaf(fineOrigin);
                const float tile = source ? 0.0f : acc.getValue(fineOrigin);
                for (int x = 0; x < kHalf; ++x)
                    for (int y = 0; y < kHalf; ++y)
                        for (int z = 0; z < kHalf; ++z) {
                            double sum = 0;
                            for (int c = 0; c < 8; ++c)
                                sum += source ? source->getValue(Leaf::coordToOffset(
                                                    Coord(2 * x + (c & 1), 2 * y + ((c >> 1) & 1), 2 * z + (c >> 2))))
                                              : tile;
                            leaf->setValueOnly(Leaf::coordToOffset(corner + Coord(x, y, z)), float(sum / 8.0));
                        }
            }
            leafs[i] = std::move(leaf);
        }
    });
    auto coarse = std::make_shared<FloatTree>(0.5f);
    for (auto& leaf : leafs) coarse->addLeaf(leaf.release());
    return coarse;
}

/// Gives every leaf-sized block of the level-@p level tree @p coarse inside @p fineBox
/// (fine index space) that is not a leaf the side of the fine tree at the block's centre
/// (the block then holds only fine tiles, all on one side).
void copyTileSides(FloatTree& coarse, const FloatTree& fine, int level,
                   const openvdb::CoordBBox& fineBox)
{
    using Leaf = FloatTree::LeafNodeType;
    const int shift = level + Leaf::LOG2DIM;
    const Coord lo(fineBox.min().x() >> shift, fineBox.min().y() >> shift, fineBox.min().z() >> shift);
    const Coord hi(fineBox.max().x() >> shift, fineBox.max().y() >> shift, fineBox.max().z() >> shift);
    openvdb::tree::ValueAccessor<const FloatTree> fineAcc(fine);
    openvdb::tree::ValueAccessor<FloatTree> acc(coarse);
    const int half = (Leaf::DIM << level) / 2;
    for (int x = lo.x(); x <= hi.x(); ++x)
        for (int y = lo.y(); y <= hi.y(); ++y)
            for (int z = lo.z(); z <= hi.z(); ++z) {
                const Coord origin(x << Leaf::LOG2DIM, y << Leaf::LOG2DIM, z << Leaf::LOG2DIM);
                if (acc.probeConstLeaf(origin)) continue;
                const Coord centre((x << shift) + half, (y << shift) + half, (z << shift) + half);
                acc.addTile(1, origin, fineAcc.getValue(centre) < 0 ? -0.5f : 0.5f, false);
            }
}

// ---------------------------------------------------------------------------------------
// Stencils: anti-aliased ball weights for V and shell weights for S (Eq. 1 and 3 of the
// paper as voxel sums), for all radii of one level at once.
//
// Entries are grouped by their squared distance n = x² + y² + z² from the centre; all
// entries of a group share one weight per radius (the mean of their exact voxel ∩ ball
// fractions, so each stencil's total is unchanged). A node's sums are then
//     V_j = Σ_groups wV[group][j] · (Σ_{entries e in group} occupancy(node + e)),
// so every entry costs one addition whatever the number of radii, and the group sums for
// eight nodes in a row are computed together as eight consecutive floats.

constexpr int kRow = 8;  // nodes per row = the leaf node's edge

struct Stencil {
    int reach = 0;      // voxels beyond the 8^3 block that the stencil reads
    int side = 0;       // 8 + 2·reach: edge of the dense block copied per leaf
    int numRadii = 0;
    /// Per fastest axis (0 = x, 1 = y, 2 = z) of the dense block: the entries' linear
    /// offsets, ordered by group.
    std::array<std::vector<std::int32_t>, 3> offsets;
    std::vector<std::uint32_t> groupFirst;  // groups' ranges in offsets (size numGroups + 1)
    std::vector<float> wV, wS;              // per group: numRadii weights
    /// Per radius: the groups [vFirst, vLast) whose V weight is neither 1 (all before) nor 0
    /// (all after), and [sFirst, sLast) those whose S weight is not 0.
    std::vector<std::uint32_t> vFirst, vLast, sFirst, sLast;
    std::vector<double> sumV, sumS;         // per radius: the stencil's own total
    std::size_t numGroups() const { return groupFirst.size() - 1; }
};

Stencil makeStencil(const std::vector<double>& rho)  // radii in voxels of the level
{
    Stencil st;
    const int nr = int(rho.size());
    st.numRadii = nr;
    st.reach = int(std::ceil(rho.back() + kShellHalfWidth + 1.0));
    st.side = kRow + 2 * st.reach;
    st.sumV.assign(nr, 0.0);
    st.sumS.assign(nr, 0.0);

    // Entries by squared distance.
    const int reach = st.reach;
    std::vector<std::vector<std::array<int, 3>>> byDistance(std::size_t(3 * reach * reach) + 1);
    for (int x = -reach; x <= reach; ++x)
        for (int y = -reach; y <= reach; ++y)
            for (int z = -reach; z <= reach; ++z)
                byDistance[std::size_t(x * x + y * y + z * z)].push_back({x, y, z});

    const int side = st.side;
    const auto offset = [side](int a, int b, int c) { return std::int32_t((a * side + b) * side + c); };
    std::vector<double> v(nr), sh(nr);
    bool interiorOpen = false;  // the last group is the merged interior (all V = 1, S = 0)
    for (const auto& group : byDistance) {
        if (group.empty()) continue;
        std::fill(v.begin(), v.end(), 0.0);
        std::fill(sh.begin(), sh.end(), 0.0);
        for (const auto& e : group)
            for (int j = 0; j < nr; ++j) {
                v[j] += detail::ballFraction(e[0], e[1], e[2], rho[j]);
                sh[j] += detail::ballFraction(e[0], e[1], e[2], rho[j] + kShellHalfWidth) -
                         detail::ballFraction(e[0], e[1], e[2], rho[j] - kShellHalfWidth);
            }
        bool any = false, interior = true;
        for (int j = 0; j < nr; ++j) {
            st.sumV[j] += v[j];
            st.sumS[j] += sh[j];
            v[j] /= double(group.size());
            sh[j] /= double(group.size());
            any = any || v[j] > 0 || sh[j] > 0;
            interior = interior && v[j] == 1.0 && sh[j] == 0.0;
        }
        if (!any) continue;
        if (!(interior && interiorOpen)) {  // start a new group (else extend the interior)
            st.groupFirst.push_back(std::uint32_t(st.offsets[0].size()));
            for (int j = 0; j < nr; ++j) {
                st.wV.push_back(float(v[j]));
                st.wS.push_back(float(sh[j]));
            }
        }
        interiorOpen = interior;
        for (const auto& e : group) {
            st.offsets[0].push_back(offset(e[1], e[2], e[0]));  // x fastest
            st.offsets[1].push_back(offset(e[0], e[2], e[1]));  // y fastest
            st.offsets[2].push_back(offset(e[0], e[1], e[2]));  // z fastest
        }
    }
    st.groupFirst.push_back(std::uint32_t(st.offsets[0].size()));
    const std::size_t ng = st.numGroups();
    st.vFirst.assign(nr, 0), st.vLast.assign(nr, 0), st.sFirst.assign(nr, std::uint32_t(ng)), st.sLast.assign(nr, 0);
    for (int j = 0; j < nr; ++j) {
        const auto v = [&](std::size_t g) { return st.wV[g * std::size_t(nr) + std::size_t(j)]; };
        const auto sh = [&](std::size_t g) { return st.wS[g * std::size_t(nr) + std::size_t(j)]; };
        std::size_t first = 0;
        while (first < ng && v(first) == 1.0f) ++first;
        std::size_t last = ng;
        while (last > first && v(last - 1) == 0.0f) --last;
        st.vFirst[j] = std::uint32_t(first), st.vLast[j] = std::uint32_t(last);
        for (std::size_t g = 0; g < ng; ++g)
            if (sh(g) != 0.0f) st.sFirst[j] = std::min(st.sFirst[j], std::uint32_t(g)), st.sLast[j] = std::uint32_t(g + 1);
        st.sFirst[j] = std::min(st.sFirst[j], st.sLast[j]);
    }
    return st;
}

/// Stencil sums for the kRow nodes of a row that starts at @p row in the dense block whose
/// fastest axis runs along the row: V and S per radius, kRow floats each (one per node);
/// S only if @p sumS is not null. The groups' sums are added up as they come (@p below[g]:
/// the sum of the groups before g), so that a radius's V is the sum below its first
/// fractional group plus its fractional groups, and its S the sum of its groups with an S
/// weight: each radius weighs only the groups near its sphere. The inner loops over kRow
/// consecutive floats become single vector instructions; an AVX2 version is compiled beside
/// the generic one and chosen at run time.
__attribute__((target_clones("avx2", "default"))) void applyStencil(
    const Stencil& st, const std::vector<std::int32_t>& offsets, const float* row,
    float* groupSum, float* below, float* sumV, float* sumS)
{
    const std::size_t ng = st.numGroups();
    const std::int32_t* off = offsets.data();
    for (std::size_t g = 0; g < ng; ++g) {
        float a0[kRow] = {}, a1[kRow] = {};
        std::uint32_t e = st.groupFirst[g];
        const std::uint32_t end = st.groupFirst[g + 1];
        for (; e + 1 < end; e += 2) {
            const float* p0 = row + off[e];
            const float* p1 = row + off[e + 1];
            for (int t = 0; t < kRow; ++t) {
                a0[t] += p0[t];
                a1[t] += p1[t];
            }
        }
        if (e < end)
            for (int t = 0; t < kRow; ++t) a0[t] += row[off[e] + t];
        for (int t = 0; t < kRow; ++t) groupSum[g * kRow + t] = a0[t] + a1[t];
    }
    // (A loop of its own: added to the one above, it would keep that from vectorising.)
    float total[kRow] = {};
    for (std::size_t g = 0; g < ng; ++g)
        for (int t = 0; t < kRow; ++t) {
            below[g * kRow + t] = total[t];
            total[t] += groupSum[g * kRow + t];
        }
    for (int t = 0; t < kRow; ++t) below[ng * kRow + t] = total[t];
    const int nr = st.numRadii;
    for (int j = 0; j < nr; ++j) {
        float v[kRow];
        const std::size_t first = st.vFirst[std::size_t(j)], last = st.vLast[std::size_t(j)];
        for (int t = 0; t < kRow; ++t) v[t] = below[first * kRow + t];
        for (std::size_t g = first; g < last; ++g) {
            const float w = st.wV[g * std::size_t(nr) + std::size_t(j)];
            for (int t = 0; t < kRow; ++t) v[t] += w * groupSum[g * kRow + t];
        }
        for (int t = 0; t < kRow; ++t) sumV[j * kRow + t] = v[t];
        if (!sumS) continue;
        float sh[kRow] = {};
        for (std::size_t g = st.sFirst[std::size_t(j)]; g < st.sLast[std::size_t(j)]; ++g) {
            const float w = st.wS[g * std::size_t(nr) + std::size_t(j)];
            for (int t = 0; t < kRow; ++t) sh[t] += w * groupSum[g * kRow + t];
        }
        for (int t = 0; t < kRow; ++t) sumS[j * kRow + t] = sh[t];
    }
}

// ---------------------------------------------------------------------------------------

/// Position of a level-l voxel centre in the fine level's index space.
inline openvdb::Vec3d fineIndexOf(const Coord& c, int level)
{
    const double scale = double(1 << level), shift = 0.5 * (scale - 1.0);
    return {c.x() * scale + shift, c.y() * scale + shift, c.z() * scale + shift};
}

/// The value a voxel centre at signed distance x·r from the surface would have on the
/// surface itself, to second order, for a surface of curvature κ (a = κr, positive where
/// convex). For a sphere of radius 1/κ the patch inside a ball whose centre is x·r outside
/// it has area P(x) = πr²(1 − x²)/(1 + a x) (a cap, Archimedes), and dV/dd = −P, so
/// V̂(x) = V̂(0) − 3x/4 + 3a x²/8 + x³/4 + O(a²x³). The plane model (a = 0) is the cap
/// volume. The x² term matters: trilinear weights cancel the linear term but not the
/// quadratic one, whose sum depends on how the grid sits around the vertex.
inline double surfaceVolume(double value, double x, double a)
{
    return value + 0.75 * x - 0.375 * a * x * x - 0.25 * x * x * x;
}

/// As surfaceVolume() for the sphere area: the sphere of radius r about a centre x·r outside
/// a sphere of curvature κ has Ŝ(x) = 1/2 − (a(1 + x²) + 2x) / (4(1 + a x)) inside, so
/// Ŝ(x) = Ŝ(0) − (2 − a²)x/4 + a x²/4 + O(x³); the plane gives Ŝ(x) = (1 − x)/2.
inline double surfaceSphere(double value, double x, double a)
{
    return value + 0.25 * (2.0 - a * a) * x - 0.25 * a * x * x;
}

/// Weights that give the second derivative at radius j of the least-squares quadratic
/// through the values at five consecutive radii around j (all radii if fewer). Three
/// radii would do, but their second difference amplifies the grid's noise by √6/Δr²;
/// five cut that by 4.6 (Savitzky–Golay), which is what keeps the results' dependence on
/// how the grid sits (rigid motions) at its level without the term.
struct BendWeights {
    std::size_t first = 0;
    std::vector<double> weights;
};

BendWeights secondDerivativeWeights(const std::vector<double>& radii, std::size_t j)
{
    const std::size_t nr = radii.size(), width = std::min<std::size_t>(5, nr);
    BendWeights bw;
    bw.first = std::min(j >= 2 ? j - 2 : 0, nr - width);
    // Normal equations of y ≈ c0 + c1 t + c2 t², t = r − r_j; the weights are row 2 of
    // (AᵀA)⁻¹Aᵀ, times 2.
    double m[3][3] = {};
    for (std::size_t k = 0; k < width; ++k) {
        const double t = radii[bw.first + k] - radii[j], p[3] = {1.0, t, t * t};
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) m[a][b] += p[a] * p[b];
    }
    // Row 2 of the inverse of the symmetric 3×3 matrix: cofactors / determinant.
    const double c0 = m[0][1] * m[1][2] - m[0][2] * m[1][1];
    const double c1 = m[0][2] * m[1][0] - m[0][0] * m[1][2];
    const double c2 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    const double det = m[2][0] * c0 + m[2][1] * c1 + m[2][2] * c2;
    for (std::size_t k = 0; k < width; ++k) {
        const double t = radii[bw.first + k] - radii[j];
        bw.weights.push_back(2.0 * (c0 + c1 * t + c2 * t * t) / det);
    }
    return bw;
}

/// Removes the smoothing bias of the voxel sums. A node's V is the sum over voxels of
/// (voxel ∩ ball fraction) × (voxel ∩ solid fraction): the ball and the solid are each
/// box-filtered, so V is V̂ convolved with a tent of variance h²/6 per axis, which adds
/// (h²/12)·ΔV̂ to the second order. The Laplacian of V̂ over ball centres is ΔV̂ = 3Ŝ'/r
/// (Ŝ' = dŜ/dr: Gauss's theorem on the ball, ΔV = ∂S/∂r − 2S/r). The shell of S is also
/// box-filtered across its radius; with Darboux's ΔŜ = Ŝ'' + 2Ŝ'/r the node's S is off by
/// (h²/12)·(4Ŝ'/r + 3Ŝ''/2). Ŝ' is taken from V̂ across neighbouring radii (for Ŝ linear in
/// r, V̂' = 3Ŝ'/4), which follows the surface at the scale of the ball whatever the grid
/// (a curvature fitted within a voxel cell would not), and Ŝ'' from Ŝ across five
/// neighbouring radii (secondDerivativeWeights; 0 on spheres, planes, edges and corners, but
/// not where the sphere sweeps over relief: wedges, rims, tool marks). On a sphere of radius
/// 10 at r = 4 (6 voxels per radius) the bias this removes is −7e-4 in V̂ and −9e-4 in Ŝ
/// (docs/method.md, Smoothing-bias removal).
void removeSmoothingBias(VolumeSphereResult& result, double h0)
{
    const auto& radii = result.radii;
    const std::size_t nr = radii.size();
    if (nr < 2) return;  // no derivative across radii
    const std::size_t nv = result.volume.front().size();
    const bool sphere = !result.sphere.empty();
    std::vector<BendWeights> bendWeights;
    if (sphere && nr >= 3)
        for (std::size_t j = 0; j < nr; ++j) bendWeights.push_back(secondDerivativeWeights(radii, j));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& range) {
        std::vector<double> slope(nr), bend(nr, 0.0);
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            // Ŝ'' from the quadratic fitted to Ŝ at the radii around j.
            if (!bendWeights.empty())
                for (std::size_t j = 0; j < nr; ++j) {
                    const BendWeights& bw = bendWeights[j];
                    double b = 0;
                    for (std::size_t k = 0; k < bw.weights.size(); ++k)
                        b += bw.weights[k] * result.sphere[bw.first + k][i];
                    bend[j] = std::isnan(b) ? 0.0 : b;
                }
            for (std::size_t j = 0; j < nr; ++j) {
                // Central difference where both neighbours exist (larger radii are masked
                // first near a border), else one-sided.
                const std::size_t lo = j > 0 ? j - 1 : j;
                std::size_t hi = j + 1 < nr ? j + 1 : j;
                if (std::isnan(result.volume[hi][i])) hi = j;
                slope[j] = hi == lo || std::isnan(result.volume[j][i])
                               ? 0.0
                               : (double(result.volume[hi][i]) - result.volume[lo][i]) /
                                     (radii[hi] - radii[lo]);
            }
            for (std::size_t j = 0; j < nr; ++j) {
                const double h = h0 * double(1 << result.levelOfRadius[j]);
                const double dS = 4.0 / 3.0 * slope[j];  // Ŝ'
                float& v = result.volume[j][i];
                v = float(std::clamp(v - h * h * dS / (4.0 * radii[j]), 0.0, 1.0));
                if (sphere) {
                    float& s = result.sphere[j][i];
                    s = float(std::clamp(s - h * h * (dS / (3.0 * radii[j]) + bend[j] / 8.0), 0.0, 1.0));
                }
            }
        }
    });
}

/// Step 1 and 2 of the file comment: occupancy on the fine level from the level set, and the
/// pyramid of coarser levels; tiles within reach of any vertex's stencil get their side.
std::vector<FloatTree::Ptr> occupancyPyramid(const LevelSet& levelSet, const LevelPlan& plan,
                                             const std::vector<double>& radii,
                                             const std::vector<openvdb::Vec3d>& globalIndex, const Coord& shiftCoord,
                                             RunContext* progress)
{
    const openvdb::FloatGrid& sdf = *levelSetImpl(levelSet).grid;
    const double h0 = sdf.voxelSize()[0];
    const int numLevels = int(plan.radiiOf.size());
    if (progress) progress->start("occupancy", std::size_t(numLevels));
    // Tiles within reach of any vertex's stencil get their side from the band on the fine
    // level (blocks of 8 fine voxels), and coarse tiles copy the fine side: coarse blocks
    // are 2^l times larger, too coarse to tell sides apart near an open border.
    openvdb::CoordBBox vertexBox;
    for (const auto& u : globalIndex) vertexBox.expand(Coord::floor(u) - shiftCoord);
    int finePad = 0;
    for (int l = 0; l < numLevels; ++l) {
        double rhoMax = 0;
        for (int j : plan.radiiOf[l]) rhoMax = std::max(rhoMax, radii[j] / (h0 * (1 << l)));
        finePad = std::max(finePad, (int(std::ceil(rhoMax)) + 12) << l);
    }
    openvdb::CoordBBox fineBox = vertexBox;
    fineBox.expand(finePad);
    std::vector<FloatTree::Ptr> occupancy{occupancyFromDistance(sdf)};
    detail::fillTileSides(*occupancy.back(), fineBox, 0.5f, -0.5f,
                          levelSetImpl(levelSet).guessedSide.get());
    if (progress) progress->advance();
    for (int l = 1; l < numLevels; ++l) {
        occupancy.push_back(restrictOccupancy(*occupancy.back()));
        copyTileSides(*occupancy.back(), *occupancy.front(), l, fineBox);
        if (progress) progress->advance();
    }
    if (progress) progress->end();
    return occupancy;
}

/// The voxel centres of one level that the vertices need: the 8 corners of the level's cell
/// around each @p active vertex, numbered in a tree (value: the node's number), with each
/// vertex's cell corner and position inside the cell.
struct LevelNodes {
    std::vector<Coord> base;                 ///< per vertex: the cell's lowest corner
    std::vector<std::array<float, 3>> frac;  ///< per vertex: position in the cell, 0..1
    Int32Tree nodes{-1};                     ///< node number per needed voxel centre
    std::vector<std::int32_t> seedVertex;    ///< per node: a vertex next to it
    std::int32_t numNodes = 0;
};

LevelNodes levelNodes(const std::vector<openvdb::Vec3d>& globalIndex, int level, const Coord& shiftCoord,
                      const std::vector<char>& active)
{
    const std::size_t nv = globalIndex.size();
    LevelNodes ln;
    std::vector<Coord>& base = ln.base;
    std::vector<std::array<float, 3>>& frac = ln.frac;
    Int32Tree& nodes = ln.nodes;
    std::vector<std::int32_t>& seedVertex = ln.seedVertex;
    std::int32_t& numNodes = ln.numNodes;
    // Voxel centres needed: the 8 corners of the level's cell around each vertex.
    const double scale = double(1 << level), shift = 0.5 * (scale - 1.0);
    base.resize(nv);
    frac.resize(nv);
    const Coord levelShift(shiftCoord.x() >> level, shiftCoord.y() >> level, shiftCoord.z() >> level);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const openvdb::Vec3d u = (globalIndex[i] - openvdb::Vec3d(shift)) / scale;
            const Coord b(int(std::floor(u.x())), int(std::floor(u.y())), int(std::floor(u.z())));
            base[i] = b - levelShift;
            frac[i] = {float(u.x() - b.x()), float(u.y() - b.y()), float(u.z() - b.z())};
        }
    });
    {
        openvdb::tree::ValueAccessor<Int32Tree> acc(nodes);
        for (std::size_t i = 0; i < nv; ++i) {
            if (!active[i]) continue;
            for (int c = 0; c < 8; ++c)  // value: a vertex next to the voxel centre
                acc.setValueOn(base[i].offsetBy(c & 1, (c >> 1) & 1, c >> 2), std::int32_t(i));
        }
    }
    std::vector<Int32Tree::LeafNodeType*> blocks;
    nodes.getNodes(blocks);
    for (auto* leaf : blocks)
        for (auto it = leaf->beginValueOn(); it; ++it) {
            seedVertex.push_back(it.getValue());
            it.setValue(numNodes++);
        }
    return ln;
}

/// Values of the level's nodes (voxel centres), normalised by the stencils' sums, with
/// each node's signed distance for the surface correction.
struct NodeValues {
    std::vector<float> volume, sphere;  ///< [node · radii + k]
    std::vector<float> phi;             ///< [node]
};

/// Step 3 of the file comment: the stencil sums at every node of @p ln, block by block.
NodeValues stencilSums(LevelNodes& ln, const FloatTree& occ, const Stencil& stencil, const LevelSet& levelSet,
                       int level, const Coord& shiftCoord, bool sphere, RunContext* progress)
{
    const int nr = stencil.numRadii;
    // Stencil sums at every needed voxel centre, block by block: the block's occupancy
    // is copied densely with the axis along which its nodes fill the fewest rows as the
    // fastest one, and the stencil is applied row by row.
    const std::int32_t numNodes = ln.numNodes;
    NodeValues out;
    std::vector<float>& nodeV = out.volume;
    std::vector<float>& nodeS = out.sphere;
    std::vector<float>& nodePhi = out.phi;
    nodeV.resize(std::size_t(numNodes) * nr);
    nodeS.resize(sphere ? std::size_t(numNodes) * nr : 0);
    nodePhi.resize(std::size_t(numNodes));
    const openvdb::FloatGrid& sdf = *levelSetImpl(levelSet).grid;
    const double h0 = sdf.voxelSize()[0];
    std::vector<Int32Tree::LeafNodeType*> blocks;
    ln.nodes.getNodes(blocks);
    const std::vector<std::int32_t>& seedVertex = ln.seedVertex;
    const int side = stencil.side;
    const std::size_t denseSize = std::size_t(side) * side * side;
    struct Scratch {
        std::vector<float> zyx, buffer;
        std::vector<float> groupSum, below, sumV, sumS;  // kRow floats per group (and one) / radius
    };
    tbb::enumerable_thread_specific<Scratch> scratch([&] {
        return Scratch{std::vector<float>(denseSize), std::vector<float>(denseSize),
                       std::vector<float>(stencil.numGroups() * kRow),
                       std::vector<float>((stencil.numGroups() + 1) * kRow),
                       std::vector<float>(nr * kRow), std::vector<float>(nr * kRow)};
    });
    if (progress) progress->start("V and S, level " + std::to_string(level), blocks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 4), [&](const auto& r) {
        Scratch& sc = scratch.local();
        openvdb::tree::ValueAccessor<const FloatTree> sdfAcc(sdf.tree());
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            const Int32Tree::LeafNodeType& leaf = *blocks[b];
            // Rows needed along each axis.
            std::array<std::uint64_t, 3> rowMask{0, 0, 0};
            for (auto it = leaf.cbeginValueOn(); it; ++it) {
                const Coord c = it.getCoord() - leaf.origin();
                rowMask[0] |= std::uint64_t(1) << (c.y() * 8 + c.z());
                rowMask[1] |= std::uint64_t(1) << (c.x() * 8 + c.z());
                rowMask[2] |= std::uint64_t(1) << (c.x() * 8 + c.y());
            }
            int axis = 2;
            for (int a = 0; a < 2; ++a)
                if (__builtin_popcountll(rowMask[a]) < __builtin_popcountll(rowMask[axis])) axis = a;

            const Coord lo = leaf.origin().offsetBy(-stencil.reach);
            const CoordBBox box(lo, lo.offsetBy(side - 1));
            openvdb::tools::Dense<float, openvdb::tools::LayoutZYX> dense(box, sc.zyx.data());
            openvdb::tools::copyToDense(occ, dense, /*serial=*/true);
            // Occupancy = 1/2 − q, laid out with `axis` fastest (z: in place).
            const std::size_t s2 = std::size_t(side) * side;
            float* occupancyBlock = sc.zyx.data();
            if (axis == 2) {
                for (float& v : sc.zyx) v = 0.5f - v;
            } else {
                for (std::size_t x = 0; x < std::size_t(side); ++x)
                    for (std::size_t y = 0; y < std::size_t(side); ++y)
                        for (std::size_t z = 0; z < std::size_t(side); ++z)
                            sc.buffer[axis == 1 ? x * s2 + z * side + y : y * s2 + z * side + x] =
                                0.5f - sc.zyx[x * s2 + y * side + z];
                occupancyBlock = sc.buffer.data();
            }

            const auto& offsets = stencil.offsets[axis];
            for (int u = 0; u < 8; ++u)
                for (int v = 0; v < 8; ++v) {
                    if (!((rowMask[axis] >> (u * 8 + v)) & 1)) continue;
                    // The row's first node in the dense block (slow, middle, fast axes).
                    const std::size_t start =
                        (std::size_t(u + stencil.reach) * side + std::size_t(v + stencil.reach)) *
                            side + std::size_t(stencil.reach);
                    applyStencil(stencil, offsets, occupancyBlock + start, sc.groupSum.data(), sc.below.data(),
                                 sc.sumV.data(), sphere ? sc.sumS.data() : nullptr);
                    for (int t = 0; t < kRow; ++t) {
                        const Coord local = axis == 2 ? Coord(u, v, t)
                                          : axis == 1 ? Coord(u, t, v)
                                                      : Coord(t, u, v);
                        const Coord ijk = leaf.origin() + local;
                        if (!leaf.isValueOn(ijk)) continue;
                        const std::size_t n = std::size_t(leaf.getValue(ijk));
                        for (int j = 0; j < nr; ++j) {
                            nodeV[n * nr + j] = float(sc.sumV[j * kRow + t] / stencil.sumV[j]);
                            if (sphere)
                                nodeS[n * nr + j] = float(sc.sumS[j * kRow + t] / stencil.sumS[j]);
                        }
                        // Signed distance of the voxel centre, for the surface correction:
                        // on the fine level straight from the (exact) band, on coarser
                        // ones from the mesh.
                        if (level == 0) {
                            nodePhi[n] = sdfAcc.getValue(ijk);
                        } else {
                            const openvdb::Vec3d w =
                                (fineIndexOf(ijk, level) + openvdb::Vec3d(shiftCoord.asVec3d())) * h0;
                            nodePhi[n] = float(levelSetImpl(levelSet).distance->exactSignedDistance(
                                Vec3(w.x(), w.y(), w.z()), std::uint32_t(seedVertex[n]), 4.0 * h0));
                        }
                    }
                }
            if (progress) progress->advance();
        }
    });
    if (progress) progress->end();
    return out;
}

/// How much farther than r a border must be for a vertex's value at r on a level of cell
/// @p hl: the stencil's reach and the interpolation's (4 cells), and 2 finest voxels.
double maskMargin(double hl, double h0)
{
    return 4.0 * hl + 2.0 * h0;
}

/// Step 4 of the file comment: back to the vertices, at the level's radii.
void interpolateToVertices(const TriMesh& mesh, const LevelSet& levelSet, const LevelNodes& ln, const NodeValues& values,
                           const std::vector<int>& levelRadii, const std::vector<double>& radii, int level,
                           const std::vector<char>& active, const VolumeSphereOptions& options,
                           VolumeSphereResult& result)
{
    const std::size_t nv = mesh.numVertices();
    const double h0 = levelSetImpl(levelSet).grid->voxelSize()[0];
    const double hl = h0 * double(1 << level);
    const int nr = int(levelRadii.size());
    const bool sphere = options.computeSphere;
    const Int32Tree& nodes = ln.nodes;
    const std::vector<Coord>& base = ln.base;
    const std::vector<std::array<float, 3>>& frac = ln.frac;
    const std::vector<float>& nodeV = values.volume;
    const std::vector<float>& nodeS = values.sphere;
    const std::vector<float>& nodePhi = values.phi;
    // Back to the vertices: trilinear interpolation of surface-corrected node values.
    // A node at signed distance x·r from the surface is moved onto it with the
    // second-order model of surfaceVolume/surfaceSphere. The node's distance is modelled as
    // ψ = n·d + κ/2·|d_t|² (vertex normal n, offset d = node − vertex, d_t its tangential
    // part), with κ fitted to the nodes' exact distances and capped at 0.5/r: V̂ and Ŝ are
    // averages over a ball of radius r, so the field they form cannot bend more sharply
    // than that, and sharp edges and corners (where the exact distance is a cone and
    // would imply κ ≈ 1/h) must not be corrected as if they were smooth. The linear part
    // n·d vanishes at the vertex under trilinear interpolation, so n's error matters
    // only through the curvature term.
    const double margin = maskMargin(hl, h0);
    const auto& distance = *levelSetImpl(levelSet).distance;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        openvdb::tree::ValueAccessor<const Int32Tree> acc(nodes);
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            if (!active[i]) continue;  // every radius of the level masked: no nodes
            const Vec3& n = distance.vertexNormal(i);
            std::array<std::int32_t, 8> idx;
            std::array<double, 8> w, along, tangential2;
            double num = 0, den = 0;
            for (int c = 0; c < 8; ++c) {
                const int cx = c & 1, cy = (c >> 1) & 1, cz = c >> 2;
                idx[c] = acc.getValue(base[i].offsetBy(cx, cy, cz));
                const double fx = cx ? frac[i][0] : 1.0 - frac[i][0];
                const double fy = cy ? frac[i][1] : 1.0 - frac[i][1];
                const double fz = cz ? frac[i][2] : 1.0 - frac[i][2];
                w[c] = fx * fy * fz;
                const Vec3 d(hl * (cx - frac[i][0]), hl * (cy - frac[i][1]),
                             hl * (cz - frac[i][2]));
                along[c] = dot(n, d);
                tangential2[c] = std::max(0.0, dot(d, d) - along[c] * along[c]);
                const double deviation = nodePhi[std::size_t(idx[c])] - along[c];
                num += deviation * tangential2[c];
                den += tangential2[c] * tangential2[c];
            }
            const double kappaFit = den > 0 ? 2.0 * num / den : 0.0;
            for (int k = 0; k < nr; ++k) {
                const int j = levelRadii[k];
                if (!options.borderDistance.empty() &&
                    radii[j] + margin > options.borderDistance[i])
                    continue;  // stays NaN: the ball reaches the border
                const double kappa = std::clamp(kappaFit, -0.5 / radii[j], 0.5 / radii[j]);
                const double a = kappa * radii[j];
                double v = 0, s = 0;
                for (int c = 0; c < 8; ++c) {
                    const std::size_t m = std::size_t(idx[c]);
                    const double psi = along[c] + 0.5 * kappa * tangential2[c];
                    const double x = std::clamp(psi / radii[j], -0.6, 0.6);
                    v += w[c] * surfaceVolume(nodeV[m * nr + k], x, a);
                    if (sphere) s += w[c] * surfaceSphere(nodeS[m * nr + k], x, a);
                }
                result.volume[j][i] = float(std::clamp(v, 0.0, 1.0));
                if (sphere) result.sphere[j][i] = float(std::clamp(s, 0.0, 1.0));
            }
        }
    });
}

} // namespace

VolumeSphereResult detail::computeVolumeSphereHere(const TriMesh& mesh, const LevelSet& levelSet,
                                                   const VolumeSphereOptions& options, RunContext* progress)
{
    const auto& radii = options.radii;
    validateRadii(radii);
    if (!(options.minVoxelsPerRadius >= 1))
        throw InvalidInputError("the precision (voxels per radius) must be at least 1");
    const std::size_t nv = mesh.numVertices();
    if (!options.borderDistance.empty() && options.borderDistance.size() != nv)
        throw InvalidInputError("border distances do not match the vertex count");

    const double h0 = levelSetImpl(levelSet).grid->voxelSize()[0];
    const LevelPlan plan = planLevels(options.levelOfRadius.empty()
                                          ? volumeSphereLevels(radii, h0, options.minVoxelsPerRadius)
                                          : options.levelOfRadius,
                                      radii.size());
    const int numLevels = int(plan.radiiOf.size());

    VolumeSphereResult result;
    result.radii = radii;
    result.levelOfRadius = plan.levelOf;
    result.numLevels = numLevels;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    result.volume.assign(radii.size(), std::vector<float>(nv, nan));
    if (options.computeSphere) result.sphere.assign(radii.size(), std::vector<float>(nv, nan));

    // Fine index positions of the vertices, global: p / h, without the grid's shift T (an
    // integer number of voxels, subtracted after rounding down), so that a vertex on a cell
    // face picks the same cell in a tile as in the whole mesh.
    const std::array<std::int64_t, 3>& shiftIndex = levelSetImpl(levelSet).shiftIndex;
    const Coord shiftCoord{int(shiftIndex[0]), int(shiftIndex[1]), int(shiftIndex[2])};
    std::vector<openvdb::Vec3d> globalIndex(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3& p = mesh.points[i];
            globalIndex[i] = openvdb::Vec3d(p.x / h0, p.y / h0, p.z / h0);
        }
    });

    Stopwatch stage;
    const std::vector<FloatTree::Ptr> occupancy =
        occupancyPyramid(levelSet, plan, radii, globalIndex, shiftCoord, progress);
    result.occupancySeconds = stage.seconds();

    for (int level = 0; level < numLevels; ++level) {
        const auto& levelRadii = plan.radiiOf[std::size_t(level)];
        if (levelRadii.empty()) continue;
        const double hl = h0 * double(1 << level);
        std::vector<double> rho;
        for (int j : levelRadii) rho.push_back(radii[std::size_t(j)] / hl);

        // The vertices with a value at a radius of the level: those whose smallest radius of
        // it is not masked (interpolateToVertices), the others need no nodes (a mesh continued
        // past its borders: the continuation's vertices).
        std::vector<char> active(nv, 1);
        if (!options.borderDistance.empty()) {
            const double margin = maskMargin(hl, h0), smallest = radii[std::size_t(levelRadii.front())];
            for (std::size_t i = 0; i < nv; ++i) active[i] = smallest + margin > options.borderDistance[i] ? 0 : 1;
        }
        stage.restart();
        LevelNodes ln = levelNodes(globalIndex, level, shiftCoord, active);
        result.numNodes += std::size_t(ln.numNodes);
        const NodeValues values = stencilSums(ln, *occupancy[std::size_t(level)], makeStencil(rho), levelSet, level,
                                              shiftCoord, options.computeSphere, progress);
        result.stencilSeconds += stage.seconds();

        stage.restart();
        interpolateToVertices(mesh, levelSet, ln, values, levelRadii, radii, level, active, options, result);
        result.interpolationSeconds += stage.seconds();
    }

    stage.restart();
    removeSmoothingBias(result, h0);
    result.interpolationSeconds += stage.seconds();
    return result;
}

} // namespace msii
