#pragma once
/// @file picture.h
/// @brief A false-colour or shaded-relief picture of map channels (from a feature map or a
/// rasterised mesh): colour of a value with a perceptual map, isolines drawn over it, virtual
/// illumination, or both (colour modulated by the shading).

#include <msii/render/colormap.h>
#include <msii/render/image.h>
#include <msii/render/shading.h>

#include <vector>

namespace msii {

/// Channels of one picture, row-major, row 0 at the top (as in feature maps). Pointers that
/// a picture does not need may be null.
struct PictureChannels {
    int width = 0, height = 0;
    const std::vector<float>* value = nullptr;  ///< the field to colour (e.g. quality, V_16 or height)
    const std::vector<float>* nx = nullptr;     ///< unit normal in the map frame, for shading
    const std::vector<float>* ny = nullptr;
    const std::vector<float>* nz = nullptr;
    const std::vector<float>* mask = nullptr;   ///< > 0.5 = the pixel sees the mesh
};

struct PictureOptions {
    bool colour = true;               ///< colour the value; false: shaded relief only (grey)
    bool shade = false;               ///< modulate by the shaded relief (with colour) or show it (without)
    ColorMapKind colorMap = ColorMapKind::Viridis;
    bool fixedRange = false;          ///< use `range`; else the percentiles below
    ValueRange range;
    double loPercentile = 1, hiPercentile = 99;
    bool centered = false;            ///< make the range symmetric about `center` (diverging maps)
    double center = 0;
    std::vector<double> isolineLevels;  ///< drawn as black lines (marching squares on the pixels)
    int isolineCount = 0;             ///< > 0: this many levels evenly inside the range (added to the above)
    /// Isolines around a region (above or below a level) of fewer pixels than this are left
    /// out: a scan's noise makes specks of a few pixels wherever the surface lies near a
    /// level, which read as dust, not as contours (cartography's minimum area). 0 draws all.
    int isolineMinPixels = 16;
    ShadingOptions shading;
    double shadeStrength = 0.6;       ///< with colour: colour × (1 − s + s·shade)
    Rgb8 background{255, 255, 255};
};

struct PictureResult {
    RgbImage image;
    ValueRange range;                  ///< the colour range used
    std::vector<double> isolineLevels; ///< all levels drawn
};

/// @throw InvalidInputError if a needed channel is missing or has the wrong size, the
/// options are out of range, or the value has no finite pixel.
PictureResult renderPicture(const PictureChannels& channels, const PictureOptions& options);

} // namespace msii
