#pragma once
/// @file sheet_raster.h
/// @brief The pixels of a figure sheet (figures/fat_cross.h): each view
/// rasterised in its own frame (featuremap/rasterize.h: hidden surfaces
/// removed, the nearest surface seen), which sides the surface shows, and the
/// views put together on the sheet, so that any per-vertex value can be
/// interpolated at every pixel of the sheet.

#include <msii/core/run_context.h>
#include <msii/featuremap/rasterize.h>
#include <msii/figures/fat_cross.h>

#include <array>
#include <cstdint>
#include <vector>

namespace msii {

/// Each view's pixels in its own frame (SheetView order).
using ViewHits = std::array<PixelHits, kSheetViews>;

/// Rasterises the six views of @p layout, each in its frame. Parallel within
/// each view; the result does not depend on the thread count.
ViewHits rasterizeViews(const TriMesh& mesh, const FatCrossLayout& layout, RunContext* context = nullptr);

/// Which sides of the object the surface shows: a one-sided scan shows one. A
/// closed surface (vector area at most 1 % of its area) shows all six.
/// Otherwise a view shows its side when at least half of its pixels that see
/// the mesh see it facing the viewer (the interpolated vertex normal within 75°
/// of the view's direction): seen from the back, or edge-on (an open tablet's
/// edges), a scan shows little of that.
struct SheetSides {
    std::array<bool, kSheetViews> scanned{true, true, true, true, true, true};  ///< SheetView order
    std::array<double, kSheetViews> facingShare{};  ///< of each view's pixels that see the mesh, those facing
        ///< it
    bool closed = true;
};
/// @p normals: the mesh's vertex normals (mesh/vertex_normals.h).
SheetSides sheetSides(const TriMesh& mesh, const std::vector<Vec3>& normals, const FatCrossLayout& layout,
                      const ViewHits& views);

/// Sets each view's `scanned` from @p sides.
void markScanned(FatCrossLayout& layout, const SheetSides& sides);

struct SheetPixels {
    /// The sheet's pixels: per pixel the triangle its view sees and where; depth
    /// along that view's normal (towards its viewer), as in the view's frame.
    /// Background outside the views' boxes and in blank (not scanned) views.
    PixelHits hits;
    std::vector<std::int8_t> view;  ///< per pixel its view (SheetView), -1 outside every box
};

/// The views' pixels (of frames the size of @p layout's) put in their boxes on
/// the sheet; views not scanned stay blank.
SheetPixels composeSheet(const FatCrossLayout& layout, const ViewHits& views);

/// Per pixel, the interpolated vertex normal (@p normals) in its view's frame:
/// x right, y up on the picture, z towards the viewer (as vertexNormalsInFrame
/// gives for one view); NaN where no view sees the mesh.
std::array<std::vector<float>, 3> sheetNormals(const TriMesh& mesh, const std::vector<Vec3>& normals,
                                               const FatCrossLayout& layout, const SheetPixels& pixels);

}  // namespace msii
