#include "patch_line_exact.h"

#include "exact_triangles.h"
#include "patch_line_samples.h"  // morton

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_set>
#include <utility>
#include <vector>

namespace msii::detail {
namespace {

/// Fixed-point sums: integers add in any order to the same total, so the triangles need no
/// fixed order, and a cell's area counts the same whether it is added whole or triangle by
/// triangle (its cells differ between a tile and the whole mesh).
__extension__ typedef __int128 Fixed;
/// Units per R² of area and per R of length: 2⁵⁰, so that one term (at most π R² or 2π R)
/// fits an int64 and rounds by 1e-15 of it; 128 bits hold any total.
constexpr double kFixedUnits = 1125899906842624.0;

/// The flagged radii of one vertex and its fixed-point sums at them, per flagged radius k
/// (radius index flagged[k]).
class FlaggedSums {
public:
    explicit FlaggedSums(const std::vector<double>& radii)
        : mRadii(radii), mAreaUnits(kFixedUnits / (radii.back() * radii.back())), mArcUnits(kFixedUnits / radii.back())
    {
    }

    /// Starts a vertex whose flagged radii are @p flagged (ascending radius indices, at
    /// least one).
    void start(const std::vector<std::uint32_t>& flagged)
    {
        mFlagged = flagged;
        const std::size_t n = flagged.size();
        mWhole.assign(n, 0), mArea.assign(n, 0), mArc.assign(n, 0);
        mSquared.resize(n + 1);  // and +∞ after the last, so that the counts below need no bound
        for (std::size_t k = 0; k < n; ++k) mSquared[k] = mRadii[flagged[k]] * mRadii[flagged[k]];
        mSquared[n] = INFINITY;
        // The counts below by a table over r², of buckets narrower than the nearest two
        // flagged radii² are apart (at most kMaxBuckets): a lookup and a step or none.
        double gap = mSquared[0];
        for (std::size_t k = 1; k < n; ++k) gap = std::min(gap, mSquared[k] - mSquared[k - 1]);
        const double top = mSquared[n - 1];
        const std::size_t buckets = gap > 0 ? std::size_t(std::min(double(kMaxBuckets), std::ceil(top / gap)) + 1) : 1;
        mPerSquared = double(buckets) / top;
        mBucket.resize(buckets + 1);
        std::size_t k = 0;
        for (std::size_t b = 0; b <= buckets; ++b) {
            while (k < n && mSquared[k] * mPerSquared < double(b)) ++k;
            mBucket[b] = std::uint32_t(k);
        }
        mLastBucket = double(buckets);
    }

    std::size_t size() const { return mFlagged.size(); }
    double largestRadius() const { return mRadii[mFlagged.back()]; }
    double radius(std::size_t k) const { return mRadii[mFlagged[k]]; }
    /// The first flagged radius k with r_k² > @p x2 (size() if none).
    std::size_t firstAbove(double x2) const
    {
        std::size_t k = guess(x2);
        while (mSquared[k] <= x2) ++k;
        return k;
    }
    /// The first flagged radius k with r_k² >= @p x2 (size() if none).
    std::size_t firstAtLeast(double x2) const
    {
        std::size_t k = guess(x2);
        while (mSquared[k] < x2) ++k;
        return k;
    }

