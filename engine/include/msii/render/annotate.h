#pragma once
/// @file annotate.h
/// @brief Figure furniture: a colour bar with tick labels and a scale bar in mesh units,
/// added around a picture (the picture's pixels are not covered).

#include <msii/render/colormap.h>
#include <msii/render/image.h>
#include <msii/render/typeface.h>

#include <string>
#include <vector>

namespace msii {

struct FigureOptions {
    bool colorBar = true;
    ColorMapKind colorMap = ColorMapKind::Viridis;
    ValueRange range;              ///< values at the bottom and top of the colour bar
    std::string label;             ///< written above the colour bar (e.g. "V_16"), may be empty
    std::vector<double> isolines;  ///< levels marked on the colour bar as black ticks
    bool scaleBar = true;
    double pixelSize = 0;          ///< mesh units per picture pixel; <= 0: no scale bar
    std::string units = "mm";      ///< written after the scale bar's length
    int fontScale = 2;             ///< font pixel size (the 5×7 font), >= 1
    /// The labels' typeface (render/typeface.h); null: the built-in 5×7 font at fontScale.
    /// With a typeface, labels are lineHeight pixels high and the bars, ticks and margins
    /// are scaled to match (fontScale is then lineHeight / 9).
    const Typeface* typeface = nullptr;
    int lineHeight = 18;           ///< with a typeface: label line height in pixels, >= 6
};

/// Returns a new image: @p picture with a margin at the right holding the colour bar (height
/// about 60 % of the picture, at least 100 pixels, with 5 "nice" tick values and labels) and a
/// margin at the bottom holding the scale bar (length a nice value 1, 2 or 5 × 10^k mesh units
/// covering about 1/5 of the width, labelled e.g. "2 mm"). White background, black text.
/// The picture is copied unchanged to the top-left corner (offset (0, 0)); the colour bar's
/// top row is colorAt(1), its bottom row colorAt(0), framed by a 1-pixel black line.
/// @throw InvalidInputError for an empty picture, fontScale < 1, a colour bar without a
/// finite range lo < hi, or a non-finite pixelSize.
RgbImage composeFigure(const RgbImage& picture, const FigureOptions& options);

/// The scale bar's length for a picture @p pictureWidth pixels wide at @p pixelSize mesh
/// units per pixel: the nice value (1, 2 or 5 × 10^k) closest to a fifth of the width.
double scaleBarLength(int pictureWidth, double pixelSize);

/// Nice tick values (1, 2, 2.5 or 5 × 10^k steps) covering [lo, hi], about @p count of them.
/// @throw InvalidInputError if lo or hi is not finite or count < 1.
std::vector<double> niceTicks(double lo, double hi, int count = 5);
/// Short label for a value given the tick step (no trailing zeros, e.g. "0.25", "-1e-04").
std::string formatTick(double value, double step);

} // namespace msii
