/// @file colormap.cpp
/// @brief The colour maps and percentile ranges.
///
/// Viridis and cividis are piecewise linear (in sRGB) through anchor colours taken from
/// matplotlib's 256-entry tables (every 8th entry and the last, plus a few more where cividis
/// bends sharply); entry i of those tables sits at t = i / 255. The interpolation error is
/// below one 8-bit level. Cool-warm follows Moreland, "Diverging Color Maps for Scientific
/// Visualization" (2009): the end colours are converted to Msh (polar CIELAB) and interpolated
/// there through an unsaturated white of M = max(M1, M2, 88), with the hue spin that keeps
/// the approach to white smooth. It is tabulated once (4097 samples) and interpolated.

#include <msii/render/colormap.h>

#include <msii/core/errors.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace msii {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// One anchor of a piecewise-linear map: the table index (0–255) and the sRGB colour in [0, 1].
struct Anchor {
    int index;
    double r, g, b;
};

constexpr Anchor kViridis[] = {
    {0, 0.2670040, 0.0048743, 0.3294152},   {8, 0.2770184, 0.0503444, 0.3757145},
    {16, 0.2823274, 0.0949555, 0.4173309},  {24, 0.2828839, 0.1359201, 0.4534273},
    {32, 0.2788262, 0.1754902, 0.4833965},  {40, 0.2705947, 0.2140690, 0.5070524},
    {48, 0.2589645, 0.2515369, 0.5247361},  {56, 0.2449721, 0.2876755, 0.5372602},
    {64, 0.2297393, 0.3223613, 0.5457063},  {72, 0.2142976, 0.3556191, 0.5511844},
    {80, 0.1994295, 0.3876068, 0.5546421},  {88, 0.1855559, 0.4185704, 0.5567529},
    {96, 0.1727188, 0.4487906, 0.5578853},  {104, 0.1606647, 0.4785396, 0.5581147},
    {112, 0.1490392, 0.5080514, 0.5572505}, {120, 0.1377705, 0.5374921, 0.5549063},
    {128, 0.1275677, 0.5669489, 0.5505555}, {136, 0.1205650, 0.5964219, 0.5436106},
    {144, 0.1206382, 0.6258283, 0.5334883}, {152, 0.1322680, 0.6550136, 0.5196609},
    {160, 0.1578515, 0.6837653, 0.5016857}, {168, 0.1965706, 0.7118267, 0.4792211},
    {176, 0.2460697, 0.7389097, 0.4520241}, {184, 0.3041480, 0.7647043, 0.4199435},
    {192, 0.3692142, 0.7888879, 0.3829144}, {200, 0.4401369, 0.8111384, 0.3409673},
    {208, 0.5159918, 0.8311578, 0.2942789}, {216, 0.5958393, 0.8487172, 0.2433288},
    {224, 0.6784887, 0.8637421, 0.1895033}, {232, 0.7623734, 0.8764239, 0.1370645},
    {240, 0.8455606, 0.8873224, 0.0997022}, {248, 0.9261058, 0.8973298, 0.1040707},
    {255, 0.9932479, 0.9061566, 0.1439362},
};

constexpr Anchor kCividis[] = {
    {0, 0.000000, 0.135112, 0.304751},   {8, 0.000000, 0.157932, 0.357521},
    {16, 0.000000, 0.178802, 0.414764},  {20, 0.000000, 0.188769, 0.439563},
    {23, 0.003602, 0.195911, 0.441564},  {24, 0.017852, 0.198528, 0.441248},
    {28, 0.068968, 0.209372, 0.438863},  {32, 0.103401, 0.220406, 0.435790},
    {40, 0.154261, 0.242475, 0.430120},  {48, 0.195057, 0.264372, 0.425924},
    {56, 0.230871, 0.286134, 0.423498},  {64, 0.263738, 0.307831, 0.422789},
    {72, 0.294669, 0.329531, 0.423716},  {80, 0.324250, 0.351289, 0.426250},
    {88, 0.352892, 0.373153, 0.430226},  {96, 0.380830, 0.395164, 0.435653},
    {104, 0.408226, 0.417357, 0.442570}, {112, 0.435168, 0.439763, 0.451134},
    {120, 0.461616, 0.462405, 0.461969}, {128, 0.488697, 0.485318, 0.471008},
    {136, 0.517920, 0.508454, 0.472707}, {144, 0.547840, 0.531895, 0.471704},
    {152, 0.578236, 0.555673, 0.468724}, {160, 0.609105, 0.579816, 0.463638},
    {168, 0.640352, 0.604354, 0.456791}, {176, 0.671991, 0.629316, 0.448018},
    {184, 0.704037, 0.654731, 0.437147}, {192, 0.736488, 0.680629, 0.424028},
    {200, 0.769353, 0.707035, 0.408516}, {208, 0.802667, 0.733978, 0.390153},
    {216, 0.836429, 0.761483, 0.368747}, {224, 0.870717, 0.789572, 0.343333},
    {232, 0.905589, 0.818257, 0.312889}, {240, 0.941147, 0.847530, 0.275815},
    {248, 0.977780, 0.877281, 0.227954}, {252, 0.994847, 0.892954, 0.203445},
    {255, 0.995737, 0.909344, 0.217772},
};