    /// For @p m items (at most kMaxItems) with nearest and farthest squared distances
    /// @p near2[j] <= @p far2[j]: first[j] = firstAbove(near2[j]) and last[j] =
    /// firstAtLeast(far2[j]), as counts of the radii² below. Every item counts the radii at or
    /// below the smallest near2, and none at or beyond the largest far2, so that only the few
    /// radii between are compared (loops that vectorise). Returns those bounds,
    /// {firstAbove(min near2), firstAtLeast(max far2)}.
    std::pair<std::size_t, std::size_t> count(std::size_t m, const double* near2, const double* far2,
                                              std::int32_t* first, std::int32_t* last) const
    {
        // The extremes in four lanes (a minimum is exact in any order) and the counts in
        // doubles, converted at the end: loops that vectorise, where a single running minimum
        // and counts in integers compared from doubles do not.
        double low[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, high[4] = {0, 0, 0, 0};
        std::size_t j = 0;
        for (; j + 4 <= m; j += 4)
            for (std::size_t l = 0; l < 4; ++l) {
                low[l] = near2[j + l] < low[l] ? near2[j + l] : low[l];
                high[l] = far2[j + l] > high[l] ? far2[j + l] : high[l];
            }
        for (; j < m; ++j) low[0] = std::min(low[0], near2[j]), high[0] = std::max(high[0], far2[j]);
        const double lowest = std::min(std::min(low[0], low[1]), std::min(low[2], low[3]));
        const double highest = std::max(std::max(high[0], high[1]), std::max(high[2], high[3]));
        const std::size_t below = firstAbove(lowest), upTo = firstAtLeast(highest);
        double countFirst[kMaxItems], countLast[kMaxItems];
        for (j = 0; j < m; ++j) countFirst[j] = double(below), countLast[j] = double(below);
        for (std::size_t k = below; k < upTo; ++k) {
            const double r2 = mSquared[k];
            for (j = 0; j < m; ++j) {
                countFirst[j] += r2 <= near2[j] ? 1.0 : 0.0;
                countLast[j] += r2 < far2[j] ? 1.0 : 0.0;
            }
        }
        for (j = 0; j < m; ++j) first[j] = std::int32_t(countFirst[j]), last[j] = std::int32_t(countLast[j]);
        return {below, upTo};
    }

    /// The fixed-point area of @p area.
    Fixed areaUnits(double area) const { return fixed(area * mAreaUnits); }
    /// Area @p area (fixed point) whole inside flagged radius k and every larger one.
    void addWhole(std::size_t k, Fixed area) { mWhole[k] += area; }
    /// A triangle cut by the sphere of flagged radius k.
    void addCut(std::size_t k, double area, double arc)
    {
        mArea[k] += fixed(area * mAreaUnits);
        mArc[k] += fixed(arc * mArcUnits);
    }

    /// P̂ and L̂ at the flagged radii, into patch[j][i] and line[j][i] (where not empty).
    void store(std::size_t i, std::vector<std::vector<float>>& patch, std::vector<std::vector<float>>& line) const
    {
        Fixed whole = 0;
        for (std::size_t k = 0; k < mFlagged.size(); ++k) {
            whole += mWhole[k];
            const std::size_t j = mFlagged[k];
            const double r = mRadii[j];
            if (!patch.empty()) patch[j][i] = float(double(whole + mArea[k]) / mAreaUnits / (kPi * r * r));
            if (!line.empty()) line[j][i] = float(double(mArc[k]) / mArcUnits / (2 * kPi * r));
        }
    }

    /// The most items count() takes at once.
    static constexpr std::size_t kMaxItems = 64;

private:
    static constexpr double kMaxBuckets = 4096;
    /// The flagged radii with r_k² · mPerSquared below the bucket of @p x2: none of them is at
    /// or above x2 (the product is monotone in r_k²), and at most one more is below it
    /// where the buckets are narrower than the radii² are apart, so the callers step up to
    /// the exact count, mostly once or not at all.
    std::size_t guess(double x2) const
    {
        // (through a 32-bit integer: one instruction, where a 64-bit unsigned one is several)
        return mBucket[std::size_t(std::int32_t(std::min(x2 * mPerSquared, mLastBucket)))];  // x2 >= 0
    }

    /// Rounded to the nearest unit (any fixed rule will do: only its sums must agree).
    static Fixed fixed(double x) { return Fixed(std::int64_t(x < 0 ? x - 0.5 : x + 0.5)); }

    const std::vector<double>& mRadii;
    const double mAreaUnits, mArcUnits;
    std::vector<std::uint32_t> mFlagged;
    std::vector<double> mSquared;  ///< of the flagged radii, and +∞
    double mPerSquared = 0;        ///< buckets per unit of r²
    double mLastBucket = 0;
    std::vector<std::uint32_t> mBucket;  ///< per bucket b: the first flagged k with r_k² ≥ b / mPerSquared, about
    std::vector<Fixed> mWhole, mArea, mArc;
};

/// Triangles binned by centroid into cells of edge c, and these into blocks of 4 × 4 × 4
/// cells, each block and each cell with the box around its triangles and their area, so that
/// a block or cell that no flagged sphere cuts is added whole and the walk about a vertex
/// opens only the blocks along the flagged spheres, and in them only the cells along them
/// (a block's cells are about a sphere's radius long: its own would be all the ball's
/// triangles). A cell's triangles are consecutive slots, each with its bounding sphere and
/// fixed-point area in arrays of one number each (the walk's tests vectorise).
class CellGrid {
public:
    /// A block or a cell: the box around its triangles, their fixed-point area, and its cells
    /// (a block's) or slots (a cell's) [first, last).
    struct Box {
        Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
        Fixed area = 0;
        std::uint32_t first = 0, last = 0;
    };
    /// The slots: per triangle its bounding sphere's centre and radius, fixed-point area and corners.
    struct Slots {
        std::vector<double> x, y, z, radius;
        std::vector<std::int64_t> area;
        /// The triangle's corners, coordinate by coordinate: corner[3 · c + a] holds axis a of
        /// corner c (loops over a run of slots vectorise).
        std::array<std::vector<double>, 9> corner;
        Vec3 at(std::size_t s, int c) const { return {corner[3 * c][s], corner[3 * c + 1][s], corner[3 * c + 2][s]}; }
    };

