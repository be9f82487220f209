/// Tests of render/image.h: RgbImage access and blending, PNG round trips, reading every
/// PNG pixel format (files built here byte by byte, with stored deflate blocks, so the reader
/// is checked independently of the writer), atomic writing and its errors, rectangles,
/// anti-aliased lines and the 5×7 bitmap font.

#include <msii/render/image.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "../support/files.h"
#include "../support/temp_dir.h"

using namespace msii;
using msii::test::readFile;
using msii::test::TempDir;
using msii::test::writeFile;

namespace {

constexpr Rgb8 kWhite{255, 255, 255};
constexpr Rgb8 kBlack{0, 0, 0};

// --- a minimal PNG encoder (uncompressed deflate) -----------------------------------------

std::uint32_t crc32(const std::string& bytes)
{
    std::uint32_t table[256];
    for (std::uint32_t n = 0; n < 256; ++n) {
        std::uint32_t c = n;
        for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        table[n] = c;
    }
    std::uint32_t crc = 0xFFFFFFFFu;
    for (unsigned char b : bytes) crc = table[(crc ^ b) & 0xFF] ^ (crc >> 8);
    return crc ^ 0xFFFFFFFFu;
}

void putU32(std::string& out, std::uint32_t v)
{
    out += char(v >> 24);
    out += char((v >> 16) & 0xFF);
    out += char((v >> 8) & 0xFF);
    out += char(v & 0xFF);
}

void putChunk(std::string& out, const std::string& type, const std::string& data)
{
    putU32(out, std::uint32_t(data.size()));
    out += type + data;
    putU32(out, crc32(type + data));
}

/// zlib stream of @p raw in stored (uncompressed) deflate blocks.
std::string zlibStored(const std::string& raw)
{
    std::string z = "\x78\x01";
    std::size_t pos = 0;
    do {
        const std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
        const bool last = pos + n == raw.size();
        z += char(last ? 1 : 0);
        z += char(n & 0xFF);
        z += char(n >> 8);
        z += char(~n & 0xFF);
        z += char((~n >> 8) & 0xFF);
        z += raw.substr(pos, n);
        pos += n;
    } while (pos < raw.size());
    std::uint32_t a = 1, b = 0;
    for (unsigned char c : raw) {
        a = (a + c) % 65521;
        b = (b + a) % 65521;
    }
    putU32(z, (b << 16) | a);
    return z;
}

/// A PNG of the given type and depth; @p rows are the packed scanlines without filter bytes.
std::string makePng(int width, int height, int colorType, int bitDepth,
                    const std::vector<std::string>& rows, const std::string& palette = "",
                    const std::string& transparency = "")
{
    std::string png = "\x89PNG\r\n\x1a\n";
    std::string ihdr;
    putU32(ihdr, std::uint32_t(width));
    putU32(ihdr, std::uint32_t(height));
    ihdr += char(bitDepth);
    ihdr += char(colorType);
    ihdr += std::string(3, '\0');  // compression, filter, interlace
    putChunk(png, "IHDR", ihdr);
    if (!palette.empty()) putChunk(png, "PLTE", palette);
    if (!transparency.empty()) putChunk(png, "tRNS", transparency);
    std::string raw;
    for (const std::string& row : rows) raw += '\0' + row;  // filter type 0 (none)
    putChunk(png, "IDAT", zlibStored(raw));
    putChunk(png, "IEND", "");
    return png;
}

std::string bytes(std::initializer_list<int> values)
{
    std::string s;
    for (int v : values) s += char(v);
    return s;
}

void expectPixel(const RgbImage& image, int x, int y, Rgb8 expected)
{
    const Rgb8 got = image.at(x, y);
    EXPECT_EQ(int(got[0]), int(expected[0])) << "at (" << x << ", " << y << ")";
    EXPECT_EQ(int(got[1]), int(expected[1])) << "at (" << x << ", " << y << ")";
    EXPECT_EQ(int(got[2]), int(expected[2])) << "at (" << x << ", " << y << ")";
}

int countColor(const RgbImage& image, Rgb8 c)
{
    int n = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) n += image.at(x, y) == c ? 1 : 0;
    return n;
}

