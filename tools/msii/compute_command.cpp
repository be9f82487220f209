/// `msii compute INPUT... --radius R [--scales N] [--output OUT.ply]`: V, S, P and L per
/// vertex (or the chosen ones), fast or exact; optionally GigaMesh-compatible files too. The
/// work is the engine's pipeline (pipeline/compute.h); this file reads, words and writes.
#include "commands.h"
#include "compute_args.h"

#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/terminal_progress.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>
#include <msii/io/gigamesh_files.h>
#include <msii/io/read_mesh.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/terrain/dem.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <limits>
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

std::vector<Invariant> invariantsOf(const ComputeArgs& args)
{
    std::vector<Invariant> list;
    try {
        list = parseInvariantList(args.invariants);
    } catch (const InvalidInputError& e) {
        throw InvalidInputError(std::string("--invariants: ") + e.what());
    }
    if (args.noSphere) list.erase(std::remove(list.begin(), list.end(), Invariant::Sphere), list.end());
    if (list.empty()) throw InvalidInputError("--invariants selects nothing but S, which --no-sphere leaves out");
    return list;
}

ComputeOptions computeOptionsOf(const ComputeArgs& args)
{
    if (args.tile >= 0 && args.tiles <= 0) throw InvalidInputError("--tile I goes with --tiles K (tiles 0 to K*K-1)");
    if (args.tile < -1) throw InvalidInputError("--tile must be 0 or more");
    ComputeOptions o;
    InvariantsOptions& inv = o.invariants;
    inv.radius = args.radius;
    inv.scales = args.scales;
    inv.voxelSize = args.voxelSize;
    inv.minVoxelsPerRadius = args.precision;
    inv.patchLinePrecision = args.plPrecision;
    inv.patchLineExactWhereBlurred = args.plCheck == "on";
    inv.select(invariantsOf(args));
    inv.exact = args.exact;
    o.repair = !args.strict;
    o.maxHolePerimeter = args.fillHoles;
    o.border = parseBorderHandling(args.border);
    o.tiling.memoryBudget = parseBytes(args.memoryBudget);
    if (!args.exact) {  // the exact mode is computed whole (at chosen vertices)
        o.tiling.tilesPerAxis = args.tiles;
        o.tiling.onlyTile = args.tile;
    } else {
        o.tiling.memoryBudget = 0;
    }
    return o;
}

namespace {

/// The vertices of the exact mode: --vertices "3,17,42", or --random-vertices K (distinct,
/// seeded, ascending, among the vertices in a face: a scan's stray points have no values),
/// or all.
std::vector<std::uint32_t> exactVertices(const ComputeArgs& args, const TriMesh& mesh)
{
    const std::size_t numVertices = mesh.numVertices();
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
        std::vector<std::uint32_t> inFace;
        {
            std::vector<char> used(numVertices, 0);
            for (const Triangle& t : mesh.triangles)
                for (const std::uint32_t v : t) used[v] = 1;
            for (std::uint32_t v = 0; v < numVertices; ++v)
                if (used[v]) inFace.push_back(v);
        }
        if (args.randomVertices > inFace.size())
            throw InvalidInputError("--random-vertices " + std::to_string(args.randomVertices) +
                                    " is more than the mesh's " + std::to_string(inFace.size()) +
                                    " vertices in a face");
        std::mt19937_64 rng(args.seed);
        std::vector<char> taken(inFace.size(), 0);
        while (out.size() < args.randomVertices) {
            const std::size_t k = std::size_t(rng() % inFace.size());
            if (!taken[k]) taken[k] = 1, out.push_back(inFace[k]);
        }
        std::sort(out.begin(), out.end());
    }
    return out;  // empty: all
}

/// GigaMesh-compatible outputs next to @p output: <stem>_r.._n.._v...volume.mat (V),
/// .surface.mat (P) and <stem>.gigamesh.ply (V, else P).
std::vector<std::string> gigameshPaths(const ComputeArgs& args, const std::string& input, const std::string& output,
                                       const InvariantsOptions& options)
{
    const fs::path dir = fs::path(output).parent_path();
    const std::string stem = fs::path(input).stem().string();
    const int precision = int(std::lround(args.precision));
    std::vector<std::string> paths;
    if (options.computeVolume)
        paths.push_back(
            (dir / gigaMeshMatFileName(stem, args.radius, args.scales, precision, GigaMeshInvariant::Volume)).string());
    if (options.computePatch)
        paths.push_back(
            (dir / gigaMeshMatFileName(stem, args.radius, args.scales, precision, GigaMeshInvariant::Patch)).string());
    paths.push_back((dir / (stem + ".gigamesh.ply")).string());
    return paths;
}