    /// The triangles @p triangles of @p mesh (with @p frames) in cells of edge @p cellSize.
    CellGrid(const TriMesh& mesh, const std::vector<TriangleFrame>& frames, const std::vector<std::uint32_t>& triangles,
             double cellSize, const FlaggedSums& units)
        : mCell(cellSize)
    {
        Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
        for (const std::uint32_t t : triangles) {
            mMaxRadius = std::max(mMaxRadius, frames[t].boundingRadius);
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], frames[t].centroid[a]);
                hi[a] = std::max(hi[a], frames[t].centroid[a]);
            }
        }
        mOrigin = lo;
        // Blocks' columns are indexed densely: at most ~1e7 of them, with cells grown if need be.
        while ((hi.x - lo.x) / (kBlock * mCell) * ((hi.y - lo.y) / (kBlock * mCell)) > 1e7) mCell *= 2;
        for (int a = 0; a < 3; ++a) mCount[a] = std::int64_t(std::floor((hi[a] - lo[a]) / (kBlock * mCell))) + 1;
        // Sorted by block, then by cell within the block (neighbours in space, neighbours in
        // memory).
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(triangles.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size()), [&](const auto& range) {
            for (std::size_t s = range.begin(); s < range.end(); ++s) {
                std::int64_t c[3];
                for (int a = 0; a < 3; ++a) c[a] = cellIndex(a, frames[triangles[s]].centroid[a]);
                const std::uint64_t within = std::uint64_t((c[0] & 3) << 4 | (c[1] & 3) << 2 | (c[2] & 3));
                keyed[s] = {blockKey(c[0] >> 2, c[1] >> 2, c[2] >> 2) << 6 | within, triangles[s]};
            }
        });
        tbb::parallel_sort(keyed.begin(), keyed.end());
        const std::size_t n = keyed.size();
        mSlots.x.resize(n), mSlots.y.resize(n), mSlots.z.resize(n), mSlots.radius.resize(n);
        mSlots.area.resize(n);
        for (std::vector<double>& axis : mSlots.corner) axis.resize(n);
        for (std::size_t s = 0; s < n; ++s) {
            const std::uint32_t t = keyed[s].second;
            const TriangleFrame& f = frames[t];
            mSlots.x[s] = f.centroid.x, mSlots.y[s] = f.centroid.y, mSlots.z[s] = f.centroid.z;
            mSlots.radius[s] = f.boundingRadius;
            for (int c = 0; c < 3; ++c)
                for (int a = 0; a < 3; ++a) mSlots.corner[std::size_t(3 * c + a)][s] = mesh.points[mesh.triangles[t][c]][a];
            mSlots.area[s] = std::int64_t(units.areaUnits(f.area));
            if (s == 0 || keyed[s].first != keyed[s - 1].first) {
                if (s == 0 || keyed[s].first >> 6 != keyed[s - 1].first >> 6) {
                    mKeys.push_back(keyed[s].first >> 6);
                    mBlocks.emplace_back();
                    mBlocks.back().first = std::uint32_t(mCells.size());
                }
                mCells.emplace_back();
                mCells.back().first = std::uint32_t(s);
                mBlocks.back().last = std::uint32_t(mCells.size());
            }
            mCells.back().last = std::uint32_t(s + 1);
            mCells.back().area += mSlots.area[s];
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mBlocks.size()), [&](const auto& range) {
            for (std::size_t b = range.begin(); b < range.end(); ++b)
                for (std::uint32_t c = mBlocks[b].first; c < mBlocks[b].last; ++c) {
                    Box& cell = mCells[c];
                    for (std::uint32_t s = cell.first; s < cell.last; ++s)
                        for (int corner = 0; corner < 3; ++corner) grow(cell, mSlots.at(s, corner));
                    grow(mBlocks[b], cell.lo), grow(mBlocks[b], cell.hi);
                    mBlocks[b].area += cell.area;
                }
        });
        // Where each column (x, y) of blocks starts among the keys.
        mColumn.assign(std::size_t(mCount[0] * mCount[1]) + 1, 0);
        for (const std::uint64_t k : mKeys) ++mColumn[std::size_t(k / std::uint64_t(mCount[2])) + 1];
        for (std::size_t c = 1; c < mColumn.size(); ++c) mColumn[c] += mColumn[c - 1];
    }

    const Slots& slots() const { return mSlots; }
    /// The cells of a block (Box::first, Box::last of forEachBlockNear's).
    const Box& cell(std::uint32_t c) const { return mCells[c]; }

    /// Calls @p visit(block) for every block whose box may come within @p reach of @p p.
    template <class Visit> void forEachBlockNear(const Vec3& p, double reach, Visit&& visit) const
    {
        // A block's box holds its triangles, which reach past the block by their bounding
        // radius: the columns searched are grown by the largest.
        const double grown = reach + mMaxRadius, side = kBlock * mCell;
        std::int64_t lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = clamp(a, (p[a] - grown - mOrigin[a]) / side);
            hi[a] = clamp(a, (p[a] + grown - mOrigin[a]) / side);
        }
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
            const double gx = gap(0, x, p.x);
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                const double gy = gap(1, y, p.y);
                if (gx * gx + gy * gy > grown * grown) continue;
                const std::size_t column = std::size_t(x * mCount[1] + y);
                const auto first = mKeys.begin() + mColumn[column], last = mKeys.begin() + mColumn[column + 1];
                const std::uint64_t top = blockKey(x, y, hi[2]);
                for (auto it = std::lower_bound(first, last, blockKey(x, y, lo[2])); it != last && *it <= top; ++it)
                    visit(mBlocks[std::size_t(it - mKeys.begin())]);
            }
        }
    }