/// The glyph of @p text (one character) at scale 1 as 7 strings of '#' and '.'.
std::string glyphPicture(const std::string& text)
{
    RgbImage image(5, 7);
    drawText(image, 0, 0, text, kBlack, 1);
    std::string s;
    for (int y = 0; y < 7; ++y)
        for (int x = 0; x < 5; ++x) s += image.at(x, y) == kBlack ? '#' : '.';
    return s;
}

} // namespace

// --- RgbImage -------------------------------------------------------------------------------

TEST(RgbImage, ConstructorFillsAndLaysOutRowMajor)
{
    RgbImage image(4, 3, {10, 20, 30});
    EXPECT_EQ(image.width, 4);
    EXPECT_EQ(image.height, 3);
    ASSERT_EQ(image.rgb.size(), 36u);
    expectPixel(image, 3, 2, {10, 20, 30});
    image.set(2, 1, {1, 2, 3});
    const std::size_t i = 3 * (1 * 4 + 2);
    EXPECT_EQ(image.rgb[i], 1);
    EXPECT_EQ(image.rgb[i + 1], 2);
    EXPECT_EQ(image.rgb[i + 2], 3);
    expectPixel(image, 2, 1, {1, 2, 3});
    EXPECT_THROW(RgbImage(-1, 2), InvalidInputError);
}

TEST(RgbImage, SetOutsideIsIgnoredAtOutsideThrows)
{
    RgbImage image(3, 3);
    const std::vector<std::uint8_t> before = image.rgb;
    image.set(-1, 0, kBlack);
    image.set(3, 0, kBlack);
    image.set(0, 3, kBlack);
    image.set(0, -5, kBlack);
    EXPECT_EQ(image.rgb, before);
    EXPECT_THROW(image.at(3, 0), InvalidInputError);
    EXPECT_THROW(image.at(0, -1), InvalidInputError);
}

TEST(RgbImage, BlendMixesByAlpha)
{
    RgbImage image(3, 1, {255, 255, 255});
    image.blend(0, 0, {0, 0, 0}, 0.5);
    image.blend(1, 0, {0, 100, 200}, 1.0);
    image.blend(2, 0, {0, 0, 0}, 0.0);
    expectPixel(image, 0, 0, {128, 128, 128});  // 127.5 rounds up
    expectPixel(image, 1, 0, {0, 100, 200});
    expectPixel(image, 2, 0, {255, 255, 255});
    image.blend(0, 0, {0, 0, 0}, 0.25);  // 128·0.75 = 96
    expectPixel(image, 0, 0, {96, 96, 96});
    image.blend(5, 0, {0, 0, 0}, 1.0);  // outside: ignored
    image.blend(1, 0, {255, 255, 255}, 7.0);  // alpha clamped to 1
    expectPixel(image, 1, 0, {255, 255, 255});
}

// --- PNG --------------------------------------------------------------------------------

TEST(Png, RoundTripIsExactAndAtomic)
{
    TempDir dir;
    RgbImage image(37, 23);
    std::mt19937 rng(7);
    for (auto& v : image.rgb) v = std::uint8_t(rng() & 0xFF);
    const std::string path = dir.file("picture.png");
    writePng(path, image);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"picture.png"});  // no temporary left
    const std::string file = readFile(path);
    ASSERT_GE(file.size(), 8u);
    EXPECT_EQ(file.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));

    const RgbImage back = readPng(path);
    EXPECT_EQ(back.width, 37);
    EXPECT_EQ(back.height, 23);
    EXPECT_EQ(back.rgb, image.rgb);

    // Overwriting replaces the file.
    RgbImage small(2, 2, {1, 2, 3});
    writePng(path, small);
    const RgbImage back2 = readPng(path);
    EXPECT_EQ(back2.width, 2);
    EXPECT_EQ(back2.rgb, small.rgb);
}

