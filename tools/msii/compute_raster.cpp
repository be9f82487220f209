/// `msii compute` on a raster (DEM): heights through GDAL, triangulated at the cell centres,
/// prepared and computed as any mesh, and the chosen features written back as a
/// Cloud-Optimized GeoTIFF on the input's grid (docs/terrain.md).
#include "compute_args.h"

#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/terminal_progress.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/raster_output.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace msii::tools {

namespace {

/// The bands asked for (--bands), from the per-vertex properties of the result.
std::vector<const VertexProperty*> chooseBands(const std::vector<VertexProperty>& props, const std::string& list,
                                               const FeatureSet& features)
{
    std::vector<const VertexProperty*> out;
    const auto find = [&](const std::string& name) -> const VertexProperty* {
        for (const VertexProperty& p : props)
            if (p.name == name) return &p;
        return nullptr;
    };
    if (list.empty()) {  // V at every radius (or the first invariant computed) and quality
        const std::vector<Invariant> present = features.invariants();
        const char letter = invariantLetter(present.front());
        for (std::size_t j = 0; j < features[present.front()].size(); ++j) out.push_back(find(featureName(letter, j)));
        out.push_back(find("quality"));
        return out;
    }
    std::stringstream in(list);
    std::string item;
    while (std::getline(in, item, ',')) {
        item.erase(0, item.find_first_not_of(" \t"));
        item.erase(item.find_last_not_of(" \t") + 1);
        if (item.empty()) continue;
        const VertexProperty* p = find(item);
        if (!p) {
            std::string names;
            for (const VertexProperty& q : props) names += (names.empty() ? "" : ", ") + q.name;
            throw InvalidInputError("--bands: no feature '" + item + "' (there are " + names + ")");
        }
        out.push_back(p);
    }
    if (out.empty()) throw InvalidInputError("--bands selects nothing");
    return out;
}

} // namespace

