#pragma once
// What `msii map` and `msii render` share: the view and resolution options, and the radii
// and parameters a feature PLY records in its comments.
#include <msii/featuremap/map_frame.h>

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace msii::tools {

struct ViewArgs {
    std::string view = "best";
    bool flip = false;
    int pixels = 0;
    double pixelSize = 0, dpi = 0;
    /// Whether each resolution option was given (a given 0 is an error, not "default").
    CLI::Option *pixelsOption = nullptr, *pixelSizeOption = nullptr, *dpiOption = nullptr;
    CLI::Option* viewOption = nullptr;
};

/// Adds --view, --flip, --pixels, --pixel-size and --dpi to @p cmd.
void addViewOptions(CLI::App* cmd, ViewArgs& args, int defaultPixels);
/// The frame options the arguments ask for (defaultPixels when no resolution is given).
MapFrameOptions frameOptions(const ViewArgs& args, int defaultPixels);

/// The radii r_j = j·R/N of a feature PLY written by `msii compute` ("R=… N=…" in a comment);
/// empty when not found.
std::vector<double> radiiFromComments(const std::vector<std::string>& comments);

/// The units a feature PLY states ("units U" in a comment, written by `msii compute --units
/// U`); empty when it states none.
std::string unitsFromComments(const std::vector<std::string>& comments);

} // namespace msii::tools
