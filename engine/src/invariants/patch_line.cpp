#include <msii/invariants/patch_line.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/vertex_normals.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <unordered_map>

namespace msii {
namespace {

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

/// One piece of a triangle cut into m² congruent sub-triangles: row i, column j, up or down.
struct Piece {
    std::uint64_t key;
    std::uint32_t triangle;
    std::uint32_t sub;  // i << 16 | j << 1 | down
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

std::size_t totalSize(const SampleParts& parts)
{
    std::size_t total = 0;
    for (const auto& part : parts) total += part.size();
    return total;
}

/// The finest samples, in parts aligned to cells of level @p coarsestLevel.
SampleParts finestSamples(const TriMesh& mesh, double h0, int coarsestLevel)
{
    const std::size_t nt = mesh.numTriangles();
    std::vector<std::uint64_t> first(nt + 1, 0);
    std::vector<int> sides(nt);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            sides[t] = piecesPerSide({mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]}, h0);
            if (sides[t] > 0x7fff) throw InvalidInputError("a triangle is too large for the sample cells");
        }
    });
    for (std::size_t t = 0; t < nt; ++t) first[t + 1] = first[t] + std::uint64_t(sides[t]) * sides[t];

    std::vector<Piece> pieces(first[nt]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            const std::array<Vec3, 3> v{mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]};
            const int m = sides[t];
            std::uint64_t k = first[t];
            for (int i = 0; i < m; ++i)
                for (int j = 0; i + j < m; ++j)
                    for (int down = 0; down < 2; ++down) {
                        if (down && i + j > m - 2) continue;
                        const std::uint32_t sub = std::uint32_t(i) << 16 | std::uint32_t(j) << 1 | std::uint32_t(down);
                        const auto c = pieceCorners(v, m, sub);
                        const CellCoord cell = cellOf((c[0] + c[1] + c[2]) / 3.0, h0);
                        pieces[k++] = {morton(std::uint64_t(cell.x), std::uint64_t(cell.y), std::uint64_t(cell.z)),
                                       std::uint32_t(t), sub};
                    }
        }
    });
    tbb::parallel_sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) {
        return a.key != b.key ? a.key < b.key : a.triangle != b.triangle ? a.triangle < b.triangle : a.sub < b.sub;
    });

    // One sample per run of equal keys; chunks aligned to runs (of coarsest cells) keep the
    // sums deterministic.
    const int alignBits = 3 * coarsestLevel;
    const auto chunks =
        runAlignedChunks(pieces.size(), 256, [&](std::size_t i) { return pieces[i].key >> alignBits; });
    SampleParts parts(chunks.size() - 1);
    tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
        auto& out = parts[c];
        for (std::size_t i = chunks[c]; i < chunks[c + 1]; ++i) {
            const Piece& p = pieces[i];
            const auto& tri = mesh.triangles[p.triangle];
            const std::array<Vec3, 3> v{mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]};
            const int m = sides[p.triangle];
            const auto c3 = pieceCorners(v, m, p.sub);
            const Vec3 normalArea = cross(v[1] - v[0], v[2] - v[0]) * (0.5 / (double(m) * m));
            const double a = norm(normalArea);
            const Vec3 nrm = a > 0 ? normalArea / a : Vec3();
            const Vec3 centroid = (c3[0] + c3[1] + c3[2]) / 3.0;
            if (out.empty() || out.back().key != p.key) out.push_back(SampleSums{p.key, 0, {}, {}, {}, centroid});
            // ∫ (x − o)(x − o)ᵀ dA over the piece: a (v vᵀ + Σ_k e_k e_kᵀ / 12), v = c − o,
            // e_k = corner k − c.
            const Vec3 offset = centroid - out.back().origin;
            std::array<double, 6> second = outer(offset, offset);
            for (const Vec3& corner : c3) {
                const auto ee = outer(corner - centroid, corner - centroid);
                for (std::size_t q = 0; q < 6; ++q) second[q] += ee[q] / 12.0;
            }
            SampleSums& s = out.back();
            s.area += a;
            s.moment += centroid * a;
            const auto nn = outer(nrm, nrm);
            for (std::size_t q = 0; q < 6; ++q) {
                s.normalTensor[q] += a * nn[q];
                s.secondMoment[q] += a * second[q];
            }
        }
    });
    return parts;
}