OneResult computeRasterOne(const ComputeArgs& args, const std::string& input, const std::string& output)
{
    const Stopwatch total;
    const Selection sel = parseInvariants(args);
    if (args.exact) throw InvalidInputError("--exact is for meshes; for a DEM, compute its mesh (msii-samples writes none: use the fast mode)");
    if (args.gigamesh) throw InvalidInputError("--gigamesh is for meshes, not rasters");
    const std::string sidecar = sidecarPathFor(output);
    for (const std::string& path : {output, sidecar}) {
        if (!args.overwrite && fs::exists(path))
            throw IOError("'" + path + "' exists already (use --overwrite to replace it)");
        checkWritable(path);
    }
    const std::string name = fs::path(input).filename().string();

    DemReadOptions readOptions;
    readOptions.band = args.band;
    const Dem dem = readDem(input, readOptions);
    const RasterGeoreference& grid = dem.georeference;
    const DemMesh dm = demToMesh(dem);
    if (dm.mesh.numTriangles() == 0)
        throw InvalidInputError(name + ": no 2 x 2 block of cells has heights, so there is no surface to compute on");
    const double readSeconds = total.seconds();

    const Stopwatch prepareWatch;
    PrepareMeshOptions prepareOptions;
    prepareOptions.repair = true;  // a grid's mesh needs none; holes are filled as for scans
    prepareOptions.maxHolePerimeter = args.fillHoles >= 0 ? args.fillHoles : defaultMaxHolePerimeter(args.radius);
    prepareOptions.radius = args.radius;
    PrepareMeshResult prepared;
    try {
        prepared = prepareMesh(dm.mesh, prepareOptions);
    } catch (const InvalidInputError& e) {
        throw InvalidInputError(name + ": " + e.what());
    }
    const double prepareSeconds = prepareWatch.seconds();

    InvariantsOptions options;
    setInvariantsOptions(args, sel, options);
    if (!args.memoryBudget.empty() || args.tiles > 0) {
        options.tilesPerAxis = args.tiles;
        if (args.tiles <= 0) throw InvalidInputError("raster inputs take --tiles K (a memory budget is not supported yet)");
    }
    TerminalProgress terminal(!args.quiet && stderrIsTerminal());
    RunContext progress(terminal.listener());
    InvariantsResult result;
    try {
        result = computeInvariants(prepared.mesh, options, &progress);
    } catch (const InvalidInputError& e) {
        throw InvalidInputError(name + ": " + e.what());
    }
    if (!args.quiet) {
        for (const Diagnostic& d : prepared.changes)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), worded(d).c_str());
        for (const Diagnostic& d : result.diagnostics)
            std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), worded(d).c_str());
    }

    // Per vertex of the prepared mesh → per DEM vertex → per cell.
    const Stopwatch write;
    std::vector<VertexProperty> props = featureProperties(result.features);
    props.push_back({"filled_share", prepared.filledShare});
    std::vector<RasterBand> bands;
    for (const VertexProperty* p : chooseBands(props, args.bands, result.features))
        bands.push_back({p->name, toCells(dm, toInputVertices(prepared, p->values))});
    props.clear();
    std::ostringstream description;
    description << "msii " << versionString() << " compute R=" << args.radius << " N=" << result.plan.radii.size()
                << " voxel=" << result.plan.voxelSize << " of " << name
                << "; V_jj = V/|B_r|, S_jj = S/(4 pi r^2) (plane 0.5), P_jj = P/(pi r^2), L_jj = L/(2 pi r) (plane 1), "
                   "r_j = j*R/N; NaN = nodata or ball reaches the border";
    RasterOutputOptions ro;
    ro.description = description.str();
    std::ostringstream radii;
    for (std::size_t j = 0; j < result.plan.radii.size(); ++j) radii << (j ? "," : "") << result.plan.radii[j];
    ro.metadata = {{"MSII_RADII", radii.str()}, {"MSII_UNITS", grid.units}, {"MSII_VERSION", versionString()}};
    writeRaster(output, grid, bands, ro);
    const double writeSeconds = write.seconds();

    nlohmann::json j;
    j["program"] = "msii";
    j["version"] = versionString();
    j["command"] = "compute";
    j["input"] = {{"path", fs::absolute(input).string()}, {"format", "raster"}, {"band", dem.band}};
    j["output"] = fs::absolute(output).string();
    j["parameters"] = {{"radius", args.radius},
                       {"scales", result.plan.radii.size()},
                       {"radii", result.plan.radii},
                       {"voxel_size", result.plan.voxelSize},
                       {"voxel_size_requested", args.voxelSize},
                       {"precision_voxels_per_radius", args.precision},
                       {"precision_patch_line", plPrecisionOf(args)},
                       {"levels", result.plan.numVolumeSphereLevels()},
                       {"level_of_radius", result.plan.volumeSphereLevels},
                       {"sample_level_of_radius", result.plan.patchLineLevels},
                       {"reach", result.plan.reach},
                       {"invariants", args.invariants},
                       {"mode", "fast"},
                       {"repair", true},
                       {"max_hole_perimeter", prepareOptions.maxHolePerimeter},
                       {"threads", args.threads}};
    j["raster"] = {{"width", grid.width},
                   {"height", grid.height},
                   {"geotransform", grid.transform},
                   {"crs", grid.crsName},
                   {"epsg", grid.epsg},
                   {"units", grid.units},
                   {"cells_with_height", dem.numValid},
                   {"nodata_cells", dem.heights.size() - dem.numValid},
                   {"bands", [&] {
                        nlohmann::json list = nlohmann::json::array();
                        for (const RasterBand& b : bands) list.push_back(b.name);
                        return list;
                    }()}};
    j["mesh"] = {{"vertices", dm.mesh.numVertices()},
                 {"faces", dm.mesh.numTriangles()},
                 {"prepared_vertices", prepared.mesh.numVertices()},
                 {"closed", result.check.closed},
                 {"masked_values", result.cost.maskedValues}};
    j["diagnostics"] = nlohmann::json::array();
    j["warnings"] = nlohmann::json::array();
    for (const std::vector<Diagnostic>* list : {&prepared.changes, &result.diagnostics})
        for (const Diagnostic& d : *list) {
            nlohmann::json figures = nlohmann::json::object();
            for (const auto& [key, value] : d.figures) figures[key] = value;
            j["diagnostics"].push_back({{"kind", d.kind}, {"count", d.count}, {"figures", figures}, {"message", d.message}});
            j["warnings"].push_back(worded(d));
        }
    if (std::ifstream status("/proc/self/status"); status) {
        for (std::string line; std::getline(status, line);)
            if (line.rfind("VmHWM:", 0) == 0) j["peak_memory_bytes"] = std::stod(line.substr(6)) * 1024.0;
    }
    const InvariantsCost& t = result.cost;
    j["timings_seconds"] = {{"read", readSeconds},         {"prepare", prepareSeconds}, {"check", t.check},
                            {"level_set", t.levelSet},     {"occupancy", t.occupancy},  {"stencils", t.stencils},
                            {"interpolation", t.interpolation}, {"samples", t.samples}, {"patch_line", t.patchLine},
                            {"write", writeSeconds},       {"total", total.seconds()}};
    writeTextFileAtomic(sidecar, j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%d x %d cells, %zu with heights, %zu bands, %.1f s)\n", input.c_str(),
                     output.c_str(), grid.width, grid.height, dem.numValid, bands.size(), total.seconds());
    return {dm.mesh.numVertices(), result.plan.voxelSize, total.seconds()};
}

} // namespace msii::tools