TEST(Png, WriteErrors)
{
    TempDir dir;
    EXPECT_THROW(writePng(dir.file("empty.png"), RgbImage()), InvalidInputError);
    EXPECT_THROW(writePng(dir.file("empty.png"), RgbImage(0, 5)), InvalidInputError);
    EXPECT_THROW(writePng(dir.file("no/such/folder/x.png"), RgbImage(2, 2)), IOError);
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Png, ReadErrors)
{
    TempDir dir;
    EXPECT_THROW(readPng(dir.file("missing.png")), IOError);
    EXPECT_THROW(readPng(dir.path().string()), IOError);  // a folder
    writeFile(dir.file("text.png"), "this is not a picture at all");
    EXPECT_THROW(readPng(dir.file("text.png")), IOError);
    writeFile(dir.file("short.png"), "\x89PNG");
    EXPECT_THROW(readPng(dir.file("short.png")), IOError);

    // A valid file cut in half, and one with a corrupted chunk checksum.
    const std::string good =
        makePng(3, 2, 2, 8,
                {bytes({1, 2, 3, 4, 5, 6, 7, 8, 9}), bytes({9, 8, 7, 6, 5, 4, 3, 2, 1})});
    writeFile(dir.file("good.png"), good);
    EXPECT_NO_THROW(readPng(dir.file("good.png")));
    writeFile(dir.file("cut.png"), good.substr(0, good.size() / 2));
    EXPECT_THROW(readPng(dir.file("cut.png")), IOError);
    std::string bad = good;
    bad[29] ^= 0x55;  // inside IHDR's CRC
    writeFile(dir.file("crc.png"), bad);
    EXPECT_THROW(readPng(dir.file("crc.png")), IOError);
}

TEST(Png, ReadsRgb8AsWritten)
{
    TempDir dir;
    writeFile(dir.file("a.png"), makePng(3, 2, 2, 8,
                                         {bytes({1, 2, 3, 4, 5, 6, 7, 8, 9}),
                                          bytes({9, 8, 7, 6, 5, 4, 3, 2, 1})}));
    const RgbImage image = readPng(dir.file("a.png"));
    ASSERT_EQ(image.width, 3);
    ASSERT_EQ(image.height, 2);
    expectPixel(image, 0, 0, {1, 2, 3});
    expectPixel(image, 2, 0, {7, 8, 9});
    expectPixel(image, 1, 1, {6, 5, 4});
}

TEST(Png, ReadsGrayAndGrayAlpha)
{
    TempDir dir;
    writeFile(dir.file("g8.png"), makePng(2, 1, 0, 8, {bytes({0, 200})}));
    RgbImage g8 = readPng(dir.file("g8.png"));
    expectPixel(g8, 0, 0, {0, 0, 0});
    expectPixel(g8, 1, 0, {200, 200, 200});

    // 2-bit gray: 0, 1, 2, 3 → 0, 85, 170, 255 (packed into one byte 00 01 10 11).
    writeFile(dir.file("g2.png"), makePng(4, 1, 0, 2, {bytes({0x1B})}));
    RgbImage g2 = readPng(dir.file("g2.png"));
    ASSERT_EQ(g2.width, 4);
    expectPixel(g2, 0, 0, {0, 0, 0});
    expectPixel(g2, 1, 0, {85, 85, 85});
    expectPixel(g2, 2, 0, {170, 170, 170});
    expectPixel(g2, 3, 0, {255, 255, 255});

    // Gray + alpha: the alpha is dropped, not applied.
    writeFile(dir.file("ga.png"), makePng(2, 1, 4, 8, {bytes({50, 0, 220, 128})}));
    RgbImage ga = readPng(dir.file("ga.png"));
    expectPixel(ga, 0, 0, {50, 50, 50});
    expectPixel(ga, 1, 0, {220, 220, 220});

    // 16-bit gray: the high byte.
    writeFile(dir.file("g16.png"), makePng(2, 1, 0, 16, {bytes({0x12, 0x12, 0xF0, 0xF0})}));
    RgbImage g16 = readPng(dir.file("g16.png"));
    expectPixel(g16, 0, 0, {0x12, 0x12, 0x12});
    expectPixel(g16, 1, 0, {0xF0, 0xF0, 0xF0});
}

TEST(Png, ReadsRgbaAnd16Bit)
{
    TempDir dir;
    writeFile(dir.file("rgba.png"), makePng(2, 1, 6, 8, {bytes({1, 2, 3, 0, 4, 5, 6, 255})}));
    RgbImage rgba = readPng(dir.file("rgba.png"));
    expectPixel(rgba, 0, 0, {1, 2, 3});
    expectPixel(rgba, 1, 0, {4, 5, 6});

    // 16-bit RGB and RGBA with values v·257 (exact under any 16 → 8 reduction).
    writeFile(dir.file("rgb16.png"),
              makePng(1, 2, 2, 16,
                      {bytes({10, 10, 20, 20, 30, 30}), bytes({255, 255, 0, 0, 128, 128})}));
    RgbImage rgb16 = readPng(dir.file("rgb16.png"));
    expectPixel(rgb16, 0, 0, {10, 20, 30});
    expectPixel(rgb16, 0, 1, {255, 0, 128});
    writeFile(dir.file("rgba16.png"),
              makePng(1, 1, 6, 16, {bytes({40, 40, 50, 50, 60, 60, 0, 0})}));
    expectPixel(readPng(dir.file("rgba16.png")), 0, 0, {40, 50, 60});
}

