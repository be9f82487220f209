/// Tests of render/picture.h's isolines: a contour is drawn around a region above a level,
/// and not around a speck of fewer than isolineMinPixels pixels (noise near a level), unless
/// that minimum is 0.

#include <msii/render/picture.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace msii;

namespace {

/// Black pixels (isolines) in the rectangle [x0, x1) × [y0, y1).
int blackIn(const RgbImage& image, int x0, int y0, int x1, int y1)
{
    int count = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const Rgb8 c = image.at(x, y);
            count += c[0] < 60 && c[1] < 60 && c[2] < 60;
        }
    return count;
}

} // namespace

TEST(PictureIsolines, SpecksAreLeftOutBlobsAreNot)
{
    const int w = 120, h = 60;
    std::vector<float> value(std::size_t(w * h), 0.0f);
    // A blob of radius 12 around (30, 30) and a 2 × 2 speck at (90, 30), both at 1.
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (std::hypot(x - 30, y - 30) < 12) value[std::size_t(y * w + x)] = 1.0f;
            if (x >= 90 && x < 92 && y >= 30 && y < 32) value[std::size_t(y * w + x)] = 1.0f;
        }
    PictureChannels ch;
    ch.width = w, ch.height = h;
    ch.value = &value;
    PictureOptions options;
    options.fixedRange = true;
    options.range = {0.0, 1.0};
    options.isolineLevels = {0.5};
    const RgbImage pruned = renderPicture(ch, options).image;
    EXPECT_GT(blackIn(pruned, 10, 10, 50, 50), 40);  // the blob's contour, about 75 pixels long
    EXPECT_EQ(blackIn(pruned, 80, 20, 100, 40), 0);  // no ring around the speck
    options.isolineMinPixels = 0;
    const RgbImage all = renderPicture(ch, options).image;
    EXPECT_EQ(blackIn(all, 10, 10, 50, 50), blackIn(pruned, 10, 10, 50, 50));
    EXPECT_GT(blackIn(all, 80, 20, 100, 40), 2);
    options.isolineMinPixels = -1;
    EXPECT_THROW(renderPicture(ch, options), InvalidInputError);
}
