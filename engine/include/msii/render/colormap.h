#pragma once
/// @file colormap.h
/// @brief Perceptual colour maps for false-colour pictures: sequential (viridis, cividis,
/// gray) and diverging (cool-warm after Moreland 2009, interpolated in Msh space), and
/// the mapping of values to [0, 1] by a range or by percentiles.

#include <msii/render/image.h>

#include <string>
#include <vector>

namespace msii {

enum class ColorMapKind {
    Viridis,   ///< sequential, perceptually uniform (matplotlib's default)
    Cividis,   ///< sequential, readable with colour-vision deficiency
    Gray,      ///< sequential, black to white
    CoolWarm,  ///< diverging blue–white–red (Moreland), for values around a centre (e.g. flat = 0)
};

/// "viridis", "cividis", "gray", "coolwarm". @throw InvalidInputError listing the names.
ColorMapKind parseColorMap(const std::string& name);
std::string colorMapName(ColorMapKind kind);
bool isDiverging(ColorMapKind kind);

/// The colour at t in [0, 1] (clamped; NaN gives the map's "no data" grey 128).
Rgb8 colorAt(ColorMapKind kind, double t);

/// How values become t in [0, 1].
struct ValueRange {
    double lo = 0, hi = 1;  ///< t = (value − lo) / (hi − lo), clamped
};

/// The range spanning the given percentiles (0–100) of the finite values; for a diverging
/// map pass @p symmetricAbout (e.g. 0) to make the range symmetric about that value using the
/// larger of the two distances. A constant field gives lo = value − 0.5, hi = value + 0.5.
/// @throw InvalidInputError if there are no finite values or the percentiles are not
/// 0 <= lo < hi <= 100.
ValueRange percentileRange(const std::vector<float>& values, double loPercent, double hiPercent,
                           const double* symmetricAbout = nullptr);

} // namespace msii
