/// `msii compute` on a raster (DEM): heights through GDAL, triangulated at the cell centres,
/// prepared and computed as any mesh, and the chosen features written back as a
/// Cloud-Optimized GeoTIFF on the input's grid (docs/terrain.md).
#include "compute_args.h"
#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/terminal_progress.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/dem_compute.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace msii::tools {

namespace {

/// N for a DEM when not given: R / cell size, between 4 and 16, so that the smallest radius
/// is at least a cell (below it, a ball holds about one cell centre: the paper's sampling
/// bound) and the radii fall on whole cells (1, 2, ... m on 1 m lidar).
int demScales(const ComputeArgs& args, const std::string& input)
{
    if (args.scalesOption && args.scalesOption->count() > 0) return args.scales;
    DemReadOptions ro;
    ro.band = args.band;
    const DemSource dem(input, ro);
    return std::clamp(int(std::floor(args.radius / shortestCellStep(dem.info().georeference) + 1e-9)), 4, 16);
}

/// The options a DEM refuses: those of meshes alone, and tiles (rasters take windows).
void refuseMeshOptions(const ComputeArgs& args)
{
    if (args.exact) throw InvalidInputError("--exact is for meshes; for a DEM, compute its mesh (msii-samples writes none: use the fast mode)");
    if (args.gigamesh) throw InvalidInputError("--gigamesh is for meshes, not rasters");
    if (args.tiles > 0) throw InvalidInputError("rasters are computed in windows: use --memory-budget or --window-cells, not --tiles");
}

/// --bands as the output's band names (those the DEM can have), an error naming the option.
void parseBands(const ComputeArgs& args, DemComputeOptions& options)
{
    if (args.bands.empty()) return;
    try {
        options.bands = parseFeatureNames(args.bands, demBandNames(options.compute));
    } catch (const InvalidInputError& e) {
        throw InvalidInputError(std::string("--bands: ") + e.what());
    }
}

/// The output's description (its TIFFTAG_IMAGEDESCRIPTION, and the PLY's comment): the
/// program, R, N, the input and what the bands and NaN mean.
std::string rasterDescription(const ComputeArgs& args, const std::string& input)
{
    std::ostringstream description;
    description << "msii " << versionString() << " compute R=" << args.radius << " N=" << args.scales << " of "
                << fs::path(input).filename().string() << "; " << featureLegend()
                << (args.border == "mask" ? "; NaN = nodata or ball reaches the border"
                                          : "; NaN = nodata; filled_share = share of the ball on continued or filled surface");
    return description.str();
}

/// The output's further metadata: the radii, the version and the input.
std::vector<std::pair<std::string, std::string>> rasterMetadata(const ComputeArgs& args, const std::string& input,
                                                                const std::string& output)
{
    std::ostringstream radii;
    for (int j = 1; j <= args.scales; ++j) radii << (j > 1 ? "," : "") << args.radius * j / args.scales;
    return {{"MSII_RADII", radii.str()},
            {"MSII_VERSION", versionString()},
            // Relative to the output's folder: found again when both move together.
            {"MSII_INPUT", fs::absolute(input).lexically_relative(fs::absolute(output).parent_path()).string()}};
}

/// Removes a file when it goes out of scope (the GeoTIFF a PLY output is written through).
struct RemoveOnExit {
    std::string path;
    ~RemoveOnExit()
    {
        if (!path.empty()) {
            std::error_code ec;
            fs::remove(path, ec);
        }
    }
};

/// computeDem, its errors worded for the command line: the option that chooses, and the
/// input's name first.
DemComputeResult computeDemWorded(const std::string& input, const std::string& rasterOutput,
                                  const DemComputeOptions& options, RunContext& progress)
{
    try {
        return computeDem(input, rasterOutput, options, &progress);
    } catch (const InvalidInputError& e) {
        std::string what = e.what();
        const std::string name = fs::path(input).filename().string();
        // The engine says what to choose; the command says with which option.
        if (const std::size_t at = what.find("choose the height band"); at != std::string::npos)
            what.insert(at + std::string("choose the height band").size(), " with --band");
        if (dynamic_cast<const MemoryLimitError*>(&e))
            what += " (--memory-budget sets the memory a window may take)";
        throw InvalidInputError(what.rfind(name, 0) == 0 ? what : name + ": " + what);
    }
}

/// A .ply output: the DEM's mesh with the raster's bands as vertex properties.
void writeRasterPly(const ComputeArgs& args, const std::string& rasterOutput, const std::string& output,
                    const std::string& description)
{
    FeatureMesh mesh = featureMeshFromRaster(rasterOutput);
    WritePlyOptions po;
    po.propertyPrefix = args.propertyPrefix;
    po.comments = mesh.comments;
    po.comments.push_back(description + " (quality: a plane's value where NaN)");
    qualityWithoutNaN(mesh.properties);
    writePly(output, mesh.mesh, mesh.properties, po);
}

/// The record's "raster": the grid, its cells, the bands and the windows computed.
nlohmann::json rasterRecord(const ComputeArgs& args, const DemComputeOptions& options, const DemComputeResult& result)
{
    const RasterGeoreference& grid = result.input.georeference;
    nlohmann::json raster = {{"width", grid.width},
                             {"height", grid.height},
                             {"geotransform", grid.transform},
                             {"crs", grid.crsName},
                             {"epsg", grid.epsg},
                             {"units", grid.units},
                             {"cells_with_height", result.input.numValid},
                             {"nodata_cells",
                              std::size_t(grid.width) * std::size_t(grid.height) - result.input.numValid},
                             {"bands", result.bands},
                             {"values", result.scaled16 ? "uint16, scale 1/65534 (1.5e-5), nodata 65535"
                                                        : "float32, nodata NaN"},
                             {"windows", {{"per_row", result.windowsPerRow}, {"per_column", result.windowsPerColumn},
                                          {"cells", result.windowCells}, {"halo_cells", result.haloCells},
                                          {"narrow_halo_cells", result.narrowHaloCells},
                                          {"windows_with_wide_halo", result.wideHaloWindows},
                                          {"windows_split_for_surface", result.splitWindows}}}};
    if (options.region.cols > 0)
        raster["tile_of_mosaic"] = {{"tile", args.tileOfMosaic},
                                    {"col", options.region.col},
                                    {"row", options.region.row},
                                    {"cols", options.region.cols},
                                    {"rows", options.region.rows}};
    return raster;
}

/// The JSON record written beside the output: the input, the parameters, the raster, the
/// route taken, the surface, the diagnostics and the stages' times.
nlohmann::json demRunRecord(const ComputeArgs& args, const std::string& input, const std::string& output,
                            const DemComputeOptions& options, const DemComputeResult& result, const Stopwatch& total)
{
    nlohmann::json j;
    j["program"] = "msii";
    j["version"] = versionString();
    j["command"] = "compute";
    j["input"] = {{"path", fs::absolute(input).string()}, {"format", "raster"}, {"band", result.input.band}};
    j["output"] = fs::absolute(output).string();
    j["parameters"] = parametersRecord(args, result.plan, invariantLetters(options.compute.invariants.selected()),
                                       args.fillHoles >= 0 ? args.fillHoles : defaultMaxHolePerimeter(args.radius));
    std::vector<std::string> computed;  // of those asked, the ones the bands need
    for (const Invariant i : result.computed) computed.push_back(std::string(1, invariantLetter(i)));
    j["parameters"]["invariants_computed"] = computed;
    j["raster"] = rasterRecord(args, options, result);
    j["engine"] = {{"asked", args.engine},
                   {"used", result.engine == DemEngine::HeightField ? "heights" : "mesh"},
                   {"note", result.engineNote}};
    j["mesh"] = {{"triangles", result.triangles},
                 {"masked_values", result.masked.total()},
                 {"cells_with_filled_share", result.masked.withFilledShare}};
    // On the height field, filled_share is computed only as a band.
    if (result.engine == DemEngine::HeightField &&
        std::find(result.bands.begin(), result.bands.end(), "filled_share") == result.bands.end())
        j["mesh"]["cells_with_filled_share"] = nullptr;
    addDiagnostics(j, result.diagnostics);
    if (const double peak = peakMemoryBytes(); peak > 0) j["peak_memory_bytes"] = peak;
    const InvariantsCost& t = result.cost;
    j["timings_seconds"] = {{"read", result.readSeconds}, {"prepare", result.prepareSeconds},
                            {"height_field", result.heightFieldSeconds}, {"check", t.check},
                            {"level_set", t.levelSet},     {"occupancy", t.occupancy},  {"stencils", t.stencils},
                            {"interpolation", t.interpolation}, {"samples", t.samples}, {"patch_line", t.patchLine},
                            {"patch_line_check", t.patchLineCheck}, {"patch_line_exact", t.patchLineExact},
                            {"write", result.writeSeconds}, {"total", total.seconds()}};
    if (t.patchLinePairs > 0) j["patch_line"] = patchLineRecord(t);
    return j;
}

/// The line on stderr that says what was written: the grid, the cells with heights, the
/// bands and the windows.
void printSummary(const std::string& input, const std::string& output, const DemComputeResult& result,
                  const Stopwatch& total)
{
    const RasterGeoreference& grid = result.input.georeference;
    const int windows = result.windowsPerRow * result.windowsPerColumn;
    const std::string split = result.splitWindows > 0 ? ", " + std::to_string(result.splitWindows) +
                                                            " split further for their spikes' surface"
                                                      : "";
    std::fprintf(stderr, "msii: %s -> %s (%d x %d cells, %zu with heights, %zu bands, %d window%s%s%s, %.1f s)\n",
                 input.c_str(), output.c_str(), grid.width, grid.height, result.input.numValid, result.bands.size(),
                 windows, windows == 1 ? "" : "s", split.c_str(), exactShareText(result.cost).c_str(), total.seconds());
}

} // namespace

