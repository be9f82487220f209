/// @file annotate.cpp
/// @brief The colour bar, the scale bar and their tick values and labels.
///
/// Layout (s = fontScale, all sizes in output pixels): the picture sits at the top left,
/// unchanged. The right margin holds, from the left, a gap of 2·pad (pad = 6s), the bar
/// (10s wide, framed by a 1-pixel black line outside it), ticks of 3s, a gap of 2s and the
/// tick labels, then pad; the label is centred above the bar. The bar is centred on the
/// picture's height where there is room. The bottom margin holds the scale bar (2s thick,
/// starting pad pixels from the left) with its label centred under it.

#include <msii/render/annotate.h>

#include <msii/core/errors.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace msii {

namespace {

constexpr Rgb8 kWhite{255, 255, 255};
constexpr Rgb8 kBlack{0, 0, 0};

/// 10^p, exact for |p| <= 22.
double powerOfTen(int p)
{
    if (p < -22 || p > 22) return std::pow(10.0, p);
    double v = 1;
    for (int i = 0; i < std::abs(p); ++i) v *= 10;
    return p < 0 ? 1 / v : v;
}

/// m × 10^p for an integer m, rounded once (so that 3 × 2 × 10^-1 gives the double of 0.6).
double scaled(long long m, int p)
{
    if (p >= 0) return double(m) * powerOfTen(p);
    if (p >= -22) return double(m) / powerOfTen(-p);
    return double(m) * std::pow(10.0, p);
}

/// The nice value (1, 2 or 5 × 10^k) closest to @p target on a log scale.
double niceLength(double target)
{
    const int e = int(std::floor(std::log10(target)));
    double best = 0, bestError = 0;
    for (int m : {1, 2, 5, 10}) {
        const double v = scaled(m, e);
        const double err = std::fabs(std::log(v / target));
        if (best == 0 || err < bestError) {
            best = v;
            bestError = err;
        }
    }
    return best;
}

/// Decimals needed to write multiples of @p step exactly (0–15).
int decimalsFor(double step)
{
    for (int d = 0; d < 15; ++d) {
        const double v = std::fabs(step) * powerOfTen(d);
        if (std::fabs(v - std::round(v)) <= 1e-6 * std::max(1.0, v)) return d;
    }
    return 15;
}

std::string stripFractionZeros(std::string text)
{
    if (text.find('.') == std::string::npos) return text;
    while (!text.empty() && text.back() == '0') text.pop_back();
    if (!text.empty() && text.back() == '.') text.pop_back();
    return text;
}

std::string formatFixed(double value, int decimals)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
    std::string text = stripFractionZeros(buf);
    if (text == "-0") text = "0";
    return text;
}

/// value in %e style with the fewest mantissa digits that keep it within step/10^6.
std::string formatScientific(double value, double step)
{
    char buf[64];
    for (int p = 0; p <= 15; ++p) {
        std::snprintf(buf, sizeof buf, "%.*e", p, value);
        if (std::fabs(std::strtod(buf, nullptr) - value) <= 1e-6 * std::fabs(step)) break;
    }
    std::string text = buf;
    const std::size_t ePos = text.find('e');
    return stripFractionZeros(text.substr(0, ePos)) + text.substr(ePos);
}

/// Sets labels in the figure's typeface, or in the built-in font at the figure's scale.
struct Pen {
    const Typeface* typeface;
    int lineHeight;  // with a typeface
    int scale;       // built-in font
    int height() const { return typeface ? lineHeight : textHeight(scale); }
    int width(const std::string& text) const
    {
        return typeface ? typeface->textWidth(text, lineHeight) : textWidth(text, scale);
    }
    void draw(RgbImage& image, int x, int y, const std::string& text) const
    {
        if (typeface) typeface->drawText(image, x, y, text, kBlack, lineHeight);
        else drawText(image, x, y, text, kBlack, scale);
    }
};

} // namespace