TEST(Png, ReadsPalette)
{
    TempDir dir;
    const std::string palette = bytes({255, 0, 0, 0, 255, 0, 0, 0, 255, 9, 8, 7});
    writeFile(dir.file("p8.png"), makePng(4, 1, 3, 8, {bytes({3, 2, 1, 0})}, palette));
    RgbImage p8 = readPng(dir.file("p8.png"));
    expectPixel(p8, 0, 0, {9, 8, 7});
    expectPixel(p8, 1, 0, {0, 0, 255});
    expectPixel(p8, 2, 0, {0, 255, 0});
    expectPixel(p8, 3, 0, {255, 0, 0});

    // 4-bit indices with a transparency chunk (dropped).
    writeFile(dir.file("p4.png"),
              makePng(3, 1, 3, 4, {bytes({0x12, 0x30})}, palette, bytes({0, 128})));
    RgbImage p4 = readPng(dir.file("p4.png"));
    ASSERT_EQ(p4.width, 3);
    expectPixel(p4, 0, 0, {0, 255, 0});
    expectPixel(p4, 1, 0, {0, 0, 255});
    expectPixel(p4, 2, 0, {9, 8, 7});
}

// --- drawing ----------------------------------------------------------------------------

TEST(Draw, FillRectIsHalfOpenAndClipped)
{
    RgbImage image(10, 8);
    fillRect(image, 2, 3, 5, 7, kBlack);  // 3 × 4 pixels
    EXPECT_EQ(countColor(image, kBlack), 12);
    expectPixel(image, 2, 3, kBlack);
    expectPixel(image, 4, 6, kBlack);
    expectPixel(image, 5, 6, kWhite);
    expectPixel(image, 4, 7, kWhite);
    fillRect(image, -5, -5, 2, 1, {1, 1, 1});  // clipped to [0, 2) × [0, 1)
    EXPECT_EQ(countColor(image, {1, 1, 1}), 2);
    fillRect(image, 6, 6, 4, 4, {2, 2, 2});  // empty
    EXPECT_EQ(countColor(image, {2, 2, 2}), 0);
    fillRect(image, 8, 0, 100, 100, {3, 3, 3});
    EXPECT_EQ(countColor(image, {3, 3, 3}), 16);
}

TEST(Draw, HorizontalLinesThroughPixelCentresAreCrisp)
{
    RgbImage image(24, 12);
    drawLine(image, 2, 5.5, 20, 5.5, kBlack, 1.0);
    for (int x = 3; x <= 19; ++x) expectPixel(image, x, 5, kBlack);
    for (int x = 0; x < 24; ++x) {
        expectPixel(image, x, 4, kWhite);
        expectPixel(image, x, 6, kWhite);
    }
    RgbImage thick(24, 12);
    drawLine(thick, 2, 5.5, 20, 5.5, kBlack, 3.0);
    for (int y = 4; y <= 6; ++y) expectPixel(thick, 10, y, kBlack);
    expectPixel(thick, 10, 3, kWhite);
    expectPixel(thick, 10, 7, kWhite);
}

TEST(Draw, DiagonalLineIsAntiAliasedAndSymmetric)
{
    RgbImage image(20, 20);
    drawLine(image, 0, 0, 20, 20, kBlack, 1.5);
    int partial = 0;
    for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 20; ++x) {
            const Rgb8 c = image.at(x, y);
            EXPECT_EQ(c, image.at(y, x));  // symmetric about the diagonal
            EXPECT_TRUE(c[0] == c[1] && c[1] == c[2]);
            if (c[0] > 0 && c[0] < 255) ++partial;
        }
    EXPECT_GT(partial, 10);                    // grey edge pixels
    EXPECT_EQ(image.at(10, 10)[0], 0);          // on the line
    EXPECT_EQ(image.at(15, 5)[0], 255);         // far from it
    EXPECT_LT(image.at(11, 10)[0], image.at(12, 10)[0]);  // fades with distance
}

