#include "patch_line_gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace msii::detail {
namespace {

/// For @p n samples seen from p (coordinates relative to p): the histogram bin of the
/// sample's mean distance d + (tr C − q)/(2d) (d = |x − p| at the centroid, with d at least
/// @p minDistance in the correction), shared linearly between the two nearest bin centres
/// (bin b gets 1 − share, b + 1 gets share; b = @p beyond beyond @p reach2, squared), and
/// the channels a·(1, g, q, g·q) with the coarea factor g = sqrt(1 − mean (û·n)²) from the
/// sample's normal tensor t and q = ûᵀCû from its covariance C (tensors xx, yy, zz, xy, xz,
/// yz). Plain loops over floats, compiled for AVX2 as well (chosen at run time; same
/// results).
__attribute__((target_clones("avx2", "default"))) void binSamples(
    std::size_t n, const float* __restrict x, const float* __restrict y, const float* __restrict z,
    const float* __restrict area, const float* __restrict txx, const float* __restrict tyy,
    const float* __restrict tzz, const float* __restrict txy, const float* __restrict txz,
    const float* __restrict tyz, const float* __restrict cxx, const float* __restrict cyy,
    const float* __restrict czz, const float* __restrict cxy, const float* __restrict cxz,
    const float* __restrict cyz, float px, float py, float pz, float reach2, float invBin, float minDistance,
    std::int32_t beyond, std::int32_t* __restrict bin, float* __restrict share, float* __restrict channels)
{
    for (std::size_t k = 0; k < n; ++k) {
        const float dx = x[k] - px, dy = y[k] - py, dz = z[k] - pz;
        const float d2 = dx * dx + dy * dy + dz * dz;
        const float inv2 = 1.0f / (d2 + 1e-30f);  // branch-free, so that the loop vectorises
        const float tn = dx * dx * txx[k] + dy * dy * tyy[k] + dz * dz * tzz[k] +
                         2.0f * (dx * dy * txy[k] + dx * dz * txz[k] + dy * dz * tyz[k]);
        const float g = std::sqrt(std::max(0.0f, 1.0f - tn * inv2));
        const float q = (dx * dx * cxx[k] + dy * dy * cyy[k] + dz * dz * czz[k] +
                         2.0f * (dx * dy * cxy[k] + dx * dz * cxz[k] + dy * dz * cyz[k])) * inv2;
        const float d = std::sqrt(d2);
        const float mean = d + 0.5f * (cxx[k] + cyy[k] + czz[k] - q) / std::max(d, minDistance);
        // The mean may lie up to 3/4 cell beyond d (a cell's covariance has trace <= 3h²/4,
        // and d is taken at least h/2): such a sample stays in the last bin with a neighbour.
        const float u = std::min(std::max(0.0f, mean * invBin - 0.5f), float(beyond - 1));
        const std::int32_t b = std::min(std::int32_t(u), beyond - 2);
        share[k] = u - float(b);
        bin[k] = d2 < reach2 ? b : beyond;
        const float a = area[k], ag = a * g;
        channels[4 * k] = a, channels[4 * k + 1] = ag, channels[4 * k + 2] = a * q, channels[4 * k + 3] = ag * q;
    }
}

/// Samples near a group of points, as floats relative to the group's origin.
struct Gathered {
    std::vector<float> x, y, z, a;
    std::array<std::vector<float>, 6> t, c;  // normal tensor, covariance
    void clear()
    {
        x.clear(), y.clear(), z.clear(), a.clear();
        for (auto& v : t) v.clear();
        for (auto& v : c) v.clear();
    }
};

/// Cells per axis of a group of points that share one list of nearby samples in the kernel
/// sums: 8, so that copying the samples' 16 numbers costs less than binning them for each
/// point (a larger group makes each point bin more samples beyond its reach).
constexpr int kGroupBits = 3;
/// Samples per run with a bounding box in a group's list (evaluatePoints).
constexpr std::size_t kChunk = 16;

} // namespace

