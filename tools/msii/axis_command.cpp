/// `msii axis MESH`: the axis of rotation of a vessel, a sherd or a cylinder seal, its shape
/// class and a vessel's rim diameter (engine: vessels/axis_of_rotation.h), printed and
/// recorded as JSON (docs/vessels.md).
#include "commands.h"
#include "feature_input.h"
#include "map_input.h"
#include "vessel_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/io/atomic_file.h>
#include <msii/io/read_mesh.h>

#include <cstdio>
#include <memory>

namespace msii::tools {
namespace {

struct AxisArgs : CommonArgs {
    std::string input, output, units;
};

int runAxis(const AxisArgs& args)
{
    const Stopwatch total;
    const std::string output = outputPath(args.input, args.output, "axis", args.overwrite, ".json");
    const ReadMeshResult read = readMesh(args.input);
    const std::string units = !args.units.empty()                         ? args.units
                              : !unitsFromComments(read.comments).empty() ? unitsFromComments(read.comments)
                                                                          : "mm";
    std::string said;
    const AxisOfRotation a = axisFromOption(read.mesh, "auto", said);
    nlohmann::json record = axisRecord(a, units);
    record["input"] = args.input;
    writeTextFileAtomic(output, record.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
    std::printf("axis: point %.6g %.6g %.6g, direction %.6f %.6f %.6f\n", a.point.x, a.point.y, a.point.z,
                a.direction.x, a.direction.y, a.direction.z);
    std::printf("shape: %s; residual %.3g %s; mean radius %.4g %s; height %.4g %s\n", revolutionShapeName(a.shape),
                a.residual, units.c_str(), a.meanRadius, units.c_str(), a.height, units.c_str());
    if (a.rimDiameter)
        std::printf("rim diameter: %.4g %s\n", *a.rimDiameter, units.c_str());
    else
        std::printf("rim diameter: none (no rim)\n");
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%.1f s)\n", args.input.c_str(), output.c_str(), total.seconds());
    return 0;
}

}  // namespace

std::function<int()> addAxisCommand(CLI::App& app)
{
    auto args = std::make_shared<AxisArgs>();
    CLI::App* cmd = app.add_subcommand(
        "axis", "The axis of rotation of a vessel, a sherd or a cylinder seal (a robust fit of the surface's normal "
                "lines, refined on the profile), the shape that fits best (cylinder, cone or surface of revolution), "
                "and a vessel's rim diameter; printed, and recorded as JSON.");
    cmd->add_option("input", args->input, "Mesh or feature PLY (PLY, OBJ, OFF, STL)")->required();
    cmd->add_option("-o,--output", args->output, "Output JSON (default <input stem>.axis.json)");
    cmd->add_option("--units", args->units,
                    "Units of the mesh, for the record (default: what the PLY states, else mm)");
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runAxis(*args);
    };
}

}  // namespace msii::tools