std::vector<double> niceTicks(double lo, double hi, int count)
{
    if (!std::isfinite(lo) || !std::isfinite(hi))
        throw InvalidInputError("tick values need a finite range.");
    if (count < 1) throw InvalidInputError("the number of ticks must be at least 1.");
    if (lo > hi) std::swap(lo, hi);
    if (hi - lo <= 0 || !std::isfinite(hi - lo)) return {lo};

    const double raw = (hi - lo) / count;
    const int e = int(std::floor(std::log10(raw)));
    // Candidate steps a × 10^p with a integer: 1, 2, 2.5, 5, 10 × 10^e.
    struct Step {
        long long a;
        int p;
    };
    const Step candidates[] = {{1, e}, {2, e}, {25, e - 1}, {5, e}, {1, e + 1}};
    Step best = candidates[0];
    double bestError = -1;
    for (const Step& c : candidates) {
        const double err = std::fabs(std::log(scaled(c.a, c.p) / raw));
        if (bestError < 0 || err < bestError - 1e-12) {
            best = c;
            bestError = err;
        }
    }
    const double step = scaled(best.a, best.p);
    const auto kFirst = static_cast<long long>(std::ceil(lo / step - 1e-9));
    const auto kLast = static_cast<long long>(std::floor(hi / step + 1e-9));
    std::vector<double> ticks;
    for (long long k = kFirst; k <= kLast; ++k) ticks.push_back(scaled(k * best.a, best.p));
    return ticks;
}

double scaleBarLength(int pictureWidth, double pixelSize) { return niceLength(pictureWidth * pixelSize / 5); }

std::string formatTick(double value, double step)
{
    if (!std::isfinite(value)) return value != value ? "nan" : (value > 0 ? "inf" : "-inf");
    if (!(step > 0) || !std::isfinite(step)) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", value);
        return buf;
    }
    if (std::fabs(value) < 1e-9 * step) value = 0;
    const int d = decimalsFor(step);
    if (value != 0 && (d >= 4 || std::fabs(value) >= 1e6)) return formatScientific(value, step);
    return formatFixed(value, d);
}