private:
    static constexpr double kBlock = 4;  ///< cells per block along each axis

    static void grow(Box& box, const Vec3& x)
    {
        for (int a = 0; a < 3; ++a) box.lo[a] = std::min(box.lo[a], x[a]), box.hi[a] = std::max(box.hi[a], x[a]);
    }
    /// Distance along @p axis from @p coordinate to the blocks of index @p i.
    double gap(int axis, std::int64_t i, double coordinate) const
    {
        const double lo = mOrigin[axis] + double(i) * kBlock * mCell, hi = lo + kBlock * mCell;
        return coordinate < lo ? lo - coordinate : (coordinate > hi ? coordinate - hi : 0.0);
    }
    /// The cell of @p coordinate along @p axis (blocks: its index >> 2).
    std::int64_t cellIndex(int axis, double coordinate) const
    {
        const double cells = (coordinate - mOrigin[axis]) / mCell;
        const std::int64_t limit = mCount[axis] * std::int64_t(kBlock) - 1;
        if (!(cells > 0)) return 0;  // also NaN
        return cells >= double(limit) ? limit : std::int64_t(cells);
    }
    /// The block of @p blocks along @p axis, within the grid.
    std::int64_t clamp(int axis, double blocks) const
    {
        if (!(blocks > 0)) return 0;
        return blocks >= double(mCount[axis] - 1) ? mCount[axis] - 1 : std::int64_t(blocks);
    }
    std::uint64_t blockKey(std::int64_t x, std::int64_t y, std::int64_t z) const
    {
        return (std::uint64_t(x) * std::uint64_t(mCount[1]) + std::uint64_t(y)) * std::uint64_t(mCount[2]) + std::uint64_t(z);
    }

    double mCell, mMaxRadius = 0;
    Vec3 mOrigin;
    std::int64_t mCount[3] = {1, 1, 1};  ///< blocks per axis
    Slots mSlots;
    std::vector<std::uint64_t> mKeys;    ///< per block
    std::vector<Box> mBlocks;
    std::vector<Box> mCells;             ///< the blocks' cells, block by block
    std::vector<std::uint32_t> mColumn;
};

/// The triangles that may meet a ball of radius up to @p R about one of @p vertices: with
/// few such vertices, those within reach of one (their centroids in the 5³ cells of edge R
/// around it, or larger than R), else all; without the triangles of no area.
std::vector<std::uint32_t> trianglesNear(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                                         const std::vector<std::uint32_t>& vertices, double R)
{
    const auto cellKey = [R](const Vec3& x, int dx, int dy, int dz) {
        const auto index = [R](double c, int d) { return std::uint64_t(std::int64_t(std::floor(c / R)) + d); };
        return index(x.x, dx) * 0x9E3779B97F4A7C15ULL ^ index(x.y, dy) * 0xC2B2AE3D27D4EB4FULL ^
               index(x.z, dz) * 0x165667B19E3779F9ULL;
    };
    const bool few = 4 * vertices.size() < mesh.numVertices();
    std::unordered_set<std::uint64_t> near;
    if (few)
        for (const std::uint32_t v : vertices)
            for (int dx = -2; dx <= 2; ++dx)
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dz = -2; dz <= 2; ++dz) near.insert(cellKey(mesh.points[v], dx, dy, dz));
    std::vector<std::uint32_t> triangles;
    for (std::uint32_t t = 0; t < frames.size(); ++t) {
        if (!(frames[t].area > 0)) continue;  // adds nothing
        if (few && frames[t].boundingRadius <= R && near.count(cellKey(frames[t].centroid, 0, 0, 0)) == 0) continue;
        triangles.push_back(t);
    }
    return triangles;
}

/// Grids of cell edge c, 4c, 16c, ... of @p triangles: each triangle in the first whose cells
/// are at least its bounding radius, so that a few long triangles (a scan's walls, a hole's
/// fill) do not widen every cell's box.
std::vector<CellGrid> gridsOfTriangles(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                                       const std::vector<std::uint32_t>& triangles, double cellSize,
                                       const FlaggedSums& units)
{
    std::vector<std::vector<std::uint32_t>> byGrid;
    for (const std::uint32_t t : triangles) {
        std::size_t g = 0;
        for (double c = cellSize; frames[t].boundingRadius > c && g < 40; c *= 4) ++g;
        if (byGrid.size() <= g) byGrid.resize(g + 1);
        byGrid[g].push_back(t);
    }
    std::vector<CellGrid> grids;
    double c = cellSize;
    for (const auto& subset : byGrid) {
        if (!subset.empty()) grids.emplace_back(mesh, frames, subset, c, units);
        c *= 4;
    }
    return grids;
}

/// Distance from @p p to the box [lo, hi]: nearest and farthest.
std::pair<double, double> boxDistances(const Vec3& p, const Vec3& lo, const Vec3& hi)
{
    double near2 = 0, far2 = 0;
    for (int a = 0; a < 3; ++a) {
        const double below = lo[a] - p[a], above = p[a] - hi[a];
        const double gap = std::max({below, above, 0.0});
        near2 += gap * gap;
        const double far = std::max(std::abs(lo[a] - p[a]), std::abs(hi[a] - p[a]));
        far2 += far * far;
    }
    return {std::sqrt(near2), std::sqrt(far2)};
}

/// Clips waiting for the batch kernel (clipBatch), as arrays of one number each: the corners
/// q of a triangle relative to p, the radius r of the sphere that cuts it, and the flagged
/// radius k its result goes to.
struct ClipBatch {
    static constexpr std::size_t kSize = 64;
    std::size_t size = 0;
    alignas(32) double x[3][kSize], y[3][kSize], z[3][kSize], r[kSize];
    alignas(32) double area[kSize], arc[kSize];
    std::uint32_t k[kSize];
    alignas(32) double done[kSize];  ///< 1 where the kernel's result holds; else clipOne takes it
};

