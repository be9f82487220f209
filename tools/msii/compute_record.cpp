/// `msii compute`'s JSON record next to each output (docs/formats.md, The JSON record).
#include "compute_args.h"

#include <msii/core/version.h>
#include <msii/io/feature_properties.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace msii::tools {

double peakMemoryBytes()
{
    // Linux's VmHWM: of this program only, unlike getrusage, which counts what a parent held
    // when it started the program.
    std::ifstream status("/proc/self/status");
    for (std::string line; std::getline(status, line);)
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) * 1024.0;
    return 0;
}

void addDiagnostics(nlohmann::json& record, const std::vector<Diagnostic>& diagnostics)
{
    // Coded (kind, count, figures) for programs, and the sentences as printed.
    record["diagnostics"] = nlohmann::json::array();
    record["warnings"] = nlohmann::json::array();
    for (const Diagnostic& d : diagnostics) {
        nlohmann::json figures = nlohmann::json::object();
        for (const auto& [name, value] : d.figures) figures[name] = value;
        record["diagnostics"].push_back({{"kind", d.kind}, {"count", d.count}, {"figures", figures}, {"message", d.message}});
        record["warnings"].push_back(worded(d));
    }
}

nlohmann::json parametersRecord(const ComputeArgs& args, const ScalePlan& plan, const std::string& letters,
                                double maxHolePerimeter)
{
    nlohmann::json invariants = nlohmann::json::array();
    for (char c : letters) invariants.push_back(std::string(1, c));
    return {{"radius", args.radius},
            {"scales", plan.radii.size()},
            {"radii", plan.radii},
            {"voxel_size", plan.voxelSize},
            {"voxel_size_requested", args.voxelSize},
            {"precision_voxels_per_radius", args.precision},
            {"precision_patch_line", plPrecisionOf(args)},
            {"pl_check", args.plCheck},
            {"levels", plan.numVolumeSphereLevels()},
            {"level_of_radius", plan.volumeSphereLevels},
            {"sample_level_of_radius", plan.patchLineLevels},
            {"reach", plan.reach},
            {"invariants", invariants},
            {"mode", args.exact ? "exact" : "fast"},
            {"repair", !args.strict},
            {"max_hole_perimeter", maxHolePerimeter},
            {"border", args.border},
            {"threads", args.threads},
            {"units", args.units}};
}

namespace {

/// The record's `conventions`: how the features are normalised and ordered.
nlohmann::json conventions(const ComputeArgs& args, const std::vector<Invariant>& invariants)
{
    const std::string quality(1, invariantLetter(invariants.front()));  // featureProperties' choice
    nlohmann::json j;
    for (Invariant i : kAllInvariants) j[std::string(1, invariantLetter(i))] = invariantConvention(i);
    j["order"] = "radius ascending: V_01 = r_1 = R/N ... V_NN = R";
    j["quality"] = quality + " (the first of V, S, P, L computed) at the largest radius with a value; "
                             "a plane's value (V, S 0.5; P, L 1) where none has one; never NaN";
    j["valid_radii"] = "how many radii have a value of the quality's invariant (0 to N)";
    if (args.border == "mask")
        j["masked"] = args.exact ? "NaN where the ball reaches a mesh border, and at vertices not computed"
                                 : "NaN where the ball of that radius reaches a mesh border";
    else
        j["masked"] = args.exact ? "NaN at vertices not computed" : "none: the surface is continued past its borders";
    j["filled_share"] = "share of the largest ball's surface not in the input (filled holes and the continuation "
                        "past borders), area / (pi R^2), at most 1";
    return j;
}

/// The record's `mesh`: the input's counts and the prepared mesh's statistics.
nlohmann::json meshRecord(const MeshRunRecord& r)
{
    const ComputeResult& result = r.result;
    const MeshStats& st = result.stats;
    std::size_t removed = 0;
    for (const Diagnostic& c : result.preparation.changes)
        if (c.kind == "degenerate_faces_removed" || c.kind == "duplicate_faces_removed" ||
            c.kind == "non_manifold_faces_removed")
            removed += c.count;
    const std::size_t faces = r.read.mesh.numTriangles();
    return {{"vertices", r.read.mesh.numVertices()},
            {"faces", faces},
            {"faces_in_file", faces},
            {"faces_removed", removed},
            {"closed", result.check.closed},
            {"border_edges", result.check.numBorderEdges},
            {"bbox_min", {st.bboxMin.x, st.bboxMin.y, st.bboxMin.z}},
            {"bbox_max", {st.bboxMax.x, st.bboxMax.y, st.bboxMax.z}},
            {"diagonal", st.diagonal},
            {"edge_length", {{"min", st.minEdge}, {"median", st.medianEdge}, {"mean", st.meanEdge}, {"max", st.maxEdge}}},
            {"area", st.area},
            {"masked_values", result.masked.total()},
            {"vertices_with_filled_share", result.masked.withFilledShare}};
}

/// The record's `preparation`: what was repaired and filled.
nlohmann::json preparationRecord(const PreparationSummary& p)
{
    nlohmann::json changes = nlohmann::json::array();
    for (const Diagnostic& c : p.changes) changes.push_back({{"kind", c.kind}, {"count", c.count}, {"message", c.message}});
    return {{"changes", changes},
            {"holes", {{"filled", p.holes.numFilled},
                       {"largest_perimeter", p.holes.largestPerimeter},
                       {"area_added", p.holes.areaAdded},
                       {"left_open_too_large", p.holes.numTooLarge},
                       {"left_open_outer_border", p.holes.numOuterBorders},
                       {"not_filled_failed", p.holes.numFailed},
                       {"max_perimeter", p.maxHolePerimeter}}},
            {"borders_continued", {{"borders", p.borders.numChains},
                                   {"border_vertices", p.borders.numBorderVertices},
                                   {"columns_trimmed", p.borders.numTrimmed},
                                   {"area_added", p.borders.areaAdded}}},
            {"isolated_vertices", p.isolatedVertices},
            {"prepared_vertices", p.vertices},
            {"prepared_faces", p.faces}};
}

} // namespace