/// Writes the GigaMesh-compatible files: V and P as .mat, and a PLY with V's (else P's)
/// feature vectors.
void writeGigaMeshFiles(const ComputeArgs& args, const std::string& input, const std::vector<std::string>& paths,
                        const TriMesh& mesh, const ComputeResult& result)
{
    const FeatureSet& features = result.features;
    GigaMeshMatInfo info;
    info.inputFile = fs::absolute(input).string();
    info.largestRadius = args.radius;
    info.radii = result.plan.radii;
    info.notes = {"msii voxel size " + std::to_string(result.plan.voxelSize) + ", precision " +
                  std::to_string(args.precision) + (args.exact ? ", exact mode" : "")};
    std::size_t k = 0;
    GigaMeshRows plyRows;
    const bool volume = features.has(Invariant::Volume);
    if (volume) {
        info.invariant = GigaMeshInvariant::Volume;
        plyRows = toGigaMeshRows(features[Invariant::Volume], GigaMeshInvariant::Volume);
        writeGigaMeshMat(paths[k++], gigaMeshMatHeader(info), plyRows);
    }
    if (features.has(Invariant::Patch)) {
        info.invariant = GigaMeshInvariant::Patch;
        const GigaMeshRows rows = toGigaMeshRows(features[Invariant::Patch], GigaMeshInvariant::Patch);
        writeGigaMeshMat(paths[k++], gigaMeshMatHeader(info), rows);
        if (!volume) plyRows = rows;
    }
    GigaMeshPlyOptions gmOptions;
    gmOptions.comments.push_back(std::string("msii ") + versionString() + ": feature_vector = " +
                                 (volume ? "2 " + invariantFormula(Invariant::Volume) + " - 1"
                                         : invariantFormula(Invariant::Patch)) +
                                 ", largest radius first; quality = largest element");
    writeGigaMeshPly(paths[k], mesh, plyRows, gmOptions);
}

/// The feature PLY of one mesh input: the input's mesh with the output properties, written
/// whole, or piece by piece as tiles are computed.
class FeaturePly {
public:
    FeaturePly(const ComputeArgs& args, const std::string& path, const TriMesh& mesh)
        : mArgs(args), mPath(path), mMesh(mesh)
    {
    }

    /// The values of some vertices (computeStreamed's sink).
    void piece(const ComputedPiece& piece)
    {
        const Stopwatch watch;
        const std::vector<VertexProperty> props = outputProperties(piece.features, piece.filledShare);
        if (!mPieces) {
            // Vertices in no piece (in no face) get NaN features, quality's stand-in and
            // valid_radii 0, as in writePly's output.
            const float standIn = qualityStandIn(piece.features);
            std::vector<PlyColumn> names;
            for (const VertexProperty& p : props)
                names.push_back({p.name, p.integer,
                                 p.integer ? 0.0f : p.name == "quality" ? standIn : std::numeric_limits<float>::quiet_NaN()});
            mPieces = std::make_unique<PlyPieceWriter>(mPath, mMesh, names, optionsFor(piece.features, piece.plan));
        }
        std::vector<const float*> columns;
        for (const VertexProperty& p : props) columns.push_back(p.values.data());
        if (!piece.vertices.empty()) mPieces->write(piece.vertices, columns);
        seconds += watch.seconds();
    }

    /// Writes the whole result, or finishes what the pieces wrote.
    void finish(const ComputeResult& result)
    {
        const Stopwatch watch;
        if (mPieces) mPieces->commit();
        else writePly(mPath, mMesh, outputProperties(result.features, result.filledShare), optionsFor(result.features, result.plan));
        seconds += watch.seconds();
    }

