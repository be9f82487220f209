/// `msii compute INPUT... --radius R [--scales N] [--output OUT.ply]`: V, S, P and L per
/// vertex (or the chosen ones), fast or exact; optionally GigaMesh-compatible files too.
#include "commands.h"
#include "compute_args.h"

#include <msii/core/terminal_progress.h>
#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/invariants/compute.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>
#include <msii/io/gigamesh_files.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/mesh/read_mesh.h>
#include <msii/terrain/dem.h>
#include <msii/tiling/tiled_compute.h>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cctype>
#include <ctime>
#include <iomanip>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>

namespace fs = std::filesystem;

namespace msii::tools {



double plPrecisionOf(const ComputeArgs& args)
{
    InvariantsOptions o;
    o.minVoxelsPerRadius = args.precision;
    o.patchLinePrecision = args.plPrecision;
    return patchLinePrecision(o);
}



Selection parseInvariants(const ComputeArgs& args)
{
    Selection sel;
    std::stringstream in(args.invariants);
    std::string item;
    while (std::getline(in, item, ',')) {
        item.erase(0, item.find_first_not_of(" \t"));
        item.erase(item.find_last_not_of(" \t") + 1);
        if (item.empty()) continue;
        if (item == "V" || item == "v") sel.volume = true;
        else if (item == "S" || item == "s") sel.sphere = true;
        else if (item == "P" || item == "p") sel.patch = true;
        else if (item == "L" || item == "l") sel.line = true;
        else
            throw InvalidInputError("unknown invariant '" + item +
                                    "' in --invariants (use any of V, S, P, L, comma-separated)");
    }
    if (args.noSphere) sel.sphere = false;
    if (!sel.volume && !sel.sphere && !sel.patch && !sel.line)
        throw InvalidInputError("--invariants selects nothing (use any of V, S, P, L)");
    return sel;
}

namespace {

/// The vertices of the exact mode: --vertices "3,17,42", or --random-vertices K (distinct,
/// seeded, ascending), or all.
std::vector<std::uint32_t> exactVertices(const ComputeArgs& args, std::size_t numVertices)
{
    std::vector<std::uint32_t> out;
    if (!args.vertices.empty()) {
        std::stringstream in(args.vertices);
        std::string item;
        while (std::getline(in, item, ',')) {
            std::size_t used = 0;
            long long v = -1;
            try {
                v = std::stoll(item, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used == 0 || item.find_first_not_of(" \t", used) != std::string::npos || v < 0)
                throw InvalidInputError("--vertices: '" + item +
                                        "' is not a vertex index (use e.g. --vertices 0,17,42)");
            if (std::size_t(v) >= numVertices)
                throw InvalidInputError("--vertices: vertex " + std::to_string(v) +
                                        " does not exist (the mesh has " +
                                        std::to_string(numVertices) + " vertices, 0 to " +
                                        std::to_string(numVertices - 1) + ")");
            out.push_back(std::uint32_t(v));
        }
        return out;
    }
    if (args.randomVertices > 0) {
        if (args.randomVertices > numVertices)
            throw InvalidInputError("--random-vertices " + std::to_string(args.randomVertices) +
                                    " is more than the mesh's " + std::to_string(numVertices) +
                                    " vertices");
        std::mt19937_64 rng(args.seed);
        std::vector<char> taken(numVertices, 0);
        while (out.size() < args.randomVertices) {
            const std::uint32_t v = std::uint32_t(rng() % numVertices);
            if (!taken[v]) taken[v] = 1, out.push_back(v);
        }
        std::sort(out.begin(), out.end());
    }
    return out;  // empty: all
}

/// GigaMesh-compatible outputs next to @p output: <stem>_r.._n.._v...volume.mat (V),
/// .surface.mat (P) and <stem>.gigamesh.ply (V, else P).
std::vector<std::string> gigameshPaths(const ComputeArgs& args, const std::string& input,
                                       const std::string& output, const Selection& sel)
{
    const fs::path dir = fs::path(output).parent_path();
    const std::string stem = fs::path(input).stem().string();
    const int precision = int(std::lround(args.precision));
    std::vector<std::string> paths;
    if (sel.volume)
        paths.push_back((dir / gigaMeshMatFileName(stem, args.radius, args.scales, precision,
                                                    GigaMeshInvariant::Volume)).string());
    if (sel.patch)
        paths.push_back((dir / gigaMeshMatFileName(stem, args.radius, args.scales, precision,
                                                    GigaMeshInvariant::Patch)).string());
    paths.push_back((dir / (stem + ".gigamesh.ply")).string());
    return paths;
}

} // namespace

std::string outputPathFor(const ComputeArgs& args, const std::string& input)
{
    const bool raster = isRasterInput(input);
    if (raster && !args.rasterOutput.empty()) return args.rasterOutput;
    if (!args.output.empty()) return args.output;
    const fs::path in(input);
    const fs::path dir = args.outputDir.empty() ? in.parent_path() : fs::path(args.outputDir);
    return (dir / (in.stem().string() + (raster ? ".msii.tif" : ".msii.ply"))).string();
}

std::string sidecarPathFor(const std::string& plyPath)
{
    fs::path p(plyPath);
    return p.replace_extension(".json").string();
}

namespace {

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


} // namespace

std::string worded(const Diagnostic& d)
{
    if (d.kind == "mostly_masked") return d.message + " (--radius; --fill-holes fills larger holes)";
    if (d.kind == "smallest_radius_below_edge") return d.message + " (raise --radius or lower --scales)";
    if (d.kind == "holes_filled") return d.message + " (--fill-holes sets the largest hole filled; 0 fills none)";
    return d.message;
}

double parseBytes(const std::string& text)
{
    if (text.empty()) return 0;
    std::size_t used = 0;
    double value = 0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    std::string unit = text.substr(used);
    std::transform(unit.begin(), unit.end(), unit.begin(), [](unsigned char c) { return char(std::toupper(c)); });
    if (!unit.empty() && unit.back() == 'B') unit.pop_back();
    const double scale = unit.empty() ? 1 : unit == "K" ? 1e3 : unit == "M" ? 1e6 : unit == "G" ? 1e9 : unit == "T" ? 1e12 : 0;
    if (used == 0 || scale == 0 || !(value > 0) || !std::isfinite(value))
        throw InvalidInputError("--memory-budget '" + text + "' is not a size (use e.g. 8G or 500M)");
    return value * scale;
}

void setInvariantsOptions(const ComputeArgs& args, const Selection& sel, InvariantsOptions& options)
{
    options.radius = args.radius;
    options.scales = args.scales;
    options.voxelSize = args.voxelSize;
    options.minVoxelsPerRadius = args.precision;
    options.patchLinePrecision = args.plPrecision;
    options.computeVolume = sel.volume;
    options.computeSphere = sel.sphere;
    options.computePatch = sel.patch;
    options.computeLine = sel.line;
    options.exact = args.exact;
}

bool isRasterInput(const std::string& input)
{
    std::string ext = fs::path(input).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".ply" || ext == ".obj" || ext == ".off" || ext == ".stl") return false;
    return fs::is_regular_file(input) && isRasterFile(input);
}

OneResult computeOne(const ComputeArgs& args, const std::string& input, const std::string& output)
{
    if (isRasterInput(input)) return computeRasterOne(args, input, output);
    const Stopwatch total;
    const std::string sidecar = sidecarPathFor(output);
    const Selection sel = parseInvariants(args);
    if (args.gigamesh && !sel.volume && !sel.patch)
        throw InvalidInputError("--gigamesh writes V and P; select at least one of them");
    const std::vector<std::string> gigameshFiles =
        args.gigamesh ? gigameshPaths(args, input, output, sel) : std::vector<std::string>{};
    std::vector<std::string> outputs{output, sidecar};
    outputs.insert(outputs.end(), gigameshFiles.begin(), gigameshFiles.end());
    for (const auto& path : outputs) {
        if (!args.overwrite && fs::exists(path))
            throw IOError("'" + path + "' exists already (use --overwrite to replace it)");
        checkWritable(path);
    }

    TerminalProgress terminal(!args.quiet && stderrIsTerminal());
    RunContext progress(terminal.listener());
    ReadMeshResult read = readMesh(input);
    const double readSeconds = total.seconds();
    const std::size_t inputFaces = read.mesh.numTriangles();

    // Mesh preparation: repair, holes. The computation runs on the prepared mesh; every
    // column is mapped back to the input's vertices before it is written.
    const Stopwatch prepareWatch;
    PrepareMeshOptions prepareOptions;
    prepareOptions.repair = !args.strict;
    prepareOptions.maxHolePerimeter = args.fillHoles >= 0 ? args.fillHoles : defaultMaxHolePerimeter(args.radius);
    prepareOptions.radius = args.radius;
    PrepareMeshResult prepared;
    try {
        prepared = prepareMesh(read.mesh, prepareOptions);
    } catch (const InvalidInputError& e) {
        const std::string hint = args.strict && std::string(e.what()).find("repair is off") != std::string::npos
                                     ? " (--strict; without it msii repairs this)"
                                     : "";
        throw InvalidInputError(fs::path(input).filename().string() + ": " + e.what() + hint);
    }
    const double prepareSeconds = prepareWatch.seconds();
    if (!args.quiet)
        for (const Diagnostic& c : prepared.changes)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), worded(c).c_str());
    const std::vector<float>& filledShare = prepared.filledShare;  // radius given: one per vertex

    InvariantsOptions options;
    setInvariantsOptions(args, sel, options);
    if (args.exact) {
        // Input vertex numbers to the prepared mesh's.
        for (std::uint32_t v : exactVertices(args, read.mesh.numVertices())) {
            if (prepared.preparedOf[v] == PrepareMeshResult::kNoVertex)
                throw InvalidInputError("--vertices: vertex " + std::to_string(v) + " belongs to no face");
            options.exactVertices.push_back(prepared.preparedOf[v]);
        }
        if (options.exactVertices.empty() && read.mesh.numVertices() > 20000 && !args.quiet)
            std::fprintf(stderr,
                         "msii: warning: %s: exact mode on all %zu vertices is slow; "
                         "--vertices or --random-vertices restrict it\n",
                         input.c_str(), read.mesh.numVertices());
    } else if (!args.vertices.empty() || args.randomVertices > 0) {
        throw InvalidInputError("--vertices and --random-vertices go with --exact");
    }
    InvariantsResult result;
    TiledComputeInfo tiledInfo;
    const bool tiled = !args.exact && (!args.memoryBudget.empty() || args.tiles > 0);
    if (args.tile >= 0 && args.tiles <= 0) throw InvalidInputError("--tile I goes with --tiles K (tiles 0 to K*K-1)");
    if (args.tile < -1) throw InvalidInputError("--tile must be 0 or more");

    // The PLY's header comments, from a result (the whole one or a tile's: same plan).
    std::string qualityName;  // e.g. "V_16"
    const auto plyOptionsFor = [&](const InvariantsResult& r) {
        qualityName = qualitySource(r.features);
        WritePlyOptions plyOptions;
        std::ostringstream comment;
        comment << "msii " << versionString() << " compute" << (args.exact ? " --exact" : "")
                << " R=" << args.radius << " N=" << r.plan.radii.size() << " voxel=" << r.plan.voxelSize
                << "; V_jj = V/|B_r|, S_jj = S/(4 pi r^2) (plane 0.5), P_jj = P/(pi r^2), L_jj = "
                   "L/(2 pi r) (plane 1), r_j = j*R/N; NaN = ball reaches the border"
                << (args.exact ? " or vertex not computed" : "") << "; quality = " << qualityName.substr(0, 1)
                << " at the largest radius with a value (a plane's value if none), valid_radii = how many "
                   "radii have one";
        plyOptions.comments.push_back(comment.str());
        if (!args.units.empty()) plyOptions.comments.push_back("units " + args.units);  // read by render and map
        plyOptions.propertyPrefix = args.propertyPrefix;
        if (args.tile >= 0)  // read by msii merge
            plyOptions.comments.push_back("msii tile " + std::to_string(args.tile) + " of " +
                                          std::to_string(args.tiles) + " x " + std::to_string(args.tiles) +
                                          " (other vertices NaN; msii merge joins the tiles)");
        return plyOptions;
    };
    // Tiled (without GigaMesh files, which need all columns at once): each tile's values go
    // straight into the output file, so neither the results nor the file are held whole.
    const bool streamed = tiled && !args.gigamesh;
    std::unique_ptr<PlyPieceWriter> pieces;
    double writeSeconds = 0;
    try {
        if (tiled) {
            TilingOptions tilingOptions;
            tilingOptions.memoryBudget = parseBytes(args.memoryBudget);
            tilingOptions.tilesPerAxis = args.tiles;
            tilingOptions.onlyTile = args.tile;
            if (streamed) {
                // Each prepared vertex of a tile goes to its input vertices (several where
                // positions were merged; none for hole-filling vertices).
                const InputVertexLists inputsOf = inputVerticesOf(prepared);
                const auto sink = [&](const TileResult& part) {
                    const Stopwatch write;
                    std::vector<VertexProperty> props = featureProperties(part.values.features);
                    std::vector<std::uint32_t> vertices;
                    std::vector<std::uint32_t> rows;  // row of part.vertices for each input vertex
                    for (std::size_t l = 0; l < part.vertices.size(); ++l)
                        for (std::size_t k = inputsOf.offsets[part.vertices[l]]; k < inputsOf.offsets[part.vertices[l] + 1]; ++k) {
                            vertices.push_back(inputsOf.inputs[k]);
                            rows.push_back(std::uint32_t(l));
                        }
                    std::vector<float> share(part.vertices.size());
                    for (std::size_t l = 0; l < part.vertices.size(); ++l) share[l] = filledShare[part.vertices[l]];
                    props.push_back({"filled_share", std::move(share)});
                    for (VertexProperty& p : props) {  // (keeps p.integer)
                        std::vector<float> expanded(rows.size());
                        for (std::size_t i = 0; i < rows.size(); ++i) expanded[i] = p.values[rows[i]];
                        p.values.swap(expanded);
                    }
                    std::vector<const float*> columns;
                    for (const VertexProperty& p : props) columns.push_back(p.values.data());
                    if (!pieces) {
                        // Vertices in no tile (in no face) get NaN features, quality's stand-in
                        // and valid_radii 0, as in writePly's output.
                        const float standIn = qualityStandIn(part.values.features);
                        std::vector<PlyColumn> names;
                        for (const VertexProperty& p : props)
                            names.push_back({p.name, p.integer,
                                             p.integer                ? 0.0f
                                             : p.name == "quality"    ? standIn
                                                                      : std::numeric_limits<float>::quiet_NaN()});
                        pieces = std::make_unique<PlyPieceWriter>(output, read.mesh, names, plyOptionsFor(part.values));
                    }
                    if (!vertices.empty()) pieces->write(vertices, columns);
                    writeSeconds += write.seconds();
                };
                result = computeTiles(prepared.mesh, options, tilingOptions, sink, &tiledInfo, &progress);
            } else {
                result = computeTiled(prepared.mesh, options, tilingOptions, &tiledInfo, &progress);
            }
        } else {
            result = computeInvariants(prepared.mesh, options, &progress);
        }
        if (!streamed) {
            for (FeatureColumns& columns : result.features.columns)
                for (std::vector<float>& column : columns) column = toInputVertices(prepared, column);
        }
    } catch (const InvalidInputError& e) {
        throw InvalidInputError(fs::path(input).filename().string() + ": " + e.what());
    }
    if (!args.quiet)
        for (const Diagnostic& d : result.diagnostics)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), worded(d).c_str());

    const FeatureSet& features = result.features;
    const ScalePlan& plan = result.plan;
    std::string letters;
    for (const auto& [on, c] : {std::pair{sel.volume, 'V'}, std::pair{sel.sphere, 'S'},
                                std::pair{sel.patch, 'P'}, std::pair{sel.line, 'L'}})
        if (on) letters += c;

    const Stopwatch write;
    if (streamed) {
        pieces->commit();
    } else {
        std::vector<VertexProperty> props = featureProperties(features);
        props.push_back({"filled_share", toInputVertices(prepared, filledShare)});
        writePly(output, read.mesh, props, plyOptionsFor(result));
    }
    if (args.gigamesh) {
        GigaMeshMatInfo info;
        info.inputFile = fs::absolute(input).string();
        info.largestRadius = args.radius;
        info.radii = plan.radii;
        info.notes = {"msii voxel size " + std::to_string(plan.voxelSize) + ", precision " +
                      std::to_string(args.precision) + (args.exact ? ", exact mode" : "")};
        std::size_t k = 0;
        GigaMeshRows plyRows;
        if (sel.volume) {
            info.invariant = GigaMeshInvariant::Volume;
            plyRows = toGigaMeshRows(features[Invariant::Volume], GigaMeshInvariant::Volume);
            writeGigaMeshMat(gigameshFiles[k++], gigaMeshMatHeader(info), plyRows);
        }
        if (sel.patch) {
            info.invariant = GigaMeshInvariant::Patch;
            const GigaMeshRows rows = toGigaMeshRows(features[Invariant::Patch], GigaMeshInvariant::Patch);
            writeGigaMeshMat(gigameshFiles[k++], gigaMeshMatHeader(info), rows);
            if (!sel.volume) plyRows = rows;
        }
        GigaMeshPlyOptions gmOptions;
        gmOptions.comments.push_back(std::string("msii ") + versionString() + ": feature_vector = " +
                                     (sel.volume ? "2 V/|B_r| - 1" : "P/(pi r^2)") +
                                     ", largest radius first; quality = largest element");
        writeGigaMeshPly(gigameshFiles[k], read.mesh, plyRows, gmOptions);
    }
    writeSeconds += write.seconds();

    const MeshRunRecord record{args,           input,   output,    read,    inputFaces, prepareOptions,
                               prepared,       options, result,    letters, qualityName, readSeconds,
                               prepareSeconds, writeSeconds, total.seconds(), tiled, tiledInfo};
    writeTextFileAtomic(sidecar, runRecord(record).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");

    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%zu vertices, %.1f s)\n", input.c_str(),
                     output.c_str(), read.mesh.numVertices(),
                     total.seconds());
    return {read.mesh.numVertices(), plan.voxelSize, total.seconds()};
}

