#include "patch_line_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace msii::detail {

namespace {

/// The weights of P's kernel of knot spacing @p wp and L's of @p w at distance @p d from
/// radius @p r, into at[0..3] (docs/method.md, Kernels and Second-order quadrature).
void kernelWeights(double r, double d, double wp, double w, float* at)
{
    const double tp = (r - d) / wp, tl = (d - r) / w;
    // (Outside a kernel's support these give exactly 1 or 0.)
    at[0] = float(fourthOrder<PatchSpline>(PatchSpline::integral, tp));                            // P: f
    at[1] = float(fourthOrder<LineSpline>(LineSpline::value, tl) / w);                             // L: f
    at[2] = float(0.5 * fourthOrder<PatchSpline>(PatchSpline::derivative, tp) / (wp * wp));        // P: f″/2
    at[3] = float(0.5 * fourthOrder<LineSpline>(LineSpline::secondDerivative, tl) / (w * w * w));  // L: f″/2
}

} // namespace

namespace {

/// Adds to @p kernel a row of P's kernel of knot spacing @p wp and L's of @p w about radius
/// @p r, and its bins.
void addRow(LevelKernel& kernel, double r, double wp, double w)
{
    const std::size_t row = std::size_t(kernel.numRows++);
    kernel.weights.resize(std::size_t(kernel.numRows) * kChannels * std::size_t(kernel.numBins), 0.0f);
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
        kernelWeights(r, d, wp, w, kernel.weights.data() + (row * kernel.numBins + std::size_t(b)) * kChannels);
    }
    // An even number of bins: one more with weights 0 if needed (d < reach, so inside <=
    // numBins − 2).
    inside = std::max(whole, inside);
    inside += (inside - whole) % 2;
    kernel.patchBins.push_back({whole, inside});
    kernel.patchScale.push_back(1.0 / (M_PI * (r * r + kernel.bin * kernel.bin / 6.0)));
    kernel.lineScale.push_back(1.0 / (2.0 * M_PI * r));
}

} // namespace

LevelKernel makeLevelKernel(const std::vector<double>& radii, double h, int level, double spacing)
{
    LevelKernel kernel;
    kernel.bin = h / kBinsPerCell;
    kernel.numRadii = int(radii.size());
    kernel.reach = kernelReach(radii.back(), h, level);
    kernel.reachCells = int(std::ceil(kernel.reach / h)) + 1;
    kernel.numBins = int(std::ceil(kernel.reach / kernel.bin)) + 2;  // bins beyond reach: 0
    for (const double r : radii) addRow(kernel, r, patchKnotSpacing(r, h), lineKnotSpacing(r, h, level));
    if (!(spacing > 0)) return kernel;
    for (const double r : radii) {
        const double mid = std::max(r - 0.5 * spacing, 0.5 * r);
        const double wpMid = patchKnotSpacing(mid, h), wMid = lineKnotSpacing(mid, h, level);
        addRow(kernel, mid, wpMid, wMid);
        addRow(kernel, mid, wpMid / kCheckNarrowing, wMid / kCheckNarrowing);
        addRow(kernel, r, patchKnotSpacing(r, h) / kCheckNarrowing, lineKnotSpacing(r, h, level) / kCheckNarrowing);
    }
    return kernel;
}

} // namespace msii::detail