    double seconds = 0;  ///< spent writing

private:
    /// The header's comments: the run, the legend of the features, units, the tile.
    WritePlyOptions optionsFor(const FeatureSet& features, const ScalePlan& plan) const
    {
        WritePlyOptions o;
        std::ostringstream comment;
        comment << "msii " << versionString() << " compute" << (mArgs.exact ? " --exact" : "") << " R=" << mArgs.radius
                << " N=" << plan.radii.size() << " voxel=" << plan.voxelSize << "; " << featureLegend()
                << (mArgs.border == "mask" ? "; NaN = ball reaches the border" : "; borders continued (filled_share)")
                << (mArgs.exact ? (mArgs.border == "mask" ? " or vertex not computed" : "; NaN = vertex not computed") : "")
                << "; quality = " << qualitySource(features).substr(0, 1)
                << " at the largest radius with a value (a plane's value if none), valid_radii = how many "
                   "radii have one";
        o.comments.push_back(comment.str());
        if (!mArgs.units.empty()) o.comments.push_back("units " + mArgs.units);  // read by render and map
        o.propertyPrefix = mArgs.propertyPrefix;
        if (mArgs.tile >= 0)  // read by msii merge
            o.comments.push_back("msii tile " + std::to_string(mArgs.tile) + " of " + std::to_string(mArgs.tiles) + " x " +
                                 std::to_string(mArgs.tiles) + " (other vertices NaN; msii merge joins the tiles)");
        return o;
    }

    const ComputeArgs& mArgs;
    std::string mPath;
    const TriMesh& mMesh;
    std::unique_ptr<PlyPieceWriter> mPieces;
};

/// The pipeline on one mesh as read, its errors named after the file; the PLY gets the
/// values piece by piece when tiled without GigaMesh files (which need all columns at once),
/// so that neither the values nor the file are held whole.
ComputeResult runPipeline(const ComputeArgs& args, const std::string& input, const TriMesh& mesh,
                          const ComputeOptions& options, FeaturePly& ply, RunContext& progress)
{
    try {
        if (options.tiling.tiled() && !args.gigamesh)
            return computeStreamed(mesh, options, [&](const ComputedPiece& p) { ply.piece(p); }, &progress);
        return compute(mesh, options, &progress);
    } catch (const MemoryLimitError& e) {
        // The engine gives the estimate; the command, the option that computes in pieces.
        throw MemoryLimitError(fs::path(input).filename().string() + ": " + e.what() +
                               " (--memory-budget computes the mesh in tiles of that size)");
    } catch (const InvalidInputError& e) {
        const std::string hint = args.strict && std::string(e.what()).find("repair is off") != std::string::npos
                                     ? " (--strict; without it msii repairs this)"
                                     : "";
        throw InvalidInputError(fs::path(input).filename().string() + ": " + e.what() + hint);
    }
}

/// @p x to 3 significant digits, written without an exponent where it has few digits
/// ("1280", not "1.28e+03").
std::string rounded(double x)
{
    if (!(x > 0) || !std::isfinite(x)) return std::to_string(x);
    const double step = std::pow(10.0, std::floor(std::log10(x)) - 2);
    std::ostringstream s;
    s << std::setprecision(12) << std::round(x / step) * step;
    return s.str();
}

/// A suggestion for R when none is given: about 30 median edges (a typical feature size for
/// scans at their native resolution), capped by a tenth of the bounding-box diagonal.
std::string radiusHint(const std::string& input)
{
    try {
        if (isRasterInput(input)) {
            // DEMs: 15 cells (15 m on 1 m lidar: ditches, mounds, field boundaries;
            // docs/terrain.md), at most a tenth of the extent.
            const DemSource dem(input, {});
            const RasterGeoreference& g = dem.info().georeference;
            const double cell = shortestCellStep(g);
            const double extent = std::hypot(g.width * cell, g.height * cell);
            const double suggestion = std::min(15.0 * cell, 0.1 * extent);
            std::ostringstream s;
            s << "; for " << fs::path(input).filename().string() << " (cells of " << rounded(cell) << " " << g.units
              << ", " << rounded(g.width * cell) << " x " << rounded(g.height * cell) << ") try --radius "
              << rounded(suggestion) << " and make R about the size of the largest feature to detect";
            return s.str();
        }
        const ReadMeshResult read = readMesh(input);
        const MeshStats stats = computeMeshStats(read.mesh);
        const double suggestion = std::min(30.0 * stats.medianEdge, 0.1 * stats.diagonal);
        std::ostringstream s;
        s << std::setprecision(3) << "; for " << fs::path(input).filename().string()
          << " (median edge " << stats.medianEdge << ", size " << stats.diagonal
          << ") try --radius " << suggestion
          << " and make R about the size of the largest feature to detect";
        return s.str();
    } catch (const Error&) {
        throw;  // the input's own problem (unreadable, in degrees) comes before the missing radius
    } catch (const std::exception&) {
        return "";
    }
}



} // namespace

