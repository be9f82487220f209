/// `msii compute`'s JSON record next to each output (docs/formats.md, The JSON record).
#include "compute_args.h"

#include <msii/core/version.h>

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

void addDiagnostics(nlohmann::json& record, const std::vector<const std::vector<Diagnostic>*>& lists)
{
    // Coded (kind, count, figures) for programs, and the sentences as printed.
    record["diagnostics"] = nlohmann::json::array();
    record["warnings"] = nlohmann::json::array();
    for (const std::vector<Diagnostic>* list : lists)
        for (const Diagnostic& d : *list) {
            nlohmann::json figures = nlohmann::json::object();
            for (const auto& [name, value] : d.figures) figures[name] = value;
            record["diagnostics"].push_back(
                {{"kind", d.kind}, {"count", d.count}, {"figures", figures}, {"message", d.message}});
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
            {"levels", plan.numVolumeSphereLevels()},
            {"level_of_radius", plan.volumeSphereLevels},
            {"sample_level_of_radius", plan.patchLineLevels},
            {"reach", plan.reach},
            {"invariants", invariants},
            {"mode", args.exact ? "exact" : "fast"},
            {"repair", !args.strict},
            {"max_hole_perimeter", maxHolePerimeter},
            {"threads", args.threads},
            {"units", args.units}};
}

nlohmann::json runRecord(const MeshRunRecord& r)
{
    const ComputeArgs& args = r.args;
    const ScalePlan& plan = r.result.plan;
    const InvariantsResult& result = r.result;
    const PrepareMeshResult& prepared = r.prepared;
    nlohmann::json j;
    j["program"] = "msii";
    j["version"] = versionString();
    j["command"] = "compute";
    j["input"] = {{"path", fs::absolute(r.input).string()}, {"format", r.read.format}};
    j["output"] = fs::absolute(r.output).string();
    j["parameters"] = parametersRecord(args, plan, r.letters, r.prepareOptions.maxHolePerimeter);
    j["parameters"]["band_half_width_voxels"] = result.cost.bandHalfWidth;
    j["parameters"]["exact_vertices"] = r.options.exactVertices.size();
    j["conventions"] = {{"V", "V/|B_r| in [0,1], flat plane 0.5, convex < 0.5"},
                        {"S", "S/(4 pi r^2) in [0,1], flat plane 0.5, convex < 0.5"},
                        {"P", "P/(pi r^2), flat plane 1"},
                        {"L", "L/(2 pi r), flat plane 1"},
                        {"order", "radius ascending: V_01 = r_1 = R/N ... V_NN = R"},
                        {"quality", r.qualityName.substr(0, 1) +
                                        " (the first of V, S, P, L computed) at the largest radius with a value; "
                                        "a plane's value (V, S 0.5; P, L 1) where none has one; never NaN"},
                        {"valid_radii", "how many radii have a value of the quality's invariant (0 to N)"},
                        {"masked", args.exact ? "NaN where the ball reaches a mesh border, and at vertices not computed"
                                              : "NaN where the ball of that radius reaches a mesh border"}};
    const auto& st = result.stats;
    j["mesh"] = {{"vertices", r.read.mesh.numVertices()},
                 {"faces", r.inputFaces},
                 {"faces_in_file", r.inputFaces},
                 {"faces_removed", [&] {
                      std::size_t removed = 0;
                      for (const Diagnostic& c : prepared.changes)
                          if (c.kind == "degenerate_faces_removed" || c.kind == "duplicate_faces_removed" ||
                              c.kind == "non_manifold_faces_removed")
                              removed += c.count;
                      return removed;
                  }()},
                 {"closed", result.check.closed},
                 {"border_edges", result.check.numBorderEdges},
                 {"bbox_min", {st.bboxMin.x, st.bboxMin.y, st.bboxMin.z}},
                 {"bbox_max", {st.bboxMax.x, st.bboxMax.y, st.bboxMax.z}},
                 {"diagonal", st.diagonal},
                 {"edge_length", {{"min", st.minEdge}, {"median", st.medianEdge}, {"mean", st.meanEdge}, {"max", st.maxEdge}}},
                 {"area", st.area},
                 {"masked_values", result.cost.maskedValues}};
    j["level_set"] = {{"active_voxels", result.cost.levelSetVoxels}, {"bytes", result.cost.levelSetBytes}};
    if (const double peak = peakMemoryBytes(); peak > 0) j["peak_memory_bytes"] = peak;
    const InvariantsCost& t = result.cost;
    j["timings_seconds"] = {{"read", r.readSeconds},     {"prepare", r.prepareSeconds}, {"check", t.check},
                            {"level_set", t.levelSet}, {"occupancy", t.occupancy},
                            {"stencils", t.stencils},  {"interpolation", t.interpolation},
                            {"samples", t.samples},    {"patch_line", t.patchLine},
                            {"exact", t.exact},        {"write", r.writeSeconds},
                            {"total", r.totalSeconds}};
    if (r.tiled)
        j["tiling"] = {{"tiles_per_axis", r.tiledInfo.tilesPerAxis},
                       {"tiles", r.tiledInfo.tiles},
                       {"largest_tile_vertices", r.tiledInfo.largestTileVertices},
                       {"halo", r.tiledInfo.haloWidth},
                       {"estimated_peak_bytes", r.tiledInfo.estimatedPeakBytes}};
    j["preparation"] = {
        {"changes", [&] {
             nlohmann::json list = nlohmann::json::array();
             for (const Diagnostic& c : prepared.changes)
                 list.push_back({{"kind", c.kind}, {"count", c.count}, {"message", c.message}});
             return list;
         }()},
        {"holes", {{"filled", prepared.holes.numFilled},
                   {"largest_perimeter", prepared.holes.largestPerimeter},
                   {"area_added", prepared.holes.areaAdded},
                   {"left_open_too_large", prepared.holes.numTooLarge},
                   {"left_open_outer_border", prepared.holes.numOuterBorders},
                   {"not_filled_failed", prepared.holes.numFailed},
                   {"max_perimeter", r.prepareOptions.maxHolePerimeter}}},
        {"isolated_vertices", prepared.numIsolatedVertices},
        {"prepared_vertices", prepared.mesh.numVertices()},
        {"prepared_faces", prepared.mesh.numTriangles()}};
    addDiagnostics(j, {&prepared.changes, &result.diagnostics});
    return j;
}

} // namespace msii::tools