/// The samples of the next coarser level: 2×2×2 cells merged exactly, part by part.
SampleParts coarser(const SampleParts& fine)
{
    SampleParts coarse(fine.size());
    tbb::parallel_for(std::size_t(0), fine.size(), [&](std::size_t c) {
        auto& out = coarse[c];
        std::size_t count = 0;  // parents, to allocate once
        for (std::size_t i = 0; i < fine[c].size(); ++i)
            count += i == 0 || (fine[c][i].key >> 3) != (fine[c][i - 1].key >> 3);
        out.reserve(count);
        for (const SampleSums& s : fine[c]) {
            const std::uint64_t key = s.key >> 3;
            if (out.empty() || out.back().key != key) out.push_back(SampleSums{key, 0, {}, {}, {}, s.origin});
            SampleSums& to = out.back();
            addSecondMoment(to, s);
            to.area += s.area;
            to.moment += s.moment;
            for (std::size_t q = 0; q < 6; ++q) to.normalTensor[q] += s.normalTensor[q];
        }
    });
    return coarse;
}

Level makeLevel(const SampleParts& parts, double h0, int index)
{
    Level level;
    level.index = index;
    level.h = h0 * double(1 << index);
    std::vector<std::size_t> first(parts.size() + 1, 0);  // each part's first sample
    for (std::size_t c = 0; c < parts.size(); ++c) first[c + 1] = first[c] + parts[c].size();
    const std::size_t n = first.back();
    level.key.resize(n);
    level.cx.resize(n), level.cy.resize(n), level.cz.resize(n);
    level.area.resize(n);
    for (auto& t : level.tensor) t.resize(n);
    for (auto& t : level.covariance) t.resize(n);
    tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
        for (std::size_t k = 0; k < parts[c].size(); ++k) {
            const SampleSums& s = parts[c][k];
            const std::size_t i = first[c] + k;
            level.key[i] = s.key;
            const Vec3 m = s.area > 0 ? s.moment / s.area : Vec3();
            level.cx[i] = m.x, level.cy[i] = m.y, level.cz[i] = m.z;
            level.area[i] = float(s.area);
            const Vec3 v = m - s.origin;  // covariance = S/a − v vᵀ about the origin o
            const auto cc = outer(v, v);
            for (std::size_t q = 0; q < 6; ++q) {
                level.tensor[q][i] = s.area > 0 ? float(s.normalTensor[q] / s.area) : 0.0f;
                level.covariance[q][i] = s.area > 0 ? float(s.secondMoment[q] / s.area - cc[q]) : 0.0f;
            }
        }
    });
    for (std::size_t i = 0; i < n;) {
        std::size_t e = i;
        while (e < n && (level.key[e] >> 9) == (level.key[i] >> 9)) ++e;
        level.blocks.emplace(level.key[i] >> 9, std::make_pair(std::uint32_t(i), std::uint32_t(e)));
        i = e;
    }
    return level;
}

// ---------------------------------------------------------------------------------------
// The kernels. Each is built from a B-spline B of odd degree (knots at the integers, ∫B = 1,
// variance σ²) as K(t) = (1 + σ²) B(t) − σ²/2 (B(t + 1) + B(t − 1)): ∫K = 1 and its second
// moment is 0, so blurring across r with K leaves any P(r) and L(r) that is locally
// quadratic unchanged (P ∗ K = P + O(w⁴ P⁗)). K is as smooth as B, with B's support widened
// by one knot each side. F is its integral; K′ and K″ serve the second-order terms of the
// quadrature (evaluatePoints). P's kernel comes from the cubic B-spline (σ² = 1/3, K in
// C², support [-3, 3]), L's from the quintic (σ² = 1/2, C⁴, support [-4, 4]).

/// The cubic B-spline: support [-2, 2].
struct CubicBSpline {
    static constexpr double kHalfSupport = 2, kVariance = 1.0 / 3.0;
    static double value(double t)
    {
        t = std::abs(t);
        if (t >= 2) return 0.0;
        if (t >= 1) return (2 - t) * (2 - t) * (2 - t) / 6.0;
        return (4 - 6 * t * t + 3 * t * t * t) / 6.0;
    }
    static double integral(double t)  // ∫ from −∞ to t
    {
        if (t <= -2) return 0.0;
        if (t >= 2) return 1.0;
        if (t < 0) return 1.0 - integral(-t);
        if (t >= 1) return 1.0 - (2 - t) * (2 - t) * (2 - t) * (2 - t) / 24.0;
        return 0.5 + (4 * t - 2 * t * t * t + 0.75 * t * t * t * t) / 6.0;
    }
    static double derivative(double t)
    {
        const double a = std::abs(t);
        if (a >= 2) return 0.0;
        if (a >= 1) return (t > 0 ? -0.5 : 0.5) * (2 - a) * (2 - a);
        return -2 * t + 1.5 * t * a;
    }
    static double secondDerivative(double t)
    {
        const double a = std::abs(t);
        if (a >= 2) return 0.0;
        if (a >= 1) return 2 - a;
        return -2 + 3 * a;
    }
};

