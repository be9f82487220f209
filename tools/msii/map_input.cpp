#include "map_input.h"

#include <msii/core/errors.h>

#include <regex>

namespace msii::tools {

void addViewOptions(CLI::App* cmd, ViewArgs& args, int defaultPixels)
{
    cmd->add_option("--view", args.view,
                    "Projection: best (least-squares plane, default), +x, -x, +y, -y, +z, -z (seen "
                    "from that side) or a direction X,Y,Z from the object towards the viewer");
    cmd->add_flag("--flip", args.flip, "With --view best: look at the other side of the plane");
    cmd->add_option("--pixels", args.pixels,
                    "Longer image side in pixels (default " + std::to_string(defaultPixels) + ")");
    cmd->add_option("--pixel-size", args.pixelSize, "Pixel size in mesh units (instead of --pixels)");
    cmd->add_option("--dpi", args.dpi, "Dots per inch for meshes in mm (instead of --pixels)");
}

MapFrameOptions frameOptions(const ViewArgs& args, int defaultPixels)
{
    MapFrameOptions o;
    parseMapView(args.view, o);
    o.flip = args.flip;
    if (args.pixels < 0) throw InvalidInputError("--pixels must be positive");
    if (args.pixelSize < 0) throw InvalidInputError("--pixel-size must be positive");
    if (args.dpi < 0) throw InvalidInputError("--dpi must be positive");
    o.longerSidePixels = args.pixels;
    o.pixelSize = args.pixelSize;
    o.dpi = args.dpi;
    if (args.pixels == 0 && args.pixelSize == 0 && args.dpi == 0) o.longerSidePixels = defaultPixels;
    return o;
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
