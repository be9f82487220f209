/// `msii compute INPUT... --radius R [--scales N] [--output OUT.ply]`: V and S per vertex.
#include "commands.h"

#include <msii/core/errors.h>
#include <msii/core/progress.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/invariants/compute.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/read_mesh.h>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <iomanip>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

namespace fs = std::filesystem;

namespace msii::tools {

namespace {

struct ComputeArgs {
    std::vector<std::string> inputs;
    std::string output, outputDir;
    double radius = 0;
    int scales = 16;
    double voxelSize = 0;
    double precision = 6.0;
    int threads = 0;
    bool quiet = false, overwrite = false, repair = false, noSphere = false;
};

/// Where the result of @p input goes: --output for a single input, else
/// <output-dir or input's folder>/<stem>.msii.ply
std::string outputPathFor(const ComputeArgs& args, const std::string& input)
{
    if (!args.output.empty()) return args.output;
    const fs::path in(input);
    const fs::path dir = args.outputDir.empty() ? in.parent_path() : fs::path(args.outputDir);
    return (dir / (in.stem().string() + ".msii.ply")).string();
}

std::string sidecarPathFor(const std::string& plyPath)
{
    fs::path p(plyPath);
    return p.replace_extension(".json").string();
}

/// A suggestion for R when none is given: about 30 median edges (a typical feature size for
/// scans at their native resolution), capped by a tenth of the bounding-box diagonal.
std::string radiusHint(const std::string& input)
{
    try {
        const ReadMeshResult read = readMesh(input);
        const MeshStats stats = computeMeshStats(read.mesh);
        const double suggestion = std::min(30.0 * stats.medianEdge, 0.1 * stats.diagonal);
        std::ostringstream s;
        s << std::setprecision(3) << "; for " << fs::path(input).filename().string()
          << " (median edge " << stats.medianEdge << ", size " << stats.diagonal
          << ") try --radius " << suggestion
          << " and make R about the size of the largest feature to detect";
        return s.str();
    } catch (const std::exception&) {
        return "";
    }
}

void computeOne(const ComputeArgs& args, const std::string& input, const std::string& output)
{
    const Stopwatch total;
    const std::string sidecar = sidecarPathFor(output);
    if (!args.overwrite && (fs::exists(output) || fs::exists(sidecar)))
        throw IOError("'" + output + "' exists already (use --overwrite to replace it)");
    checkWritable(output);
    checkWritable(sidecar);

    Progress progress(!args.quiet && Progress::stderrIsTerminal());
    ReadMeshResult read = readMesh(input);
    const double readSeconds = total.seconds();
    const std::size_t inputFaces = read.mesh.numTriangles();

    ComputeOptions options;
    options.radius = args.radius;
    options.scales = args.scales;
    options.voxelSize = args.voxelSize;
    options.minVoxelsPerRadius = args.precision;
    options.computeSphere = !args.noSphere;
    options.repair = args.repair;
    ComputeResult result;
    try {
        result = computeInvariants(read.mesh, options, &progress);
    } catch (const InvalidInputError& e) {
        throw InvalidInputError(fs::path(input).filename().string() + ": " + e.what());
    }
    if (!args.quiet)
        for (const auto& w : result.warnings)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), w.c_str());

    const std::vector<VertexProperty> props = featureProperties(result.invariants);
    const auto& inv = result.invariants;
    const std::size_t n = inv.radii.size();

    const Stopwatch write;
    WritePlyOptions plyOptions;
    std::ostringstream comment;
    comment << "msii " << versionString() << " compute R=" << args.radius << " N=" << n
            << " voxel=" << result.voxelSize
            << "; V_jj = V/|B_r|, S_jj = S/(4 pi r^2) (plane = 0.5), r_j = j*R/N; NaN = ball "
               "reaches the border; quality = V_NN";
    plyOptions.comments.push_back(comment.str());
    writePly(output, read.mesh, props, plyOptions);
    const double writeSeconds = write.seconds();