/// The quintic B-spline: support [-3, 3]; pieces in x = |t| over 120.
struct QuinticBSpline {
    static constexpr double kHalfSupport = 3, kVariance = 0.5;
    static double value(double t)
    {
        const double x = std::abs(t), x2 = x * x;
        if (x >= 3) return 0.0;
        if (x >= 2) return std::pow(3 - x, 5) / 120.0;
        if (x >= 1) return (51 + x * (75 + x * (-210 + x * (150 + x * (-45 + 5 * x))))) / 120.0;
        return (66 + x2 * (-60 + x2 * (30 - 10 * x))) / 120.0;
    }
    static double integral(double t)
    {
        if (t <= -3) return 0.0;
        if (t >= 3) return 1.0;
        if (t < 0) return 1.0 - integral(-t);
        if (t >= 2) return 1.0 - std::pow(3 - t, 6) / 720.0;
        const auto middle = [](double x) {  // 120 ∫ of the middle piece
            return x * (51 + x * (37.5 + x * (-70 + x * (37.5 + x * (-9 + x * 5.0 / 6.0)))));
        };
        const double firstPiece = 66 - 20 + 6 - 10.0 / 6.0;  // 120 ∫ over [0, 1]
        if (t >= 1) return 0.5 + (firstPiece + middle(t) - middle(1)) / 120.0;
        const double t2 = t * t;
        return 0.5 + t * (66 + t2 * (-20 + t2 * (6 - t * 10.0 / 6.0))) / 120.0;
    }
    static double derivative(double t)
    {
        const double x = std::abs(t), s = t < 0 ? -1.0 : 1.0;
        if (x >= 3) return 0.0;
        if (x >= 2) return -s * std::pow(3 - x, 4) / 24.0;
        if (x >= 1) return s * (75 + x * (-420 + x * (450 + x * (-180 + 25 * x)))) / 120.0;
        return s * x * (-120 + x * x * (120 - 50 * x)) / 120.0;
    }
    static double secondDerivative(double t)
    {
        const double x = std::abs(t);
        if (x >= 3) return 0.0;
        if (x >= 2) return std::pow(3 - x, 3) / 6.0;
        if (x >= 1) return (-420 + x * (900 + x * (-540 + 100 * x))) / 120.0;
        return (-120 + x * x * (360 - 200 * x)) / 120.0;
    }
};

/// (1 + σ²) f(t) − σ²/2 (f(t + 1) + f(t − 1)): the kernel K from B (or F, K′, K″ from B's).
template <class Spline, class Function>
inline double fourthOrder(Function f, double t)
{
    constexpr double s = Spline::kVariance;
    return (1 + s) * f(t) - 0.5 * s * (f(t + 1) + f(t - 1));
}

using PatchSpline = CubicBSpline;
using LineSpline = QuinticBSpline;
/// How many knots each kernel reaches to either side.
constexpr double kPatchHalfSupport = PatchSpline::kHalfSupport + 1;
constexpr double kLineHalfSupport = LineSpline::kHalfSupport + 1;
/// Knot spacing of P's kernel in cells of the level: one cell (docs/method.md, Kernels). P
/// sums areas, so a sample's shape matters little, and what remains against the exact mode
/// is the blur of P(r)'s kinks, where a sphere meets a crease: the narrower the kernel, the
/// less of it.
constexpr double kPatchKernelCells = 1.0;
/// Knot spacing of L's kernel in cells of the level: 1.25 cells, 1.5 on the finest level.
/// L(r) has square-root onsets (a sphere becoming tangent to a facet, or meeting the
/// bottom of a groove), and blurring them across r is what L̂ differs from the exact mode
/// by, in proportion to the kernel's width. L is a density, so its kernel must also be
/// smooth and wide enough for the samples' irregular shapes to average out: the quintic
/// kernel (C⁴) does that at little more than a cell, where the cubic one (third derivative
/// jumping at the knots) would need two. Narrower still, the shapes show through, most on
/// the finest level, whose samples hold only a few triangle pieces each.
constexpr double kLineKernelCells = 1.25;
constexpr double kLineKernelCellsFinest = 1.5;
/// Histogram bins per cell. Linear sharing between bin centres blurs d by a tent of
/// variance bin²/6; few bins keep the weighted sums per radius cheap.
constexpr int kBinsPerCell = 8;
/// Histogram channels per bin: a, a·g, a·q and a·g·q, all shared linearly between the bins
/// b and b + 1, as one vector of 4 floats.
constexpr std::size_t kChannels = 4;
typedef float Channels __attribute__((vector_size(16)));