OneResult computeRasterOne(const ComputeArgs& given, const std::string& input, const std::string& output)
{
    ComputeArgs args = given;
    args.scales = demScales(given, input);
    const Stopwatch total;
    refuseMeshOptions(args);
    DemComputeOptions options;
    options.compute = computeOptionsOf(args);
    parseBands(args, options);
    const std::string sidecar = sidecarPathFor(output);
    checkOutputs({output, sidecar}, args.overwrite);
    options.band = args.band;
    options.windowCells = args.windowCells;
    options.float32 = args.float32;
    options.engine = args.engine == "mesh" ? DemEngine::Mesh : DemEngine::HeightField;
    if (!args.tileOfMosaic.empty()) options.region = regionOfPart(input, args.tileOfMosaic);
    const std::string description = rasterDescription(args, input);
    options.output.description = description;
    options.output.metadata = rasterMetadata(args, input, output);

    // A .ply name: the DEM's mesh with the bands as vertex properties (as msii metric writes
    // one), through a GeoTIFF beside it that is removed once the PLY is written.
    const bool ply = fs::path(output).extension() == ".ply";
    const std::string rasterOutput = ply ? output + ".part.tif" : output;
    const RemoveOnExit removeRaster{ply ? rasterOutput : std::string()};
    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    const DemComputeResult result = computeDemWorded(input, rasterOutput, options, progress);
    if (ply) writeRasterPly(args, rasterOutput, output, description);
    if (!args.quiet)
        for (const Diagnostic& d : result.diagnostics)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), printableLine(worded(d)).c_str());
    const nlohmann::json j = demRunRecord(args, input, output, options, result, total);
    writeTextFileAtomic(sidecar, j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
    if (!args.quiet) printSummary(input, output, result, total);
    return {result.input.numValid, result.plan.voxelSize, total.seconds()};
}

} // namespace msii::tools