/// arctan(t) for |t| <= 1/4, to rounding: t·Σ (−t²)ⁿ/(2n + 1) for n <= 13 (the next term is
/// below 1e-17 of t), in Horner's form, unrolled so that it vectorises.
inline double smallArctan(double t)
{
    const double s = t * t;
    double sum = 1.0 / 27;
    sum = 1.0 / 25 - s * sum, sum = 1.0 / 23 - s * sum, sum = 1.0 / 21 - s * sum, sum = 1.0 / 19 - s * sum;
    sum = 1.0 / 17 - s * sum, sum = 1.0 / 15 - s * sum, sum = 1.0 / 13 - s * sum, sum = 1.0 / 11 - s * sum;
    sum = 1.0 / 9 - s * sum, sum = 1.0 / 7 - s * sum, sum = 1.0 / 5 - s * sum, sum = 1.0 / 3 - s * sum;
    sum = 1.0 - s * sum;
    return t * sum;
}

/// What one edge (from corner a to corner b, relative to p) of a triangle with unit normal n
/// adds to its clip by a disc of radius rho about the foot point c (clipBatch): the area of
/// its piece inside the disc's chord, a factor of the product whose argument is half the
/// angle that piece subtends at c, and whether c lies on its inner side; and whether c is
/// far enough from its line for that product to keep its precision.
struct EdgePiece {
    double area, re, im;
    double inner, precise;  ///< 1 or 0 (numbers, so that the batch loop vectorises)
};
inline EdgePiece edgePiece(double ax, double ay, double az, double bx, double by, double bz, double nx, double ny,
                           double nz, double rho, double far2)
{
    const double wx = bx - ax, wy = by - ay, wz = bz - az;
    const double length = std::sqrt(wx * wx + wy * wy + wz * wz), over = 1.0 / length;
    const double ux = wx * over, uy = wy * over, uz = wz * over;
    const double h = (ay * uz - az * uy) * nx + (az * ux - ax * uz) * ny + (ax * uy - ay * ux) * nz;
    const double e = std::abs(h), e2 = e * e;
    const double tA = ax * ux + ay * uy + az * uz, tB = tA + length;
    const double ts = std::sqrt(std::max(0.0, (rho - e) * (rho + e)));
    const double t1 = std::max(tA, -ts), t2 = std::min(tB, ts);
    const bool piece = e < rho && t2 > t1;
    const double crossX = piece ? (h > 0 ? e : -e) * (t2 - t1) : 0.0;
    EdgePiece out;
    out.area = 0.5 * crossX;
    out.re = piece ? std::sqrt((e2 + t1 * t1) * (e2 + t2 * t2)) + e2 + t1 * t2 : 1.0;
    out.im = crossX;
    out.inner = h > 0 ? 1.0 : 0.0;
    out.precise = e2 > 1e-8 * far2 ? 1.0 : 0.0;
    return out;
}

/// The area of each batched triangle ∩ B_r and the length of the sphere's circle in it
/// (exact.cpp: the sectors of the edges about the foot point c of p, only the pieces along
/// an edge evaluated, their angles summed as the argument of a product of complex
/// numbers). In 3D from the corners: edge i runs along u_i from tA_i to tB_i at signed
/// distance h_i = (q_i × u_i)·n from c. Branch-free, so that it vectorises: where the
/// summed half-angle exceeds 1/4 (c inside the triangle, or the triangle near c), or c lies
/// close to an edge's line (exact.cpp, Straddler::precise), done is 0 and clipOne takes
/// the clip instead. Compiled for AVX-512 and AVX2 as well, chosen at run time, with the
/// same results (the file has no fused multiply-adds, which the AVX-512 variant would have).
__attribute__((target_clones("avx512f", "avx2", "default"))) void clipBatch(ClipBatch& b)
{
    for (std::size_t j = 0; j < b.size; ++j) {
        const double ax = b.x[0][j], ay = b.y[0][j], az = b.z[0][j];
        const double bx = b.x[1][j], by = b.y[1][j], bz = b.z[1][j];
        const double cx = b.x[2][j], cy = b.y[2][j], cz = b.z[2][j];
        const double ux = bx - ax, uy = by - ay, uz = bz - az, vx = cx - ax, vy = cy - ay, vz = cz - az;
        double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const double inverse = 1.0 / std::sqrt(nx * nx + ny * ny + nz * nz);
        nx *= inverse, ny *= inverse, nz *= inverse;
        const double qa = ax * ax + ay * ay + az * az, qb = bx * bx + by * by + bz * bz, qc = cx * cx + cy * cy + cz * cz;
        // The nearest corner (the first of equals), as the exact mode takes d from it.
        const double da = ax * nx + ay * ny + az * nz, db = bx * nx + by * ny + bz * nz, dc = cx * nx + cy * ny + cz * nz;
        const double d = qa <= qb ? (qa <= qc ? da : dc) : (qb <= qc ? db : dc);
        const double far2 = std::max(qa, std::max(qb, qc));
        const double ad = std::abs(d), r = b.r[j];
        const double rho2 = std::max(0.0, (r - ad) * (r + ad)), rho = std::sqrt(rho2);
        const EdgePiece e0 = edgePiece(ax, ay, az, bx, by, bz, nx, ny, nz, rho, far2);
        const EdgePiece e1 = edgePiece(bx, by, bz, cx, cy, cz, nx, ny, nz, rho, far2);
        const EdgePiece e2 = edgePiece(cx, cy, cz, ax, ay, az, nx, ny, nz, rho, far2);
        const double lineArea = e0.area + e1.area + e2.area;
        const double re01 = e0.re * e1.re - e0.im * e1.im, im01 = e0.re * e1.im + e0.im * e1.re;
        const double re = re01 * e2.re - im01 * e2.im, im = re01 * e2.im + im01 * e2.re;
        const double precise = e0.precise * e1.precise * e2.precise, inside = e0.inner * e1.inner * e2.inner;
        // half = arg(re + i im), evaluated here where small.
        const double small = std::abs(im) <= 0.25 * re && re > 0 ? 1.0 : 0.0;
        const double half = smallArctan(small > 0 ? im / re : 0.0);
        const double disc = inside * (2 * kPi) - 2 * half;
        const double cut = r > ad ? 1.0 : 0.0;
        b.area[j] = cut * (0.5 * rho2 * disc + lineArea);
        b.arc[j] = cut * rho * disc;
        b.done[j] = std::max(1.0 - cut, precise * small * (1.0 - inside));
    }
}

