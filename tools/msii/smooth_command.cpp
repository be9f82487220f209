/// `msii smooth INPUT.ply [--filter mean|median] [--iterations 30]`: fast 1-ring smoothing
/// (paper §3.2) of `quality`, of chosen properties, or of every feature element.
#include "commands.h"
#include "feature_input.h"

#include <msii/core/terminal_progress.h>
#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/io/write_ply.h>
#include <msii/smoothing/ring_smoothing.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

namespace msii::tools {

namespace {

struct SmoothArgs : CommonArgs {
    std::string input, output;
    std::vector<std::string> matFiles;
    std::string filter = "mean";
    int iterations = 30;
    std::string delta = "global";
    std::string weights = "balanced";
    std::string border = "ring";
    std::string properties = "quality";
    bool allFeatures = false;
};

SmoothingOptions smoothingOptions(const SmoothArgs& args)
{
    SmoothingOptions o;
    if (args.iterations < 0)
        throw InvalidInputError("--iterations must be 0 or more, not " + std::to_string(args.iterations));
    o.iterations = args.iterations;
    if (args.filter == "mean") o.filter = SmoothingFilter::Mean;
    else if (args.filter == "median") o.filter = SmoothingFilter::Median;
    else throw InvalidInputError("unknown --filter '" + args.filter + "' (use mean or median)");
    if (args.delta == "global") o.radius = RingRadius::Global;
    else if (args.delta == "ring") o.radius = RingRadius::Ring;
    else throw InvalidInputError("unknown --delta '" + args.delta + "' (use global or ring)");
    if (args.weights == "balanced") o.weights = RingWeights::Balanced;
    else if (args.weights == "area") o.weights = RingWeights::IsoscelesArea;
    else throw InvalidInputError("unknown --weights '" + args.weights + "' (use balanced or area)");
    if (args.border == "ring") o.border = BorderMode::OpenRing;
    else if (args.border == "keep") o.border = BorderMode::Keep;
    else throw InvalidInputError("unknown --border '" + args.border + "' (use ring or keep)");
    return o;
}


int runSmooth(const SmoothArgs& args)
{
    const Stopwatch total;
    const SmoothingOptions options = smoothingOptions(args);
    const std::string output = outputPath(args.input, args.output, "smooth", args.overwrite,
                                          featureOutputExtension(args.input, args.output));
    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);

    // Which properties: --all-features (every V_/S_/P_/L_ element and quality), else the list.
    std::vector<std::size_t> chosen;
    if (args.allFeatures) {
        for (std::size_t k = 0; k < in.properties.size(); ++k)
            if (isFeatureName(in.properties[k].name) || in.properties[k].name == "quality") chosen.push_back(k);
        if (chosen.empty()) throw InvalidInputError("the input has no features (V_01 ...) and no quality to smooth");
    } else {
        chosen = findProperties(in, args.properties);
    }

    RingSmoother smoother(in.mesh, options);
    const SmoothingInfo& info = smoother.info();
    if (!args.quiet && options.radius == RingRadius::Global && info.globalDeltaTooSmall && options.iterations > 0)
        std::fprintf(stderr,
                     "msii: warning: the shortest edge (%.3g) is below a tenth of the median edge "
                     "(%.3g), so with --delta global (the paper's choice) the filter hardly changes "
                     "anything; --delta ring uses each ring's own shortest edge\n",
                     info.globalDelta, info.medianEdge);
    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    for (std::size_t k : chosen) smoother.smooth(in.properties[k].values, &progress);

    std::ostringstream comment;
    comment << "msii " << versionString() << " smooth --filter " << args.filter << " --iterations "
            << args.iterations << " --delta " << args.delta << " (delta " << info.globalDelta
            << ") --weights " << args.weights << " --border " << args.border;
    if (std::filesystem::path(output).extension() == ".tif") {
        // On the raster's grid: the smoothed bands, float32 (smoothed values fall between the
        // 16-bit steps of msii compute's fractions).
        std::vector<const VertexProperty*> bands;
        for (std::size_t k : chosen) bands.push_back(&in.properties[k]);
        writeFeatureRaster(output, in, bands, comment.str());
    } else {
        WritePlyOptions plyOptions;
        plyOptions.propertyPrefix = args.propertyPrefix;
        plyOptions.comments = in.comments;  // keep the provenance (e.g. compute's R and N)
        plyOptions.comments.push_back(comment.str());
        qualityWithoutNaN(in.properties);
        writePly(output, in.mesh, in.properties, plyOptions);
    }
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%zu vertices, %zu properties, %d x %s, %.1f s)\n",
                     args.input.c_str(), output.c_str(), in.mesh.numVertices(), chosen.size(),
                     args.iterations, args.filter.c_str(), total.seconds());
    return 0;
}

} // namespace

std::function<int()> addSmoothCommand(CLI::App& app)
{
    auto args = std::make_shared<SmoothArgs>();
    CLI::App* cmd = app.add_subcommand(
        "smooth", "Fast 1-ring mean or median smoothing (paper Sec. 3.2), repeated k times, of "
                  "quality (default), chosen properties or every feature element; writes a PLY "
                  "with every property of the input; for a GeoTIFF from msii compute on a DEM, a "
                  "GeoTIFF on its grid with the smoothed bands (float32).");
    cmd->add_option("input", args->input,
                    "PLY with per-vertex values (e.g. from msii metric or compute), or a GeoTIFF from them")
        ->required();
    cmd->add_option("-o,--output", args->output,
                    "Output PLY (default <input stem>.smooth.ply), or for a GeoTIFF input a GeoTIFF "
                    "(default <input stem>.smooth.tif; a .ply name gives the DEM's mesh)");
    cmd->add_option("--mat", args->matFiles,
                    "GigaMesh feature file(s) for the input mesh (*.volume.mat, *.surface.mat)");
    cmd->add_option("--filter", args->filter, "mean (Eq. 16, default) or median (Eq. 17)");
    cmd->add_option("-k,--iterations", args->iterations, "Passes (default 30, as in the paper)");
    cmd->add_option("--delta", args->delta,
                    "Disc radius: global (the mesh's shortest edge, the paper's choice, default) or "
                    "ring (each ring's shortest edge, Eq. 12: robust to near-zero edges of scans)");
    cmd->add_option("--weights", args->weights,
                    "Triangle weights: balanced (tan of half the angle at the vertex: keeps linear "
                    "functions, default) or area (Eq. 15)");
    cmd->add_option("--border", args->border,
                    "Border vertices: ring (smoothed over the triangles they have, default) or keep");
    cmd->add_option("--properties", args->properties,
                    "Vertex properties to smooth, comma-separated (default quality)");
    cmd->add_flag("--all-features", args->allFeatures,
                  "Smooth every feature element (V_01 ..., S_, P_, L_) and quality");
    addCommonOptions(cmd, *args);
    addPropertyNamesOption(cmd, args->propertyPrefix);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runSmooth(*args);
    };
}

} // namespace msii::tools
