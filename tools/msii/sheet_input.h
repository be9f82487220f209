#pragma once
// What `msii render` and `msii map` share for figure sheets (--layout
// fat-cross): the orientation the options ask for, the sheet's scale, and the
// record of its views.
#include "map_input.h"

#include <msii/figures/fat_cross.h>
#include <msii/figures/sheet_raster.h>

#include <nlohmann/json.hpp>

#include <string>

namespace msii::tools {

/// --front, --up and --orientation (a sheet's JSON record) as the engine takes
/// them; a record's pixel size goes to @p recordPixelSize (0 when none is
/// read).
/// @throw InvalidInputError naming the option: a direction that is not X,Y,Z of
/// non-zero length, front parallel to up, --orientation with --front or --up,
/// or a record without front and up.
SheetOrientationOptions sheetOrientationOptions(const std::string& front, const std::string& up,
                                                const std::string& orientationFile, double& recordPixelSize);

/// The sheet's scale for --pixels, --pixel-size or --dpi (@p defaultPixels when
/// none is given, or the record's pixel size when there is one).
/// @throw InvalidInputError for --view or --flip, which a sheet does not take,
/// and as frameOptions.
FatCrossOptions sheetScale(const ViewArgs& view, int defaultPixels, double recordPixelSize);

/// A sheet laid out: its layout, its views' pixels and the sides they show.
struct SheetViews {
    FatCrossLayout layout;
    ViewHits views;
    SheetSides sides;
};
/// Lays out the sheet at @p scale, rasterises its views and marks the sides
/// they show.
SheetViews layOutSheet(const TriMesh& mesh, const std::vector<Vec3>& normals, const SheetOrientation& orientation,
                       const FatCrossOptions& scale, RunContext* progress);

/// The views as the record and the EXR header list them: {name, label, scanned,
/// box, to_pixel} each, box = [x0, y0, x1, y1] in pixels.
nlohmann::json sheetViewsRecord(const FatCrossLayout& layout);

/// What a sheet's record says of its orientation and scale: layout, pixel_size,
/// front, up, right, orientation_rule, size and views.
nlohmann::json sheetRecord(const FatCrossLayout& layout, const std::string& units);

}  // namespace msii::tools
