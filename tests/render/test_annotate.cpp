/// Tests of render/annotate.h: nice tick values and their labels, and the composed figure
/// (margins, the picture copied unchanged at the top left, the colour bar running from
/// colorAt(0) at the bottom to colorAt(1) at the top inside a black frame, ticks at the tick
/// values, isoline marks, the label, and a scale bar whose length in pixels is its labelled
/// length over the pixel size).

#include <msii/render/annotate.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

using namespace msii;

namespace {

constexpr Rgb8 kWhite{255, 255, 255};
constexpr Rgb8 kBlack{0, 0, 0};

/// A picture of smooth colours that occur neither in the maps' ends nor as black or white.
RgbImage testPicture(int w, int h)
{
    RgbImage p(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            p.set(x, y, {std::uint8_t(20 + (x * 200) / w), std::uint8_t(30 + (y * 180) / h), 77});
    return p;
}

bool near(Rgb8 a, Rgb8 b, int tolerance)
{
    for (int k = 0; k < 3; ++k)
        if (std::abs(int(a[std::size_t(k)]) - int(b[std::size_t(k)])) > tolerance) return false;
    return true;
}

/// Where the colour bar is: its columns [x0, x1] and rows [top, bottom].
struct BarBox {
    int x0 = -1, x1 = -1, top = -1, bottom = -1;
};

/// Finds the colour bar right of the picture as the first column holding colorAt(1) above
/// colorAt(0), and its extent.
BarBox findBar(const RgbImage& figure, int pictureWidth, ColorMapKind map)
{
    const Rgb8 high = colorAt(map, 1), low = colorAt(map, 0);
    BarBox box;
    for (int x = pictureWidth; x < figure.width && box.x0 < 0; ++x) {
        int top = -1, bottom = -1;
        for (int y = 0; y < figure.height; ++y) {
            if (top < 0 && figure.at(x, y) == high) top = y;
            if (figure.at(x, y) == low) bottom = y;
        }
        if (top >= 0 && bottom > top) {
            box.x0 = x;
            box.top = top;
            box.bottom = bottom;
        }
    }
    if (box.x0 < 0) return box;
    box.x1 = box.x0;
    while (box.x1 + 1 < figure.width && figure.at(box.x1 + 1, box.top) == high) ++box.x1;
    return box;
}

/// The longest horizontal run of black pixels in rows [y0, height), and its row.
int longestBlackRun(const RgbImage& image, int y0, int* rowOut = nullptr)
{
    int best = 0;
    for (int y = y0; y < image.height; ++y) {
        int run = 0;
        for (int x = 0; x < image.width; ++x) {
            run = image.at(x, y) == kBlack ? run + 1 : 0;
            if (run > best) {
                best = run;
                if (rowOut) *rowOut = y;
            }
        }
    }
    return best;
}

int blackPixelsIn(const RgbImage& image, int x0, int y0, int x1, int y1)
{
    int n = 0;
    for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y)
        for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x)
            n += image.at(x, y) == kBlack ? 1 : 0;
    return n;
}

} // namespace

// --- ticks ---------------------------------------------------------------------------------

TEST(NiceTicks, UnitRange)
{
    const std::vector<double> t = niceTicks(0, 1, 5);
    const std::vector<double> expected = {0, 0.2, 0.4, 0.6, 0.8, 1};
    ASSERT_EQ(t.size(), expected.size());
    for (std::size_t i = 0; i < t.size(); ++i) EXPECT_DOUBLE_EQ(t[i], expected[i]) << i;
}

TEST(NiceTicks, SmallRangeAcrossZero)
{
    const std::vector<double> t = niceTicks(-0.013, 0.021);
    ASSERT_GE(t.size(), 3u);
    ASSERT_LE(t.size(), 9u);
    const double step = t[1] - t[0];
    EXPECT_TRUE(std::fabs(step - 0.005) < 1e-12 || std::fabs(step - 0.01) < 1e-12) << step;
    for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, 1e-12);
    EXPECT_GE(t.front(), -0.013);
    EXPECT_LT(t.front() - step, -0.013);  // no tick left out at the low end
    EXPECT_LE(t.back(), 0.021);
    EXPECT_GT(t.back() + step, 0.021);
    bool hasZero = false;
    for (double v : t) hasZero = hasZero || v == 0.0;
    EXPECT_TRUE(hasZero);
}