/// One clip that clipBatch left: as its measures() with the full arctangent, or by the
/// sector decomposition where c lies close to an edge's line (exact.cpp).
Measures clipOne(const std::array<Vec3, 3>& q, double r)
{
    const double q2[3] = {squaredNorm(q[0]), squaredNorm(q[1]), squaredNorm(q[2])};
    const Vec3 normal = cross(q[1] - q[0], q[2] - q[0]);
    const Vec3 n = normal / norm(normal);
    const int nearest = q2[0] <= q2[1] ? (q2[0] <= q2[2] ? 0 : 2) : (q2[1] <= q2[2] ? 1 : 2);
    const double d = dot(q[nearest], n), far2 = std::max({q2[0], q2[1], q2[2]});
    Measures m;
    const double ad = std::abs(d);
    if (!(r > ad)) return m;
    bool precise = true;
    int positive = 0;
    double e[3], sigma[3], tA[3], tB[3];
    for (int i = 0; i < 3; ++i) {
        const Vec3 w = q[(i + 1) % 3] - q[i];
        const double length = norm(w);
        const Vec3 u = w / length;
        const double h = dot(cross(q[i], u), n);
        sigma[i] = h > 0 ? 1.0 : -1.0;
        positive += h > 0;
        e[i] = std::abs(h);
        tA[i] = dot(q[i], u);
        tB[i] = tA[i] + length;
        precise = precise && e[i] * e[i] > 1e-8 * far2;
    }
    if (!precise) {
        // The triangle's own frame; its corners relative to p as they are.
        const TriangleFrame frame = makeFrame(q[0], q[1], q[2]);
        return LocalTriangle(q, frame).sectors(r, false);
    }
    const double rho2 = (r - ad) * (r + ad), rho = std::sqrt(rho2);
    double lineArea = 0;
    Complex angle;
    for (int i = 0; i < 3; ++i) {
        if (e[i] >= rho) continue;
        const double ts = std::sqrt((rho - e[i]) * (rho + e[i]));
        const double t1 = std::max(tA[i], -ts), t2 = std::min(tB[i], ts);
        if (!(t2 > t1)) continue;
        const double e2 = e[i] * e[i];
        const double crossX = sigma[i] * e[i] * (t2 - t1), dotX = e2 + t1 * t2;
        lineArea += 0.5 * crossX;
        angle.multiply(std::sqrt((e2 + t1 * t1) * (e2 + t2 * t2)) + dotX, crossX);
    }
    double half = angle.arg();
    const bool inside = positive == 3;
    if (inside && half < -0.5 * kPi) half += 2 * kPi;
    const double disc = (inside ? 2 * kPi : 0.0) - 2 * half;
    m.area = 0.5 * rho2 * disc + lineArea;
    m.arcLength = rho * disc;
    return m;
}

/// The ball sums of one vertex p over the triangles near it.
class VertexWalk {
public:
    explicit VertexWalk(FlaggedSums& sums) : mSums(sums)
    {
    }

    /// Adds every triangle of @p grids near @p p to the sums.
    void run(const Vec3& p, const std::vector<CellGrid>& grids)
    {
        mRunWhole.resize(mSums.size() + 1);
        const double reach = mSums.largestRadius();
        // A margin against rounding: a block is added whole only if no flagged radius comes
        // near its nearest or farthest point, so that each of its triangles would be
        // counted alike one by one (the same total in any tile).
        const double margin = 1e-9 * reach;
        const std::size_t n = mSums.size();
        // Whether a box is settled without its triangles: beyond reach, or whole inside from one
        // flagged radius on (added whole); else a flagged sphere cuts it.
        const auto settled = [&](const CellGrid::Box& box) {
            const auto [near, far] = boxDistances(p, box.lo, box.hi);
            if (near >= reach) return true;
            const double nearBelow = std::max(0.0, near - margin), farAbove = far + margin;
            const std::size_t first = mSums.firstAbove(nearBelow * nearBelow);
            const std::size_t inside = mSums.firstAtLeast(farAbove * farAbove);
            if (first != inside) return false;
            if (inside < n) mSums.addWhole(inside, box.area);
            return true;
        };
        for (const CellGrid& grid : grids)
            grid.forEachBlockNear(p, reach, [&](const CellGrid::Box& block) {
                if (settled(block)) return;
                // Cut: its cells, and the triangles of those cut one by one, in runs of
                // consecutive slots over consecutive cells.
                std::uint32_t cut[kCellsPerBlock];
                const std::size_t cuts = addCells(p, grid, block, margin, cut);
                for (std::size_t c = 0; c < cuts;) {
                    std::uint32_t s = grid.cell(cut[c]).first, end = grid.cell(cut[c]).last;
                    for (++c; c < cuts && cut[c] == cut[c - 1] + 1; ++c) end = grid.cell(cut[c]).last;
                    for (; s < end; s += kChunk) addTriangles(p, grid.slots(), s, std::min(end, s + std::uint32_t(kChunk)), margin);
                }
            });
        flush();
    }

private:
    static constexpr std::size_t kChunk = FlaggedSums::kMaxItems;
    static constexpr std::size_t kCellsPerBlock = FlaggedSums::kMaxItems;  // 4 × 4 × 4
    static constexpr double kBeyond = std::numeric_limits<double>::max();

