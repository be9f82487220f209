#pragma once
/// @file patch_line_gather.h
/// @brief Steps 3 and 5 of P and L (msii/invariants/patch_line.h): the kernel sums. Per point
/// and level, one pass over the samples within reach builds the histograms over the distance
/// (each sample binned at its mean distance, the second-order quadrature of its spread) and
/// weighs them with the level's kernel (evaluatePoints); the grouping of points by cells and
/// the walk over a level's blocks, which the fit (step 6) uses too.
/// Private to the engine (patch_line.cpp and its parts).

#include "patch_line_kernels.h"
#include "patch_line_samples.h"

#include <msii/core/run_context.h>
#include <msii/core/vec3.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace msii::detail {

/// Calls @p visit(s) for the samples of @p level in the 8³-cell blocks that overlap the
/// level-l cells [lo, hi] (per axis, inclusive).
template <class Visit>
void forEachSampleInCells(const Level& level, const std::int64_t lo[3], const std::int64_t hi[3],
                          Visit&& visit)
{
    for (std::int64_t bx = std::max<std::int64_t>(0, lo[0]) >> 3; bx <= hi[0] >> 3; ++bx)
        for (std::int64_t by = std::max<std::int64_t>(0, lo[1]) >> 3; by <= hi[1] >> 3; ++by)
            for (std::int64_t bz = std::max<std::int64_t>(0, lo[2]) >> 3; bz <= hi[2] >> 3; ++bz) {
                const auto it = level.blocks.find(morton(std::uint64_t(bx), std::uint64_t(by), std::uint64_t(bz)));
                if (it == level.blocks.end()) continue;
                for (std::uint32_t s = it->second.first; s < it->second.second; ++s) visit(s);
            }
}

/// Points in groups of (2^groupBits)³ cells of level l (Morton order), so that a group can
/// share one gathered list of nearby samples: order[k] = (group key, point), groups
/// [start[g], start[g + 1]), and each point's level-l cell.
struct CellGroups {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order;
    std::vector<std::size_t> start;
    std::vector<CellCoord> cell;
};

/// @p points grouped by cells of level @p l, (2^@p groupBits)³ cells a group.
CellGroups groupByCells(const std::vector<Vec3>& points, double h0, int l, int groupBits = 2);

/// Unnormalised P ∗ K and L ∗ K at points, for the radii of one level: [k·n + q] for radius
/// k and point q of n; with the check, its differences of P̂ and L̂ between the default and
/// the narrow kernels, the larger of those at r and halfway to the radius below.
struct KernelSums {
    std::vector<float> patch, line;
    std::vector<float> checkPatch, checkLine;  ///< empty without the check
    /// Fitted to vertices (patch_line_fit.h), with the check: the fit's residuals of patch and
    /// line; else empty.
    std::vector<float> patchResidual, lineResidual;
    double checkCpuSeconds = 0;  ///< the check's kernels' time, summed over threads
};

/// The kernel sums (KernelSums) of one level at @p points, into @p out.
/// Each sample stands for its area spread around its centroid with covariance C: a
/// second-order quadrature, ∫ f(|x − p|) dA ≈ a (f(d) + ½ (f″(d) q + f′(d) s)), with q =
/// ûᵀCû and s = (tr C − q)/d (the Hessian of f(|x − p|) is f″ ûûᵀ + f′ (I − ûûᵀ)/d). The
/// f′ term is the shift of the mean distance, d + s/2, where the sample is binned; the f″
/// term goes into channels of its own.
/// Points whose @p skip is set are left alone. Points go in groups of 2^kGroupBits cells per
/// axis that share one gathered list of nearby samples; each point bins the runs of kChunk
/// samples of the list whose bounding box comes within its reach (about 4/5 of the list on
/// the finest level of the benchmark surface, of which 2/3 lie within reach).
void evaluatePoints(const Level& level, const LevelKernel& kernel, double h0,
                    const std::vector<Vec3>& points, const std::vector<char>& skip, KernelSums& out,
                    RunContext* progress);

} // namespace msii::detail