RgbImage composeFigure(const RgbImage& picture, const FigureOptions& options)
{
    if (picture.width <= 0 || picture.height <= 0)
        throw InvalidInputError("cannot annotate an empty picture.");
    if (picture.rgb.size() != 3 * std::size_t(picture.width) * std::size_t(picture.height))
        throw InvalidInputError("the picture's pixel buffer does not match its size.");
    if (options.fontScale < 1)
        throw InvalidInputError("the font scale must be at least 1 (got " +
                                std::to_string(options.fontScale) + ").");
    if (options.typeface && options.lineHeight < 6)
        throw InvalidInputError("the labels' line height must be at least 6 pixels (got " +
                                std::to_string(options.lineHeight) + ").");
    const ValueRange range = options.range;
    if (options.colorBar &&
        !(std::isfinite(range.lo) && std::isfinite(range.hi) && range.hi > range.lo))
        throw InvalidInputError("the colour bar needs a finite value range with low < high.");
    if (options.scaleBar && !std::isfinite(options.pixelSize))
        throw InvalidInputError("the pixel size for the scale bar must be finite.");

    const int s = options.typeface ? std::max(1, options.lineHeight / 9) : options.fontScale;
    const Pen pen{options.typeface, options.lineHeight, s};
    const int pad = 6 * s;
    const int th = pen.height();
    const int w = picture.width, h = picture.height;

    // --- colour bar layout ---
    const bool withBar = options.colorBar;
    const int barW = 10 * s, tickLen = 3 * s;
    const int barH = std::max(100, int(std::lround(0.6 * h)));
    const int barX = w + 2 * pad;
    std::vector<double> ticks;
    std::vector<std::string> tickLabels;
    int barTop = 0, right = w;
    if (withBar) {
        ticks = niceTicks(range.lo, range.hi, 5);
        const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : std::fabs(range.hi - range.lo);
        int labelWidth = 0;
        for (double v : ticks) {
            tickLabels.push_back(formatTick(v, step));
            labelWidth = std::max(labelWidth, pen.width(tickLabels.back()));
        }
        right = barX + barW + 1 + tickLen + 2 * s + labelWidth + pad;
        const int topRoom = options.label.empty() ? pad + th / 2 : pad + th + pad;
        barTop = std::max(topRoom, (h - barH) / 2);
        if (!options.label.empty()) {
            const int lw = pen.width(options.label);
            const int lx = std::max(w + pad, barX + barW / 2 - lw / 2);
            right = std::max(right, lx + lw + pad);
        }
    }
    const int contentH = withBar ? std::max(h, barTop + barH + th / 2 + pad) : h;

    // --- scale bar layout ---
    const bool withScale = options.scaleBar && options.pixelSize > 0;
    double scaleLength = 0;
    int scalePixels = 0;
    std::string scaleLabel;
    const int scaleThick = 2 * s;
    int bottom = contentH;
    if (withScale) {
        scaleLength = scaleBarLength(w, options.pixelSize);
        scalePixels = std::max(1, int(std::lround(scaleLength / options.pixelSize)));
        scaleLabel = formatTick(scaleLength, scaleLength);
        if (!options.units.empty()) scaleLabel += " " + options.units;
        bottom = contentH + pad + scaleThick + 2 * s + th + pad;
        right = std::max({right, pad + scalePixels + pad, pad + pen.width(scaleLabel) + pad});
    }

    RgbImage out(right, bottom, kWhite);
    const std::size_t rowBytes = 3 * std::size_t(w);
    for (int y = 0; y < h; ++y)
        std::copy_n(picture.rgb.begin() + std::ptrdiff_t(y * rowBytes), rowBytes,
                    out.rgb.begin() + std::ptrdiff_t(std::size_t(y) * 3 * std::size_t(out.width)));

    if (withBar) {
        // Rows from the top: the top row is colorAt(1), the bottom row colorAt(0).
        for (int r = 0; r < barH; ++r) {
            const Rgb8 c = colorAt(options.colorMap, double(barH - 1 - r) / double(barH - 1));
            fillRect(out, barX, barTop + r, barX + barW, barTop + r + 1, c);
        }
        fillRect(out, barX - 1, barTop - 1, barX + barW + 1, barTop, kBlack);
        fillRect(out, barX - 1, barTop + barH, barX + barW + 1, barTop + barH + 1, kBlack);
        fillRect(out, barX - 1, barTop, barX, barTop + barH, kBlack);
        fillRect(out, barX + barW, barTop, barX + barW + 1, barTop + barH, kBlack);

        const auto rowOf = [&](double v) {
            const double t = (v - range.lo) / (range.hi - range.lo);
            return barTop + int(std::lround((1 - t) * (barH - 1)));
        };
        const int tickX = barX + barW + 1;
        for (std::size_t i = 0; i < ticks.size(); ++i) {
            const int row = rowOf(ticks[i]);
            fillRect(out, tickX, row, tickX + tickLen, row + 1, kBlack);
            pen.draw(out, tickX + tickLen + 2 * s, row - th / 2, tickLabels[i]);
        }
        for (double level : options.isolines) {
            if (!std::isfinite(level) || level < range.lo || level > range.hi) continue;
            const int row = rowOf(level);
            fillRect(out, barX - 1 - tickLen, row, barX + barW, row + 1, kBlack);
        }
        if (!options.label.empty()) {
            const int lw = pen.width(options.label);
            const int lx = std::max(w + pad, barX + barW / 2 - lw / 2);
            pen.draw(out, lx, barTop - pad - th, options.label);
        }
    }

    if (withScale) {
        const int y0 = contentH + pad;
        fillRect(out, pad, y0, pad + scalePixels, y0 + scaleThick, kBlack);
        const int lw = pen.width(scaleLabel);
        const int lx = std::max(0, pad + scalePixels / 2 - lw / 2);
        pen.draw(out, lx, y0 + scaleThick + 2 * s, scaleLabel);
    }
    return out;
}

} // namespace msii
