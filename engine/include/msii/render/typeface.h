#pragma once
/// @file typeface.h
/// @brief Text for the pictures' labels (colour-bar ticks, scale bar, titles) in a real
/// typeface, anti-aliased (FreeType), or in the built-in 5×7 pixel font (render/image.h)
/// when no font file is found.
///
/// Which font: FontOptions::file if given, else the environment variable MSII_FONT, else
/// what fontconfig matches for "DejaVu Sans" (Debian's fonts-dejavu-core; fontconfig
/// substitutes another sans-serif face where DejaVu is missing). A file that cannot be read
/// is an error when it was asked for (file or MSII_FONT); when fontconfig finds nothing
/// the built-in font is used with a warning, since a picture with crude labels is better
/// than no picture.

#include <msii/render/image.h>

#include <memory>
#include <string>

namespace msii {

struct FontOptions {
    std::string file;  ///< a TrueType/OpenType file; empty: MSII_FONT, then fontconfig
};

/// A loaded face, or the built-in pixel font (isBuiltIn()). Sizes are the line height in
/// pixels: ascender to descender, the room a line of labels takes. Not for concurrent use
/// from several threads (FreeType faces are not).
class Typeface {
public:
    Typeface();  ///< the built-in pixel font
    ~Typeface();
    Typeface(const Typeface&) = delete;
    Typeface& operator=(const Typeface&) = delete;
    Typeface(Typeface&&) noexcept;
    Typeface& operator=(Typeface&&) noexcept;

    /// Loads @p file. @throw IOError if FreeType cannot read it as a font.
    static Typeface load(const std::string& file);

    bool isBuiltIn() const { return !mFace; }
    const std::string& file() const { return mFile; }  ///< empty for the built-in font

    /// Width in pixels of @p text (UTF-8) set in lines @p lineHeight pixels high.
    int textWidth(const std::string& text, int lineHeight) const;
    /// Draws @p text with its line box's top-left at (x, y), blending its coverage over the
    /// pixels (anti-aliased); returns the width drawn.
    int drawText(RgbImage& image, int x, int y, const std::string& text, Rgb8 color, int lineHeight) const;

private:
    struct Face;
    std::unique_ptr<Face> mFace;
    std::string mFile;
};

struct FontResult {
    Typeface typeface;    ///< the built-in font if none was found
    std::string warning;  ///< one sentence when falling back to the built-in font, else empty
};

/// Finds and loads the labels' typeface (file comment). @throw IOError if the file asked
/// for (options or MSII_FONT) cannot be loaded.
FontResult findFont(const FontOptions& options = {});

/// The line height of labels for a picture @p pictureHeight pixels high: about 1/40 of it,
/// at least 14 and at most 48 pixels, so labels stay readable on small pictures and do not
/// dominate large ones.
int labelLineHeight(int pictureHeight);

} // namespace msii