TEST(NiceTicks, StepsAreOneTwoTwoPointFiveOrFive)
{
    EXPECT_EQ(niceTicks(0, 100, 5), (std::vector<double>{0, 20, 40, 60, 80, 100}));
    EXPECT_EQ(niceTicks(0, 10, 4), (std::vector<double>{0, 2.5, 5, 7.5, 10}));
    EXPECT_EQ(niceTicks(-3, 3, 6), (std::vector<double>{-3, -2, -1, 0, 1, 2, 3}));
    EXPECT_EQ(niceTicks(1, 0, 5), niceTicks(0, 1, 5));  // order of the ends does not matter
    for (auto [lo, hi] : {std::pair{0.0013, 0.0171}, {-250.0, 1234.0}, {3e-7, 9e-7}, {5.0, 6.0}}) {
        const std::vector<double> t = niceTicks(lo, hi, 5);
        ASSERT_GE(t.size(), 3u) << lo << " " << hi;
        ASSERT_LE(t.size(), 9u) << lo << " " << hi;
        const double step = t[1] - t[0];
        const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
        bool nice = false;
        for (double m : {1.0, 2.0, 2.5, 5.0}) nice = nice || std::fabs(mantissa - m) < 1e-6;
        EXPECT_TRUE(nice) << "step " << step << " for " << lo << " .. " << hi;
        EXPECT_GE(t.front(), lo - 1e-12 * std::fabs(step));
        EXPECT_LE(t.back(), hi + 1e-12 * std::fabs(step));
    }
}

TEST(NiceTicks, DegenerateAndBadInput)
{
    EXPECT_EQ(niceTicks(5, 5), std::vector<double>{5});
    EXPECT_THROW(niceTicks(0, std::numeric_limits<double>::infinity()), InvalidInputError);
    EXPECT_THROW(niceTicks(std::nan(""), 1), InvalidInputError);
    EXPECT_THROW(niceTicks(0, 1, 0), InvalidInputError);
}

TEST(FormatTick, ShortLabels)
{
    EXPECT_EQ(formatTick(0.25, 0.05), "0.25");
    EXPECT_EQ(formatTick(-0.005, 0.005), "-0.005");
    EXPECT_EQ(formatTick(0.6000000000000001, 0.2), "0.6");
    EXPECT_EQ(formatTick(1, 0.2), "1");
    EXPECT_EQ(formatTick(0, 0.2), "0");
    EXPECT_EQ(formatTick(-1e-17, 0.1), "0");  // rounding noise is not "-0"
    EXPECT_EQ(formatTick(7.5, 2.5), "7.5");
    EXPECT_EQ(formatTick(1500, 500), "1500");
    EXPECT_EQ(formatTick(-20, 20), "-20");
    EXPECT_EQ(formatTick(0.01, 0.01), "0.01");
    EXPECT_EQ(formatTick(-1e-4, 1e-4), "-1e-04");
    EXPECT_EQ(formatTick(2.5e-5, 2.5e-5), "2.5e-05");
    EXPECT_EQ(formatTick(0, 1e-4), "0");
}

// --- the figure -------------------------------------------------------------------------

TEST(ComposeFigure, AddsMarginsAndKeepsThePicture)
{
    const RgbImage picture = testPicture(300, 200);
    FigureOptions options;
    options.range = {0, 1};
    options.pixelSize = 0.01;
    const RgbImage figure = composeFigure(picture, options);
    EXPECT_GT(figure.width, picture.width + 40);    // room for bar, ticks and labels
    EXPECT_GT(figure.height, picture.height + 20);  // room for the scale bar and its label
    for (int y = 0; y < picture.height; ++y)
        for (int x = 0; x < picture.width; ++x)
            ASSERT_EQ(figure.at(x, y), picture.at(x, y)) << "(" << x << ", " << y << ")";
    // The margins are white apart from the furniture: the corner pixels are white.
    EXPECT_EQ(figure.at(figure.width - 1, figure.height - 1), kWhite);
    EXPECT_EQ(figure.at(figure.width - 1, 0), kWhite);
    EXPECT_EQ(figure.at(0, figure.height - 1), kWhite);
}