    nlohmann::json j;
    j["program"] = "msii";
    j["version"] = versionString();
    j["command"] = "compute";
    j["input"] = {{"path", fs::absolute(input).string()}, {"format", read.format}};
    j["output"] = fs::absolute(output).string();
    j["parameters"] = {{"radius", args.radius},
                       {"scales", n},
                       {"radii", inv.radii},
                       {"voxel_size", result.voxelSize},
                       {"voxel_size_requested", args.voxelSize},
                       {"precision_voxels_per_radius", args.precision},
                       {"levels", inv.numLevels},
                       {"level_of_radius", inv.levelOfRadius},
                       {"band_half_width_voxels", result.bandHalfWidth},
                       {"invariants", options.computeSphere ? nlohmann::json{"V", "S"} : nlohmann::json{"V"}},
                       {"repair", args.repair},
                       {"threads", args.threads}};
    j["conventions"] = {{"V", "V/|B_r| in [0,1], flat plane 0.5, convex < 0.5"},
                        {"S", "S/(4 pi r^2) in [0,1], flat plane 0.5, convex < 0.5"},
                        {"order", "radius ascending: V_01 = r_1 = R/N ... V_NN = R"},
                        {"quality", "V_NN (volume fraction at the largest radius)"},
                        {"masked", "NaN where the ball of that radius reaches a mesh border"}};
    const auto& st = result.stats;
    j["mesh"] = {{"vertices", st.numVertices},
                 {"faces", st.numTriangles},
                 {"faces_in_file", inputFaces},
                 {"faces_removed", result.removedFaces},
                 {"closed", result.check.closed},
                 {"border_edges", result.check.numBorderEdges},
                 {"bbox_min", {st.bboxMin.x, st.bboxMin.y, st.bboxMin.z}},
                 {"bbox_max", {st.bboxMax.x, st.bboxMax.y, st.bboxMax.z}},
                 {"diagonal", st.diagonal},
                 {"edge_length", {{"min", st.minEdge}, {"median", st.medianEdge}, {"mean", st.meanEdge}, {"max", st.maxEdge}}},
                 {"area", st.area},
                 {"masked_values", inv.numMaskedValues}};
    j["level_set"] = {{"active_voxels", result.levelSetVoxels}, {"bytes", result.levelSetBytes}};
    const auto& t = result.timings;
    j["timings_seconds"] = {{"read", readSeconds},     {"check", t.check},
                            {"level_set", t.levelSet}, {"occupancy", t.occupancy},
                            {"stencils", t.stencils},  {"interpolation", t.interpolation},
                            {"write", writeSeconds},
                            {"total", total.seconds()}};
    j["warnings"] = result.warnings;
    writeTextFileAtomic(sidecar, j.dump(2) + "\n");

    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%zu vertices, %.1f s)\n", input.c_str(),
                     output.c_str(), st.numVertices,
                     total.seconds());
}

} // namespace

std::function<int()> addComputeCommand(CLI::App& app)
{
    auto args = std::make_shared<ComputeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "compute", "Compute the volume (V) and sphere-area (S) integral invariants at N radii "
                   "for every vertex; writes a PLY with V_01..V_NN, S_01..S_NN and quality, and a "
                   "JSON record next to it.");
    cmd->add_option("inputs", args->inputs, "Mesh files (PLY, OBJ, OFF, STL)")->required();
    cmd->add_option("-r,--radius", args->radius,
                    "Largest radius R in mesh units (usually mm): about the size of the largest "
                    "feature to detect. Radii are r_j = j*R/N.");
    cmd->add_option("-n,--scales", args->scales, "Number of radii N (default 16)");
    cmd->add_option("-o,--output", args->output, "Output PLY (one input only)");
    cmd->add_option("--output-dir", args->outputDir,
                    "Folder for the outputs <name>.msii.ply (default: next to each input)");
    cmd->add_option("--voxel-size", args->voxelSize,
                    "Finest voxel edge in mesh units (default: automatic, see README)");
    cmd->add_option("--precision", args->precision,
                    "Voxels per radius on the grid each radius is computed on (default 6; "
                    "higher = more exact and slower)");
    cmd->add_option("-j,--threads", args->threads, "Worker threads (default: all cores)");
    cmd->add_flag("-q,--quiet", args->quiet, "No progress, no summary; errors only");
    cmd->add_flag("--overwrite", args->overwrite, "Replace existing outputs");
    cmd->add_flag("--repair", args->repair,
                  "Drop degenerate and duplicate faces instead of stopping");
    cmd->add_flag("--no-sphere", args->noSphere, "Compute V only");

    return [args]() {
        if (!(args->radius > 0)) {
            if (args->radius != 0 || !std::isfinite(args->radius))
                throw InvalidInputError("the radius must be a positive number");
            throw InvalidInputError("--radius is required" + radiusHint(args->inputs.front()));
        }
        if (!args->output.empty() && args->inputs.size() > 1)
            throw InvalidInputError("--output takes one input; use --output-dir for several");
        if (args->threads < 0) throw InvalidInputError("--threads must be 0 (all cores) or more");
        std::unique_ptr<tbb::global_control> limit;
        if (args->threads > 0)
            limit = std::make_unique<tbb::global_control>(
                tbb::global_control::max_allowed_parallelism, std::size_t(args->threads));
        int failures = 0;
        for (const auto& input : args->inputs) {
            try {
                computeOne(*args, input, outputPathFor(*args, input));
            } catch (const Error& e) {
                if (args->inputs.size() == 1) throw;
                std::fprintf(stderr, "msii: error: %s\n", e.what());
                ++failures;
            }
        }
        if (failures > 0 && !args->quiet)
            std::fprintf(stderr, "msii: %d of %zu inputs failed\n", failures, args->inputs.size());
        return failures > 0 ? 1 : 0;
    };
}

} // namespace msii::tools