/// A kernel's knot spacing at radius r on a level of cell h: @p cells cells, but at most
/// r / @p halfSupport, so that the kernel stays within d >= 0 (small radii on the finest
/// level).
inline double kernelKnotSpacing(double r, double h, double cells, double halfSupport)
{
    return std::min(cells * h, r / halfSupport);
}

/// P's knot spacing at radius r on a level of cell h.
inline double patchKnotSpacing(double r, double h)
{
    return kernelKnotSpacing(r, h, kPatchKernelCells, kPatchHalfSupport);
}
/// L's knot spacing at radius r on level @p level (cell h).
inline double lineKnotSpacing(double r, double h, int level)
{
    return kernelKnotSpacing(r, h, level == 0 ? kLineKernelCellsFinest : kLineKernelCells, kLineHalfSupport);
}

/// How far from a point a radius's kernels reach on level @p level (cell h): the farther of
/// P's and L's.
inline double kernelReach(double r, double h, int level)
{
    return r + std::max(kPatchHalfSupport * patchKnotSpacing(r, h), kLineHalfSupport * lineKnotSpacing(r, h, level));
}

/// The 4 floats at @p from as one vector (an unaligned load, without aliasing floats).
inline Channels loadChannels(const float* from)
{
    Channels v;
    std::memcpy(&v, from, sizeof(v));
    return v;
}

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

/// The kernel of one level: weights per radius and histogram bin.
struct LevelKernel {
    double bin = 0, reach = 0;
    int reachCells = 0, numBins = 0, numRadii = 0;
    /// [(k · numBins + b) · kChannels + c]: the weight of channel c (a, a·g, a·q, a·g·q) of
    /// bin b for radius k of the level: P from the channels a and a·q, L from the others.
    std::vector<float> weights;
    /// Per radius, the bins [first, last) of the kernel's support, an even number of them.
    /// Below first, P's weights are those of a whole area, (1, 0): a running sum of areas.
    std::vector<std::pair<int, int>> patchBins;
};

/// The kernel of the radii @p r (ascending) on a level of cell @p h: weights per radius and
/// bin centre d_b = (b + 1/2)·bin (paper Eq. 2 for P and L as sums over the distance
/// histogram): f(d) = F((r − d)/w) for P, K((d − r)/w)/w for L (coarea formula), and f″/2
/// for the channels a·q and a·g·q (evaluatePoints).
LevelKernel makeLevelKernel(const std::vector<double>& radii, double h, int level)
{
    LevelKernel kernel;
    kernel.bin = h / kBinsPerCell;
    kernel.numRadii = int(radii.size());
    kernel.reach = kernelReach(radii.back(), h, level);
    kernel.reachCells = int(std::ceil(kernel.reach / h)) + 1;
    kernel.numBins = int(std::ceil(kernel.reach / kernel.bin)) + 2;  // bins beyond reach: 0
    kernel.weights.assign(radii.size() * kChannels * std::size_t(kernel.numBins), 0.0f);
    for (std::size_t k = 0; k < radii.size(); ++k) {
        // w for L, wp for P: the bins [whole, inside) cover both supports.
        const double r = radii[k], w = lineKnotSpacing(r, h, level), wp = patchKnotSpacing(r, h);
        int whole = 0, inside = 0;  // whole areas on bins [0, whole), nothing from inside on
        for (int b = 0; b < kernel.numBins; ++b) {
            const double d = (b + 0.5) * kernel.bin, tp = (r - d) / wp, tl = (d - r) / w;
            const bool patchWhole = tp >= kPatchHalfSupport, patchNone = tp <= -kPatchHalfSupport;
            const bool lineNone = std::abs(tl) >= kLineHalfSupport;
            if (patchWhole && lineNone && whole == b) {
                whole = b + 1;
                continue;
            }
            if (patchNone && lineNone) continue;
            inside = b + 1;
            float* at = kernel.weights.data() + (k * kernel.numBins + std::size_t(b)) * kChannels;
            // (Outside a kernel's support these give exactly 1 or 0.)
            at[0] = float(fourthOrder<PatchSpline>(PatchSpline::integral, tp));                            // P: f
            at[1] = float(fourthOrder<LineSpline>(LineSpline::value, tl) / w);                             // L: f
            at[2] = float(0.5 * fourthOrder<PatchSpline>(PatchSpline::derivative, tp) / (wp * wp));        // P: f″/2
            at[3] = float(0.5 * fourthOrder<LineSpline>(LineSpline::secondDerivative, tl) / (w * w * w));  // L: f″/2
        }
        // An even number of bins: one more with weights 0 if needed (d < reach, so
        // inside <= numBins − 2).
        inside = std::max(whole, inside);
        inside += (inside - whole) % 2;
        kernel.patchBins.push_back({whole, inside});
    }
    return kernel;
}

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

