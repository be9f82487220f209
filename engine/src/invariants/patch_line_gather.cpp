#include "patch_line_gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <chrono>
#include <mutex>

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
/// yz). Plain loops over floats, compiled for AVX-512 and AVX2 as well (chosen at run time;
/// the same results: the file has no fused multiply-adds, which the AVX-512 variant would
/// have).
__attribute__((target_clones("avx512f", "avx2", "default"))) void binSamples(
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
    void resize(std::size_t n)
    {
        x.resize(n), y.resize(n), z.resize(n), a.resize(n);
        for (auto& v : t) v.resize(n);
        for (auto& v : c) v.resize(n);
    }
};

/// Cells per axis of a group of points that share one list of nearby samples in the kernel
/// sums: 8, so that copying the samples' 16 numbers costs less than binning them for each
/// point (a larger group makes each point bin more samples beyond its reach).
constexpr int kGroupBits = 3;
/// Samples per run with a bounding box in a group's list (evaluatePoints).
constexpr std::size_t kChunk = 16;

/// Bounding boxes (min x, y, z, max x, y, z) of the runs of kChunk samples of @p near
/// (close together in Morton order), so that a point can skip the runs wholly beyond its reach.
void boundChunks(const Gathered& near, std::vector<std::array<float, 6>>& chunkBox)
{
    const std::size_t ns = near.x.size();
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
}

/// A group of points: its first cell on the level and the origin that its gathered samples
/// and its points are measured from (floats relative to it keep their precision).
struct GroupOrigin {
    std::int64_t gx, gy, gz;
    double ox, oy, oz;
};

/// Per-thread buffers of evaluatePoints.
struct GatherScratch {
    Gathered near;
    std::vector<std::uint32_t> picked;  // the level's samples in near, in order
    std::vector<std::array<float, 6>> chunkBox;  // min x, y, z, max x, y, z
    std::vector<std::int32_t> bins;
    std::vector<float> share;
    std::vector<float> channels;  // kChannels per sample
    std::vector<Channels> hist;   // numBins + 2: the last two for the samples beyond reach
};

/// The kernel sums of one level at points in groups of cells (evaluatePoints): what every
/// group shares, the samples gathered for a group, and the sums at each of its points.
class LevelGather {
public:
    LevelGather(const Level& level, const LevelKernel& kernel)
        : mLevel(level), mKernel(kernel), mL(level.index), mH(level.h), mReachCells(kernel.reachCells),
          mNumBins(kernel.numBins), mNumRadii(kernel.numRadii), mGroupCells(std::int64_t(1) << kGroupBits),
          mGroupSide(double(mGroupCells) * mH), mReach2(kernel.reach * kernel.reach),
          mGroupBox{0, 0, 0, mGroupSide, mGroupSide, mGroupSide},
          // A run of samples is skipped only if its box lies beyond reach with a margin
          // against rounding: the samples binned, and their order, are those of the whole list.
          mSkipBeyond2(1.001f * float(mReach2))
    {
    }

    /// Buffers for one thread.
    GatherScratch scratch() const
    {
        GatherScratch s;
        s.hist.resize(static_cast<std::size_t>(mNumBins) + 2);
        return s;
    }

    /// The group whose first point lies in the level-l cell @p c0.
    GroupOrigin groupOrigin(const CellCoord& c0) const
    {
        GroupOrigin g;
        g.gx = c0.x & ~(mGroupCells - 1), g.gy = c0.y & ~(mGroupCells - 1), g.gz = c0.z & ~(mGroupCells - 1);
        g.ox = double(g.gx - (kOffset >> mL)) * mH, g.oy = double(g.gy - (kOffset >> mL)) * mH,
        g.oz = double(g.gz - (kOffset >> mL)) * mH;
        return g;
    }

