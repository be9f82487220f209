#pragma once
/// @file patch_line_samples.h
/// @brief Step 1 of P and L (msii/invariants/patch_line.h): the samples. The triangles are cut
/// into pieces no larger than the finest cell h0, the pieces gathered per cell into one sample
/// (area, centroid, covariance of position, mean normal tensor), and coarser levels merge
/// 2×2×2 cells exactly; the cells' Morton keys group the samples by cell and by block.
/// Private to the engine (patch_line.cpp and its parts).

#include <msii/core/vec3.h>
#include <msii/mesh/trimesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace msii::detail {

// ---------------------------------------------------------------------------------------
// Cells: integer coordinates floor(x / h0) shifted by kOffset into [0, 2^21), packed as a
// Morton code, so that a level-l cell is key >> 3l and an 8³ block of cells is key >> 9:
// samples sorted by key are grouped by cell, by parent cell and by block at once.

constexpr std::int64_t kOffset = std::int64_t(1) << 20;
constexpr std::int64_t kCoordLimit = std::int64_t(1) << 21;

inline std::uint64_t spreadBits(std::uint64_t v)  // 21 bits -> every third bit
{
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

inline std::uint64_t morton(std::uint64_t x, std::uint64_t y, std::uint64_t z)
{
    return spreadBits(x) | spreadBits(y) << 1 | spreadBits(z) << 2;
}

struct CellCoord {
    std::int64_t x, y, z;  // shifted, level 0
};

inline CellCoord cellOf(const Vec3& p, double h0)
{
    return {std::int64_t(std::floor(p.x / h0)) + kOffset, std::int64_t(std::floor(p.y / h0)) + kOffset,
            std::int64_t(std::floor(p.z / h0)) + kOffset};
}

// ---------------------------------------------------------------------------------------
// Samples of one level, as running sums in double (merged exactly between levels) and, for
// the gather, as floats relative to a group's origin.

struct SampleSums {
    std::uint64_t key = 0;
    double area = 0;
    Vec3 moment;      // Σ a·c (first moment)
    std::array<double, 6> normalTensor{};  // Σ a·n nᵀ: xx, yy, zz, xy, xz, yz
    /// Σ ∫ (x − o)(x − o)ᵀ dA over the pieces (same order), about the point o = origin
    /// (a point of the sample, so that the covariance keeps its digits far from 0).
    std::array<double, 6> secondMoment{};
    Vec3 origin;
};

/// The six entries xx, yy, zz, xy, xz, yz of u vᵀ (symmetrised by the caller's use).
inline std::array<double, 6> outer(const Vec3& u, const Vec3& v)
{
    return {u.x * v.x, u.y * v.y, u.z * v.z, u.x * v.y, u.x * v.z, u.y * v.z};
}

/// Adds the second moment of @p from (about its origin) to @p to, about to's origin.
inline void addSecondMoment(SampleSums& to, const SampleSums& from)
{
    // x − o_to = (x − o_from) + δ: S + δ fᵀ + f δᵀ + a δ δᵀ, f = Σ a (x − o_from).
    const Vec3 delta = from.origin - to.origin, f = from.moment - from.origin * from.area;
    const auto df = outer(delta, f), fd = outer(f, delta), dd = outer(delta, delta);
    for (std::size_t q = 0; q < 6; ++q)
        to.secondMoment[q] += from.secondMoment[q] + (q < 3 ? 2.0 * df[q] : df[q] + fd[q]) + from.area * dd[q];
}

struct Level {
    int index = 0;  // l: cells of h0·2^l
    double h = 0;
    std::vector<std::uint64_t> key;
    std::vector<double> cx, cy, cz;       // centroids
    std::vector<float> area;
    /// Mean of n nᵀ over the sample's area (xx, yy, zz, xy, xz, yz): (û·n)² averaged over a
    /// piece that spans a crease, where the mean normal would be wrong for both sides.
    std::array<std::vector<float>, 6> tensor;
    /// Covariance of position over the sample's area (same order): how its area spreads
    /// around the centroid, for the second-order quadrature of the kernel sums.
    std::array<std::vector<float>, 6> covariance;
    std::unordered_map<std::uint64_t, std::pair<std::uint32_t, std::uint32_t>> blocks;
};

/// One piece of a triangle: of the m² congruent sub-triangles it is cut into (sub = row
/// i << 16 | column j << 1 | up or down), or for a sliver, which is cut along the cells
/// instead, the index of the piece's corners (finestSamples).
struct Piece {
    std::uint64_t key;
    std::uint32_t triangle;
    std::uint32_t sub;
};

inline std::array<Vec3, 3> pieceCorners(const std::array<Vec3, 3>& t, int m, std::uint32_t sub)
{
    const int i = int(sub >> 16), j = int((sub >> 1) & 0x7fff);
    const bool down = sub & 1;
    const Vec3 u = (t[1] - t[0]) / double(m), v = (t[2] - t[0]) / double(m);
    const auto at = [&](int a, int b) { return t[0] + u * double(a) + v * double(b); };
    if (!down) return {at(i, j), at(i + 1, j), at(i, j + 1)};
    return {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
}

inline int piecesPerSide(const std::array<Vec3, 3>& t, double h0)
{
    const double longest = std::sqrt(std::max({squaredNorm(t[1] - t[0]), squaredNorm(t[2] - t[1]),
                                               squaredNorm(t[0] - t[2])}));
    return std::max(1, int(std::ceil(longest / h0)));
}

/// Squared distance from (x, y, z) to the box {lo x, y, z, hi x, y, z} (0 inside it).
template <class T>
inline T squaredDistanceToBox(T x, T y, T z, const std::array<T, 6>& box)
{
    const T dx = std::max({T(0), box[0] - x, x - box[3]}), dy = std::max({T(0), box[1] - y, y - box[4]}),
            dz = std::max({T(0), box[2] - z, z - box[5]});
    return dx * dx + dy * dy + dz * dz;
}

/// Runs of equal keys in a sorted range, for parallel reduction: chunk starts moved forward
/// to the beginning of a run.
template <class KeyAt>
std::vector<std::size_t> runAlignedChunks(std::size_t n, std::size_t chunks, KeyAt keyAt)
{
    std::vector<std::size_t> start;
    for (std::size_t c = 0; c < chunks; ++c) {
        std::size_t s = n * c / chunks;
        while (s > 0 && s < n && keyAt(s) == keyAt(s - 1)) ++s;
        if (start.empty() || s > start.back()) start.push_back(s);
    }
    if (start.empty() || start.back() != n) start.push_back(n);
    return start;
}

/// Samples in parts: runs of samples sorted by key, each part holding whole cells of the
/// coarsest level, so that every level can be built from the parts in parallel.
using SampleParts = std::vector<std::vector<SampleSums>>;

/// The number of samples in all parts.
std::size_t totalSize(const SampleParts& parts);

/// The finest samples, in parts aligned to cells of level @p coarsestLevel.
SampleParts finestSamples(const TriMesh& mesh, double h0, int coarsestLevel);

/// The samples of the next coarser level: 2×2×2 cells merged exactly, part by part.
SampleParts coarser(const SampleParts& fine);

/// Level @p index (cells of h0·2^index) from its samples @p parts, with its 8³-cell blocks.
Level makeLevel(const SampleParts& parts, double h0, int index);

} // namespace msii::detail
