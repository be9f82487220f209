/// `msii unroll INPUT`: the surface of a vessel, a column or a cylinder seal laid onto the
/// plane around its axis (engine: vessels/unroll.h), as a PLY whose vertex i is the input's
/// vertex i with all its properties, and a JSON record (docs/vessels.md).
#include "commands.h"
#include "feature_input.h"
#include "map_input.h"
#include "vessel_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/write_ply.h>
#include <msii/vessels/unroll.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace msii::tools {
namespace {

struct UnrollArgs : CommonArgs {
    std::vector<std::string> matFiles;
    std::string input, output, axis = "auto", shape = "auto", cutThrough;
    bool impression = false;
};

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

/// auto: a cone where the fitted cone fits the outer wall clearly better (within four fifths
/// of the cylinder's misfit), else a cylinder.
UnrollShape shapeOf(const std::string& option, const AxisOfRotation& axis)
{
    if (option == "cylinder") return UnrollShape::Cylinder;
    if (option == "cone") return UnrollShape::Cone;
    return axis.coneMisfit < 0.8 * axis.cylinderMisfit && std::abs(axis.coneSlope) > 1e-3 ? UnrollShape::Cone
                                                                                          : UnrollShape::Cylinder;
}

nlohmann::json unrollRecord(const UnrollArgs& args, const AxisOfRotation& axis, const Unrolled& u,
                            std::size_t inputVertices)
{
    nlohmann::json r;
    r["input"] = args.input;
    r["shape"] = u.shape == UnrollShape::Cylinder ? "cylinder" : "cone";
    if (u.shape == UnrollShape::Cylinder)
        r["radius"] = u.radius;
    else
        r["cone"] = {{"half_angle_degrees", u.halfAngle * kDegrees},
                     {"apex",
                      {axis.point.x + axis.direction.x * u.apexHeight, axis.point.y + axis.direction.y * u.apexHeight,
                       axis.point.z + axis.direction.z * u.apexHeight}}};
    r["seam"] = {{"point", {u.seamPoint.x, u.seamPoint.y, u.seamPoint.z}}, {"angle_degrees", u.seamAngle * kDegrees}};
    r["axis"] = axisRecord(axis, "");
    r["impression"] = args.impression;
    r["distortion"] = {
        {"largest", u.maxDistortion}, {"percentile_99", u.distortion99}, {"edges_measured", u.edgesMeasured}};
    r["vertices"] = {{"input", inputVertices}, {"seam_copies", u.copyOf.size()}};
    r["triangles_left_out_at_the_axis"] = u.trianglesLeftOut;
    return r;
}

int runUnroll(const UnrollArgs& args)
{
    const Stopwatch total;
    if (args.shape != "auto" && args.shape != "cylinder" && args.shape != "cone")
        throw InvalidInputError("--shape takes auto, cylinder or cone (got '" + args.shape + "')");
    const std::string output = outputPath(args.input, args.output, "roll", args.overwrite, ".ply");
    const std::string json = output.substr(0, output.size() - 4) + ".json";
    checkOutputs({json}, args.overwrite);
    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);
    std::string said;
    const AxisOfRotation axis = axisFromOption(in.mesh, args.axis, said);
    UnrollOptions o;
    o.shape = shapeOf(args.shape, axis);
    o.impression = args.impression;
    if (!args.cutThrough.empty()) {
        const std::vector<double> p = parseNumberList(args.cutThrough, "--cut-through");
        if (p.size() != 3) throw InvalidInputError("--cut-through takes X,Y,Z (got '" + args.cutThrough + "')");
        o.cutThrough = Vec3(p[0], p[1], p[2]);
    }
    const Unrolled u = unrollSurface(in.mesh, axis, o);
    // Every property carries over; the seam's copies take their originals' values.
    for (VertexProperty& p : in.properties)
        for (std::uint32_t i : u.copyOf) p.values.push_back(p.values[i]);
    WritePlyOptions po;
    po.comments = in.comments;
    po.comments.push_back(std::string("msii ") + versionString() + " unroll " +
                          (o.shape == UnrollShape::Cylinder ? "cylinder" : "cone") +
                          (o.impression ? " impression" : ""));
    // The record's text first: nothing is written if it cannot be made.
    const std::string record = unrollRecord(args, axis, u, in.mesh.numVertices())
                                   .dump(2, ' ', false, nlohmann::json::error_handler_t::replace) +
                               "\n";
    writePly(output, u.mesh, in.properties, po);
    writeTextFileAtomic(json, record);
    if (!args.quiet)
        std::fprintf(stderr,
                     "msii: %s -> %s (%s, axis %s, seam %.1f degrees, %zu seam copies; length distortion up to %.2g "
                     "%%, 99 %% within %.2g %%; %.1f s)\n",
                     args.input.c_str(), output.c_str(), o.shape == UnrollShape::Cylinder ? "cylinder" : "cone",
                     said.c_str(), u.seamAngle * kDegrees, u.copyOf.size(), 100 * u.maxDistortion, 100 * u.distortion99,
                     total.seconds());
    return 0;
}

}  // namespace

std::function<int()> addUnrollCommand(CLI::App& app)
{
    auto args = std::make_shared<UnrollArgs>();
    CLI::App* cmd = app.add_subcommand(
        "unroll",
        "The surface laid onto the plane around its axis of rotation (a vessel's decoration, a column, a "
        "cylinder seal's rollout): a cylinder to x = R theta, y = height; a cone to its exact development; "
        "z the relief. A PLY with the input's vertices in order and all their properties, and a JSON record.");
    cmd->add_option("input", args->input, "Mesh or feature PLY (PLY, OBJ, OFF, STL)")->required();
    cmd->add_option("-o,--output", args->output, "Output PLY (default <input stem>.roll.ply; the record beside it)");
    cmd->add_option("--mat", args->matFiles, "GigaMesh feature file(s) for the input mesh");
    cmd->add_option("--axis", args->axis,
                    "auto (fit it, as msii axis), PX,PY,PZ:DX,DY,DZ or an axis record of msii axis (default auto)");
    cmd->add_option("--shape", args->shape,
                    "auto (a cone where one fits the outer wall clearly better than a cylinder), cylinder or cone");
    cmd->add_option(
        "--cut-through", args->cutThrough,
        "The seam runs along the surface's line through this point X,Y,Z (default: the axis frame's angle 0, "
        "stated in the record)");
    cmd->add_flag("--impression", args->impression,
                  "The impression the surface leaves rolled over clay: the rollout mirrored, its relief inverted");
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runUnroll(*args);
    };
}

}  // namespace msii::tools