/// Cells per axis of a group of points that share one list of nearby samples in the kernel
/// sums: 8, so that copying the samples' 16 numbers costs less than binning them for each
/// point (a larger group makes each point bin more samples beyond its reach).
constexpr int kGroupBits = 3;
/// Samples per run with a bounding box in a group's list (evaluatePoints).
constexpr std::size_t kChunk = 16;

/// Points in groups of (2^groupBits)³ cells of level l (Morton order), so that a group can
/// share one gathered list of nearby samples: order[k] = (group key, point), groups
/// [start[g], start[g + 1]), and each point's level-l cell.
struct CellGroups {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order;
    std::vector<std::size_t> start;
    std::vector<CellCoord> cell;
};

CellGroups groupByCells(const std::vector<Vec3>& points, double h0, int l, int groupBits = 2)
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

/// Unnormalised P ∗ K and L ∗ K at @p points for the radii of one level: out[k·n + q].
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

/// Samples whose normals lie within about 18° of a point's normal on average (mean (n·n_p)²
/// at least this) are on the same smooth side of the surface: P̂ and L̂ bend across creases,
/// where a fit over both sides would blur them.
constexpr double kSameSide = 0.9;
/// The fit needs at least 6 such samples spread around the point: det M / M₀₀³ of its
/// normal equations at least this (a full disc of samples gives about 0.2).
constexpr double kWellSpread = 0.02;

/// Levels whose cells are at most this many vertex spacings are evaluated at the vertices,
/// coarser ones at the samples. On an evenly triangulated surface the samples outnumber the
/// vertices up to cells of about 1.0-1.1 median edges. Not exactly 1: the automatic voxel
/// is often half a median edge, which puts the second level's cells at exactly one, where
/// the smallest change of the mesh would flip the route.
constexpr double kDirectCellsPerSpacing = 1.2;