std::string outputPathFor(const ComputeArgs& args, const std::string& input)
{
    const bool raster = isRasterInput(input);
    if (raster && !args.rasterOutput.empty()) return args.rasterOutput;
    if (!args.output.empty()) return args.output;
    const fs::path in(input);
    const fs::path dir = args.outputDir.empty() ? in.parent_path() : fs::path(args.outputDir);
    // One part of a mosaic: named after the part, so that the parts' outputs do not collide.
    const std::string stem = raster && !args.tileOfMosaic.empty() ? fs::path(args.tileOfMosaic).stem().string()
                                                                  : in.stem().string();
    return (dir / (stem + (raster ? ".msii.tif" : ".msii.ply"))).string();
}

std::string sidecarPathFor(const std::string& plyPath)
{
    fs::path p(plyPath);
    return p.replace_extension(".json").string();
}

std::string worded(const Diagnostic& d)
{
    if (d.kind == "mostly_masked")
        return d.message + " (--radius; --fill-holes fills larger holes; --border continue gives values everywhere)";
    if (d.kind == "borders_continued") return d.message + " (--border mask gives NaN there instead)";
    if (d.kind == "smallest_radius_below_edge") return d.message + " (raise --radius or lower --scales)";
    if (d.kind == "holes_filled") return d.message + " (--fill-holes sets the largest hole filled; 0 fills none)";
    if (d.kind == "undeclared_nodata") {
        std::ostringstream value;
        value << std::setprecision(9) << float(d.figure("value_1"));  // as stored: gdal_edit must match it exactly
        return d.message + " (to declare it: gdal_edit.py -a_nodata " + value.str() + " FILE for a GeoTIFF, "
               "gdal_translate -a_nodata " + value.str() + " IN OUT for any raster)";
    }
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

bool isRasterInput(const std::string& input)
{
    std::string ext = fs::path(input).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".ply" || ext == ".obj" || ext == ".off" || ext == ".stl") return false;
    // The extensions of DEM formats: rasters even when missing or unreadable, so that the
    // error says so (not "unknown mesh extension").
    static const char* const rasterExtensions[] = {".tif", ".tiff", ".vrt", ".asc", ".img", ".hgt", ".bil",
                                                   ".flt", ".grd", ".dem", ".nc",  ".xyz", ".jp2"};
    for (const char* e : rasterExtensions)
        if (ext == e) return true;
    return fs::is_regular_file(input) && isRasterFile(input);
}