std::uint8_t toByte(double v)
{
    return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

template <std::size_t N>
Rgb8 interpolateAnchors(const Anchor (&anchors)[N], double t)
{
    const double pos = t * 255.0;
    std::size_t i = 1;
    while (i + 1 < N && anchors[i].index < pos) ++i;
    const Anchor& a = anchors[i - 1];
    const Anchor& b = anchors[i];
    const double f = std::clamp((pos - a.index) / double(b.index - a.index), 0.0, 1.0);
    return {toByte(a.r + f * (b.r - a.r)), toByte(a.g + f * (b.g - a.g)),
            toByte(a.b + f * (b.b - a.b))};
}

// --- Msh (Moreland 2009) ------------------------------------------------------------------

struct Vec3 {
    double x, y, z;
};

constexpr double kWhiteX = 0.95047, kWhiteY = 1.0, kWhiteZ = 1.08883;  // D65

double srgbToLinear(double c)
{
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

double linearToSrgb(double c)
{
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

double labF(double t)
{
    constexpr double d = 6.0 / 29.0;
    return t > d * d * d ? std::cbrt(t) : t / (3 * d * d) + 4.0 / 29.0;
}

double labFInverse(double t)
{
    constexpr double d = 6.0 / 29.0;
    return t > d ? t * t * t : 3 * d * d * (t - 4.0 / 29.0);
}

/// sRGB in [0, 1] → CIELAB (D65).
Vec3 srgbToLab(Vec3 c)
{
    const double r = srgbToLinear(c.x), g = srgbToLinear(c.y), b = srgbToLinear(c.z);
    const double x = 0.4124564 * r + 0.3575761 * g + 0.1804375 * b;
    const double y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
    const double z = 0.0193339 * r + 0.1191920 * g + 0.9503041 * b;
    const double fx = labF(x / kWhiteX), fy = labF(y / kWhiteY), fz = labF(z / kWhiteZ);
    return {116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)};
}

/// CIELAB (D65) → sRGB, not clamped.
Vec3 labToSrgb(Vec3 lab)
{
    const double fy = (lab.x + 16) / 116;
    const double fx = fy + lab.y / 500;
    const double fz = fy - lab.z / 200;
    const double x = kWhiteX * labFInverse(fx), y = kWhiteY * labFInverse(fy),
                 z = kWhiteZ * labFInverse(fz);
    const double r = 3.2404542 * x - 1.5371385 * y - 0.4985314 * z;
    const double g = -0.9692660 * x + 1.8760108 * y + 0.0415560 * z;
    const double b = 0.0556434 * x - 0.2040259 * y + 1.0572252 * z;
    return {linearToSrgb(r), linearToSrgb(g), linearToSrgb(b)};
}

/// CIELAB → Msh: magnitude, saturation (angle from the L axis), hue.
Vec3 labToMsh(Vec3 lab)
{
    const double m = std::sqrt(lab.x * lab.x + lab.y * lab.y + lab.z * lab.z);
    const double s = m > 0 ? std::acos(std::clamp(lab.x / m, -1.0, 1.0)) : 0.0;
    const double h = std::atan2(lab.z, lab.y);
    return {m, s, h};
}

Vec3 mshToLab(Vec3 msh)
{
    return {msh.x * std::cos(msh.y), msh.x * std::sin(msh.y) * std::cos(msh.z),
            msh.x * std::sin(msh.y) * std::sin(msh.z)};
}

/// The hue an unsaturated colour of magnitude @p mUnsat should take next to the saturated
/// @p saturated (Moreland's AdjustHue).
double adjustHue(Vec3 saturated, double mUnsat)
{
    if (saturated.x >= mUnsat) return saturated.z;
    const double spin = saturated.y * std::sqrt(mUnsat * mUnsat - saturated.x * saturated.x) /
                        (saturated.x * std::sin(saturated.y));
    return saturated.z > -kPi / 3 ? saturated.z + spin : saturated.z - spin;
}

/// Moreland's diverging interpolation between two colours (sRGB in [0, 1]) at t in [0, 1].
Vec3 divergingColor(Vec3 rgb1, Vec3 rgb2, double t)
{
    Vec3 m1 = labToMsh(srgbToLab(rgb1));
    Vec3 m2 = labToMsh(srgbToLab(rgb2));
    if (m1.y > 0.05 && m2.y > 0.05 && std::fabs(m1.z - m2.z) > kPi / 3) {
        const double mMid = std::max({m1.x, m2.x, 88.0});
        if (t < 0.5) {
            m2 = {mMid, 0, 0};
            t = 2 * t;
        } else {
            m1 = {mMid, 0, 0};
            t = 2 * t - 1;
        }
    }
    if (m1.y < 0.05 && m2.y > 0.05)
        m1.z = adjustHue(m2, m1.x);
    else if (m2.y < 0.05 && m1.y > 0.05)
        m2.z = adjustHue(m1, m2.x);
    const Vec3 m{(1 - t) * m1.x + t * m2.x, (1 - t) * m1.y + t * m2.y, (1 - t) * m1.z + t * m2.z};
    return labToSrgb(mshToLab(m));
}

constexpr int kCoolWarmSamples = 4096;  ///< intervals of the tabulated cool-warm map

const std::vector<Vec3>& coolWarmTable()
{
    static const std::vector<Vec3> table = [] {
        const Vec3 cool{59 / 255.0, 76 / 255.0, 192 / 255.0};
        const Vec3 warm{180 / 255.0, 4 / 255.0, 38 / 255.0};
        std::vector<Vec3> values(kCoolWarmSamples + 1);
        for (int i = 0; i <= kCoolWarmSamples; ++i)
            values[std::size_t(i)] = divergingColor(cool, warm, double(i) / kCoolWarmSamples);
        return values;
    }();
    return table;
}

Rgb8 coolWarm(double t)
{
    const std::vector<Vec3>& table = coolWarmTable();
    const double pos = t * kCoolWarmSamples;
    const int i = std::min(int(pos), kCoolWarmSamples - 1);
    const double f = pos - i;
    const Vec3& a = table[std::size_t(i)];
    const Vec3& b = table[std::size_t(i) + 1];
    return {toByte(a.x + f * (b.x - a.x)), toByte(a.y + f * (b.y - a.y)),
            toByte(a.z + f * (b.z - a.z))};
}

/// The q-th order statistic (0-based) of @p v, which is reordered.
double orderStatistic(std::vector<float>& v, std::size_t q)
{
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(q), v.end());
    return v[q];
}

/// The percentile @p p (0–100) of @p v, linear between order statistics; reorders @p v.
double percentileOf(std::vector<float>& v, double p)
{
    const double rank = p / 100.0 * double(v.size() - 1);
    const auto k = std::size_t(std::floor(rank));
    const double frac = rank - double(k);
    const double lo = orderStatistic(v, k);
    if (frac <= 0 || k + 1 >= v.size()) return lo;
    // After nth_element everything behind position k is >= v[k]: its minimum is the next one.
    const double hi = *std::min_element(v.begin() + std::ptrdiff_t(k) + 1, v.end());
    return lo + frac * (hi - lo);
}

} // namespace

