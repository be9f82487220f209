/// `msii map INPUT.ply`: an OpenEXR feature map of the mesh seen orthographically:
/// height over the plane, normal, mask and every vertex property, with the frame in the header.
#include "commands.h"
#include "feature_input.h"
#include "map_input.h"

#include <msii/core/terminal_progress.h>
#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/featuremap/feature_map.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

namespace msii::tools {

namespace {

struct MapArgs : CommonArgs {
    std::string input, output;
    std::vector<std::string> matFiles;
    ViewArgs view;
    std::string properties;  // empty: all
    std::string compression = "piz";
    bool half = false;
    std::string units;  // empty: what the PLY states, else mm
};

constexpr int kDefaultPixels = 2048;

int runMap(const MapArgs& args)
{
    const Stopwatch total;
    MapFrameOptions frameOpts = frameOptions(args.view, kDefaultPixels);
    FeatureMapOptions options;
    options.compression = parseExrCompression(args.compression);
    options.half = args.half;
    options.units = args.units;
    const std::string output = outputPath(args.input, args.output, "map", args.overwrite, ".exr");
    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);
    if (in.cellSize > 0) {  // a raster: seen from above, a pixel per cell unless asked otherwise
        if (!args.view.viewOption || args.view.viewOption->count() == 0) parseMapView("+z", frameOpts);
        const auto given = [](const CLI::Option* o) { return o && o->count() > 0; };
        if (!given(args.view.pixelsOption) && !given(args.view.pixelSizeOption) && !given(args.view.dpiOption))
            frameOpts.longerSidePixels = 0, frameOpts.pixelSize = in.cellSize;
        frameOpts.margin = 0.5 * in.cellSize;  // the cells around their centres
    }
    if (options.units.empty()) options.units = unitsFromComments(in.comments);
    if (options.units.empty()) options.units = "mm";

    std::vector<VertexProperty> chosen;
    if (args.properties.empty()) chosen = std::move(in.properties);
    else
        for (std::size_t k : findProperties(in, args.properties)) chosen.push_back(in.properties[k]);
    // Names the map reserves for its own channels.
    for (VertexProperty& p : chosen)
        if (p.name == "height" || p.name == "mask" || p.name.rfind("normal.", 0) == 0) p.name = "input." + p.name;

    const MapFrame frame = makeMapFrame(in.mesh, frameOpts);
    options.source = std::filesystem::absolute(args.input).string();
    options.radii = radiiFromComments(in.comments);
    std::string params;
    for (const std::string& c : in.comments) params += (params.empty() ? "" : "\n") + c;
    options.parameters = std::string("msii ") + versionString() + " map --view " + args.view.view + (params.empty() ? "" : "\n" + params);
    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    const FeatureMapInfo info = writeFeatureMap(output, in.mesh, frame, chosen, options, &progress);
    if (!args.quiet)
        std::fprintf(stderr,
                     "msii: %s -> %s (%d x %d pixels of %.4g %s, %zu channels, %.1f %% covered; "
                     "raster %.1f s, write %.1f s, total %.1f s)\n",
                     args.input.c_str(), output.c_str(), frame.width, frame.height, frame.pixelSize,
                     options.units.c_str(), info.channels.size(),
                     100.0 * double(info.coveredPixels) / (double(frame.width) * frame.height),
                     info.rasterSeconds, info.writeSeconds, total.seconds());
    return 0;
}

} // namespace

std::function<int()> addMapCommand(CLI::App& app)
{
    auto args = std::make_shared<MapArgs>();
    CLI::App* cmd = app.add_subcommand(
        "map", "OpenEXR feature map: the mesh projected orthographically onto its best-fit plane or "
               "a chosen view; channels height, normal.x/y/z, mask and every vertex property "
               "(quality, V_01 ...), 32-bit float (or half), lossless compression; the frame is in "
               "the header.");
    cmd->add_option("input", args->input,
                    "Mesh or feature PLY (e.g. from msii compute), or a GeoTIFF from msii compute on a DEM "
                    "(one pixel per cell)")
        ->required();
    cmd->add_option("-o,--output", args->output, "Output EXR (default <input stem>.map.exr)");
    cmd->add_option("--mat", args->matFiles, "GigaMesh feature file(s) for the input mesh");
    addViewOptions(cmd, args->view, kDefaultPixels);
    cmd->add_option("--properties", args->properties,
                    "Vertex properties to map, comma-separated (default: all)");
    cmd->add_option("--compression", args->compression, "piz (default: the smallest files of feature data), zip, zips, rle or none (about 5 times faster than piz, twice the size); all lossless");
    cmd->add_flag("--half", args->half, "16-bit half channels instead of 32-bit float");
    cmd->add_option("--units", args->units, "Units of the mesh, for the header (default: what the PLY states, else mm)");
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runMap(*args);
    };
}

} // namespace msii::tools