/// Interpolates fields given at the samples of @p level (values[k·numSamples + s], k <
/// numFields) to the points @p p with normals @p n (out[k·n + i]; points with @p skip set
/// are left alone): a linear fit in the tangent plane (value and two slopes) over the
/// samples within 2h on the point's side of the surface (kSameSide), weighted (1 −
/// (d/2h)²)⁸, so linear fields are reproduced. Where such samples do not span the plane
/// (creases, corners), @p unresolved is set instead: those points are evaluated directly.
/// Points go in groups of 2³ cells (of 4³, four fifths of the samples near a group lie
/// beyond 2h of a point; of 2³, two thirds).
constexpr int kFitGroupBits = 1;
void interpolateFromSamples(const Level& level, double h0, const std::vector<Vec3>& p,
                            const std::vector<Vec3>& n, const std::vector<char>& skip,
                            int numFields, const std::vector<const float*>& values,
                            const std::vector<float*>& out, std::vector<char>& unresolved)
{
    unresolved.assign(p.size(), 0);
    const double h = level.h, radius2 = 4.0 * h * h;
    const CellGroups groups = groupByCells(p, h0, level.index, kFitGroupBits);
    const std::int64_t groupCells = std::int64_t(1) << kFitGroupBits;
    const double groupSide = double(groupCells) * h;
    const std::array<double, 6> groupBox{0, 0, 0, groupSide, groupSide, groupSide};  // about (ox, oy, oz)
    const auto& order = groups.order;
    const auto& groupStart = groups.start;

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupStart.size() - 1), [&](const auto& range) {
        // The group's nearby samples, copied together (index, centroid, normal tensor), so
        // that each point's loop over them reads memory in order.
        std::vector<std::uint32_t> near, index;
        std::vector<double> nearX, nearY, nearZ;
        std::array<std::vector<float>, 6> nearT;
        std::vector<double> weight;
        std::vector<std::array<double, 3>> basis;
        for (std::size_t g = range.begin(); g < range.end(); ++g) {
            const CellCoord& c0 = groups.cell[order[groupStart[g]].second];
            const std::int64_t gx = c0.x & ~(groupCells - 1), gy = c0.y & ~(groupCells - 1),
                               gz = c0.z & ~(groupCells - 1);
            near.clear();
            // Samples within 2h of the group's box: at most 2 cells beyond it.
            const std::int64_t lo[3] = {gx - 2, gy - 2, gz - 2},
                               hi[3] = {gx + groupCells + 1, gy + groupCells + 1, gz + groupCells + 1};
            const double ox = double(gx - (kOffset >> level.index)) * h,
                         oy = double(gy - (kOffset >> level.index)) * h,
                         oz = double(gz - (kOffset >> level.index)) * h;
            forEachSampleInCells(level, lo, hi, [&](std::uint32_t s) {
                if (squaredDistanceToBox(level.cx[s] - ox, level.cy[s] - oy, level.cz[s] - oz, groupBox) < radius2)
                    near.push_back(s);
            });
            nearX.resize(near.size()), nearY.resize(near.size()), nearZ.resize(near.size());
            for (auto& t : nearT) t.resize(near.size());
            for (std::size_t k = 0; k < near.size(); ++k) {
                const std::uint32_t s = near[k];
                nearX[k] = level.cx[s], nearY[k] = level.cy[s], nearZ[k] = level.cz[s];
                for (std::size_t c = 0; c < 6; ++c) nearT[c][k] = level.tensor[c][s];
            }
            for (std::size_t q = groupStart[g]; q < groupStart[g + 1]; ++q) {
                const std::uint32_t i = order[q].second;
                if (skip[i]) continue;
                const Vec3& nrm = n[i];
                const Vec3 u = normalized(std::abs(nrm.x) < 0.9 ? cross(nrm, Vec3(1, 0, 0)) : cross(nrm, Vec3(0, 1, 0)));
                const Vec3 v = cross(nrm, u);
                double m[3][3] = {};
                index.clear(), weight.clear(), basis.clear();
                for (std::size_t k = 0; k < near.size(); ++k) {
                    const Vec3 d(nearX[k] - p[i].x, nearY[k] - p[i].y, nearZ[k] - p[i].z);
                    const double d2 = squaredNorm(d);
                    if (d2 >= radius2) continue;  // (no division for the many beyond)
                    const double q2 = d2 / radius2;
                    const auto& t = nearT;
                    const double agree = nrm.x * nrm.x * t[0][k] + nrm.y * nrm.y * t[1][k] + nrm.z * nrm.z * t[2][k] +
                                         2.0 * (nrm.x * nrm.y * t[3][k] + nrm.x * nrm.z * t[4][k] + nrm.y * nrm.z * t[5][k]);
                    if (agree < kSameSide) continue;
                    // (1 − q²)⁸ ≈ exp(−2 |d|²/h²): the fit leans on the samples within about
                    // h/2, as P̂ and L̂ bend on a scale of h near creases (docs/method.md,
                    // Where P and L are evaluated).
                    const double s2 = (1.0 - q2) * (1.0 - q2), s4 = s2 * s2;
                    const double wt = s4 * s4;
                    const std::array<double, 3> phi{1.0, dot(d, u) / h, dot(d, v) / h};
                    for (int a = 0; a < 3; ++a)
                        for (int b = 0; b < 3; ++b) m[a][b] += wt * phi[a] * phi[b];
                    index.push_back(near[k]);
                    weight.push_back(wt);
                    basis.push_back(phi);
                }
                if (index.size() < 6) {
                    unresolved[i] = 1;
                    continue;
                }
                // First row of m⁻¹ (cofactors): the fitted value is Σ wt·(row·φ)·f.
                const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
                const double c01 = -(m[1][0] * m[2][2] - m[1][2] * m[2][0]);
                const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
                const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
                if (!(det > kWellSpread * m[0][0] * m[0][0] * m[0][0])) {
                    unresolved[i] = 1;
                    continue;
                }
                for (std::size_t k = 0; k < index.size(); ++k)
                    weight[k] *= (c00 * basis[k][0] + c01 * basis[k][1] + c02 * basis[k][2]) / det;
                for (int f = 0; f < numFields; ++f) {
                    double sum = 0;
                    for (std::size_t k = 0; k < index.size(); ++k)
                        sum += weight[k] * values[std::size_t(f)][index[k]];
                    out[std::size_t(f)][i] = float(sum);
                }
            }
        }
    });
}

} // namespace

