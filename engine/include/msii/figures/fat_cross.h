#pragma once
/// @file fat_cross.h
/// @brief The "fat cross": the six orthographic views of an object on one
/// sheet, at one scale, laid out as cuneiformists publish tablets
/// (docs/figures.md):
///
///                 top
///         left  obverse  right
///                bottom
///                reverse
///
/// the obverse in the centre, the four edges folded out around it (each turned
/// as if folded out from the obverse, so that the edge it shares with the
/// obverse faces it), and the reverse below the bottom edge, turned about the
/// horizontal axis as a tablet is turned to be read on (its top is the tablet's
/// bottom, next to the bottom edge). Views are separated by a small gap and may
/// have a caption (the top edge's above it, the others' below).

#include <msii/featuremap/map_frame.h>
#include <msii/figures/sheet_orientation.h>
#include <msii/mesh/trimesh.h>

#include <array>
#include <string>

namespace msii {

enum class SheetView { Obverse, Reverse, Top, Bottom, Left, Right };
constexpr int kSheetViews = 6;

/// "obverse", "reverse", "top", "bottom", "left", "right".
const char* sheetViewName(SheetView view);
/// The conventional caption: "obv.", "rev.", "t.e.", "b.e.", "l.e.", "r.e.".
const char* sheetViewLabel(SheetView view);

struct FatCrossOptions {
    /// The scale, one of: the sheet's longer side in pixels (the views, gaps and
    /// captions), the pixel size in mesh units, or dots per inch for meshes in
    /// millimetres (25.4 / dpi).
    int longerSidePixels = 0;
    double pixelSize = 0;
    double dpi = 0;
    double gap = 0.04;  ///< between views, a share of the obverse's longer side
        ///< (at least 2 pixels)
    /// Captions: their line height in pixels (0: none) and each view's caption
    /// width (SheetView order; 0: that view has none). Columns widen to hold
    /// them.
    int captionHeight = 0;
    std::array<int, kSheetViews> captionWidth{};
    int maxSidePixels = 16384;  ///< largest allowed side of the sheet
};

/// A 3 × 4 matrix A: [column, row, depth]ᵀ = A · [x, y, z, 1]ᵀ for a point of
/// the input (column and row in the sheet's pixels, pixel (i, j) covering [i,
/// i+1) × [j, j+1); depth along the view's direction towards its viewer, in
/// mesh units from the centroid).
using ToPixel = std::array<std::array<double, 4>, 3>;

struct SheetViewBox {
    SheetView view = SheetView::Obverse;
    /// The view's orthographic frame (featuremap/map_frame.h): its pixel (x, y)
    /// is the sheet's pixel (x0 + x, y0 + y); its normal points towards the
    /// view's viewer.
    MapFrame frame;
    int x0 = 0, y0 = 0;
    bool scanned = true;  ///< false: the view stays blank ("not scanned",
        ///< figures/sheet_raster.h)
    int captionX = 0, captionY = 0;  ///< the caption's top centre (when captioned)
    ToPixel toPixel() const;
    /// [column, row, depth] of @p p (the input's coordinates) through toPixel().
    Vec3 project(const Vec3& p) const;
};

struct FatCrossLayout {
    SheetOrientation orientation;
    double pixelSize = 0;  ///< mesh units per pixel
    int width = 0, height = 0;  ///< the sheet, pixels
    int captionHeight = 0;  ///< as FatCrossOptions::captionHeight
    Vec3 size;  ///< the object's extent along right, up and front (mesh units)
    std::array<SheetViewBox, kSheetViews> views;  ///< in SheetView order
};

/// Lays out the six views of @p mesh, oriented by @p orientation, at the scale
/// of @p options (with --pixels, the largest scale whose sheet fits).
/// @throw InvalidInputError for an empty mesh or one without area, a scale not
/// given exactly once or not positive, or a sheet larger than maxSidePixels.
FatCrossLayout layoutFatCross(const TriMesh& mesh, const SheetOrientation& orientation, const FatCrossOptions& options);

}  // namespace msii
