/// Tests of render/colormap.h: names, matplotlib's anchor colours of viridis and cividis,
/// gray, Moreland's cool-warm (end points, white-ish middle, lightness running up to the
/// middle and down after it), smoothness, clamping and NaN, and percentile ranges against a
/// sort-based reference.

#include <msii/render/colormap.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

using namespace msii;

namespace {

const float kNaNf = std::numeric_limits<float>::quiet_NaN();
const float kInff = std::numeric_limits<float>::infinity();

void expectColorNear(Rgb8 got, Rgb8 expected, int tolerance, const std::string& what)
{
    for (int c = 0; c < 3; ++c)
        EXPECT_LE(std::abs(int(got[std::size_t(c)]) - int(expected[std::size_t(c)])), tolerance)
            << what << ": channel " << c << " is " << int(got[std::size_t(c)]) << ", expected "
            << int(expected[std::size_t(c)]);
}

/// CIELAB lightness L* of an sRGB colour (D65), computed independently of the library.
double lightness(Rgb8 c)
{
    const auto lin = [](int v) {
        const double s = v / 255.0;
        return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
    };
    const double y = 0.2126729 * lin(c[0]) + 0.7151522 * lin(c[1]) + 0.0721750 * lin(c[2]);
    const double f = y > 216.0 / 24389.0 ? std::cbrt(y) : (24389.0 / 27.0 * y + 16) / 116;
    return 116 * f - 16;
}

/// The p-th percentile of the finite values by sorting, linear between order statistics.
double referencePercentile(std::vector<float> values, double p)
{
    values.erase(std::remove_if(values.begin(), values.end(),
                                [](float v) { return !std::isfinite(v); }),
                 values.end());
    std::sort(values.begin(), values.end());
    const double rank = p / 100 * double(values.size() - 1);
    const auto k = std::size_t(std::floor(rank));
    if (k + 1 >= values.size()) return values[k];
    return values[k] + (rank - double(k)) * (values[k + 1] - values[k]);
}

} // namespace

TEST(ColorMap, NamesRoundTrip)
{
    for (ColorMapKind kind : {ColorMapKind::Viridis, ColorMapKind::Cividis, ColorMapKind::Gray,
                              ColorMapKind::CoolWarm})
        EXPECT_EQ(parseColorMap(colorMapName(kind)), kind);
    EXPECT_EQ(colorMapName(ColorMapKind::Viridis), "viridis");
    EXPECT_EQ(colorMapName(ColorMapKind::Cividis), "cividis");
    EXPECT_EQ(colorMapName(ColorMapKind::Gray), "gray");
    EXPECT_EQ(colorMapName(ColorMapKind::CoolWarm), "coolwarm");
    EXPECT_EQ(parseColorMap("Viridis"), ColorMapKind::Viridis);
    EXPECT_TRUE(isDiverging(ColorMapKind::CoolWarm));
    EXPECT_FALSE(isDiverging(ColorMapKind::Viridis));
    EXPECT_FALSE(isDiverging(ColorMapKind::Cividis));
    EXPECT_FALSE(isDiverging(ColorMapKind::Gray));
}

TEST(ColorMap, UnknownNameListsTheChoices)
{
    EXPECT_THROW(parseColorMap("jet"), InvalidInputError);
    EXPECT_THROW(parseColorMap(""), InvalidInputError);
    try {
        parseColorMap("jet");
    } catch (const InvalidInputError& e) {
        const std::string what = e.what();
        for (const char* name : {"jet", "viridis", "cividis", "gray", "coolwarm"})
            EXPECT_NE(what.find(name), std::string::npos) << what;
    }
}

TEST(ColorMap, ViridisAnchors)
{
    expectColorNear(colorAt(ColorMapKind::Viridis, 0.0), {68, 1, 84}, 3, "viridis(0)");
    expectColorNear(colorAt(ColorMapKind::Viridis, 0.5), {33, 145, 140}, 3, "viridis(0.5)");
    expectColorNear(colorAt(ColorMapKind::Viridis, 1.0), {253, 231, 37}, 3, "viridis(1)");
    // matplotlib's entries 64 and 191 of 256.
    expectColorNear(colorAt(ColorMapKind::Viridis, 64 / 255.0), {59, 82, 139}, 2, "viridis(64)");
    expectColorNear(colorAt(ColorMapKind::Viridis, 191 / 255.0), {92, 200, 99}, 2,
                    "viridis(191)");
}

