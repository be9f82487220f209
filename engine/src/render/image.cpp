/// @file image.cpp
/// @brief RgbImage, PNG input and output through libpng, and the drawing primitives.
///
/// libpng reports errors by longjmp. The two functions that call setjmp (encodePng and
/// decodePng) hold no C++ objects with destructors: everything they fill (the output byte
/// vector, the image) belongs to their callers, and an error is passed back as text in a
/// plain struct. Allocations inside them are wrapped in try/catch so that no exception
/// leaves while libpng's structures are alive.

#include <msii/render/image.h>

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <limits>

namespace msii {

namespace {

// ---------------------------------------------------------------------------------------
// PNG
// ---------------------------------------------------------------------------------------

/// What the libpng callbacks share with the function that called setjmp. Plain data only.
struct PngContext {
    char error[256] = {};                      ///< libpng's message, empty if none
    std::vector<std::uint8_t>* out = nullptr;  ///< encoding: the bytes written so far
    const std::uint8_t* in = nullptr;          ///< decoding: the file's bytes
    std::size_t inSize = 0, inPos = 0;
};

void copyMessage(PngContext* ctx, const char* message)
{
    std::snprintf(ctx->error, sizeof ctx->error, "%s", message ? message : "libpng error");
}

[[noreturn]] void pngError(png_structp png, png_const_charp message)
{
    auto* ctx = static_cast<PngContext*>(png_get_error_ptr(png));
    if (ctx) copyMessage(ctx, message);
    png_longjmp(png, 1);
}

void pngWarning(png_structp, png_const_charp) {}

void pngWrite(png_structp png, png_bytep data, png_size_t length)
{
    auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
    bool ok = true;
    try {
        ctx->out->insert(ctx->out->end(), data, data + length);
    } catch (...) {
        ok = false;
    }
    if (!ok) png_error(png, "out of memory");
}

void pngFlush(png_structp) {}

void pngRead(png_structp png, png_bytep data, png_size_t length)
{
    auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
    if (ctx->inSize - ctx->inPos < length) png_error(png, "the file is truncated");
    std::memcpy(data, ctx->in + ctx->inPos, length);
    ctx->inPos += length;
}

/// Encodes @p image into ctx->out. Returns false with ctx->error set on failure.
bool encodePng(const RgbImage& image, PngContext* ctx)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, ctx, pngError, pngWarning);
    if (!png) {
        copyMessage(ctx, "cannot initialise libpng");
        return false;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        copyMessage(ctx, "cannot initialise libpng");
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return false;
    }
    png_set_write_fn(png, ctx, pngWrite, pngFlush);
    // zlib level 3: as small as the default (6) on pictures, in half the time.
    png_set_compression_level(png, 3);
    png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    const std::size_t stride = 3 * std::size_t(image.width);
    for (int y = 0; y < image.height; ++y)
        png_write_row(png, image.rgb.data() + std::size_t(y) * stride);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return true;
}

/// Decodes ctx->in into @p image (8-bit RGB). Returns false with ctx->error set on failure.
bool decodePng(PngContext* ctx, RgbImage* image)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, ctx, pngError, pngWarning);
    if (!png) {
        copyMessage(ctx, "cannot initialise libpng");
        return false;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_read_struct(&png, nullptr, nullptr);
        copyMessage(ctx, "cannot initialise libpng");
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        return false;
    }
    png_set_read_fn(png, ctx, pngRead);
    png_read_info(png, info);
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_set_strip_alpha(png);
    const int passes = png_set_interlace_handling(png);
    png_read_update_info(png, info);

    const png_uint_32 width = png_get_image_width(png, info);
    const png_uint_32 height = png_get_image_height(png, info);
    if (png_get_channels(png, info) != 3 || png_get_bit_depth(png, info) != 8 ||
        png_get_rowbytes(png, info) != 3 * std::size_t(width))
        png_error(png, "unsupported pixel format");
    if (width > png_uint_32(std::numeric_limits<int>::max() / 3) ||
        height > png_uint_32(std::numeric_limits<int>::max()))
        png_error(png, "the image is too large");

    bool allocated = true;
    try {
        image->width = int(width);
        image->height = int(height);
        image->rgb.assign(3 * std::size_t(width) * height, 0);
    } catch (...) {
        allocated = false;
    }
    if (!allocated) png_error(png, "out of memory");

    const std::size_t stride = 3 * std::size_t(width);
    for (int pass = 0; pass < passes; ++pass)
        for (png_uint_32 y = 0; y < height; ++y)
            png_read_row(png, image->rgb.data() + std::size_t(y) * stride, nullptr);
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return true;
}

// ---------------------------------------------------------------------------------------
// The 5×7 font
// ---------------------------------------------------------------------------------------

