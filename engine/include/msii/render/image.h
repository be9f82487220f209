#pragma once
/// @file image.h
/// @brief An 8-bit RGB raster, PNG reading and writing (libpng), and the few drawing
/// primitives the pictures need (filled rectangles, lines, text in a built-in bitmap font).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace msii {

using Rgb8 = std::array<std::uint8_t, 3>;

/// Row-major RGB pixels, row 0 at the top: pixel (x, y) is rgb[3 * (y * width + x) + c].
struct RgbImage {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgb;

    RgbImage() = default;
    RgbImage(int w, int h, Rgb8 fill = {255, 255, 255});
    Rgb8 at(int x, int y) const;                       ///< @throw InvalidInputError outside
    void set(int x, int y, Rgb8 c);                    ///< ignores pixels outside the image
    void blend(int x, int y, Rgb8 c, double alpha);    ///< c over the pixel, alpha in [0, 1]
};

/// Writes @p image as an 8-bit RGB PNG, atomically (io/atomic_file.h).
/// @throw InvalidInputError for an empty image, IOError if the file cannot be written.
void writePng(const std::string& path, const RgbImage& image);

/// Reads an 8-bit or 16-bit PNG (gray, gray+alpha, RGB, RGBA, palette) as RGB (alpha dropped).
/// @throw IOError if the file is missing or not a PNG.
RgbImage readPng(const std::string& path);

void fillRect(RgbImage& image, int x0, int y0, int x1, int y1, Rgb8 c);  ///< [x0, x1) × [y0, y1)
/// An anti-aliased line of the given width (pixels), endpoints in pixel coordinates (pixel
/// centres at +0.5).
void drawLine(RgbImage& image, double x0, double y0, double x1, double y1, Rgb8 c, double width = 1.0);

/// Splits UTF-8 text into code points; a malformed byte counts as one character, U+FFFD.
std::vector<char32_t> decodeUtf8(const std::string& text);

/// Text in a built-in 5×7 bitmap font (digits, letters A–Z/a–z, space and . , - + ( ) / : % _ =
/// ×; other characters as a box), each font pixel drawn as scale×scale pixels, top-left at
/// (x, y). Returns the width drawn, in pixels.
int drawText(RgbImage& image, int x, int y, const std::string& text, Rgb8 c, int scale = 2);
int textWidth(const std::string& text, int scale = 2);
inline int textHeight(int scale = 2) { return 7 * scale; }

} // namespace msii
