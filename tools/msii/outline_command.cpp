/// `msii outline INPUT.ply --levels …`: isolines of a per-vertex value as SVG outlines in
/// the map plane, for tracing and drawing.
#include "commands.h"
#include "feature_input.h"
#include "map_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/outline/isolines.h>
#include <msii/render/colormap.h>

#include <cstdio>
#include <memory>

namespace msii::tools {

namespace {

struct OutlineArgs : CommonArgs {
    std::string input, output;
    std::vector<std::string> matFiles;
    std::string property = "quality";
    std::string levels, percentiles = "1,99";
    int count = 0;
    ViewArgs view;
    std::string units = "mm";
};

int runOutline(const OutlineArgs& args)
{
    const Stopwatch total;
    std::vector<double> levels;
    if (!args.levels.empty()) levels = parseNumberList(args.levels, "--levels");
    if (args.count < 0) throw InvalidInputError("--count must be 0 or more");
    if (levels.empty() && args.count == 0) throw InvalidInputError("give --levels or --count");
    const MapFrameOptions frameOpts = frameOptions(args.view, 1024);
    const std::string output = outputPath(args.input, args.output, "outline", args.overwrite, ".svg");
    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);
    const VertexProperty& f = in.properties[findProperty(in, args.property)];
    if (args.count > 0) {
        const std::vector<double> p = parseNumberList(args.percentiles, "--percentiles");
        if (p.size() != 2) throw InvalidInputError("--percentiles takes LOW,HIGH");
        const ValueRange r = percentileRange(f.values, p[0], p[1]);
        for (double l : evenLevels(r.lo, r.hi, args.count)) levels.push_back(l);
    }
    const MapFrame frame = makeMapFrame(in.mesh, frameOpts);
    const std::vector<Polyline> lines = computeIsolines(in.mesh, f.values, levels);
    std::vector<Polyline2> flat;
    flat.reserve(lines.size());
    for (const Polyline& l : lines) {
        Polyline2 p{l.level, l.closed, {}};
        p.points.reserve(l.points.size());
        for (const Vec3& q : l.points) {
            const Vec3 m = frame.toMap(q);
            p.points.push_back({m.x, m.y});
        }
        flat.push_back(std::move(p));
    }
    SvgOptions svg;
    svg.minX = frame.minU;
    svg.width = frame.width * frame.pixelSize;
    svg.height = frame.height * frame.pixelSize;
    svg.minY = frame.maxV - svg.height;
    svg.units = args.units;
    writeSvg(output, flat, svg);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%zu lines at %zu levels, %.1f s)\n", args.input.c_str(),
                     output.c_str(), flat.size(), levels.size(), total.seconds());
    return 0;
}

} // namespace

std::function<int()> addOutlineCommand(CLI::App& app)
{
    auto args = std::make_shared<OutlineArgs>();
    CLI::App* cmd = app.add_subcommand(
        "outline", "Isolines of a per-vertex value as SVG outlines in the map plane (mesh units), one "
                   "path per line, for tracing and drawings.");
    cmd->add_option("input", args->input, "PLY with per-vertex values")->required();
    cmd->add_option("-o,--output", args->output, "Output SVG (default <input stem>.outline.svg)");
    cmd->add_option("--mat", args->matFiles, "GigaMesh feature file(s) for the input mesh");
    cmd->add_option("--property", args->property, "Vertex property (default quality)");
    cmd->add_option("--levels", args->levels, "Isoline values, comma-separated");
    cmd->add_option("--count", args->count, "Or: this many levels evenly inside the --percentiles range");
    cmd->add_option("--percentiles", args->percentiles, "Range for --count (default 1,99)");
    cmd->add_option("--view", args->view.view, "Projection as for msii map (default best)");
    cmd->add_flag("--flip", args->view.flip, "With --view best: the other side");
    cmd->add_option("--units", args->units, "Units of the mesh for the SVG size (default mm)");
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runOutline(*args);
    };
}

} // namespace msii::tools
