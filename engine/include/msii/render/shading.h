#pragma once
/// @file shading.h
/// @brief Virtual illumination of a normal map: shaded relief with an adjustable light, and
/// a high-contrast mode that makes shallow strokes visible.

#include <vector>

namespace msii {

struct ShadingOptions {
    double azimuthDeg = 315;   ///< light direction in the picture plane, degrees counter-clockwise from +x (right); 315 = from the top left
    double elevationDeg = 45;  ///< light elevation above the picture plane, degrees (0, 90]
    double ambient = 0.15;     ///< brightness of surfaces facing away from the light, in [0, 1)
    /// High contrast: shade the normal's deviation from its local mean (a box of
    /// contrastRadius pixels) instead of the normal itself, then stretch the 1st–99th percentile
    /// to the full range, so that strokes a few micrometres deep on a curved tablet show up.
    bool highContrast = false;
    int contrastRadius = 16;   ///< pixels, >= 1
};

/// Brightness in [0, 1] per pixel (row-major, width × height, row 0 at the top), from unit
/// normals nx, ny, nz in the picture frame (x right, y up on the picture, z towards the viewer).
/// The azimuth is the direction the light travels, so the unit vector towards the light is
/// l = (−cos az · cos el, −sin az · cos el, sin el) and brightness = ambient + (1 − ambient) ·
/// max(0, n·l). Pixels with mask == 0 get NaN. @throw InvalidInputError for sizes that do
/// not match or options out of range.
std::vector<float> shadeRelief(int width, int height, const std::vector<float>& nx,
                               const std::vector<float>& ny, const std::vector<float>& nz,
                               const std::vector<float>& mask, const ShadingOptions& options);

} // namespace msii