nlohmann::json patchLineRecord(const InvariantsCost& cost)
{
    return {{"pairs", cost.patchLinePairs},
            {"pairs_exact", cost.patchLinePairsExact},
            {"share_exact", double(cost.patchLinePairsExact) / double(std::max<std::size_t>(1, cost.patchLinePairs))},
            {"vertices_exact", cost.patchLineVerticesExact}};
}

std::string exactShareText(const InvariantsCost& cost)
{
    if (cost.patchLinePairs == 0) return "";
    char text[96];
    std::snprintf(text, sizeof(text), ", P and L exact at %.1f %% of values",
                  100.0 * double(cost.patchLinePairsExact) / double(cost.patchLinePairs));
    return text;
}

nlohmann::json runRecord(const MeshRunRecord& r)
{
    const ComputeArgs& args = r.args;
    const ComputeResult& result = r.result;
    nlohmann::json j;
    j["program"] = "msii";
    j["version"] = versionString();
    j["command"] = "compute";
    j["input"] = {{"path", fs::absolute(r.input).string()}, {"format", r.read.format}};
    j["output"] = fs::absolute(r.output).string();
    j["parameters"] = parametersRecord(args, result.plan, invariantLetters(r.options.invariants.selected()),
                                       result.preparation.maxHolePerimeter);
    j["parameters"]["band_half_width_voxels"] = result.cost.bandHalfWidth;
    j["parameters"]["exact_vertices"] = r.options.invariants.exactVertices.size();
    j["conventions"] = conventions(args, r.options.invariants.selected());
    j["mesh"] = meshRecord(r);
    j["level_set"] = {{"active_voxels", result.cost.levelSetVoxels}, {"bytes", result.cost.levelSetBytes}};
    if (const double peak = peakMemoryBytes(); peak > 0) j["peak_memory_bytes"] = peak;
    const InvariantsCost& t = result.cost;
    j["timings_seconds"] = {{"read", r.readSeconds},     {"prepare", result.preparation.seconds}, {"check", t.check},
                            {"level_set", t.levelSet}, {"occupancy", t.occupancy},
                            {"stencils", t.stencils},  {"interpolation", t.interpolation},
                            {"samples", t.samples},    {"patch_line", t.patchLine},
                            {"patch_line_check", t.patchLineCheck}, {"patch_line_exact", t.patchLineExact},
                            {"exact", t.exact},        {"write", r.writeSeconds},
                            {"total", r.totalSeconds}};
    if (t.patchLinePairs > 0) j["patch_line"] = patchLineRecord(t);
    if (result.tiled)
        j["tiling"] = {{"tiles_per_axis", result.tiling.tilesPerAxis},
                       {"tiles", result.tiling.tiles},
                       {"largest_tile_vertices", result.tiling.largestTileVertices},
                       {"halo", result.tiling.haloWidth},
                       {"estimated_peak_bytes", result.tiling.estimatedPeakBytes}};
    j["preparation"] = preparationRecord(result.preparation);
    addDiagnostics(j, result.diagnostics);
    return j;
}

} // namespace msii::tools