TEST(Draw, TextWidthAndHeight)
{
    EXPECT_EQ(textWidth("", 2), 0);
    EXPECT_EQ(textWidth("1", 1), 5);
    EXPECT_EQ(textWidth("12", 1), 11);  // advance 6
    EXPECT_EQ(textWidth("12", 2), 22);
    EXPECT_EQ(textWidth("\xC3\x97", 1), 5);  // '×' is one character
    EXPECT_EQ(textWidth("2\xC3\x97" "3", 3), 51);
    EXPECT_EQ(textHeight(3), 21);
    RgbImage image(60, 20);
    EXPECT_EQ(drawText(image, 1, 1, "0.25 mm", kBlack, 1), textWidth("0.25 mm", 1));
}

TEST(Draw, GlyphsArePlacedAndScaled)
{
    // '-' is the middle row (row 3), all 5 columns.
    RgbImage one(10, 10);
    drawText(one, 1, 1, "-", {7, 8, 9}, 1);
    EXPECT_EQ(countColor(one, {7, 8, 9}), 5);
    for (int x = 1; x <= 5; ++x) expectPixel(one, x, 4, {7, 8, 9});

    RgbImage two(20, 20);
    drawText(two, 1, 1, "-", kBlack, 2);
    EXPECT_EQ(countColor(two, kBlack), 20);
    for (int x = 1; x <= 10; ++x) {
        expectPixel(two, x, 7, kBlack);
        expectPixel(two, x, 8, kBlack);
    }

    // The second character starts 6 font pixels to the right.
    RgbImage pair(20, 10);
    drawText(pair, 0, 0, "--", kBlack, 1);
    expectPixel(pair, 4, 3, kBlack);
    expectPixel(pair, 5, 3, kWhite);
    expectPixel(pair, 6, 3, kBlack);

    // Partly outside the image: clipped, no crash.
    RgbImage edge(4, 4);
    drawText(edge, -3, -3, "8", kBlack, 2);
    EXPECT_GT(countColor(edge, kBlack), 0);
}

TEST(Draw, FontCoversTheListedCharactersWithDistinctGlyphs)
{
    std::vector<std::string> chars;
    for (char c = '0'; c <= '9'; ++c) chars.push_back(std::string(1, c));
    for (char c = 'A'; c <= 'Z'; ++c) chars.push_back(std::string(1, c));
    for (char c = 'a'; c <= 'z'; ++c) chars.push_back(std::string(1, c));
    for (const char* p : {".", ",", "-", "+", "(", ")", "/", ":", "%", "_", "=", "\xC3\x97"})
        chars.push_back(p);
    ASSERT_EQ(chars.size(), 74u);

    const std::string box = glyphPicture("#");
    EXPECT_EQ(box, "#####"
                   "#...#"
                   "#...#"
                   "#...#"
                   "#...#"
                   "#...#"
                   "#####");
    EXPECT_EQ(glyphPicture("@"), box);
    EXPECT_EQ(glyphPicture("\xC3\xA9"), box);  // 'é': one unknown character, one box
    EXPECT_EQ(textWidth("\xC3\xA9", 1), 5);
    EXPECT_EQ(glyphPicture(" "), std::string(35, '.'));

    std::set<std::string> seen;
    for (const std::string& c : chars) {
        const std::string g = glyphPicture(c);
        EXPECT_NE(g, box) << "'" << c << "' is drawn as the unknown box";
        EXPECT_NE(g, std::string(35, '.')) << "'" << c << "' is blank";
        EXPECT_TRUE(seen.insert(g).second) << "'" << c << "' looks like another character";
    }

    // A few glyphs by hand.
    EXPECT_EQ(glyphPicture("1"), "..#.."
                                 ".##.."
                                 "..#.."
                                 "..#.."
                                 "..#.."
                                 "..#.."
                                 ".###.");
    EXPECT_EQ(glyphPicture("\xC3\x97"), "....."
                                        "#...#"
                                        ".#.#."
                                        "..#.."
                                        ".#.#."
                                        "#...#"
                                        ".....");
}