OneResult computeOne(const ComputeArgs& args, const std::string& input, const std::string& output)
{
    if (isRasterInput(input)) return computeRasterOne(args, input, output);
    if (!args.tileOfMosaic.empty()) throw InvalidInputError("--tile-of-mosaic is for raster mosaics (VRT), not meshes");
    const Stopwatch total;
    ComputeOptions options = computeOptionsOf(args);
    if (args.gigamesh && !options.invariants.computeVolume && !options.invariants.computePatch)
        throw InvalidInputError("--gigamesh writes V and P; select at least one of them");
    const std::string sidecar = sidecarPathFor(output);
    const std::vector<std::string> gigameshFiles =
        args.gigamesh ? gigameshPaths(args, input, output, options.invariants) : std::vector<std::string>{};
    std::vector<std::string> outputs{output, sidecar};
    outputs.insert(outputs.end(), gigameshFiles.begin(), gigameshFiles.end());
    checkOutputs(outputs, args.overwrite);

    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    const ReadMeshResult read = readMesh(input);
    const double readSeconds = total.seconds();
    if (!args.exact && (!args.vertices.empty() || args.randomVertices > 0))
        throw InvalidInputError("--vertices and --random-vertices go with --exact");
    if (args.exact) {
        options.invariants.exactVertices = exactVertices(args, read.mesh);
        if (options.invariants.exactVertices.empty() && read.mesh.numVertices() > 20000 && !args.quiet)
            std::fprintf(stderr,
                         "msii: warning: %s: exact mode on all %zu vertices is slow; "
                         "--vertices or --random-vertices restrict it\n",
                         input.c_str(), read.mesh.numVertices());
    }
    FeaturePly ply(args, output, read.mesh);
    const ComputeResult result = runPipeline(args, input, read.mesh, options, ply, progress);
    if (!args.quiet)
        for (const Diagnostic& d : result.diagnostics)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), printableLine(worded(d)).c_str());
    ply.finish(result);
    const Stopwatch write;
    if (args.gigamesh) writeGigaMeshFiles(args, input, gigameshFiles, read.mesh, result);
    const double writeSeconds = ply.seconds + write.seconds();

    const MeshRunRecord record{args, input, output, read, options, result, readSeconds, writeSeconds, total.seconds()};
    writeTextFileAtomic(sidecar, runRecord(record).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%zu vertices%s, %.1f s)\n", input.c_str(), output.c_str(),
                     read.mesh.numVertices(), exactShareText(result.cost).c_str(), total.seconds());
    return {read.mesh.numVertices(), result.plan.voxelSize, total.seconds()};
}