/// One glyph: seven rows from the top, bit 4 the leftmost column, bit 0 the rightmost.
struct Glyph {
    char32_t code;
    std::uint8_t rows[7];
};

constexpr char32_t kTimes = 0xD7;  ///< '×'

constexpr Glyph kGlyphs[] = {
    {U' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},
    {U'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {U'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {U'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {U'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {U'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {U'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {U'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {U'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {U'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {U'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {U'A', {0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11}},
    {U'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {U'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {U'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {U'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {U'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {U'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {U'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {U'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {U'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {U'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {U'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {U'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {U'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {U'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {U'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {U'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {U'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {U'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {U'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {U'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {U'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {U'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {U'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {U'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {U'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {U'a', {0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F}},
    {U'b', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E}},
    {U'c', {0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E}},
    {U'd', {0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F}},
    {U'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {U'f', {0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08}},
    {U'g', {0x00, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
    {U'h', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {U'i', {0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E}},
    {U'j', {0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0C}},
    {U'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {U'l', {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {U'm', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}},
    {U'n', {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {U'o', {0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E}},
    {U'p', {0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10}},
    {U'q', {0x00, 0x00, 0x0D, 0x13, 0x0F, 0x01, 0x01}},
    {U'r', {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}},
    {U's', {0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E}},
    {U't', {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06}},
    {U'u', {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D}},
    {U'v', {0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {U'w', {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A}},
    {U'x', {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {U'y', {0x00, 0x00, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
    {U'z', {0x00, 0x00, 0x1F, 0x02, 0x04, 0x08, 0x1F}},
    {U'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {U',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {U'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {U'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {U'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {U')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {U'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {U':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {U'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {U'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {U'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {kTimes, {0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x00}},
};

/// Drawn for characters the font does not have.
constexpr std::uint8_t kBoxRows[7] = {0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F};

const std::uint8_t* glyphRows(char32_t code)
{
    for (const Glyph& g : kGlyphs)
        if (g.code == code) return g.rows;
    return kBoxRows;
}

constexpr int kGlyphWidth = 5;
constexpr int kAdvance = 6;  ///< font pixels from one character to the next

int widthOf(std::size_t characters, int scale)
{
    if (characters == 0) return 0;
    return (kAdvance * int(characters) - (kAdvance - kGlyphWidth)) * scale;
}

} // namespace

// ---------------------------------------------------------------------------------------

std::vector<char32_t> decodeUtf8(const std::string& text)
{
    std::vector<char32_t> codes;
    codes.reserve(text.size());
    std::size_t i = 0;
    while (i < text.size()) {
        const auto b = static_cast<unsigned char>(text[i]);
        int extra = 0;
        char32_t code = b;
        if (b >= 0xC0 && b < 0xE0) {
            extra = 1;
            code = b & 0x1F;
        } else if (b >= 0xE0 && b < 0xF0) {
            extra = 2;
            code = b & 0x0F;
        } else if (b >= 0xF0 && b < 0xF8) {
            extra = 3;
            code = b & 0x07;
        } else if (b >= 0x80) {
            codes.push_back(0xFFFD);  // stray continuation byte
            ++i;
            continue;
        }
        bool valid = i + std::size_t(extra) < text.size();
        for (int k = 1; valid && k <= extra; ++k) {
            const auto c = static_cast<unsigned char>(text[i + std::size_t(k)]);
            if ((c & 0xC0) != 0x80)
                valid = false;
            else
                code = (code << 6) | (c & 0x3F);
        }
        if (!valid) {
            codes.push_back(0xFFFD);
            ++i;
            continue;
        }
        codes.push_back(code);
        i += std::size_t(extra) + 1;
    }
    return codes;
}

// RgbImage
// ---------------------------------------------------------------------------------------

RgbImage::RgbImage(int w, int h, Rgb8 fill) : width(w), height(h)
{
    if (w < 0 || h < 0)
        throw InvalidInputError("an image cannot have a negative size (" + std::to_string(w) +
                                " x " + std::to_string(h) + ").");
    const std::size_t n = std::size_t(w) * std::size_t(h);
    rgb.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
        rgb[3 * i] = fill[0];
        rgb[3 * i + 1] = fill[1];
        rgb[3 * i + 2] = fill[2];
    }
}

Rgb8 RgbImage::at(int x, int y) const
{
    if (x < 0 || y < 0 || x >= width || y >= height)
        throw InvalidInputError("pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                ") is outside the " + std::to_string(width) + " x " +
                                std::to_string(height) + " image.");
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void RgbImage::set(int x, int y, Rgb8 c)
{
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    rgb[i] = c[0];
    rgb[i + 1] = c[1];
    rgb[i + 2] = c[2];
}

void RgbImage::blend(int x, int y, Rgb8 c, double alpha)
{
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    if (!(alpha > 0)) return;  // also NaN
    if (alpha > 1) alpha = 1;
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    for (int k = 0; k < 3; ++k) {
        const double v = alpha * c[std::size_t(k)] + (1 - alpha) * rgb[i + std::size_t(k)];
        rgb[i + std::size_t(k)] = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
    }
}

// ---------------------------------------------------------------------------------------
// PNG files
// ---------------------------------------------------------------------------------------

void writePng(const std::string& path, const RgbImage& image)
{
    if (image.width <= 0 || image.height <= 0)
        throw InvalidInputError("cannot write '" + path + "': the image is empty.");
    if (image.rgb.size() != 3 * std::size_t(image.width) * std::size_t(image.height))
        throw InvalidInputError("cannot write '" + path +
                                "': the pixel buffer does not match the image size.");
    std::vector<std::uint8_t> bytes;
    PngContext ctx;
    ctx.out = &bytes;
    if (!encodePng(image, &ctx))
        throw IOError("cannot write '" + path + "': " + ctx.error + ".");
    AtomicFile file(path);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

RgbImage readPng(const std::string& path)
{
    std::vector<std::uint8_t> bytes;
    {
        std::FILE* file = std::fopen(path.c_str(), "rb");
        if (!file) throw IOError("cannot read '" + path + "': " + std::strerror(errno) + ".");
        std::uint8_t buffer[65536];
        std::size_t n = 0;
        int error = 0;
        try {
            while ((n = std::fread(buffer, 1, sizeof buffer, file)) > 0)
                bytes.insert(bytes.end(), buffer, buffer + n);
        } catch (...) {
            std::fclose(file);
            throw;
        }
        if (std::ferror(file)) error = errno;
        std::fclose(file);
        if (error != 0)
            throw IOError("cannot read '" + path + "': " + std::strerror(error) + ".");
    }
    if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0)
        throw IOError("cannot read '" + path + "': it is not a PNG file.");

    RgbImage image;
    PngContext ctx;
    ctx.in = bytes.data();
    ctx.inSize = bytes.size();
    if (!decodePng(&ctx, &image))
        throw IOError("cannot read '" + path + "': " + ctx.error + ".");
    return image;
}

// ---------------------------------------------------------------------------------------
// Drawing
// ---------------------------------------------------------------------------------------

void fillRect(RgbImage& image, int x0, int y0, int x1, int y1, Rgb8 c)
{
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, image.width);
    y1 = std::min(y1, image.height);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) image.set(x, y, c);
}

void drawLine(RgbImage& image, double x0, double y0, double x1, double y1, Rgb8 c, double width)
{
    if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1) ||
        !(width > 0) || !std::isfinite(width))
        return;
    // Coverage of a pixel = clamp(half width + 0.5 − distance of its centre to the segment):
    // a box-filter approximation that is exact for axis-parallel lines through pixel centres.
    const double half = 0.5 * width;
    const double reach = half + 1.0;
    const int xa = std::max(0, int(std::floor(std::min(x0, x1) - reach)));
    const int xb = std::min(image.width - 1, int(std::ceil(std::max(x0, x1) + reach)));
    const int ya = std::max(0, int(std::floor(std::min(y0, y1) - reach)));
    const int yb = std::min(image.height - 1, int(std::ceil(std::max(y0, y1) + reach)));
    const double dx = x1 - x0, dy = y1 - y0;
    const double len2 = dx * dx + dy * dy;
    for (int y = ya; y <= yb; ++y) {
        for (int x = xa; x <= xb; ++x) {
            const double px = x + 0.5 - x0, py = y + 0.5 - y0;
            double t = len2 > 0 ? (px * dx + py * dy) / len2 : 0.0;
            t = std::clamp(t, 0.0, 1.0);
            const double ex = px - t * dx, ey = py - t * dy;
            const double d = std::sqrt(ex * ex + ey * ey);
            const double coverage = std::clamp(half + 0.5 - d, 0.0, 1.0);
            if (coverage > 0) image.blend(x, y, c, coverage);
        }
    }
}

int drawText(RgbImage& image, int x, int y, const std::string& text, Rgb8 c, int scale)
{
    if (scale < 1) scale = 1;
    const std::vector<char32_t> codes = decodeUtf8(text);
    int penX = x;
    for (char32_t code : codes) {
        const std::uint8_t* rows = glyphRows(code);
        for (int r = 0; r < 7; ++r)
            for (int col = 0; col < kGlyphWidth; ++col)
                if (rows[r] & (0x10 >> col))
                    fillRect(image, penX + col * scale, y + r * scale, penX + (col + 1) * scale,
                             y + (r + 1) * scale, c);
        penX += kAdvance * scale;
    }
    return widthOf(codes.size(), scale);
}

int textWidth(const std::string& text, int scale)
{
    if (scale < 1) scale = 1;
    return widthOf(decodeUtf8(text).size(), scale);
}

} // namespace msii
