#include <msii/render/picture.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace msii {
namespace {

void checkChannel(const std::vector<float>* c, std::size_t n, const char* what)
{
    if (!c) throw InvalidInputError(std::string("the picture needs the ") + what + " channel");
    if (c->size() != n) throw InvalidInputError(std::string("the ") + what + " channel has the wrong size");
}

/// Marks (1) the pixels of the 4-connected regions above or below @p level (finite pixels
/// only) with fewer than @p minPixels pixels.
std::vector<std::uint8_t> smallRegions(const std::vector<float>& f, int w, int h, double level, int minPixels)
{
    const std::size_t n = std::size_t(w) * std::size_t(h);
    std::vector<std::uint8_t> small(n, 0);
    if (minPixels <= 1) return small;
    std::vector<std::uint8_t> seen(n, 0);
    std::vector<std::size_t> region, stack;
    for (std::size_t start = 0; start < n; ++start) {
        if (seen[start] || !std::isfinite(f[start])) continue;
        const bool above = f[start] >= level;
        region.clear();
        stack.assign(1, start);
        seen[start] = 1;
        while (!stack.empty()) {
            const std::size_t i = stack.back();
            stack.pop_back();
            region.push_back(i);
            const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
            const std::size_t next[4] = {x > 0 ? i - 1 : n, x + 1 < w ? i + 1 : n, y > 0 ? i - std::size_t(w) : n,
                                         y + 1 < h ? i + std::size_t(w) : n};
            for (const std::size_t j : next)
                if (j < n && !seen[j] && std::isfinite(f[j]) && (f[j] >= level) == above) {
                    seen[j] = 1;
                    stack.push_back(j);
                }
        }
        if (region.size() < std::size_t(minPixels))
            for (const std::size_t i : region) small[i] = 1;
    }
    return small;
}

/// Isolines by marching squares over the pixel centres: per cell of four neighbouring
/// pixels, the segments where the bilinear field crosses each level (saddles split by the
/// cell's mean), drawn anti-aliased; not around regions of fewer than @p minPixels pixels.
void drawIsolines(RgbImage& image, const std::vector<float>& f, int w, int h, const std::vector<double>& levels,
                  int minPixels)
{
    if (levels.empty()) return;
    std::vector<double> sorted(levels);
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::vector<std::uint8_t>> small;
    for (const double level : sorted) small.push_back(smallRegions(f, w, h, level, minPixels));
    const Rgb8 black{0, 0, 0};
    for (int y = 0; y + 1 < h; ++y)
        for (int x = 0; x + 1 < w; ++x) {
            // Corners counter-clockwise: (x, y), (x+1, y), (x+1, y+1), (x, y+1).
            const double v[4] = {f[std::size_t(y) * w + x], f[std::size_t(y) * w + x + 1],
                                 f[std::size_t(y + 1) * w + x + 1], f[std::size_t(y + 1) * w + x]};
            if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) && std::isfinite(v[3]))) continue;
            const double lo = std::min({v[0], v[1], v[2], v[3]}), hi = std::max({v[0], v[1], v[2], v[3]});
            const double px[4] = {x + 0.5, x + 1.5, x + 1.5, x + 0.5}, py[4] = {y + 0.5, y + 0.5, y + 1.5, y + 1.5};
            for (auto it = std::upper_bound(sorted.begin(), sorted.end(), lo); it != sorted.end() && *it <= hi; ++it) {
                const double level = *it;
                const std::vector<std::uint8_t>& tiny = small[std::size_t(it - sorted.begin())];
                const std::size_t i0 = std::size_t(y) * w + x, i1 = i0 + std::size_t(w);
                if (tiny[i0] || tiny[i0 + 1] || tiny[i1] || tiny[i1 + 1]) continue;
                double cx[4], cy[4];
                int n = 0;
                for (int e = 0; e < 4; ++e) {
                    const int a = e, b = (e + 1) % 4;
                    const bool sa = v[a] >= level, sb = v[b] >= level;
                    if (sa == sb) continue;
                    const double t = (level - v[a]) / (v[b] - v[a]);
                    cx[n] = px[a] + t * (px[b] - px[a]);
                    cy[n] = py[a] + t * (py[b] - py[a]);
                    ++n;
                }
                if (n == 2) {
                    drawLine(image, cx[0], cy[0], cx[1], cy[1], black, 1.0);
                } else if (n == 4) {
                    // Saddle: pair the crossings so that the cell's mean side stays connected.
                    const bool meanAbove = 0.25 * (v[0] + v[1] + v[2] + v[3]) >= level;
                    const bool firstAbove = v[0] >= level;
                    if (meanAbove == firstAbove) {
                        drawLine(image, cx[0], cy[0], cx[1], cy[1], black, 1.0);
                        drawLine(image, cx[2], cy[2], cx[3], cy[3], black, 1.0);
                    } else {
                        drawLine(image, cx[0], cy[0], cx[3], cy[3], black, 1.0);
                        drawLine(image, cx[1], cy[1], cx[2], cy[2], black, 1.0);
                    }
                }
            }
        }
}

} // namespace