TEST(ComposeFigure, ColourBarRunsFromLowAtTheBottomToHighAtTheTop)
{
    for (ColorMapKind map : {ColorMapKind::Viridis, ColorMapKind::CoolWarm}) {
        const RgbImage picture = testPicture(300, 200);
        FigureOptions options;
        options.colorMap = map;
        options.range = {-1, 1};
        options.scaleBar = false;
        const RgbImage figure = composeFigure(picture, options);
        EXPECT_EQ(figure.height, picture.height);  // the bar fits beside the picture
        const BarBox bar = findBar(figure, picture.width, map);
        ASSERT_GE(bar.x0, picture.width) << colorMapName(map);
        const int height = bar.bottom - bar.top + 1;
        EXPECT_NEAR(height, 120, 2);  // 60 % of 200
        EXPECT_GE(bar.x1 - bar.x0 + 1, 8);
        for (int y = bar.top; y <= bar.bottom; ++y) {
            const double t = 1.0 - double(y - bar.top) / double(bar.bottom - bar.top);
            for (int x = bar.x0; x <= bar.x1; ++x)
                ASSERT_TRUE(near(figure.at(x, y), colorAt(map, t), 1))
                    << colorMapName(map) << " row " << y << " t " << t;
        }
        // The black frame just outside the bar.
        for (int x = bar.x0 - 1; x <= bar.x1 + 1; ++x) {
            EXPECT_EQ(figure.at(x, bar.top - 1), kBlack);
            EXPECT_EQ(figure.at(x, bar.bottom + 1), kBlack);
        }
        for (int y = bar.top; y <= bar.bottom; ++y) {
            EXPECT_EQ(figure.at(bar.x0 - 1, y), kBlack);
            EXPECT_EQ(figure.at(bar.x1 + 1, y), kBlack);
        }
    }
}

TEST(ComposeFigure, BarIsAtLeast100PixelsHigh)
{
    const RgbImage picture = testPicture(120, 60);
    FigureOptions options;
    options.range = {0, 5};
    options.scaleBar = false;
    const RgbImage figure = composeFigure(picture, options);
    const BarBox bar = findBar(figure, picture.width, options.colorMap);
    ASSERT_GE(bar.x0, 0);
    EXPECT_EQ(bar.bottom - bar.top + 1, 100);
    EXPECT_GT(figure.height, bar.bottom + 1);  // the figure grew to hold it
}

TEST(ComposeFigure, TicksSitAtTheTickValues)
{
    const RgbImage picture = testPicture(300, 250);
    FigureOptions options;
    options.range = {0, 1};  // ticks 0, 0.2, …, 1
    options.scaleBar = false;
    const RgbImage figure = composeFigure(picture, options);
    const BarBox bar = findBar(figure, picture.width, options.colorMap);
    ASSERT_GE(bar.x0, 0);
    const int tickX = bar.x1 + 2;  // right of the frame
    const auto rowOf = [&](double v) {
        return bar.top + int(std::lround((1 - v) * (bar.bottom - bar.top)));
    };
    for (double v : {0.0, 0.2, 0.4, 0.6, 0.8, 1.0})
        EXPECT_EQ(figure.at(tickX, rowOf(v)), kBlack) << v;
    for (double v : {0.1, 0.3, 0.5, 0.7, 0.9}) EXPECT_EQ(figure.at(tickX, rowOf(v)), kWhite) << v;
    // Labels right of the ticks, next to each tick.
    for (double v : {0.0, 0.4, 1.0})
        EXPECT_GT(blackPixelsIn(figure, tickX + 4, rowOf(v) - 8, figure.width, rowOf(v) + 8), 5)
            << v;
}

TEST(ComposeFigure, IsolinesAndLabelAreMarked)
{
    const RgbImage picture = testPicture(300, 250);
    FigureOptions options;
    options.range = {0, 1};
    options.scaleBar = false;
    const RgbImage plain = composeFigure(picture, options);
    options.isolines = {0.5, 3.0};  // 3 is outside the range and ignored
    options.label = "V_16";
    const RgbImage marked = composeFigure(picture, options);
    const BarBox bar = findBar(marked, picture.width, options.colorMap);
    ASSERT_GE(bar.x0, 0);
    const int row = bar.top + int(std::lround(0.5 * (bar.bottom - bar.top)));
    EXPECT_EQ(marked.at((bar.x0 + bar.x1) / 2, row), kBlack);
    EXPECT_EQ(marked.at(bar.x0 - 2, row), kBlack);  // the tick outside, left of the frame
    EXPECT_EQ(marked.at((bar.x0 + bar.x1) / 2, row + 3),
              colorAt(options.colorMap, 1 - double(row + 3 - bar.top) / (bar.bottom - bar.top)));
    const BarBox plainBar = findBar(plain, picture.width, options.colorMap);
    EXPECT_NE(plain.at((plainBar.x0 + plainBar.x1) / 2, row), kBlack);
    // The label: black pixels above the frame, none there without a label.
    EXPECT_GT(blackPixelsIn(marked, picture.width, 0, marked.width, bar.top - 1), 20);
    EXPECT_EQ(blackPixelsIn(plain, picture.width, 0, plain.width, plainBar.top - 10), 0);
}

