#include <msii/invariants/volume_sphere.h>

#include "../levelset/levelset_impl.h"
#include "cube_fraction.h"

#include <msii/core/errors.h>

#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <array>
#include <chrono>
#include <cmath>

namespace msii {

namespace {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatTree;
using openvdb::Int32Tree;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Half width of the shell kernel for S = dV/dr, in voxels of the radius' level.
constexpr double kShellHalfWidth = 0.5;

// ---------------------------------------------------------------------------------------
// Levels: radius j goes to the coarsest level l (voxel h·2^l) with r_j / (h·2^l) >= k.

struct LevelPlan {
    std::vector<int> levelOf;                 // per radius
    std::vector<std::vector<int>> radiiOf;    // per level: radius indices, ascending
};

LevelPlan planLevels(const std::vector<double>& radii, double h, double k)
{
    LevelPlan plan;
    int maxLevel = 0;
    for (double r : radii) {
        const int level = std::max(0, int(std::floor(std::log2(r / (k * h)) + 1e-9)));
        plan.levelOf.push_back(level);
        maxLevel = std::max(maxLevel, level);
    }
    plan.radiiOf.resize(maxLevel + 1);
    for (std::size_t j = 0; j < radii.size(); ++j) plan.radiiOf[plan.levelOf[j]].push_back(int(j));
    return plan;
}

// ---------------------------------------------------------------------------------------
// Occupancy, stored as q = 1/2 - occupancy so that OpenVDB's signed flood fill can give
// every voxel outside the band its side (q = +1/2 outside, -1/2 inside).

/// Level 0 from the signed distance field: fraction of each voxel inside the solid.
FloatTree::Ptr occupancyFromDistance(const openvdb::FloatGrid& sdf)
{
    const FloatTree& dist = sdf.tree();
    const double h = sdf.voxelSize()[0];
    auto q = std::make_shared<FloatTree>(dist);  // same topology, values replaced below

    openvdb::tree::LeafManager<FloatTree> leaves(*q);
    leaves.foreach([&](FloatTree::LeafNodeType& leaf, std::size_t) {
        openvdb::tree::ValueAccessor<const FloatTree> acc(dist);
        for (auto it = leaf.beginValueAll(); it; ++it) {
            const Coord ijk = it.getCoord();
            const double phi = acc.getValue(ijk);
            if (!it.isValueOn() || std::abs(phi) >= 1.5 * h) {
                it.setValue(phi < 0 ? -0.5f : 0.5f);
                continue;
            }
            const auto at = [&](int dx, int dy, int dz) {
                return double(acc.getValue(ijk.offsetBy(dx, dy, dz)));
            };
            const double gx = at(1, 0, 0) - at(-1, 0, 0), gy = at(0, 1, 0) - at(0, -1, 0),
                         gz = at(0, 0, 1) - at(0, 0, -1);
            const double g = std::sqrt(gx * gx + gy * gy + gz * gz);
            double occupancy;
            if (g < 1e-12) {
                occupancy = phi < 0 ? 1.0 : 0.0;
            } else {
                // Mean curvature term: the surface bends away from its tangent plane by
                // h²·Δφ/24 on average over a voxel cross-section (Δφ = 2H for a distance).
                double lap = (at(1, 0, 0) + at(-1, 0, 0) + at(0, 1, 0) + at(0, -1, 0) +
                              at(0, 0, 1) + at(0, 0, -1) - 6.0 * phi) / (h * h);
                lap = std::clamp(lap, -2.0 / h, 2.0 / h);
                const double phiEff = phi + h * h * lap / 24.0;
                occupancy = detail::cubeFraction(-phiEff / h, std::abs(gx) / g,
                                                 std::abs(gy) / g, std::abs(gz) / g);
            }
            it.setValue(float(0.5 - occupancy));
        }
    });
    for (auto it = q->beginValueOff(); it; ++it) {
        if (it.isTileValue()) it.setValue(it.getValue() < 0 ? -0.5f : 0.5f);
    }
    q->root().setBackground(0.5f, /*updateChildNodes=*/true);
    return q;
}

/// Level l+1 from level l: mean of the 2×2×2 children (exact for volume fractions).
FloatTree::Ptr restrictOccupancy(const FloatTree& fine)
{
    std::vector<const FloatTree::LeafNodeType*> leafs;
    leafs.reserve(fine.leafCount());
    for (auto it = fine.cbeginLeaf(); it; ++it) leafs.push_back(it.getLeaf());
    std::vector<std::array<float, 64>> coarseValues(leafs.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leafs.size()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const auto& leaf = *leafs[i];
            for (int x = 0; x < 4; ++x)
                for (int y = 0; y < 4; ++y)
                    for (int z = 0; z < 4; ++z) {
                        double sum = 0;
                        for (int c = 0; c < 8; ++c)
                            sum += leaf.getValue(FloatTree::LeafNodeType::coordToOffset(
                                leaf.origin() + Coord(2 * x + (c & 1), 2 * y + ((c >> 1) & 1),
                                                      2 * z + (c >> 2))));
                        coarseValues[i][(x * 4 + y) * 4 + z] = float(sum / 8.0);
                    }
        }
    });
    auto coarse = std::make_shared<FloatTree>(0.5f);
    auto acc = openvdb::tree::ValueAccessor<FloatTree>(*coarse);
    for (std::size_t i = 0; i < leafs.size(); ++i) {
        const Coord origin(leafs[i]->origin().x() >> 1, leafs[i]->origin().y() >> 1,
                           leafs[i]->origin().z() >> 1);
        for (int x = 0; x < 4; ++x)
            for (int y = 0; y < 4; ++y)
                for (int z = 0; z < 4; ++z)
                    acc.setValueOn(origin.offsetBy(x, y, z), coarseValues[i][(x * 4 + y) * 4 + z]);
    }
    openvdb::tools::signedFloodFillWithValues(*coarse, 0.5f, -0.5f);
    return coarse;
}