TEST(ColorMap, CividisAnchors)
{
    expectColorNear(colorAt(ColorMapKind::Cividis, 0.0), {0, 34, 78}, 3, "cividis(0)");
    expectColorNear(colorAt(ColorMapKind::Cividis, 0.5), {124, 123, 120}, 3, "cividis(0.5)");
    expectColorNear(colorAt(ColorMapKind::Cividis, 1.0), {254, 232, 56}, 3, "cividis(1)");
    // Entry 21 sits in the short stretch where red is still 0 and blue levels off.
    expectColorNear(colorAt(ColorMapKind::Cividis, 21 / 255.0), {0, 49, 112}, 2, "cividis(21)");
}

TEST(ColorMap, Gray)
{
    expectColorNear(colorAt(ColorMapKind::Gray, 0.0), {0, 0, 0}, 0, "gray(0)");
    expectColorNear(colorAt(ColorMapKind::Gray, 1.0), {255, 255, 255}, 0, "gray(1)");
    expectColorNear(colorAt(ColorMapKind::Gray, 0.5), {128, 128, 128}, 1, "gray(0.5)");
    const Rgb8 c = colorAt(ColorMapKind::Gray, 0.3);
    EXPECT_TRUE(c[0] == c[1] && c[1] == c[2]);
}

TEST(ColorMap, CoolWarmEndsAndMiddle)
{
    expectColorNear(colorAt(ColorMapKind::CoolWarm, 0.0), {59, 76, 192}, 1, "coolwarm(0)");
    expectColorNear(colorAt(ColorMapKind::CoolWarm, 1.0), {180, 4, 38}, 1, "coolwarm(1)");
    expectColorNear(colorAt(ColorMapKind::CoolWarm, 0.5), {221, 221, 221}, 3, "coolwarm(0.5)");
    const Rgb8 cool = colorAt(ColorMapKind::CoolWarm, 0.25);
    const Rgb8 warm = colorAt(ColorMapKind::CoolWarm, 0.75);
    EXPECT_GT(cool[2], cool[0] + 60);  // clearly blue
    EXPECT_GT(warm[0], warm[2] + 60);  // clearly red
    // Moreland's table (2009) at 0.75: (244, 154, 123).
    expectColorNear(warm, {244, 154, 123}, 3, "coolwarm(0.75)");
}

TEST(ColorMap, SequentialMapsGetLighterThroughout)
{
    for (ColorMapKind kind : {ColorMapKind::Viridis, ColorMapKind::Cividis, ColorMapKind::Gray}) {
        double previous = -1;
        for (int i = 0; i <= 64; ++i) {
            const double l = lightness(colorAt(kind, i / 64.0));
            EXPECT_GT(l, previous) << colorMapName(kind) << " at t = " << i / 64.0;
            previous = l;
        }
    }
}

TEST(ColorMap, CoolWarmLightnessPeaksInTheMiddle)
{
    double previous = -1;
    for (int i = 0; i <= 32; ++i) {
        const double l = lightness(colorAt(ColorMapKind::CoolWarm, 0.5 * i / 32));
        EXPECT_GT(l, previous) << "t = " << 0.5 * i / 32;
        previous = l;
    }
    for (int i = 1; i <= 32; ++i) {
        const double l = lightness(colorAt(ColorMapKind::CoolWarm, 0.5 + 0.5 * i / 32));
        EXPECT_LT(l, previous) << "t = " << 0.5 + 0.5 * i / 32;
        previous = l;
    }
}

TEST(ColorMap, MapsAreSmooth)
{
    // No jumps between neighbouring steps of 1/1024: a wrong anchor would show up here.
    for (ColorMapKind kind : {ColorMapKind::Viridis, ColorMapKind::Cividis, ColorMapKind::Gray,
                              ColorMapKind::CoolWarm}) {
        Rgb8 previous = colorAt(kind, 0);
        int largest = 0;
        for (int i = 1; i <= 1024; ++i) {
            const Rgb8 c = colorAt(kind, i / 1024.0);
            for (int k = 0; k < 3; ++k)
                largest = std::max(largest, std::abs(int(c[std::size_t(k)]) -
                                                     int(previous[std::size_t(k)])));
            previous = c;
        }
        EXPECT_LE(largest, 3) << colorMapName(kind);
    }
}