void addPropertyNamesOption(CLI::App* cmd, std::string& prefix)
{
    static const std::map<std::string, std::string> styles{{"msii", ""}, {"cloudcompare", "scalar_"}};
    cmd->add_option("--property-names", prefix,
                    "Names of the output PLY's vertex properties: msii (V_01 ... quality; default) or "
                    "cloudcompare (scalar_V_01 ... scalar_quality, which CloudCompare's command line "
                    "loads as scalar fields)")
        ->transform(CLI::CheckedTransformer(styles, CLI::ignore_case));
}

std::unique_ptr<tbb::global_control> limitThreads(int threads)
{
    if (threads < 0) throw InvalidInputError("--threads must be 0 (all cores) or more");
    if (threads == 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 std::size_t(threads));
}

std::function<int()> addComputeCommand(CLI::App& app)
{
    auto args = std::make_shared<ComputeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "compute", "Compute the integral invariants V (volume), S (sphere area), P (patch "
                   "area) and L (line length) at N radii for every vertex; writes a PLY with "
                   "V_01..V_NN, S_.., P_.., L_.. and quality, and a JSON record next to it.");
    cmd->add_option("inputs", args->inputs,
                    "Mesh files (PLY, OBJ, OFF, STL) or folders of them; several inputs or a folder "
                    "make a collection: finished outputs are skipped, failures reported, a manifest "
                    "written")
        ->required();
    cmd->add_option("-r,--radius", args->radius,
                    "Largest radius R in mesh units (usually mm): about the size of the largest "
                    "feature to detect. Radii are r_j = j*R/N.");
    cmd->add_option("-n,--scales", args->scales, "Number of radii N (default 16)");
    cmd->add_option("-o,--output", args->output, "Output PLY (one input only)");
    cmd->add_option("--manifest", args->manifest,
                    "Collections: JSON-lines record of each input (appended; default "
                    "<output folder>/msii-manifest.jsonl)");
    cmd->add_flag("--recursive", args->recursive, "Folders: include their subfolders");
    cmd->add_option("--memory-budget", args->memoryBudget,
                    "Compute in spatial tiles sized to fit this memory (e.g. 8G); results equal the "
                    "untiled run");
    cmd->add_option("--tiles", args->tiles, "Tiles per axis (instead of sizing them from --memory-budget)");
    cmd->add_option("--tile", args->tile,
                    "With --tiles K: compute only tile I (0 to K*K-1), e.g. one cluster job per tile; "
                    "msii merge joins the parts");
    cmd->add_option("--raster-output", args->rasterOutput,
                    "Raster (DEM) inputs: the output GeoTIFF (default <input stem>.msii.tif): a Cloud-Optimized "
                    "GeoTIFF on the input's grid, one float32 band per feature")
        ->group("Terrain (DEM rasters)");
    cmd->add_option("--bands", args->bands,
                    "Raster inputs: the features written as bands, comma-separated, e.g. quality,V_04,V_16,S_16 "
                    "(default: V at every radius and quality)")
        ->group("Terrain (DEM rasters)");
    cmd->add_option("--band", args->band, "Raster inputs: the height band of a multi-band raster (1, 2, ...)")
        ->group("Terrain (DEM rasters)");
    cmd->add_option("--window-cells", args->windowCells,
                    "Raster inputs: own cells per window side (default: windows sized to --memory-budget, 3G)")
        ->group("Terrain (DEM rasters)");
    cmd->add_option("--output-dir", args->outputDir,
                    "Folder for the outputs <name>.msii.ply (default: next to each input)");
    cmd->add_option("--voxel-size", args->voxelSize,
                    "Finest voxel edge in mesh units (default: automatic, see README)");
    cmd->add_option("--precision", args->precision,
                    "Voxels per radius on the grid each radius is computed on (default 6; "
                    "higher = more exact and slower)");
    cmd->add_option("--pl-precision", args->plPrecision,
                    "Cells per radius for P and L alone (default: 4/3 of --precision, i.e. 8; their "
                    "kernels blur sharp edges over about a cell, so higher is more exact at sharp edges, "
                    "and slower)")
        // Given, it must be a precision: 0 (the engine's default) is not one.
        ->check([](const std::string& text) -> std::string {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (end == text.c_str()) return {};  // not a number: CLI11 says so
            return v >= 1 && v <= 64 ? std::string() : "the P and L precision must be between 1 and 64 cells per radius";
        });
    cmd->add_option("-j,--threads", args->threads, "Worker threads (default: all cores)");
    cmd->add_flag("-q,--quiet", args->quiet, "No progress, no summary; errors only");
    cmd->add_flag("--overwrite", args->overwrite, "Replace existing outputs");
    addPropertyNamesOption(cmd, args->propertyPrefix);
    cmd->add_option("--units", args->units,
                    "Units of the mesh's coordinates, e.g. mm or m, recorded in the outputs so that pictures' scale "
                    "bars say them (default: unstated, shown as mm; rasters state theirs)");
    cmd->add_flag("--strict", args->strict,
                  "Refuse meshes that need repair (duplicate or degenerate faces, non-manifold edges or "
                  "vertices, vertices at the same position, inconsistent orientation) instead of repairing them");
    cmd->add_flag("--repair", args->repair, "Repair is the default now; accepted for old scripts")->group("");
    cmd->add_option("--fill-holes", args->fillHoles,
                    "Fill holes whose border is at most SIZE long (mesh units), for the computation only; "
                    "default pi*R (holes up to about R across); 0 fills none")
        ->type_name("SIZE")
        ->check([](const std::string& text) -> std::string {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (end == text.c_str()) return {};  // not a number: CLI11 says so
            return v >= 0 && std::isfinite(v) ? std::string() : "the hole size must be 0 (fill none) or a positive length";
        });
    cmd->add_option("--invariants", args->invariants,
                    "Which invariants, comma-separated (default V,S,P,L)");
    cmd->add_flag("--no-sphere", args->noSphere, "Leave out S (same as omitting it from --invariants)");
    cmd->add_flag("--exact", args->exact,
                  "Exact reference mode: from the triangles themselves, no voxels or samples "
                  "(slow; restrict it with --vertices or --random-vertices)");
    cmd->add_option("--vertices", args->vertices,
                    "With --exact: vertex indices, comma-separated (0-based); others are NaN");
    cmd->add_option("--random-vertices", args->randomVertices,
                    "With --exact: this many distinct random vertices (see --seed)");
    cmd->add_option("--seed", args->seed, "Seed for --random-vertices (default 1)");
    cmd->add_flag("--gigamesh", args->gigamesh,
                  "Also write GigaMesh-compatible files next to the output: "
                  "<name>_r<R>_n<log2 N>_v<precision>.volume.mat (2V/|B|-1) and .surface.mat "
                  "(P), radii largest first, and <name>.gigamesh.ply with a feature_vector list");

    return [args]() {
        if (!(args->radius > 0)) {
            if (args->radius != 0 || !std::isfinite(args->radius))
                throw InvalidInputError("the radius must be a positive number");
            throw InvalidInputError("--radius is required" + radiusHint(args->inputs.front()));
        }
        const auto limit = limitThreads(args->threads);
        bool collection = false;
        const std::vector<std::string> inputs = expandInputs(*args, collection);
        if (!args->output.empty() && inputs.size() > 1)
            throw InvalidInputError("--output takes one input; use --output-dir for several");
        if (!args->outputDir.empty()) {
            std::error_code ec;
            fs::create_directories(args->outputDir, ec);
            if (ec) throw IOError("cannot create the output folder " + args->outputDir + ": " + ec.message());
        }
        if (!collection) {
            computeOne(*args, inputs.front(), outputPathFor(*args, inputs.front()));
            return 0;
        }
        return computeCollection(*args, inputs);
    };
}

} // namespace msii::tools