    /// The samples within reach of the group's box [0, groupSide)³, relative to its origin,
    /// into @p near, and the bounding boxes of their runs.
    void gather(const GroupOrigin& g, GatherScratch& scratch) const
    {
        // Which samples first, then each of their numbers in a loop of its own (the same
        // values in the same order as pushing them sample by sample, at a fraction of the cost).
        std::vector<std::uint32_t>& picked = scratch.picked;
        picked.clear();
        // The 8³-cell blocks around the group: one wholly beyond reach of its box is not
        // looked up, one wholly within reach is taken whole, the others sample by sample
        // (with margins against rounding, the samples taken are those of the test alone).
        const std::int64_t g0[3] = {g.gx, g.gy, g.gz};
        std::int64_t lo[3], hi[3];
        for (int a = 0; a < 3; ++a)
            lo[a] = std::max<std::int64_t>(0, g0[a] - mReachCells) >> 3, hi[a] = (g0[a] + mGroupCells - 1 + mReachCells) >> 3;
        const auto gaps = [&](int a, std::int64_t b) {  // block b's nearest and farthest gap to the box, axis a
            const double b0 = double(8 * b - g0[a]) * mH, b1 = b0 + 8 * mH;
            const double nearGap = std::max({0.0, b0 - mGroupSide, -b1}), farGap = std::max({0.0, b1 - mGroupSide, -b0});
            return std::pair<double, double>(nearGap * nearGap, farGap * farGap);
        };
        const double beyond2 = mReach2 * (1 + 1e-6), within2 = mReach2 * (1 - 1e-6);
        for (std::int64_t bx = lo[0]; bx <= hi[0]; ++bx) {
            const auto [nx, fx] = gaps(0, bx);
            for (std::int64_t by = lo[1]; by <= hi[1]; ++by) {
                const auto [ny, fy] = gaps(1, by);
                if (nx + ny >= beyond2) continue;
                for (std::int64_t bz = lo[2]; bz <= hi[2]; ++bz) {
                    const auto [nz, fz] = gaps(2, bz);
                    if (nx + ny + nz >= beyond2) continue;
                    const auto it = mLevel.blocks.find(morton(std::uint64_t(bx), std::uint64_t(by), std::uint64_t(bz)));
                    if (it == mLevel.blocks.end()) continue;
                    const auto [first, last] = it->second;
                    if (fx + fy + fz < within2) {
                        for (std::uint32_t s = first; s < last; ++s) picked.push_back(s);
                        continue;
                    }
                    for (std::uint32_t s = first; s < last; ++s) {
                        const double x = mLevel.cx[s] - g.ox, y = mLevel.cy[s] - g.oy, z = mLevel.cz[s] - g.oz;
                        if (squaredDistanceToBox(x, y, z, mGroupBox) < mReach2) picked.push_back(s);
                    }
                }
            }
        }
        const std::size_t n = picked.size();
        Gathered& near = scratch.near;
        near.resize(n);
        const std::uint32_t* at = picked.data();
        for (std::size_t k = 0; k < n; ++k) near.x[k] = float(mLevel.cx[at[k]] - g.ox);
        for (std::size_t k = 0; k < n; ++k) near.y[k] = float(mLevel.cy[at[k]] - g.oy);
        for (std::size_t k = 0; k < n; ++k) near.z[k] = float(mLevel.cz[at[k]] - g.oz);
        for (std::size_t k = 0; k < n; ++k) near.a[k] = mLevel.area[at[k]];
        for (std::size_t c = 0; c < 6; ++c) {
            const float* tensor = mLevel.tensor[c].data();
            const float* covariance = mLevel.covariance[c].data();
            float* t = near.t[c].data();
            float* cv = near.c[c].data();
            for (std::size_t k = 0; k < n; ++k) t[k] = tensor[at[k]];
            for (std::size_t k = 0; k < n; ++k) cv[k] = covariance[at[k]];
        }
        const std::size_t ns = near.x.size();
        scratch.bins.resize(ns), scratch.share.resize(ns), scratch.channels.resize(kChannels * ns);
        boundChunks(near, scratch.chunkBox);
    }

    /// The histograms over the distance from the point (px, py, pz) (relative to the
    /// group's origin) of the gathered samples within its reach, into scratch.hist.
    void histogram(float px, float py, float pz, GatherScratch& scratch) const
    {
        const Gathered& near = scratch.near;
        const std::vector<std::array<float, 6>>& chunkBox = scratch.chunkBox;
        std::vector<Channels>& hist = scratch.hist;
        const std::size_t ns = near.x.size(), numChunks = chunkBox.size();
        const int numBins = mNumBins;
        const auto beyondReach = [&](std::size_t c) {
            return squaredDistanceToBox(px, py, pz, chunkBox[c]) > mSkipBeyond2;
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
                       near.c[5].data() + first, px, py, pz, float(mReach2), float(1.0 / mKernel.bin),
                       float(0.5 * mH), numBins, scratch.bins.data(), scratch.share.data(),
                       scratch.channels.data());
            // Samples beyond reach (bin numBins) go to two bins of their own that no kernel
            // reads: a branch here would be mispredicted for about a fifth of them.
            for (std::size_t s = 0; s < count; ++s) {
                Channels* at = hist.data() + scratch.bins[s];
                const Channels v = loadChannels(scratch.channels.data() + kChannels * s), vw = v * scratch.share[s];
                at[0] += v - vw;  // bin b
                at[1] += vw;      // bin b + 1
            }
        }
    }

    /// The histograms @p hist weighed with the kernel of each radius k of the level: P and
    /// L at point @p i of @p n, into out.patch and out.line at [k·n + i].
    void weigh(const std::vector<Channels>& hist, std::size_t i, std::size_t n, KernelSums& out) const
    {
        double inside = 0;  // area of the bins below `counted`
        int counted = 0;
        for (int k = 0; k < mNumRadii; ++k) {
            const auto [sumP, sumL] = weighRow(hist, k, inside, counted);
            out.patch[std::size_t(k) * n + i] = float(sumP);
            out.line[std::size_t(k) * n + i] = float(sumL);
        }
    }

    /// The check (docs/method.md, Exact where the kernels blur): per radius k, the larger
    /// |P̂ − P̂_narrow| and |L̂ − L̂_narrow| at r and halfway to the radius below, into
    /// out.checkPatch and out.checkLine at [k·n + i] (after weigh()).
    void check(const std::vector<Channels>& hist, std::size_t i, std::size_t n, KernelSums& out) const
    {
        double inside = 0;
        int counted = 0;
        for (int k = 0; k < mNumRadii; ++k) {
            const int row = mNumRadii + 3 * k;
            const auto [midP, midL] = weighRow(hist, row, inside, counted);
            const auto [midNarrowP, midNarrowL] = weighRow(hist, row + 1, inside, counted);
            const auto [narrowP, narrowL] = weighRow(hist, row + 2, inside, counted);
            const std::size_t at = std::size_t(k) * n + i;
            const double p = double(out.patch[at]), l = double(out.line[at]);
            const std::size_t mid = std::size_t(row), r = std::size_t(row + 2);
            out.checkPatch[at] = float(std::max(std::abs(midP - midNarrowP) * mKernel.patchScale[mid],
                                                std::abs(p - narrowP) * mKernel.patchScale[r]));
            out.checkLine[at] = float(std::max(std::abs(midL - midNarrowL) * mKernel.lineScale[mid],
                                               std::abs(l - narrowL) * mKernel.lineScale[r]));
        }
    }