PictureResult renderPicture(const PictureChannels& ch, const PictureOptions& options)
{
    if (ch.width <= 0 || ch.height <= 0) throw InvalidInputError("the picture is empty");
    const std::size_t n = std::size_t(ch.width) * std::size_t(ch.height);
    if (!options.colour && !options.shade) throw InvalidInputError("the picture shows neither colour nor shading");
    if (!(options.shadeStrength >= 0 && options.shadeStrength <= 1))
        throw InvalidInputError("the shading strength must be in [0, 1]");
    if (options.isolineCount < 0) throw InvalidInputError("the isoline count must not be negative");
    std::vector<float> ones;
    const std::vector<float>* mask = ch.mask;
    if (mask) checkChannel(mask, n, "mask");
    else {
        ones.assign(n, 1.0f);
        mask = &ones;
    }

    PictureResult result;
    std::vector<float> shade;
    if (options.shade) {
        checkChannel(ch.nx, n, "normal.x");
        checkChannel(ch.ny, n, "normal.y");
        checkChannel(ch.nz, n, "normal.z");
        shade = shadeRelief(ch.width, ch.height, *ch.nx, *ch.ny, *ch.nz, *mask, options.shading);
    }
    std::vector<float> masked;  // the value where the mask is set, NaN elsewhere
    if (options.colour) {
        checkChannel(ch.value, n, "value");
        masked.resize(n);
        for (std::size_t i = 0; i < n; ++i) masked[i] = (*mask)[i] > 0.5f ? (*ch.value)[i] : NAN;
        if (options.fixedRange) {
            if (!(std::isfinite(options.range.lo) && std::isfinite(options.range.hi) && options.range.lo < options.range.hi))
                throw InvalidInputError("the colour range must be two finite values, low < high");
            result.range = options.range;
        } else {
            result.range = percentileRange(masked, options.loPercentile, options.hiPercentile,
                                           options.centered ? &options.center : nullptr);
        }
        if (options.fixedRange && options.centered) {
            const double d = std::max(std::abs(result.range.lo - options.center), std::abs(result.range.hi - options.center));
            result.range = {options.center - d, options.center + d};
        }
    }

    RgbImage image(ch.width, ch.height, options.background);
    const double lo = result.range.lo, span = result.range.hi - result.range.lo;
    tbb::parallel_for(tbb::blocked_range<int>(0, ch.height), [&](const auto& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < ch.width; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(ch.width) + std::size_t(x);
                if (!((*mask)[i] > 0.5f)) continue;
                double r = 255, g = 255, b = 255;
                if (options.colour) {
                    const Rgb8 c = colorAt(options.colorMap, std::isfinite(masked[i]) ? (masked[i] - lo) / span : NAN);
                    r = c[0], g = c[1], b = c[2];
                }
                if (options.shade) {
                    const double s = std::isfinite(shade[i]) ? shade[i] : 0.5;
                    const double m = options.colour ? 1.0 - options.shadeStrength + options.shadeStrength * s : s;
                    r *= m, g *= m, b *= m;
                }
                image.set(x, y, Rgb8{std::uint8_t(std::lround(std::clamp(r, 0.0, 255.0))),
                                     std::uint8_t(std::lround(std::clamp(g, 0.0, 255.0))),
                                     std::uint8_t(std::lround(std::clamp(b, 0.0, 255.0)))});
            }
    });

    if (options.colour) {
        result.isolineLevels = options.isolineLevels;
        for (int k = 1; k <= options.isolineCount; ++k)
            result.isolineLevels.push_back(lo + span * k / (options.isolineCount + 1));
        for (double l : result.isolineLevels)
            if (!std::isfinite(l)) throw InvalidInputError("isoline levels must be finite");
        if (options.isolineMinPixels < 0) throw InvalidInputError("the isolines' minimum region must not be negative");
        drawIsolines(image, masked, ch.width, ch.height, result.isolineLevels, options.isolineMinPixels);
    }
    result.image = std::move(image);
    return result;
}

} // namespace msii
