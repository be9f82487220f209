#include "map_input.h"

#include <msii/core/errors.h>

#include <cmath>
#include <regex>

namespace msii::tools {

void addViewOptions(CLI::App* cmd, ViewArgs& args, int defaultPixels)
{
    args.viewOption = cmd->add_option("--view", args.view,
                    "Projection: best (least-squares plane, default), +x, -x, +y, -y, +z, -z (seen "
                    "from that side) or a direction X,Y,Z from the object towards the viewer");
    cmd->add_flag("--flip", args.flip, "With --view best: look at the other side of the plane");
    args.pixelsOption = cmd->add_option("--pixels", args.pixels,
                    "Longer image side in pixels (default " + std::to_string(defaultPixels) + ")");
    args.pixelSizeOption = cmd->add_option("--pixel-size", args.pixelSize, "Pixel size in mesh units (instead of --pixels)");
    args.dpiOption = cmd->add_option("--dpi", args.dpi, "Dots per inch for meshes in mm (instead of --pixels)");
}

MapFrameOptions frameOptions(const ViewArgs& args, int defaultPixels)
{
    MapFrameOptions o;
    parseMapView(args.view, o);
    o.flip = args.flip;
    const auto given = [](const CLI::Option* option) { return option && option->count() > 0; };
    const int count = given(args.pixelsOption) + given(args.pixelSizeOption) + given(args.dpiOption);
    if (count > 1) throw InvalidInputError("give only one of --pixels, --pixel-size and --dpi");
    if (given(args.pixelsOption) && args.pixels <= 0)
        throw InvalidInputError("--pixels must be positive, not " + std::to_string(args.pixels));
    if (given(args.pixelSizeOption) && !(args.pixelSize > 0 && std::isfinite(args.pixelSize)))
        throw InvalidInputError("--pixel-size must be a positive number");
    if (given(args.dpiOption) && !(args.dpi > 0 && std::isfinite(args.dpi)))
        throw InvalidInputError("--dpi must be a positive number");
    o.longerSidePixels = given(args.pixelsOption) ? args.pixels : 0;
    o.pixelSize = given(args.pixelSizeOption) ? args.pixelSize : 0;
    o.dpi = given(args.dpiOption) ? args.dpi : 0;
    if (count == 0) o.longerSidePixels = defaultPixels;
    return o;
}

std::string unitsFromComments(const std::vector<std::string>& comments)
{
    for (const std::string& c : comments)
        if (c.rfind("units ", 0) == 0 && c.size() > 6) return c.substr(6);
    return "";
}

std::vector<double> radiiFromComments(const std::vector<std::string>& comments)
{
    static const std::regex pattern(R"(msii .* compute.* R=([0-9.eE+-]+) N=([0-9]+))");
    for (const std::string& c : comments) {
        std::smatch m;
        if (!std::regex_search(c, m, pattern)) continue;
        try {
            const double R = std::stod(m[1].str());
            const int n = std::stoi(m[2].str());
            if (!(R > 0) || n < 1 || n > 4096) continue;
            std::vector<double> radii;
            for (int j = 1; j <= n; ++j) radii.push_back(R * j / n);
            return radii;
        } catch (const std::exception&) {
        }
    }
    return {};
}

} // namespace msii::tools
