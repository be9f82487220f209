#include "patch_line_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace msii::detail {

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

} // namespace msii::detail