TEST(ComposeFigure, ScaleBarLengthMatchesItsLabel)
{
    struct Case {
        int width;
        double pixelSize, length;  // the nice length expected for about 1/5 of the width
    };
    for (const Case& c : {Case{300, 0.01, 0.5}, Case{300, 0.03, 2.0}, Case{500, 0.01, 1.0},
                          Case{640, 2.0, 200.0}, Case{256, 1e-4, 0.005}}) {
        const RgbImage picture = testPicture(c.width, 150);
        FigureOptions options;
        options.colorBar = false;
        options.pixelSize = c.pixelSize;
        const RgbImage figure = composeFigure(picture, options);
        ASSERT_GT(figure.height, picture.height);
        int row = -1;
        const int run = longestBlackRun(figure, picture.height, &row);
        EXPECT_NEAR(run, c.length / c.pixelSize, 1.0) << c.width << " " << c.pixelSize;
        EXPECT_NEAR(run, c.width / 5.0, c.width / 5.0 * 0.6);  // about 1/5 of the width
        // The label below the bar.
        EXPECT_GT(blackPixelsIn(figure, 0, row + 2, figure.width, figure.height), 20);
    }
}

TEST(ComposeFigure, ScaleBarLabelText)
{
    // The label "0.5 mm" is drawn centred under the bar: compare with the text drawn alone.
    const RgbImage picture = testPicture(300, 150);
    FigureOptions options;
    options.colorBar = false;
    options.pixelSize = 0.01;
    options.fontScale = 1;
    const RgbImage figure = composeFigure(picture, options);
    const int expected = textWidth("0.5 mm", 1);
    // Count the black columns below the bar: the label's extent.
    int row = -1;
    const int run = longestBlackRun(figure, picture.height, &row);
    while (blackPixelsIn(figure, 0, row + 1, figure.width, row + 2) >= run) ++row;  // bar rows
    int first = figure.width, last = -1;
    for (int y = row + 1; y < figure.height; ++y)
        for (int x = 0; x < figure.width; ++x)
            if (figure.at(x, y) == kBlack) {
                first = std::min(first, x);
                last = std::max(last, x);
            }
    EXPECT_EQ(last - first + 1, expected);
    options.units = "micrometres";
    const RgbImage other = composeFigure(picture, options);
    first = other.width;
    last = -1;
    for (int y = row + 1; y < other.height; ++y)
        for (int x = 0; x < other.width; ++x)
            if (other.at(x, y) == kBlack) {
                first = std::min(first, x);
                last = std::max(last, x);
            }
    EXPECT_EQ(last - first + 1, textWidth("0.5 micrometres", 1));
}

TEST(ComposeFigure, NothingToAddGivesThePicture)
{
    const RgbImage picture = testPicture(50, 40);
    FigureOptions options;
    options.colorBar = false;
    options.scaleBar = false;
    RgbImage figure = composeFigure(picture, options);
    EXPECT_EQ(figure.width, 50);
    EXPECT_EQ(figure.height, 40);
    EXPECT_EQ(figure.rgb, picture.rgb);
    options.scaleBar = true;
    options.pixelSize = 0;  // no scale bar either
    figure = composeFigure(picture, options);
    EXPECT_EQ(figure.rgb, picture.rgb);
}

TEST(ComposeFigure, FontScaleGrowsTheMargins)
{
    const RgbImage picture = testPicture(200, 200);
    FigureOptions options;
    options.range = {0, 1};
    options.pixelSize = 0.05;
    options.fontScale = 1;
    const RgbImage small = composeFigure(picture, options);
    options.fontScale = 3;
    const RgbImage large = composeFigure(picture, options);
    EXPECT_GT(large.width, small.width);
    EXPECT_GT(large.height, small.height);
}

TEST(ComposeFigure, RejectsBadInput)
{
    const RgbImage picture = testPicture(20, 20);
    FigureOptions options;
    options.range = {0, 1};
    EXPECT_THROW(composeFigure(RgbImage(), options), InvalidInputError);
    FigureOptions bad = options;
    bad.fontScale = 0;
    EXPECT_THROW(composeFigure(picture, bad), InvalidInputError);
    bad = options;
    bad.range = {1, 1};
    EXPECT_THROW(composeFigure(picture, bad), InvalidInputError);
    bad.range = {0, std::numeric_limits<double>::infinity()};
    EXPECT_THROW(composeFigure(picture, bad), InvalidInputError);
    bad.colorBar = false;  // the range is not used then
    EXPECT_NO_THROW(composeFigure(picture, bad));
    bad = options;
    bad.pixelSize = std::nan("");
    EXPECT_THROW(composeFigure(picture, bad), InvalidInputError);
}