    /// The cells of @p block: each either settled (beyond reach, or whole inside from one
    /// flagged radius on, added whole) or cut by a flagged sphere, into @p cut (ascending).
    /// As the boxes of run() (the same margins), all cells together in loops that vectorise;
    /// returns the number cut.
    std::size_t addCells(const Vec3& p, const CellGrid& grid, const CellGrid::Box& block, double margin,
                         std::uint32_t (&cut)[kCellsPerBlock])
    {
        const std::uint32_t c0 = block.first;
        const std::size_t m = block.last - block.first;
        const double reach = mSums.largestRadius();
        double near2[kCellsPerBlock], far2[kCellsPerBlock];
        for (std::size_t j = 0; j < m; ++j) {
            const CellGrid::Box& box = grid.cell(c0 + std::uint32_t(j));
            double n2 = 0, f2 = 0;
            for (int a = 0; a < 3; ++a) {
                const double below = box.lo[a] - p[a], above = p[a] - box.hi[a];
                const double gap = std::max(std::max(below, above), 0.0);
                n2 += gap * gap;
                const double far = std::max(std::abs(box.lo[a] - p[a]), std::abs(box.hi[a] - p[a]));
                f2 += far * far;
            }
            const double near = std::sqrt(n2), far = std::sqrt(f2);
            // Beyond reach: every radius below it, settled, as settled() has it (the largest
            // double, not +∞, which the counts would step past).
            const double nearBelow = std::max(0.0, near - margin), farAbove = far + margin;
            const bool beyond = near >= reach;
            near2[j] = beyond ? kBeyond : nearBelow * nearBelow, far2[j] = beyond ? kBeyond : farAbove * farAbove;
        }
        const std::size_t n = mSums.size();
        std::int32_t first[kCellsPerBlock], inside[kCellsPerBlock];
        mSums.count(m, near2, far2, first, inside);
        std::size_t cuts = 0;
        for (std::size_t j = 0; j < m; ++j) {
            if (first[j] == inside[j]) {
                if (std::size_t(inside[j]) < n) mSums.addWhole(std::size_t(inside[j]), grid.cell(c0 + std::uint32_t(j)).area);
                continue;
            }
            cut[cuts++] = c0 + std::uint32_t(j);
        }
        return cuts;
    }

    /// Adds the triangles of slots [@p s0, @p s1) (at most kChunk): as the exact mode's
    /// VertexBall (exact.cpp), at the flagged radii, all together in loops that vectorise.
    /// A triangle is whole inside from the first flagged radius at or beyond its farthest
    /// corner on, and cut, perhaps, by those above a lower bound of its distance: that of
    /// its bounding sphere (less a margin, as the boxes of run()), or (nearest corner)² − ρ_t²;
    /// a clip gives 0 where the sphere passes it by.
    void addTriangles(const Vec3& p, const CellGrid::Slots& slots, std::uint32_t s0, std::uint32_t s1, double margin)
    {
        const std::size_t m = s1 - s0;
        double low2[kChunk], farthest2[kChunk];
        const double* cx[3] = {slots.corner[0].data() + s0, slots.corner[3].data() + s0, slots.corner[6].data() + s0};
        const double* cy[3] = {slots.corner[1].data() + s0, slots.corner[4].data() + s0, slots.corner[7].data() + s0};
        const double* cz[3] = {slots.corner[2].data() + s0, slots.corner[5].data() + s0, slots.corner[8].data() + s0};
        for (std::size_t j = 0; j < m; ++j) {
            const double dx = slots.x[s0 + j] - p.x, dy = slots.y[s0 + j] - p.y, dz = slots.z[s0 + j] - p.z;
            const double centre = std::sqrt(dx * dx + dy * dy + dz * dz), rho = slots.radius[s0 + j];
            const double near = std::max(0.0, centre - rho - margin);
            double lo = INFINITY, hi = 0;
            for (int c = 0; c < 3; ++c) {
                const double qx = cx[c][j] - p.x, qy = cy[c][j] - p.y, qz = cz[c][j] - p.z;
                const double q2 = qx * qx + qy * qy + qz * qz;
                lo = std::min(lo, q2), hi = std::max(hi, q2);
            }
            low2[j] = std::max(lo - rho * rho, near * near), farthest2[j] = hi;
        }
        // The first flagged radius above low2 (cutFrom) and at or beyond farthest2 (wholeFrom).
        const std::size_t n = mSums.size();
        std::int32_t cutFrom[kChunk], wholeFrom[kChunk];
        const auto [below, upTo] = mSums.count(m, low2, farthest2, cutFrom, wholeFrom);
        // The areas whole inside, in sums of the run (64 triangles inside a ball of radius R,
        // each at most 1.3 R², fit 64 bits); beyond the last flagged radius, slot n, unused
        // (unsigned, so that it may wrap).
        std::uint64_t* runWhole = mRunWhole.data();
        std::fill(runWhole + below, runWhole + upTo + 1, 0);
        for (std::size_t j = 0; j < m; ++j) runWhole[wholeFrom[j]] += std::uint64_t(slots.area[s0 + j]);
        for (std::size_t k = below; k < std::min(upTo + 1, n); ++k)
            if (runWhole[k] != 0) mSums.addWhole(k, Fixed(std::int64_t(runWhole[k])));
        for (std::size_t j = 0; j < m; ++j) {
            if (cutFrom[j] >= wholeFrom[j]) continue;
            const std::size_t s = s0 + j;
            const std::array<Vec3, 3> q{slots.at(s, 0) - p, slots.at(s, 1) - p, slots.at(s, 2) - p};
            for (std::int32_t k = cutFrom[j]; k < wholeFrom[j]; ++k) queue(q, std::size_t(k));
        }
    }