// ---------------------------------------------------------------------------------------
// Stencils: anti-aliased ball weights for V and shell weights for S, for the radii of one
// level, laid out for a dense block of (8 + 2·reach)^3 voxels (z fastest).

constexpr int kLanes = 8;  // radii are processed in groups of 8 (vectorisable inner loop)

struct Stencil {
    int reach = 0;                 // voxels beyond the 8^3 block that the stencil reads
    int side = 0;                  // 8 + 2·reach
    int numRadii = 0, numGroups = 0;
    std::vector<std::int32_t> offsets;  // per entry: linear offset in the dense block
    std::vector<float> wV, wS;          // per entry: numGroups·kLanes weights
    std::vector<double> sumV, sumS;     // per radius: the stencil's own total (normaliser)
};

Stencil makeStencil(const std::vector<double>& rho)  // radii in voxels of the level
{
    Stencil st;
    st.numRadii = int(rho.size());
    st.numGroups = (st.numRadii + kLanes - 1) / kLanes;
    const double rhoMax = rho.back() + kShellHalfWidth;
    st.reach = int(std::ceil(rhoMax + 1.0));
    st.side = 8 + 2 * st.reach;
    st.sumV.assign(st.numRadii, 0.0);
    st.sumS.assign(st.numRadii, 0.0);
    const int width = st.numGroups * kLanes;
    std::vector<float> v(width), s(width);
    for (int x = -st.reach; x <= st.reach; ++x)
        for (int y = -st.reach; y <= st.reach; ++y)
            for (int z = -st.reach; z <= st.reach; ++z) {
                std::fill(v.begin(), v.end(), 0.f);
                std::fill(s.begin(), s.end(), 0.f);
                bool any = false;
                for (int j = 0; j < st.numRadii; ++j) {
                    const double ball = detail::ballFraction(x, y, z, rho[j]);
                    const double shell =
                        detail::ballFraction(x, y, z, rho[j] + kShellHalfWidth) -
                        detail::ballFraction(x, y, z, rho[j] - kShellHalfWidth);
                    v[j] = float(ball);
                    s[j] = float(shell);
                    st.sumV[j] += v[j];
                    st.sumS[j] += s[j];
                    any = any || ball > 0 || shell > 0;
                }
                if (!any) continue;
                st.offsets.push_back((x * st.side + y) * st.side + z);
                st.wV.insert(st.wV.end(), v.begin(), v.end());
                st.wS.insert(st.wS.end(), s.begin(), s.end());
            }
    return st;
}