CellGroups groupByCells(const std::vector<Vec3>& points, double h0, int l, int groupBits)
{
    const std::size_t n = points.size();
    CellGroups g;
    g.order.resize(n);
    g.cell.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const CellCoord c0 = cellOf(points[i], h0);
            g.cell[i] = {c0.x >> l, c0.y >> l, c0.z >> l};
            g.order[i] = {morton(std::uint64_t(g.cell[i].x), std::uint64_t(g.cell[i].y),
                                 std::uint64_t(g.cell[i].z)) >> (3 * groupBits),
                          std::uint32_t(i)};
        }
    });
    tbb::parallel_sort(g.order.begin(), g.order.end());
    for (std::size_t i = 0; i < n; ++i)
        if (i == 0 || g.order[i].first != g.order[i - 1].first) g.start.push_back(i);
    g.start.push_back(n);
    return g;
}

void evaluatePoints(const Level& level, const LevelKernel& kernel, double h0,
                    const std::vector<Vec3>& points, const std::vector<char>& skip,
                    std::vector<float>& outP, std::vector<float>& outL, RunContext* progress)
{
    const std::size_t n = points.size();
    const int l = level.index;
    const double h = level.h;
    outP.assign(std::size_t(kernel.numRadii) * n, 0.0f);
    outL.assign(std::size_t(kernel.numRadii) * n, 0.0f);
    const CellGroups groups = groupByCells(points, h0, l, kGroupBits);
    const auto& order = groups.order;
    const auto& groupStart = groups.start;
    const auto& cell = groups.cell;

    const int reachCells = kernel.reachCells, numBins = kernel.numBins, nr = kernel.numRadii;
    const std::int64_t groupCells = std::int64_t(1) << kGroupBits;
    const double groupSide = double(groupCells) * h, reach2 = kernel.reach * kernel.reach;
    const std::array<double, 6> groupBox{0, 0, 0, groupSide, groupSide, groupSide};  // about (ox, oy, oz)
    // A run of samples is skipped only if its box lies beyond reach with a margin against
    // rounding: the samples binned, and their order, are those of the whole list.
    const float skipBeyond2 = 1.001f * float(reach2);
    if (progress) progress->start("P and L, level " + std::to_string(l), groupStart.size() - 1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupStart.size() - 1), [&](const auto& range) {
        Gathered near;
        std::vector<std::int32_t> bins;
        std::vector<float> share;
        std::vector<float> channels;  // kChannels per sample
        std::vector<std::array<float, 6>> chunkBox;  // min x, y, z, max x, y, z
        std::vector<Channels> hist(static_cast<std::size_t>(numBins) + 1);
        for (std::size_t g = range.begin(); g < range.end(); ++g) {
            const std::size_t begin = groupStart[g], end = groupStart[g + 1];
            const CellCoord& c0 = cell[order[begin].second];
            const std::int64_t gx = c0.x & ~(groupCells - 1), gy = c0.y & ~(groupCells - 1), gz = c0.z & ~(groupCells - 1);
            const double ox = double(gx - (kOffset >> l)) * h, oy = double(gy - (kOffset >> l)) * h,
                         oz = double(gz - (kOffset >> l)) * h;
            near.clear();
            const std::int64_t lo[3] = {gx - reachCells, gy - reachCells, gz - reachCells};
            const std::int64_t hi[3] = {gx + groupCells - 1 + reachCells, gy + groupCells - 1 + reachCells,
                                        gz + groupCells - 1 + reachCells};
            forEachSampleInCells(level, lo, hi, [&](std::uint32_t s) {
                // Only samples within reach of the group's box [0, groupSide)³ (the blocks
                // bring more).
                const double x = level.cx[s] - ox, y = level.cy[s] - oy, z = level.cz[s] - oz;
                if (squaredDistanceToBox(x, y, z, groupBox) >= reach2) return;
                near.x.push_back(float(x));
                near.y.push_back(float(y));
                near.z.push_back(float(z));
                near.a.push_back(level.area[s]);
                for (std::size_t c = 0; c < 6; ++c) {
                    near.t[c].push_back(level.tensor[c][s]);
                    near.c[c].push_back(level.covariance[c][s]);
                }
            });
            const std::size_t ns = near.x.size();
            bins.resize(ns), share.resize(ns), channels.resize(kChannels * ns);
            // Bounding boxes of runs of kChunk samples (close together in Morton order): a
            // point skips the runs wholly beyond its reach (about a fifth of the list).
            const std::size_t numChunks = (ns + kChunk - 1) / kChunk;
            chunkBox.resize(numChunks);
            for (std::size_t c = 0; c < numChunks; ++c) {
                auto& box = chunkBox[c];
                box = {near.x[c * kChunk], near.y[c * kChunk], near.z[c * kChunk],
                       near.x[c * kChunk], near.y[c * kChunk], near.z[c * kChunk]};
                for (std::size_t k = c * kChunk; k < std::min(ns, (c + 1) * kChunk); ++k) {
                    box[0] = std::min(box[0], near.x[k]), box[3] = std::max(box[3], near.x[k]);
                    box[1] = std::min(box[1], near.y[k]), box[4] = std::max(box[4], near.y[k]);
                    box[2] = std::min(box[2], near.z[k]), box[5] = std::max(box[5], near.z[k]);
                }
            }
            for (std::size_t q = begin; q < end; ++q) {
                const std::uint32_t i = order[q].second;
                if (skip[i]) continue;
                const float px = float(points[i].x - ox), py = float(points[i].y - oy), pz = float(points[i].z - oz);
                const auto beyondReach = [&](std::size_t c) {
                    return squaredDistanceToBox(px, py, pz, chunkBox[c]) > skipBeyond2;
                };
                std::fill(hist.begin(), hist.end(), Channels{});
                // Runs of consecutive chunks within reach; the chunk that ends a run is
                // beyond it and is stepped over (c + 1) without a second test.
                for (std::size_t c = 0; c < numChunks; ++c) {
                    if (beyondReach(c)) continue;
                    const std::size_t first = c * kChunk;
                    while (c < numChunks && !beyondReach(c)) ++c;
                    const std::size_t count = std::min(ns, c * kChunk) - first;
                    binSamples(count, near.x.data() + first, near.y.data() + first, near.z.data() + first,
                               near.a.data() + first, near.t[0].data() + first, near.t[1].data() + first,
                               near.t[2].data() + first, near.t[3].data() + first, near.t[4].data() + first,
                               near.t[5].data() + first, near.c[0].data() + first, near.c[1].data() + first,
                               near.c[2].data() + first, near.c[3].data() + first, near.c[4].data() + first,
                               near.c[5].data() + first, px, py, pz, float(reach2), float(1.0 / kernel.bin),
                               float(0.5 * h), numBins, bins.data(), share.data(),
                               channels.data());
                    for (std::size_t s = 0; s < count; ++s) {
                        if (bins[s] == numBins) continue;  // beyond reach
                        Channels* at = hist.data() + bins[s];
                        const Channels v = loadChannels(channels.data() + kChannels * s), vw = v * share[s];
                        at[0] += v - vw;  // bin b
                        at[1] += vw;      // bin b + 1
                    }
                }
                double inside = 0;  // area of the bins below `counted`
                int counted = 0;
                for (int k = 0; k < nr; ++k) {
                    const auto [firstP, lastP] = kernel.patchBins[std::size_t(k)];
                    if (firstP < counted) inside = 0, counted = 0;  // not expected: radii ascend
                    for (; counted < firstP; ++counted) inside += double(hist[std::size_t(counted)][0]);
                    // Bins [firstP, lastP) hold the kernel's support for P and L alike; in
                    // pairs of bins: P in the channels 0 and 2, L in 1 and 3.
                    const float* wk = kernel.weights.data() + std::size_t(k) * kChannels * kernel.numBins;
                    Channels even{}, odd{};
                    for (int b = firstP; b < lastP; b += 2) {
                        even += hist[std::size_t(b)] * loadChannels(wk + kChannels * std::size_t(b));
                        odd += hist[std::size_t(b) + 1] * loadChannels(wk + kChannels * (std::size_t(b) + 1));
                    }
                    const double sumP = inside + double(even[0] + even[2]) + double(odd[0] + odd[2]);
                    const double sumL = double(even[1] + even[3]) + double(odd[1] + odd[3]);
                    outP[std::size_t(k) * n + i] = float(sumP);
                    outL[std::size_t(k) * n + i] = float(sumL);
                }
            }
            if (progress) progress->advance();
        }
    });
    if (progress) progress->end();
}

} // namespace msii::detail