    /// Queues the clip of the triangle @p q (corners relative to p) by flagged radius k.
    void queue(const std::array<Vec3, 3>& q, std::size_t k)
    {
        ClipBatch& b = mBatch;
        const std::size_t j = b.size++;
        for (int c = 0; c < 3; ++c) b.x[c][j] = q[c].x, b.y[c][j] = q[c].y, b.z[c][j] = q[c].z;
        b.r[j] = mSums.radius(k);
        b.k[j] = std::uint32_t(k);
        if (b.size == ClipBatch::kSize) flush();
    }

    /// Clips the queued triangles and adds them to the sums.
    void flush()
    {
        ClipBatch& b = mBatch;
        clipBatch(b);
        for (std::size_t j = 0; j < b.size; ++j) {
            if (b.done[j] != 0) {
                mSums.addCut(b.k[j], b.area[j], b.arc[j]);
                continue;
            }
            const std::array<Vec3, 3> q{Vec3(b.x[0][j], b.y[0][j], b.z[0][j]), Vec3(b.x[1][j], b.y[1][j], b.z[1][j]),
                                        Vec3(b.x[2][j], b.y[2][j], b.z[2][j])};
            const Measures m = clipOne(q, b.r[j]);
            mSums.addCut(b.k[j], m.area, m.arcLength);
        }
        b.size = 0;
    }

    FlaggedSums& mSums;
    ClipBatch mBatch;
    std::vector<std::uint64_t> mRunWhole;  ///< addTriangles's sums of areas per flagged radius, and beyond
};

} // namespace

ExactPairsCount evaluatePairsExactly(const TriMesh& mesh, const std::vector<double>& radii, double cellSize,
                                     const std::vector<std::vector<std::uint8_t>>& flagged,
                                     std::vector<std::vector<float>>& patch, std::vector<std::vector<float>>& line,
                                     RunContext* progress)
{
    ExactPairsCount count;
    const std::size_t nv = mesh.numVertices(), nr = radii.size();
    std::vector<std::uint32_t> vertices;
    for (std::size_t i = 0; i < nv; ++i)
        for (std::size_t j = 0; j < nr; ++j)
            if (flagged[j][i]) {
                vertices.push_back(std::uint32_t(i));
                break;
            }
    for (std::size_t j = 0; j < nr; ++j)
        for (std::size_t i = 0; i < nv; ++i) count.pairs += flagged[j][i] != 0;
    count.vertices = vertices.size();
    if (vertices.empty() || mesh.numTriangles() == 0) return count;
    // Walked in the order of their cells of edge R (Morton order), so that vertices walked
    // one after another read mostly the same triangles (each vertex's sums are its own:
    // the order changes no value).
    {
        const double R = radii.back();
        Vec3 lo = mesh.points[vertices[0]];
        for (const std::uint32_t v : vertices)
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], mesh.points[v][a]);
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(vertices.size());
        for (std::size_t k = 0; k < vertices.size(); ++k) {
            std::uint64_t c[3];
            for (int a = 0; a < 3; ++a)
                c[a] = std::uint64_t(std::min(2097151.0, std::floor((mesh.points[vertices[k]][a] - lo[a]) / R)));
            keyed[k] = {morton(c[0], c[1], c[2]), vertices[k]};
        }
        tbb::parallel_sort(keyed.begin(), keyed.end());
        for (std::size_t k = 0; k < vertices.size(); ++k) vertices[k] = keyed[k].second;
    }

    const FlaggedSums units(radii);
    const std::vector<TriangleFrame> frames = triangleFrames(mesh);
    const std::vector<CellGrid> grids =
        gridsOfTriangles(mesh, frames, trianglesNear(mesh, frames, vertices, radii.back()), cellSize, units);
    if (progress) progress->start("P and L, exact where the kernels blur", vertices.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 16), [&](const auto& range) {
        FlaggedSums sums(radii);
        VertexWalk walk(sums);
        std::vector<std::uint32_t> own;
        for (std::size_t v = range.begin(); v < range.end(); ++v) {
            const std::uint32_t i = vertices[v];
            own.clear();
            for (std::size_t j = 0; j < nr; ++j)
                if (flagged[j][i]) own.push_back(std::uint32_t(j));
            sums.start(own);
            walk.run(mesh.points[i], grids);
            sums.store(i, patch, line);
        }
        if (progress) progress->advance(range.size());
    });
    if (progress) progress->end();
    return count;
}

} // namespace msii::detail