/// Stencil sums at one voxel centre: acc[0..numGroups·kLanes) for V and S.
inline void applyStencil(const Stencil& st, const float* occupancy, float* accV, float* accS)
{
    const int width = st.numGroups * kLanes;
    for (int l = 0; l < width; ++l) accV[l] = accS[l] = 0.f;
    const std::size_t n = st.offsets.size();
    const float* wV = st.wV.data();
    const float* wS = st.wS.data();
    for (std::size_t e = 0; e < n; ++e) {
        const float o = occupancy[st.offsets[e]];
        if (o == 0.f) {
            wV += width;
            wS += width;
            continue;
        }
        for (int g = 0; g < st.numGroups; ++g) {
            float* aV = accV + g * kLanes;
            float* aS = accS + g * kLanes;
            for (int l = 0; l < kLanes; ++l) {
                aV[l] += o * wV[l];
                aS[l] += o * wS[l];
            }
            wV += kLanes;
            wS += kLanes;
        }
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
/// surface itself, by the plane model: a ball whose centre is x·r outside a plane holds
/// V̂(x) = 1/2 − 3x/4 + x³/4 of its volume (cap volume). A curvature term (±H r x²) was
/// tried and made the sphere tests worse, so it is not applied.
inline double surfaceVolume(double value, double x)
{
    return value + 0.75 * x - 0.25 * x * x * x;
}

/// As surfaceVolume() for the sphere area: Ŝ(x) = (1 − x)/2 for a plane.
inline double surfaceSphere(double value, double x)
{
    return value + 0.5 * x;
}

} // namespace

VolumeSphereResult computeVolumeSphere(const TriMesh& mesh, const LevelSet& levelSet,
                                       const VolumeSphereOptions& options, Progress* progress)
{
    const auto& radii = options.radii;
    if (radii.empty()) throw InvalidInputError("no radii given");
    for (std::size_t j = 0; j < radii.size(); ++j) {
        if (!(radii[j] > 0) || !std::isfinite(radii[j]))
            throw InvalidInputError("radii must be positive and finite");
        if (j > 0 && !(radii[j] > radii[j - 1]))
            throw InvalidInputError("radii must be strictly ascending");
    }
    if (!(options.minVoxelsPerRadius >= 1))
        throw InvalidInputError("the precision (voxels per radius) must be at least 1");
    const std::size_t nv = mesh.numVertices();
    if (!options.borderDistance.empty() && options.borderDistance.size() != nv)
        throw InvalidInputError("border distances do not match the vertex count");

    const openvdb::FloatGrid& sdf = *levelSet.impl().grid;
    const double h0 = sdf.voxelSize()[0];
    const LevelPlan plan = planLevels(radii, h0, options.minVoxelsPerRadius);
    const int numLevels = int(plan.radiiOf.size());

    VolumeSphereResult result;
    result.radii = radii;
    result.levelOfRadius = plan.levelOf;
    result.numLevels = numLevels;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    result.volume.assign(radii.size(), std::vector<float>(nv, nan));
    if (options.computeSphere) result.sphere.assign(radii.size(), std::vector<float>(nv, nan));

    // Fine index positions of the vertices.
    std::vector<openvdb::Vec3d> fineIndex(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3& p = mesh.points[i];
            fineIndex[i] = sdf.transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
        }
    });

    auto t0 = Clock::now();
    if (progress) progress->start("occupancy", std::size_t(numLevels));
    std::vector<FloatTree::Ptr> occupancy{occupancyFromDistance(sdf)};
    if (progress) progress->advance();
    for (int l = 1; l < numLevels; ++l) {
        occupancy.push_back(restrictOccupancy(*occupancy.back()));
        if (progress) progress->advance();
    }
    if (progress) progress->end();
    result.occupancySeconds = secondsSince(t0);

    for (int level = 0; level < numLevels; ++level) {
        const auto& levelRadii = plan.radiiOf[level];
        if (levelRadii.empty()) continue;
        const double hl = h0 * double(1 << level);
        std::vector<double> rho;
        for (int j : levelRadii) rho.push_back(radii[j] / hl);
        const Stencil stencil = makeStencil(rho);
        const int width = stencil.numGroups * kLanes;
        const int nr = stencil.numRadii;

        // Voxel centres needed: the 8 corners of the level's cell around each vertex.
        t0 = Clock::now();
        const double scale = double(1 << level), shift = 0.5 * (scale - 1.0);
        std::vector<Coord> base(nv);
        std::vector<std::array<float, 3>> frac(nv);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const openvdb::Vec3d u = (fineIndex[i] - openvdb::Vec3d(shift)) / scale;
                const Coord b(int(std::floor(u.x())), int(std::floor(u.y())), int(std::floor(u.z())));
                base[i] = b;
                frac[i] = {float(u.x() - b.x()), float(u.y() - b.y()), float(u.z() - b.z())};
            }
        });
        Int32Tree nodes(-1);
        {
            openvdb::tree::ValueAccessor<Int32Tree> acc(nodes);
            for (std::size_t i = 0; i < nv; ++i)
                for (int c = 0; c < 8; ++c)  // value: a vertex next to the voxel centre
                    acc.setValueOn(base[i].offsetBy(c & 1, (c >> 1) & 1, c >> 2), std::int32_t(i));
        }
        std::vector<Int32Tree::LeafNodeType*> blocks;
        nodes.getNodes(blocks);
        std::int32_t numNodes = 0;
        std::vector<std::int32_t> seedVertex;
        for (auto* leaf : blocks)
            for (auto it = leaf->beginValueOn(); it; ++it) {
                seedVertex.push_back(it.getValue());
                it.setValue(numNodes++);
            }
        result.numNodes += std::size_t(numNodes);

        // Stencil sums at every needed voxel centre, block by block.
        std::vector<float> nodeV(std::size_t(numNodes) * nr), nodeS(std::size_t(numNodes) * nr);
        std::vector<float> nodePhi(numNodes);
        const FloatTree& occ = *occupancy[level];
        const std::size_t denseSize = std::size_t(stencil.side) * stencil.side * stencil.side;
        tbb::enumerable_thread_specific<std::vector<float>> buffers(
            [&] { return std::vector<float>(denseSize); });
        if (progress) progress->start("V and S, level " + std::to_string(level), blocks.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 4), [&](const auto& r) {
            auto& buffer = buffers.local();
            std::vector<float> accV(width), accS(width);
            openvdb::tree::ValueAccessor<const FloatTree> sdfAcc(sdf.tree());
            for (std::size_t b = r.begin(); b < r.end(); ++b) {
                const Int32Tree::LeafNodeType& leaf = *blocks[b];
                const Coord lo = leaf.origin().offsetBy(-stencil.reach);
                const CoordBBox box(lo, lo.offsetBy(stencil.side - 1));
                openvdb::tools::Dense<float, openvdb::tools::LayoutZYX> dense(box, buffer.data());
                openvdb::tools::copyToDense(occ, dense, /*serial=*/true);
                for (float& v : buffer) v = 0.5f - v;
                for (auto it = leaf.cbeginValueOn(); it; ++it) {
                    const Coord local = it.getCoord() - lo;
                    const float* centre =
                        buffer.data() + (std::size_t(local.x()) * stencil.side + local.y()) *
                                            stencil.side + local.z();
                    applyStencil(stencil, centre, accV.data(), accS.data());
                    const std::size_t n = std::size_t(it.getValue());
                    for (int j = 0; j < nr; ++j) {
                        nodeV[n * nr + j] = float(accV[j] / stencil.sumV[j]);
                        nodeS[n * nr + j] = float(accS[j] / stencil.sumS[j]);
                    }
                    // Signed distance of the voxel centre, for the plane correction: on the
                    // fine level straight from the (exact) band, on coarser ones from the mesh.
                    if (level == 0) {
                        nodePhi[n] = sdfAcc.getValue(it.getCoord());
                    } else {
                        const openvdb::Vec3d w =
                            sdf.transform().indexToWorld(fineIndexOf(it.getCoord(), level));
                        nodePhi[n] = float(levelSet.impl().distance->exactSignedDistance(
                            Vec3(w.x(), w.y(), w.z()), seedVertex[n], 2.0 * h0));
                    }
                }
                if (progress) progress->advance();
            }
        });
        if (progress) progress->end();
        result.stencilSeconds += secondsSince(t0);

        // Back to the vertices: trilinear interpolation of the plane-corrected values.
        t0 = Clock::now();
        const double margin = 2.75 * hl + 2.0 * h0;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
            openvdb::tree::ValueAccessor<const Int32Tree> acc(nodes);
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                std::array<std::int32_t, 8> idx;
                std::array<double, 8> w;
                for (int c = 0; c < 8; ++c) {
                    idx[c] = acc.getValue(base[i].offsetBy(c & 1, (c >> 1) & 1, c >> 2));
                    const double fx = (c & 1) ? frac[i][0] : 1.0 - frac[i][0];
                    const double fy = ((c >> 1) & 1) ? frac[i][1] : 1.0 - frac[i][1];
                    const double fz = (c >> 2) ? frac[i][2] : 1.0 - frac[i][2];
                    w[c] = fx * fy * fz;
                }
                for (int k = 0; k < nr; ++k) {
                    const int j = levelRadii[k];
                    if (!options.borderDistance.empty() &&
                        radii[j] + margin > options.borderDistance[i])
                        continue;  // stays NaN: the ball reaches the border
                    double v = 0, s = 0;
                    for (int c = 0; c < 8; ++c) {
                        const std::size_t n = std::size_t(idx[c]);
                        const double x = std::clamp(double(nodePhi[n]) / radii[j], -0.6, 0.6);
                        v += w[c] * surfaceVolume(nodeV[n * nr + k], x);
                        s += w[c] * surfaceSphere(nodeS[n * nr + k], x);
                    }
                    result.volume[j][i] = float(std::clamp(v, 0.0, 1.0));
                    if (options.computeSphere) result.sphere[j][i] = float(std::clamp(s, 0.0, 1.0));
                }
            }
        });
        result.interpolationSeconds += secondsSince(t0);
    }

    for (const auto& column : result.volume)
        for (float v : column) result.numMaskedValues += std::isnan(v) ? 1 : 0;
    return result;
}

} // namespace msii
