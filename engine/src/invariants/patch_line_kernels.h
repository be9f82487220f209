#pragma once
/// @file patch_line_kernels.h
/// @brief Steps 3 and 4 of P and L (msii/invariants/patch_line.h): the kernels. K from the
/// cubic B-spline (P) and the quintic one (L), with zero second moment, and F its integral;
/// their knot spacings and reach per level; the histogram's bins and channels; and a level's
/// weights per radius and bin (LevelKernel). What the kernel sums call is inline here.
/// Private to the engine (patch_line.cpp and its parts).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <utility>
#include <vector>

namespace msii::detail {

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

/// How much narrower the check's kernels are than the default ones (docs/method.md, Exact
/// where the kernels blur): knot spacings w/1.5. Within the default kernels' support.
constexpr double kCheckNarrowing = 1.5;

/// The kernel of one level: weights per row and histogram bin. Rows [0, numRadii) are the
/// level's radii; with the check, each radius k also has three rows from numRadii + 3k on:
/// the default kernel halfway to the radius below (r − Δ/2, Δ the spacing of the radii), the
/// narrow one there, and the narrow one at r (docs/method.md, The check).
struct LevelKernel {
    double bin = 0, reach = 0;
    int reachCells = 0, numBins = 0, numRadii = 0, numRows = 0;
    /// [(row · numBins + b) · kChannels + c]: the weight of channel c (a, a·g, a·q, a·g·q) of
    /// bin b for a row: P from the channels a and a·q, L from the others.
    std::vector<float> weights;
    /// Per row, the bins [first, last) of the kernel's support, an even number of them.
    /// Below first, P's weights are those of a whole area, (1, 0): a running sum of areas.
    std::vector<std::pair<int, int>> patchBins;
    /// Per row: what turns its sums into P̂ (1/(π (r² + bin²/6))) and L̂ (1/(2π r)).
    std::vector<double> patchScale, lineScale;
    bool check() const { return numRows > numRadii; }
};

/// The kernel of the radii @p r (ascending) on a level of cell @p h: weights per radius and
/// bin centre d_b = (b + 1/2)·bin (paper Eq. 2 for P and L as sums over the distance
/// histogram): f(d) = F((r − d)/w) for P, K((d − r)/w)/w for L (coarea formula), and f″/2
/// for the channels a·q and a·g·q (evaluatePoints). With @p spacing > 0 (Δ, the spacing of
/// all radii), also the check's rows.
LevelKernel makeLevelKernel(const std::vector<double>& radii, double h, int level, double spacing = 0);

} // namespace msii::detail