namespace {

/// The options for DEM rasters (the group "Terrain (DEM rasters)" of msii compute --help).
void addTerrainOptions(CLI::App& cmd, ComputeArgs& args)
{
    cmd.add_option("--raster-output", args.rasterOutput,
                    "Raster (DEM) inputs: the output GeoTIFF (default <input stem>.msii.tif): a Cloud-Optimized "
                    "GeoTIFF on the input's grid, one band per feature: 16-bit integers scaled to 1.5e-5 when every "
                    "band is a fraction in [0, 1] (V, S, their quality, filled_share), else float32")
        ->group("Terrain (DEM rasters)");
    cmd.add_option("--bands", args.bands,
                    "Raster inputs: the features written as bands, comma-separated, e.g. quality,V_04,V_16,S_16 "
                    "(default: quality and V at a quarter, half, three quarters of R and R; quality,V writes V at every "
                    "radius); only the invariants they need are computed")
        ->group("Terrain (DEM rasters)");
    cmd.add_option("--tile-of-mosaic", args.tileOfMosaic,
                    "Raster inputs: compute only the cells of this source tile of the mosaic (a VRT's file, by path, "
                    "name or stem), reading the mosaic around it as far as its values depend on; writes "
                    "<tile>.msii.tif on the tile's grid. The tiles' outputs joined (msii merge) equal the mosaic "
                    "computed in one piece, bit for bit: one job per tile on a cluster")
        ->group("Terrain (DEM rasters)");
    cmd.add_flag("--float32", args.float32,
                  "Raster inputs: float32 bands even where 16-bit scaled integers would hold them (3 times the size)")
        ->group("Terrain (DEM rasters)");
    cmd.add_option("--band", args.band, "Raster inputs: the height band of a multi-band raster (1, 2, ...)")
        ->group("Terrain (DEM rasters)");
    cmd.add_option("--window-cells", args.windowCells,
                    "Raster inputs: own cells per window side (default: windows sized to --memory-budget, 3G)")
        ->group("Terrain (DEM rasters)");
}

/// The inputs, the radii and where the outputs go, and the tiles the work is split into (the
/// first options of msii compute --help).
void addInputOptions(CLI::App* cmd, ComputeArgs& args)
{
    cmd->add_option("inputs", args.inputs,
                    "Mesh files (PLY, OBJ, OFF, STL), DEM rasters (GeoTIFF, VRT mosaic, ESRI ASCII grid, "
                    "any GDAL raster) or folders of meshes; several inputs or a folder "
                    "make a collection: finished outputs are skipped, failures reported, a manifest "
                    "written")
        ->required();
    cmd->add_option("-r,--radius", args.radius,
                    "Largest radius R in mesh units (usually mm): about the size of the largest "
                    "feature to detect. Radii are r_j = j*R/N.");
    args.scalesOption = cmd->add_option("-n,--scales", args.scales,
                                        "Number of radii N (default 16; for DEMs R / cell size, 4 to 16, so that "
                                        "the smallest radius is at least a cell)");
    cmd->add_option("-o,--output", args.output, "Output PLY (one input only)");
    cmd->add_option("--manifest", args.manifest,
                    "Collections: JSON-lines record of each input (appended; default "
                    "<output folder>/msii-manifest.jsonl)");
    cmd->add_flag("--recursive", args.recursive, "Folders: include their subfolders");
    cmd->add_option("--memory-budget", args.memoryBudget,
                    "Compute in spatial tiles sized to fit this memory (e.g. 8G); results equal the "
                    "untiled run");
    cmd->add_option("--tiles", args.tiles, "Tiles per axis (instead of sizing them from --memory-budget)");
    cmd->add_option("--tile", args.tile,
                    "With --tiles K: compute only tile I (0 to K*K-1), e.g. one cluster job per tile; "
                    "msii merge joins the parts");
}

/// The grids the invariants are computed on: the finest voxel and the cells per radius.
void addPrecisionOptions(CLI::App* cmd, ComputeArgs& args)
{
    cmd->add_option("--voxel-size", args.voxelSize,
                    "Finest voxel edge in mesh units (default: automatic, see README)");
    cmd->add_option("--precision", args.precision,
                    "Voxels per radius on the grid each radius is computed on (default 6; "
                    "higher = more exact and slower)");
    cmd->add_option("--pl-precision", args.plPrecision,
                    "Cells per radius for P and L alone (default: 4/3 of --precision, i.e. 8; their "
                    "kernels blur sharp edges over about a cell, so higher is more exact at sharp edges, "
                    "and slower)")
        // Given, it must be a precision: 0 (the engine's default) is not one.
        ->check(numberCheck([](double v) { return v >= 1 && v <= 64; },
                            "the P and L precision must be between 1 and 64 cells per radius"));
    cmd->add_option("--pl-check", args.plCheck,
                    "on (default): P and L are also summed with kernels 1.5 times narrower, and where the two "
                    "disagree (a sphere meeting a thin part, a fold or a crease) evaluated exactly from the "
                    "triangles, so that the values are within the bounds of docs/accuracy.md (which says where "
                    "they are not); off: the kernel sums alone, faster on scans with many thin parts")
        ->check(CLI::IsMember({"on", "off"}));
}

/// What the surface is taken as: its units, its repair, its holes and borders, and for a
/// DEM the route (level set or height field).
void addSurfaceOptions(CLI::App* cmd, ComputeArgs& args)
{
    cmd->add_option("--units", args.units,
                    "Units of the mesh's coordinates, e.g. mm or m, recorded in the outputs so that pictures' scale "
                    "bars say them (default: unstated, shown as mm; rasters state theirs)");
    cmd->add_flag("--strict", args.strict,
                  "Refuse meshes that need repair (duplicate or degenerate faces, non-manifold edges or "
                  "vertices, vertices at the same position, inconsistent orientation) instead of repairing them");
    cmd->add_flag("--repair", args.repair, "Repair is the default now; accepted for old scripts")->group("");
    cmd->add_option("--fill-holes", args.fillHoles,
                    "Fill holes whose border is at most SIZE long (mesh units), for the computation only; "
                    "default pi*R (holes up to about R across); 0 fills none")
        ->type_name("SIZE")
        ->check(numberCheck([](double v) { return v >= 0 && std::isfinite(v); },
                            "the hole size must be 0 (fill none) or a positive length"));
    cmd->add_option("--border", args.border,
                    "Where a ball reaches a border of an open surface (a scan's rim, a DEM's edge, a gap too large "
                    "to fill): continue (default) continues the surface past it, so every vertex and cell gets "
                    "values, and filled_share says how much of the ball rests on the continuation; mask gives NaN "
                    "there")
        ->type_name("continue|mask")
        ->check(CLI::IsMember({"continue", "mask"}));
    cmd->add_option("--engine", args.engine,
                    "For a DEM: heights (default) computes V and S straight from the height field, without a "
                    "level set; mesh computes them on the DEM's mesh through the level set, as for scans. P and L "
                    "always take the mesh (the record says so). Meshes, terrain given as a PLY included, always "
                    "take the level set")
        ->type_name("heights|mesh")
        ->check(CLI::IsMember({"heights", "mesh"}));
}

/// Which invariants, and the exact mode's vertices and GigaMesh's files.
void addInvariantOptions(CLI::App* cmd, ComputeArgs& args)
{
    cmd->add_option("--invariants", args.invariants,
                    "Which invariants: letters of V, S, P and L, together or comma-separated (default V,S,P,L; "
                    "VS and v,s are alike)");
    cmd->add_flag("--no-sphere", args.noSphere, "Leave out S (same as omitting it from --invariants)");
    cmd->add_flag("--exact", args.exact,
                  "Exact reference mode: from the triangles themselves, no voxels or samples "
                  "(slow; restrict it with --vertices or --random-vertices)");
    cmd->add_option("--vertices", args.vertices,
                    "With --exact: vertex indices, comma-separated (0-based); others are NaN");
    cmd->add_option("--random-vertices", args.randomVertices,
                    "With --exact: this many distinct random vertices (see --seed)");
    cmd->add_option("--seed", args.seed, "Seed for --random-vertices (default 1)");
    cmd->add_flag("--gigamesh", args.gigamesh,
                  "Also write GigaMesh-compatible files next to the output: "
                  "<name>_r<R>_n<log2 N>_v<precision>.volume.mat (2V/|B|-1) and .surface.mat "
                  "(P), radii largest first, and <name>.gigamesh.ply with a feature_vector list");
}

/// msii compute as parsed: the radius checked, one input to its output or a collection.
int runCompute(const ComputeArgs& args)
{
    if (!(args.radius > 0)) {
        if (args.radius != 0 || !std::isfinite(args.radius))
            throw InvalidInputError("the radius must be a positive number");
        throw InvalidInputError("--radius is required" + radiusHint(args.inputs.front()));
    }
    const auto limit = limitThreads(args.threads);
    bool collection = false;
    const std::vector<std::string> inputs = expandInputs(args, collection);
    if (!args.output.empty() && inputs.size() > 1)
        throw InvalidInputError("--output takes one input; use --output-dir for several");
    if (!args.outputDir.empty()) {
        std::error_code ec;
        fs::create_directories(args.outputDir, ec);
        if (ec) throw IOError("cannot create the output folder " + args.outputDir + ": " + ec.message());
    }
    if (!collection) {
        const std::string output = outputPathFor(args, inputs.front());
        // The default place, next to the input, may be a data folder the user cannot
        // write to (a read-only share, a DVD): say where else the output can go.
        if (args.output.empty() && args.outputDir.empty() && args.rasterOutput.empty()) {
            try {
                checkWritable(output);
            } catch (const IOError& e) {
                throw IOError(std::string(e.what()) + " Write it elsewhere with -o FILE or --output-dir FOLDER.");
            }
        }
        computeOne(args, inputs.front(), output);
        return 0;
    }
    return computeCollection(args, inputs);
}

} // namespace

std::function<int()> addComputeCommand(CLI::App& app)
{
    auto args = std::make_shared<ComputeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "compute", "Compute the integral invariants V (volume), S (sphere area), P (patch "
                   "area) and L (line length) at N radii for every vertex of a mesh, or every cell of a "
                   "DEM raster; writes a PLY with V_01..V_NN, S_.., P_.., L_.. and quality (a GeoTIFF "
                   "on the DEM's grid for rasters), and a JSON record next to it.");
    addInputOptions(cmd, *args);
    addTerrainOptions(*cmd, *args);
    cmd->add_option("--output-dir", args->outputDir,
                    "Folder for the outputs <name>.msii.ply (default: next to each input)");
    addPrecisionOptions(cmd, *args);
    addCommonOptions(cmd, *args);
    addPropertyNamesOption(cmd, args->propertyPrefix);
    addSurfaceOptions(cmd, *args);
    addInvariantOptions(cmd, *args);

    return [args]() { return runCompute(*args); };
}

} // namespace msii::tools