TEST(ColorMap, ClampsAndShowsNaNAsGray)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (ColorMapKind kind : {ColorMapKind::Viridis, ColorMapKind::Cividis, ColorMapKind::Gray,
                              ColorMapKind::CoolWarm}) {
        EXPECT_EQ(colorAt(kind, -0.5), colorAt(kind, 0.0));
        EXPECT_EQ(colorAt(kind, 7.0), colorAt(kind, 1.0));
        EXPECT_EQ(colorAt(kind, -std::numeric_limits<double>::infinity()), colorAt(kind, 0.0));
        EXPECT_EQ(colorAt(kind, nan), (Rgb8{128, 128, 128}));
    }
}

TEST(PercentileRange, InterpolatesBetweenOrderStatistics)
{
    std::vector<float> values;
    for (int i = 100; i >= 0; --i) values.push_back(float(i));  // 0..100, reversed
    ValueRange r = percentileRange(values, 5, 95);
    EXPECT_DOUBLE_EQ(r.lo, 5);
    EXPECT_DOUBLE_EQ(r.hi, 95);
    r = percentileRange(values, 0, 100);
    EXPECT_DOUBLE_EQ(r.lo, 0);
    EXPECT_DOUBLE_EQ(r.hi, 100);

    r = percentileRange({10.0f, 0.0f}, 25, 75);
    EXPECT_DOUBLE_EQ(r.lo, 2.5);
    EXPECT_DOUBLE_EQ(r.hi, 7.5);
    r = percentileRange({0.0f, 1.0f, 2.0f, 4.0f}, 50, 90);  // ranks 1.5 and 2.7
    EXPECT_DOUBLE_EQ(r.lo, 1.5);
    EXPECT_NEAR(r.hi, 2 + 0.7 * 2, 1e-12);
}

TEST(PercentileRange, IgnoresNonFiniteValues)
{
    const ValueRange r =
        percentileRange({kNaNf, 3.0f, kInff, 1.0f, -kInff, 2.0f, kNaNf}, 0, 100);
    EXPECT_DOUBLE_EQ(r.lo, 1);
    EXPECT_DOUBLE_EQ(r.hi, 3);
}

TEST(PercentileRange, MatchesSortingOnRandomData)
{
    std::mt19937 rng(3);
    std::vector<float> values(5001);
    for (float& v : values) v = float(double(rng()) / 4294967296.0 * 20 - 5);
    values[17] = kNaNf;
    for (auto [lo, hi] : {std::pair{1.0, 99.0}, {0.5, 99.5}, {2.0, 98.0}, {0.0, 37.3}}) {
        const ValueRange r = percentileRange(values, lo, hi);
        EXPECT_NEAR(r.lo, referencePercentile(values, lo), 1e-6) << lo;
        EXPECT_NEAR(r.hi, referencePercentile(values, hi), 1e-6) << hi;
    }
}

TEST(PercentileRange, SymmetricAboutACentre)
{
    const std::vector<float> values = {-1, 0, 1, 2, 3};
    double zero = 0;
    ValueRange r = percentileRange(values, 0, 100, &zero);
    EXPECT_DOUBLE_EQ(r.lo, -3);
    EXPECT_DOUBLE_EQ(r.hi, 3);
    double one = 1;
    r = percentileRange({-4, 0, 2}, 0, 100, &one);  // distances 5 and 1
    EXPECT_DOUBLE_EQ(r.lo, -4);
    EXPECT_DOUBLE_EQ(r.hi, 6);
}

TEST(PercentileRange, ConstantFieldGetsAUnitRange)
{
    ValueRange r = percentileRange({4, 4, 4, kNaNf}, 1, 99);
    EXPECT_DOUBLE_EQ(r.lo, 3.5);
    EXPECT_DOUBLE_EQ(r.hi, 4.5);
    double zero = 0;
    r = percentileRange({0, 0}, 1, 99, &zero);
    EXPECT_DOUBLE_EQ(r.lo, -0.5);
    EXPECT_DOUBLE_EQ(r.hi, 0.5);
}

TEST(PercentileRange, RejectsBadInput)
{
    EXPECT_THROW(percentileRange({}, 1, 99), InvalidInputError);
    EXPECT_THROW(percentileRange({kNaNf, kInff}, 1, 99), InvalidInputError);
    const std::vector<float> v = {1, 2, 3};
    EXPECT_THROW(percentileRange(v, -1, 50), InvalidInputError);
    EXPECT_THROW(percentileRange(v, 50, 50), InvalidInputError);
    EXPECT_THROW(percentileRange(v, 60, 40), InvalidInputError);
    EXPECT_THROW(percentileRange(v, 0, 100.5), InvalidInputError);
    EXPECT_THROW(percentileRange(v, std::nan(""), 50), InvalidInputError);
    EXPECT_NO_THROW(percentileRange(v, 0, 100));
}