std::vector<int> patchLineLevelOfRadius(const std::vector<double>& radii, double h0, double minCellsPerRadius)
{
    std::vector<int> level = gridLevelOfRadius(radii, h0, minCellsPerRadius);
    const std::size_t n = radii.size();
    if (n < 2 || level[n - 1] == 0 || level[n - 2] != level[n - 1] - 1) return level;
    // Samples binned on a level of cell h and reach ρ, per unit area: (points ∝ 1/h², its
    // samples or the vertices if fewer) × (samples within reach ∝ (ρ/h)²). With c = 2h the
    // coarsest cell, extending the level below from the radius before to r costs
    // 16 (ρ_h(r)² − ρ_h(r_prev)²) / c⁴, and the coarsest level's own pass ρ_c(r)² / c⁴.
    const double r = radii[n - 1], below = h0 * std::ldexp(1.0, level[n - 1] - 1);
    const int lb = level[n - 1] - 1;
    const double extend = 16.0 * (std::pow(kernelReach(r, below, lb), 2) - std::pow(kernelReach(radii[n - 2], below, lb), 2));
    if (extend <= std::pow(kernelReach(r, 2.0 * below, lb + 1), 2)) --level[n - 1];
    return level;
}

PatchLineResult computePatchLine(const TriMesh& mesh, const PatchLineOptions& options,
                                 RunContext* progress)
{
    const auto& radii = options.radii;
    validateRadii(radii);
    const double h0 = options.cellSize;
    if (!(h0 > 0) || !std::isfinite(h0)) throw InvalidInputError("the sample cell size must be positive");
    if (!(options.minCellsPerRadius >= 1))
        throw InvalidInputError("the precision (cells per radius) must be at least 1");
    const std::size_t nv = mesh.numVertices();
    const double spacing = options.vertexSpacing > 0 ? options.vertexSpacing : computeMeshStats(mesh).medianEdge;
    if (!options.borderDistance.empty() && options.borderDistance.size() != nv)
        throw InvalidInputError("border distances do not match the vertex count");
    for (const Vec3& p : mesh.points) {
        const CellCoord c = cellOf(p, h0);
        if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= kCoordLimit || c.y >= kCoordLimit || c.z >= kCoordLimit)
            throw InvalidInputError("the mesh reaches more than a million sample cells from the origin; "
                                    "use a larger voxel size or move the mesh near the origin");
    }

    PatchLineResult result;
    result.radii = radii;
    const std::vector<int> planLevel = gridLevelOfRadius(radii, h0, options.minCellsPerRadius);
    result.levelOfRadius = options.levelOfRadius.empty() ? patchLineLevelOfRadius(radii, h0, options.minCellsPerRadius)
                                                         : options.levelOfRadius;
    if (result.levelOfRadius.size() != radii.size())
        throw InvalidInputError("the sample levels do not match the radii");
    const int numLevels = *std::max_element(result.levelOfRadius.begin(), result.levelOfRadius.end()) + 1;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    if (options.computePatch) result.patch.assign(radii.size(), std::vector<float>(nv, nan));
    if (options.computeLine) result.line.assign(radii.size(), std::vector<float>(nv, nan));
    if (!options.computePatch && !options.computeLine) return result;

    Stopwatch stage;
    std::vector<Level> levels;
    {
        SampleParts sums = finestSamples(mesh, h0, numLevels - 1);
        result.numSamples = totalSize(sums);
        for (int l = 0; l < numLevels; ++l) {
            if (l > 0) sums = coarser(sums);
            levels.push_back(makeLevel(sums, h0, l));
        }
    }
    result.samplingSeconds = stage.seconds();
    stage.restart();

    std::vector<Vec3> vertexNormal;                // for interpolation, when needed

    for (int l = 0; l < numLevels; ++l) {
        std::vector<int> levelRadii;
        for (std::size_t j = 0; j < radii.size(); ++j)
            if (result.levelOfRadius[j] == l) levelRadii.push_back(int(j));
        if (levelRadii.empty()) continue;
        const Level& level = levels[std::size_t(l)];
        std::vector<double> levelR;
        for (int j : levelRadii) levelR.push_back(radii[std::size_t(j)]);
        const LevelKernel kernel = makeLevelKernel(levelR, level.h, l);
        const double binVariance = kernel.bin * kernel.bin / 6.0;
        // A value is masked when the kernel's reach, plus the spread of a sample, gets to a
        // border: max(kernelReach, r + 4h) + 2 h0, with h the cell of the radius's level in
        // the V/S plan, so at least where V and S are (r + 4h + 2 h0), also for a merged level.
        std::vector<double> maskReach(levelR.size());  // per radius of the level
        for (std::size_t k = 0; k < levelR.size(); ++k) {
            const double r = levelR[k];
            const double vs = r + 4.0 * h0 * std::ldexp(1.0, planLevel[std::size_t(levelRadii[k])]);
            maskReach[k] = std::max(kernelReach(r, level.h, l), vs) + 2.0 * h0;
        }
        const auto masked = [&](std::size_t i, std::size_t k) {
            return !options.borderDistance.empty() && maskReach[k] > options.borderDistance[i];
        };
        const auto store = [&](std::size_t i, std::size_t k, double sumP, double sumL) {
            const std::size_t j = std::size_t(levelRadii[k]);
            const double r = radii[j];
            if (masked(i, k)) return;
            // K has no second moment, but the binning adds a tent of variance bin²/6 to the
            // blur across r: P = π r² gives π (r² + bin²/6), divided out.
            if (options.computePatch) result.patch[j][i] = float(sumP / (M_PI * (r * r + binVariance)));
            if (options.computeLine) result.line[j][i] = float(sumL / (2.0 * M_PI * r));
        };
        std::vector<char> skip(nv);  // every radius of the level is masked
        for (std::size_t i = 0; i < nv; ++i) skip[i] = masked(i, 0);
        std::vector<float> sumP, sumL;
        const std::size_t numSamples = level.cx.size();
        if (level.h <= kDirectCellsPerSpacing * spacing) {
            // Cells about the vertex spacing or finer, so about as many samples as vertices
            // or more: evaluate at the vertices themselves. Decided from the whole mesh's
            // spacing, not from this mesh's counts, so that a tile with more or less of the
            // surface per vertex than the whole takes the same route (bit-identical tiles).
            evaluatePoints(level, kernel, h0, mesh.points, skip, sumP, sumL, progress);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& range) {
                for (std::size_t i = range.begin(); i < range.end(); ++i)
                    for (std::size_t k = 0; k < levelRadii.size(); ++k)
                        store(i, k, sumP[k * nv + i], sumL[k * nv + i]);
            });
        } else {
            // Far fewer samples than vertices (coarse levels of dense meshes): evaluate at the
            // samples (one per cell, on the surface) and interpolate to the vertices. P̂ and L̂
            // vary on the scale of r >= minCellsPerRadius·h, so a linear fit over 2h loses
            // about (h/r)²/8 of their variation.
            std::vector<Vec3> at(numSamples);
            for (std::size_t s = 0; s < numSamples; ++s) at[s] = Vec3(level.cx[s], level.cy[s], level.cz[s]);
            evaluatePoints(level, kernel, h0, at, std::vector<char>(numSamples, 0), sumP, sumL, progress);
            if (vertexNormal.empty()) vertexNormal = vertexNormals(mesh, Vec3(0, 0, 1));
            const int nr = int(levelRadii.size());
            std::vector<float> atP(std::size_t(nr) * nv), atL(std::size_t(nr) * nv);
            std::vector<const float*> from;
            std::vector<float*> to;
            for (int k = 0; k < nr; ++k) {
                from.push_back(sumP.data() + std::size_t(k) * numSamples);
                from.push_back(sumL.data() + std::size_t(k) * numSamples);
                to.push_back(atP.data() + std::size_t(k) * nv);
                to.push_back(atL.data() + std::size_t(k) * nv);
            }
            std::vector<char> unresolved;
            interpolateFromSamples(level, h0, mesh.points, vertexNormal, skip, 2 * nr, from, to, unresolved);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& range) {
                for (std::size_t i = range.begin(); i < range.end(); ++i)
                    if (!skip[i] && !unresolved[i])
                        for (std::size_t k = 0; k < levelRadii.size(); ++k)
                            store(i, k, atP[k * nv + i], atL[k * nv + i]);
            });
            // Vertices on creases and corners: evaluated where they are.
            std::vector<std::uint32_t> direct;
            for (std::size_t i = 0; i < nv; ++i)
                if (unresolved[i] && !skip[i]) direct.push_back(std::uint32_t(i));
            result.directEvaluations += direct.size();
            if (!direct.empty()) {
                std::vector<Vec3> points(direct.size());
                for (std::size_t q = 0; q < direct.size(); ++q) points[q] = mesh.points[direct[q]];
                evaluatePoints(level, kernel, h0, points, std::vector<char>(direct.size(), 0), sumP, sumL, nullptr);
                const std::size_t nd = direct.size();
                for (std::size_t q = 0; q < nd; ++q)
                    for (std::size_t k = 0; k < levelRadii.size(); ++k)
                        store(direct[q], k, sumP[k * nd + q], sumL[k * nd + q]);
            }
        }
    }
    result.gatherSeconds = stage.seconds();
    return result;
}

} // namespace msii
