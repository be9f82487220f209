/// Tests of render/typeface.h: the labels' font is found (DejaVu Sans from Debian's
/// fonts-dejavu-core, which the set-up script installs), text is set anti-aliased inside its
/// line box and measured as drawn, sizes follow the line height, a font file asked for that
/// cannot be read is an error, and the built-in pixel font draws as render/image.h does.
/// Figures set with the typeface keep the picture and hold their labels in the margins.

#include <msii/render/annotate.h>
#include <msii/render/typeface.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>

#include "../support/temp_dir.h"

using namespace msii;

namespace {

/// Ink of a black-on-white image: bounding box and how many pixels are grey (neither black
/// nor white: anti-aliased edges).
struct Ink {
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    std::size_t pixels = 0, grey = 0;
};

Ink inkOf(const RgbImage& image)
{
    Ink ink;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const Rgb8 c = image.at(x, y);
            if (c[0] == 255) continue;
            ++ink.pixels;
            if (c[0] != 0) ++ink.grey;
            ink.x0 = std::min(ink.x0, x), ink.x1 = std::max(ink.x1, x);
            ink.y0 = std::min(ink.y0, y), ink.y1 = std::max(ink.y1, y);
        }
    return ink;
}

} // namespace

TEST(Typeface, FindsDejaVuSansAndSetsTextAntiAliased)
{
    ::unsetenv("MSII_FONT");
    const FontResult found = findFont();
    ASSERT_FALSE(found.typeface.isBuiltIn()) << found.warning;
    EXPECT_TRUE(found.warning.empty());
    EXPECT_NE(found.typeface.file().find("DejaVu"), std::string::npos) << found.typeface.file();

    const Typeface& face = found.typeface;
    const std::string text = "0.25 mm";
    for (const int lineHeight : {14, 24, 48}) {
        SCOPED_TRACE(lineHeight);
        RgbImage image(300, 80);
        const int width = face.drawText(image, 10, 10, text, {0, 0, 0}, lineHeight);
        EXPECT_EQ(width, face.textWidth(text, lineHeight));
        const Ink ink = inkOf(image);
        ASSERT_GT(ink.pixels, 0u);
        EXPECT_GT(ink.grey, ink.pixels / 5);  // anti-aliased, not a bitmap font
        // Inside the line box [10, 10 + width) × [10, 10 + lineHeight).
        EXPECT_GE(ink.x0, 10);
        EXPECT_LE(ink.x1, 10 + width);
        EXPECT_GE(ink.y0, 10);
        EXPECT_LT(ink.y1, 10 + lineHeight);
        // Digits fill most of the space above the baseline.
        EXPECT_GT(ink.y1 - ink.y0 + 1, lineHeight / 2);
    }
    EXPECT_GT(face.textWidth(text, 48), 2 * face.textWidth(text, 20));
    EXPECT_EQ(face.textWidth("", 20), 0);
}

TEST(Typeface, AskedFontThatCannotBeReadIsAnError)
{
    const msii::test::TempDir dir;
    const std::string notAFont = dir.file("not-a-font.ttf");
    std::ofstream(notAFont) << "hello";
    EXPECT_THROW(Typeface::load(notAFont), IOError);
    EXPECT_THROW(Typeface::load(dir.file("missing.ttf")), IOError);
    FontOptions options;
    options.file = notAFont;
    EXPECT_THROW(findFont(options), IOError);
    ::setenv("MSII_FONT", dir.file("missing.ttf").c_str(), 1);
    EXPECT_THROW(findFont(), IOError);
    ::unsetenv("MSII_FONT");
}

TEST(Typeface, BuiltInFontDrawsAsTheImageFont)
{
    const Typeface builtIn;
    ASSERT_TRUE(builtIn.isBuiltIn());
    RgbImage a(200, 40), b(200, 40);
    // Line height 18: scale 2, the 14 glyph rows centred in the line box.
    const int width = builtIn.drawText(a, 3, 5, "1.5 mm", {0, 0, 0}, 18);
    drawText(b, 3, 7, "1.5 mm", {0, 0, 0}, 2);
    EXPECT_EQ(width, textWidth("1.5 mm", 2));
    EXPECT_EQ(a.rgb, b.rgb);
}

TEST(Typeface, LabelLineHeightFollowsThePicture)
{
    EXPECT_EQ(labelLineHeight(100), 14);
    EXPECT_EQ(labelLineHeight(1000), 25);
    EXPECT_EQ(labelLineHeight(10000), 48);
}

TEST(Typeface, FigureWithTypefaceKeepsThePictureAndLabelsTheMargins)
{
    const FontResult found = findFont();
    ASSERT_FALSE(found.typeface.isBuiltIn()) << found.warning;
    RgbImage picture(400, 300, {90, 120, 150});
    FigureOptions options;
    options.range = {0.25, 0.75};
    options.label = "V_16";
    options.pixelSize = 0.01;
    options.typeface = &found.typeface;
    options.lineHeight = 24;
    const RgbImage figure = composeFigure(picture, options);
    ASSERT_GT(figure.width, picture.width);
    ASSERT_GT(figure.height, picture.height);
    for (int y = 0; y < picture.height; ++y)
        for (int x = 0; x < picture.width; ++x) ASSERT_EQ(figure.at(x, y), picture.at(x, y)) << x << "," << y;
    // The bottom margin holds the scale bar and its label, "1 mm" (about 1/5 of 4 mm),
    // whose text is set in the typeface: grey edge pixels below the bar.
    RgbImage bottom(figure.width, figure.height - picture.height);
    for (int y = 0; y < bottom.height; ++y)
        for (int x = 0; x < bottom.width; ++x) bottom.set(x, y, figure.at(x, picture.height + y));
    const Ink ink = inkOf(bottom);
    EXPECT_GT(ink.grey, 10u);
    EXPECT_LT(ink.y1, bottom.height);
    options.lineHeight = 3;
    EXPECT_THROW(composeFigure(picture, options), InvalidInputError);
}
