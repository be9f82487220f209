#pragma once
// What `msii render` and its figure sheets (render_sheet.cpp) share: the
// arguments, and the picture's options and labels' font as the arguments ask
// for them.
#include "commands.h"
#include "map_input.h"

#include <msii/render/annotate.h>
#include <msii/render/picture.h>
#include <msii/render/typeface.h>

#include <string>
#include <vector>

namespace msii::tools {

struct RenderArgs : CommonArgs {
    std::vector<std::string> inputs;
    std::string output, outputDir;
    std::vector<std::string> matFiles;
    ViewArgs view;
    std::string show;  // a property/channel, "relief" or "height"; empty: quality,
        // else relief
    std::string colorMap;
    std::string range, percentiles = "1,99";
    double center = 0;
    CLI::Option* centerOption = nullptr;
    int isolines = 0;
    std::string levels;
    std::string light = "315,45";
    bool highContrast = false;
    int contrastRadius = 16;
    bool shade = false;
    double shadeStrength = 0.6;
    bool noColorBar = false, noScaleBar = false;
    std::string units;
    std::string font;  // --font: a TrueType/OpenType file; empty: MSII_FONT, then
        // fontconfig
    // Figure sheets (--layout fat-cross, render_sheet.cpp)
    std::string layout;  // empty: one view; "fat-cross": the six views on one sheet
    bool labels = false;  // --labels: obv., rev., t.e., b.e., l.e., r.e.
    std::string front, up;  // --front, --up: X,Y,Z
    std::string orientationFile;  // --orientation: a sheet's JSON record
    bool viewsSeparately = false;  // --views-separately: each view also as its own PNG
};

constexpr int kDefaultPixels = 2048;

/// The picture's options the arguments ask for (colours, range, isolines,
/// light, shading).
/// @throw InvalidInputError naming the option.
PictureOptions pictureOptionsOf(const RenderArgs& args);

/// The value shown (empty for the relief) for --show, given whether the input
/// has quality; sets @p options' colour and shading to match.
/// @throw InvalidInputError for value options with --show relief.
std::string shownValue(const RenderArgs& args, bool hasQuality, PictureOptions& options);

/// The labels' typeface for --font, with its warning printed unless --quiet.
FontResult labelsFont(const RenderArgs& args);
/// Sets @p figure's labels in @p font at the size for a picture @p
/// pictureHeight high.
void setLabelsFont(FigureOptions& figure, const FontResult& font, int pictureHeight);

/// `msii render INPUT… --layout fat-cross`: one sheet of six views per input
/// (render_sheet.cpp).
int runSheets(const RenderArgs& args);

}  // namespace msii::tools
