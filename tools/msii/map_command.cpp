/// `msii map INPUT.ply`: an OpenEXR feature map of the mesh seen orthographically:
/// height over the plane, normal, mask and every vertex property, with the frame in the header.
#include "commands.h"
#include "feature_input.h"
#include "map_input.h"
#include "sheet_input.h"

#include <msii/core/terminal_progress.h>
#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/featuremap/feature_map.h>
#include <msii/mesh/vertex_normals.h>

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
    std::string layout;                   // "fat-cross": the six views on one sheet
    std::string front, up, orientationFile;  // the sheet's orientation (sheet_input.h)
};

constexpr int kDefaultPixels = 2048;

/// The properties --properties chooses (all by default), renamed where the map reserves
/// their names for its own channels.
std::vector<VertexProperty> chosenProperties(const MapArgs& args, FeatureMesh& in)
{
    std::vector<VertexProperty> chosen;
    if (args.properties.empty()) chosen = std::move(in.properties);
    else
        for (std::size_t k : findProperties(in, args.properties)) chosen.push_back(in.properties[k]);
    for (VertexProperty& p : chosen)
        if (p.name == "height" || p.name == "mask" || p.name.rfind("normal.", 0) == 0) p.name = "input." + p.name;
    return chosen;
}

/// The header's record of the input: source, radii and msii's parameters.
void describeInput(const MapArgs& args, const FeatureMesh& in, const std::string& how, FeatureMapOptions& options)
{
    options.source = std::filesystem::absolute(args.input).string();
    options.radii = radiiFromComments(in.comments);
    std::string params;
    for (const std::string& c : in.comments) params += (params.empty() ? "" : "\n") + c;
    options.parameters = std::string("msii ") + versionString() + " map " + how + (params.empty() ? "" : "\n" + params);
}

/// `--layout fat-cross`: the six views on one sheet (figures/fat_cross.h), their frames in the
/// header's msii:views.
int runMapSheet(const MapArgs& args, FeatureMapOptions& options)
{
    const Stopwatch total;
    double recordPixelSize = 0;
    const SheetOrientationOptions orient = sheetOrientationOptions(args.front, args.up, args.orientationFile, recordPixelSize);
    const FatCrossOptions scale = sheetScale(args.view, kDefaultPixels, recordPixelSize);
    const std::string output = outputPath(args.input, args.output, "sheet", args.overwrite, ".exr");
    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);
    if (in.cellSize > 0) throw InvalidInputError("a sheet of six views needs a mesh (PLY, OBJ, OFF or STL), not a raster");
    if (options.units.empty()) options.units = unitsFromComments(in.comments);
    if (options.units.empty()) options.units = "mm";
    const std::vector<VertexProperty> chosen = chosenProperties(args, in);
    describeInput(args, in, "--layout fat-cross", options);

    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    const SheetOrientation orientation = orientSheet(in.mesh, orient);
    const SheetViews views = layOutSheet(in.mesh, vertexNormals(in.mesh), orientation, scale, &progress);
    const SheetPixels pixels = composeSheet(views.layout, views.views);
    FeatureSheet sheet;
    sheet.hits = &pixels.hits;
    sheet.view = &pixels.view;
    for (const SheetViewBox& box : views.layout.views) sheet.frames.push_back(box.frame);
    sheet.pixelSize = views.layout.pixelSize;
    sheet.attributes = {{"msii:layout", "fat-cross"}, {"msii:views", sheetRecord(views.layout, options.units).dump()}};
    const FeatureMapInfo info = writeFeatureSheet(output, in.mesh, sheet, chosen, options, &progress);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (a sheet of %d x %d pixels of %.4g %s, %zu channels; total %.1f s)\n",
                     args.input.c_str(), output.c_str(), views.layout.width, views.layout.height,
                     views.layout.pixelSize, options.units.c_str(), info.channels.size(), total.seconds());
    return 0;
}

int runMap(const MapArgs& args)
{
    const Stopwatch total;
    FeatureMapOptions options;
    options.compression = parseExrCompression(args.compression);
    options.half = args.half;
    options.units = args.units;
    if (!args.layout.empty()) return runMapSheet(args, options);
    if (!args.front.empty() || !args.up.empty() || !args.orientationFile.empty())
        throw InvalidInputError("--front, --up and --orientation orient a sheet: they need --layout fat-cross");
    MapFrameOptions frameOpts = frameOptions(args.view, kDefaultPixels);
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

    const std::vector<VertexProperty> chosen = chosenProperties(args, in);

    const MapFrame frame = makeMapFrame(in.mesh, frameOpts);
    describeInput(args, in, "--view " + args.view.view, options);
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
    cmd->add_option("-o,--output", args->output,
                    "Output EXR (default <input stem>.map.exr; with --layout: <input stem>.sheet.exr)");
    cmd->add_option("--mat", args->matFiles, "GigaMesh feature file(s) for the input mesh");
    addViewOptions(cmd, args->view, kDefaultPixels);
    cmd->add_option("--properties", args->properties,
                    "Vertex properties to map, comma-separated (default: all)");
    cmd->add_option("--compression", args->compression, "piz (default: the smallest files of feature data), zip, zips, rle or none (about 5 times faster than piz, twice the size); all lossless");
    cmd->add_flag("--half", args->half, "16-bit half channels instead of 32-bit float");
    cmd->add_option("--units", args->units, "Units of the mesh, for the header (default: what the PLY states, else mm)");
    cmd->add_option("--layout", args->layout,
                    "fat-cross: the six views on one sheet as msii render --layout fat-cross lays them out, every "
                    "channel; the views' boxes and matrices in the header's msii:views (docs/figures.md)")
        ->check(CLI::IsMember({"fat-cross"}));
    cmd->add_option("--front", args->front, "With --layout: the direction X,Y,Z towards a viewer of the obverse");
    cmd->add_option("--up", args->up, "With --layout: the direction X,Y,Z that is up on the obverse");
    cmd->add_option("--orientation", args->orientationFile, "With --layout: front and up from a sheet's JSON record");
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runMap(*args);
    };
}

} // namespace msii::tools