private:
    /// Row @p row of the kernel applied to @p hist: (P, L). @p inside and @p counted keep the
    /// running sum of the areas below the rows' supports (from 0 again where a row's support
    /// starts below the last one's).
    std::pair<double, double> weighRow(const std::vector<Channels>& hist, int row, double& inside, int& counted) const
    {
        const auto [firstP, lastP] = mKernel.patchBins[std::size_t(row)];
        if (firstP < counted) inside = 0, counted = 0;
        for (; counted < firstP; ++counted) inside += double(hist[std::size_t(counted)][0]);
        // Bins [firstP, lastP) hold the kernel's support for P and L alike; in pairs of
        // bins: P in the channels 0 and 2, L in 1 and 3.
        const float* wk = mKernel.weights.data() + std::size_t(row) * kChannels * mKernel.numBins;
        Channels even{}, odd{};
        for (int b = firstP; b < lastP; b += 2) {
            even += hist[std::size_t(b)] * loadChannels(wk + kChannels * std::size_t(b));
            odd += hist[std::size_t(b) + 1] * loadChannels(wk + kChannels * (std::size_t(b) + 1));
        }
        const double sumP = inside + double(even[0] + even[2]) + double(odd[0] + odd[2]);
        const double sumL = double(even[1] + even[3]) + double(odd[1] + odd[3]);
        return {sumP, sumL};
    }

    const Level& mLevel;
    const LevelKernel& mKernel;
    const int mL;
    const double mH;
    const int mReachCells, mNumBins, mNumRadii;
    const std::int64_t mGroupCells;
    const double mGroupSide, mReach2;
    const std::array<double, 6> mGroupBox;  // about the group's origin
    const float mSkipBeyond2;
};

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
                    const std::vector<Vec3>& points, const std::vector<char>& skip, KernelSums& out,
                    RunContext* progress)
{
    const std::size_t n = points.size(), size = std::size_t(kernel.numRadii) * n;
    out.patch.assign(size, 0.0f);
    out.line.assign(size, 0.0f);
    out.checkPatch.assign(kernel.check() ? size : 0, 0.0f);
    out.checkLine.assign(out.checkPatch.size(), 0.0f);
    out.checkCpuSeconds = 0;
    const CellGroups groups = groupByCells(points, h0, level.index, kGroupBits);
    const auto& order = groups.order;
    const auto& groupStart = groups.start;
    const LevelGather gather(level, kernel);
    if (progress) progress->start("P and L, level " + std::to_string(level.index), groupStart.size() - 1);
    const bool check = kernel.check();
    std::mutex checkMutex;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupStart.size() - 1), [&](const auto& range) {
        GatherScratch scratch = gather.scratch();
        double checkSeconds = 0;  // of this range's check
        for (std::size_t g = range.begin(); g < range.end(); ++g) {
            const std::size_t begin = groupStart[g], end = groupStart[g + 1];
            const GroupOrigin origin = gather.groupOrigin(groups.cell[order[begin].second]);
            gather.gather(origin, scratch);
            for (std::size_t q = begin; q < end; ++q) {
                const std::uint32_t i = order[q].second;
                if (skip[i]) continue;
                const float px = float(points[i].x - origin.ox), py = float(points[i].y - origin.oy),
                            pz = float(points[i].z - origin.oz);
                gather.histogram(px, py, pz, scratch);
                gather.weigh(scratch.hist, i, n, out);
                if (!check) continue;
                const auto start = std::chrono::steady_clock::now();
                gather.check(scratch.hist, i, n, out);
                checkSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            }
            if (progress) progress->advance();
        }
        const std::lock_guard<std::mutex> lock(checkMutex);
        out.checkCpuSeconds += checkSeconds;
    });
    if (progress) progress->end();
}

} // namespace msii::detail