ColorMapKind parseColorMap(const std::string& name)
{
    std::string lower = name;
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (lower == "viridis") return ColorMapKind::Viridis;
    if (lower == "cividis") return ColorMapKind::Cividis;
    if (lower == "gray") return ColorMapKind::Gray;
    if (lower == "coolwarm") return ColorMapKind::CoolWarm;
    throw InvalidInputError("unknown colour map '" + name +
                            "' (expected viridis, cividis, gray or coolwarm).");
}

std::string colorMapName(ColorMapKind kind)
{
    switch (kind) {
    case ColorMapKind::Viridis: return "viridis";
    case ColorMapKind::Cividis: return "cividis";
    case ColorMapKind::Gray: return "gray";
    case ColorMapKind::CoolWarm: return "coolwarm";
    }
    return "viridis";
}

bool isDiverging(ColorMapKind kind) { return kind == ColorMapKind::CoolWarm; }

Rgb8 colorAt(ColorMapKind kind, double t)
{
    if (std::isnan(t)) return {128, 128, 128};
    t = std::clamp(t, 0.0, 1.0);
    switch (kind) {
    case ColorMapKind::Viridis: return interpolateAnchors(kViridis, t);
    case ColorMapKind::Cividis: return interpolateAnchors(kCividis, t);
    case ColorMapKind::Gray: {
        const std::uint8_t v = toByte(t);
        return {v, v, v};
    }
    case ColorMapKind::CoolWarm: return coolWarm(t);
    }
    return {128, 128, 128};
}

ValueRange percentileRange(const std::vector<float>& values, double loPercent, double hiPercent,
                           const double* symmetricAbout)
{
    if (!(loPercent >= 0 && loPercent < hiPercent && hiPercent <= 100))
        throw InvalidInputError("the percentiles must satisfy 0 <= low < high <= 100 (got " +
                                std::to_string(loPercent) + " and " + std::to_string(hiPercent) +
                                ").");
    if (symmetricAbout && !std::isfinite(*symmetricAbout))
        throw InvalidInputError("the centre of a symmetric value range must be finite.");
    std::vector<float> finite;
    finite.reserve(values.size());
    for (float v : values)
        if (std::isfinite(v)) finite.push_back(v);
    if (finite.empty())
        throw InvalidInputError("cannot choose a value range: there are no finite values.");

    ValueRange range;
    range.lo = percentileOf(finite, loPercent);
    range.hi = percentileOf(finite, hiPercent);
    if (symmetricAbout) {
        const double c = *symmetricAbout;
        const double d = std::max(std::fabs(range.lo - c), std::fabs(range.hi - c));
        range.lo = c - d;
        range.hi = c + d;
    }
    if (!(range.hi > range.lo)) {  // a constant field (or constant between the percentiles)
        const double v = range.lo;
        range.lo = v - 0.5;
        range.hi = v + 0.5;
    }
    return range;
}

} // namespace msii
