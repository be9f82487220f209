/// @file typeface.cpp
/// @brief FreeType faces and fontconfig's lookup behind render/typeface.h.
#include <msii/render/typeface.h>

#include <msii/core/errors.h>

#include <fontconfig/fontconfig.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace msii {

namespace {

/// The built-in font's scale for a line height: its glyphs are 7 rows, lines 9.
int builtInScale(int lineHeight) { return std::max(1, lineHeight / 9); }

FT_Library library()
{
    // One library for the process; FreeType frees it at exit with the faces.
    static FT_Library lib = [] {
        FT_Library l = nullptr;
        if (FT_Init_FreeType(&l) != 0) throw IOError("FreeType could not be initialised.");
        return l;
    }();
    return lib;
}

/// fontconfig's best match for "DejaVu Sans", or empty.
std::string fontconfigMatch()
{
    if (!FcInit()) return {};
    std::string file;
    FcPattern* pattern = FcNameParse(reinterpret_cast<const FcChar8*>("DejaVu Sans"));
    if (!pattern) return {};
    FcConfigSubstitute(nullptr, pattern, FcMatchPattern);
    FcDefaultSubstitute(pattern);
    FcResult result = FcResultNoMatch;
    if (FcPattern* match = FcFontMatch(nullptr, pattern, &result)) {
        FcChar8* path = nullptr;
        if (FcPatternGetString(match, FC_FILE, 0, &path) == FcResultMatch && path)
            file = reinterpret_cast<const char*>(path);
        FcPatternDestroy(match);
    }
    FcPatternDestroy(pattern);
    return file;
}

} // namespace

struct Typeface::Face {
    FT_Face face = nullptr;
    int size = 0;  // pixel size set on the face
    ~Face()
    {
        if (face) FT_Done_Face(face);
    }
    /// Sets the size whose line box (ascender − descender) is @p lineHeight pixels.
    void setLineHeight(int lineHeight)
    {
        if (lineHeight == size) return;
        // units_per_EM / (ascender − descender) of the face scales a line to an em.
        const double em = double(face->units_per_EM) / double(face->ascender - face->descender);
        FT_Set_Pixel_Sizes(face, 0, FT_UInt(std::max(1L, std::lround(lineHeight * em))));
        size = lineHeight;
    }
};

Typeface::Typeface() = default;
Typeface::~Typeface() = default;
Typeface::Typeface(Typeface&&) noexcept = default;
Typeface& Typeface::operator=(Typeface&&) noexcept = default;

Typeface Typeface::load(const std::string& file)
{
    Typeface t;
    auto face = std::make_unique<Face>();
    if (FT_New_Face(library(), file.c_str(), 0, &face->face) != 0 || !face->face)
        throw IOError("'" + file + "' is not a font FreeType can read.");
    if (!FT_IS_SCALABLE(face->face) || face->face->ascender - face->face->descender <= 0)
        throw IOError("'" + file + "' is not a scalable font.");
    t.mFace = std::move(face);
    t.mFile = file;
    return t;
}

namespace {

/// Lays @p text out on face @p f from pen position 0 (26.6 fixed point), with kerning: loads
/// each glyph with @p loadFlags and calls visit(slot, pen) before advancing the pen past it.
/// Returns the pen's final position.
template <class Visit>
long layOut(FT_Face f, const std::string& text, FT_Int32 loadFlags, const Visit& visit)
{
    long pen = 0;
    FT_UInt previous = 0;
    for (const char32_t code : decodeUtf8(text)) {
        const FT_UInt glyph = FT_Get_Char_Index(f, code);
        if (previous && glyph && FT_HAS_KERNING(f)) {
            FT_Vector kern;
            if (FT_Get_Kerning(f, previous, glyph, FT_KERNING_DEFAULT, &kern) == 0) pen += kern.x;
        }
        previous = glyph;
        if (FT_Load_Glyph(f, glyph, loadFlags) != 0) continue;
        visit(f->glyph, pen);
        pen += f->glyph->advance.x;
    }
    return pen;
}

} // namespace

int Typeface::textWidth(const std::string& text, int lineHeight) const
{
    if (!mFace) return msii::textWidth(text, builtInScale(lineHeight));
    mFace->setLineHeight(lineHeight);
    return int((layOut(mFace->face, text, FT_LOAD_DEFAULT, [](FT_GlyphSlot, long) {}) + 63) >> 6);
}

int Typeface::drawText(RgbImage& image, int x, int y, const std::string& text, Rgb8 color, int lineHeight) const
{
    if (!mFace) {
        const int s = builtInScale(lineHeight);
        // The 7 glyph rows centred in the line box.
        return msii::drawText(image, x, y + (lineHeight - 7 * s) / 2, text, color, s);
    }
    mFace->setLineHeight(lineHeight);
    const int baseline = y + int((mFace->face->size->metrics.ascender + 32) >> 6);
    const long width = layOut(mFace->face, text, FT_LOAD_RENDER, [&](FT_GlyphSlot g, long pen) {
        const FT_Bitmap& bitmap = g->bitmap;
        if (bitmap.pixel_mode != FT_PIXEL_MODE_GRAY) return;
        const int left = x + int((pen + 32) >> 6) + g->bitmap_left, top = baseline - g->bitmap_top;
        for (unsigned r = 0; r < bitmap.rows; ++r)
            for (unsigned c = 0; c < bitmap.width; ++c) {
                const unsigned char a = bitmap.buffer[std::ptrdiff_t(r) * bitmap.pitch + c];
                if (a) image.blend(left + int(c), top + int(r), color, a / 255.0);
            }
    });
    return int((width + 63) >> 6);
}

FontResult findFont(const FontOptions& options)
{
    FontResult result;
    std::string asked = options.file;
    if (asked.empty())
        if (const char* env = std::getenv("MSII_FONT"); env && *env) asked = env;
    if (!asked.empty()) {
        result.typeface = Typeface::load(asked);
        return result;
    }
    const std::string matched = fontconfigMatch();
    if (!matched.empty()) {
        try {
            result.typeface = Typeface::load(matched);
            return result;
        } catch (const IOError&) {
            // fall through to the built-in font
        }
    }
    result.warning = "no font found (install fonts-dejavu-core, or name a TrueType file in MSII_FONT); "
                     "labels use the built-in pixel font";
    return result;
}

int labelLineHeight(int pictureHeight)
{
    return std::clamp(int(std::lround(pictureHeight / 40.0)), 14, 48);
}

} // namespace msii
