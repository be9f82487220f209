/// `msii profile MESH`: the profile drawing of a vessel or a sherd, the section through its
/// axis of rotation, as SVG at a stated scale and as CSV (engine: vessels/profile_section.h);
/// with --plane, the section by any plane (docs/vessels.md).
#include "commands.h"
#include "feature_input.h"
#include "map_input.h"
#include "vessel_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/io/atomic_file.h>
#include <msii/io/read_mesh.h>
#include <msii/vessels/profile_section.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

namespace msii::tools {
namespace {

struct ProfileArgs : CommonArgs {
    std::string input, output, axis = "auto", through, plane, scale = "1:1", units;
};

Vec3 triple(const std::string& text, const char* option)
{
    const std::vector<double> v = parseNumberList(text, option);
    if (v.size() != 3) throw InvalidInputError(std::string(option) + " takes X,Y,Z (got '" + text + "')");
    return {v[0], v[1], v[2]};
}

/// "1:K" (or "K") to drawing units per mesh unit, 1/K.
double parseScale(const std::string& text)
{
    const std::string k = text.rfind("1:", 0) == 0 ? text.substr(2) : text;
    const std::vector<double> v = parseNumberList(k, "--scale");
    if (v.size() != 1 || !(v[0] > 0))
        throw InvalidInputError("--scale takes 1:K with K > 0, e.g. 1:2 (got '" + text + "')");
    return 1.0 / v[0];
}

std::string csvOf(const Section& s)
{
    std::ostringstream csv;
    csv.precision(9);
    csv << "line,x,y\n";
    for (std::size_t l = 0; l < s.lines.size(); ++l)
        for (const auto& p : s.lines[l].points) csv << l << ',' << p[0] << ',' << p[1] << '\n';
    return csv.str();
}

int runProfile(const ProfileArgs& args)
{
    const Stopwatch total;
    if (!args.plane.empty() && (args.axis != "auto" || !args.through.empty()))
        throw InvalidInputError("--plane cuts any plane: not with --axis or --through");
    const std::string svg = outputPath(args.input, args.output, "profile", args.overwrite, ".svg");
    const std::string csv = svg.substr(0, svg.size() - 4) + ".csv";
    checkOutputs({csv}, args.overwrite);
    const ReadMeshResult read = readMesh(args.input);
    const std::string fromFile = unitsFromComments(read.comments);
    ProfileDrawingOptions draw;
    draw.scale = parseScale(args.scale);
    draw.units = !args.units.empty() ? args.units : !fromFile.empty() ? fromFile : "mm";
    Section section;
    std::string said;
    if (!args.plane.empty()) {
        const std::size_t colon = args.plane.find(':');
        if (colon == std::string::npos)
            throw InvalidInputError("--plane takes PX,PY,PZ:NX,NY,NZ (a point and a normal)");
        const Vec3 point = triple(args.plane.substr(0, colon), "--plane"),
                   normal = triple(args.plane.substr(colon + 1), "--plane");
        section = planeSection(read.mesh, point, normal);
        said = "the plane through " + args.plane.substr(0, colon) + " with normal " + args.plane.substr(colon + 1);
    } else {
        const AxisOfRotation axis = axisFromOption(read.mesh, args.axis, said);
        const Vec3 through = args.through.empty() ? defaultThrough(read.mesh, axis) : triple(args.through, "--through");
        section = axisSection(read.mesh, axis, through);
        char text[160];
        std::snprintf(text, sizeof text, "the plane through the axis (%s) and %.6g,%.6g,%.6g", said.c_str(), through.x,
                      through.y, through.z);
        said = text;
        draw.axisX = 0.0;
        draw.rimDiameter = axis.rimDiameter;
    }
    draw.title = std::filesystem::path(args.input).filename().string();
    writeTextFileAtomic(csv, csvOf(section));
    writeProfileSvg(svg, section, draw);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s, %s (section by %s: %zu lines, %.4g %s long; %.1f s)\n",
                     args.input.c_str(), svg.c_str(), csv.c_str(), said.c_str(), section.lines.size(), section.length,
                     draw.units.c_str(), total.seconds());
    return 0;
}

}  // namespace

std::function<int()> addProfileCommand(CLI::App& app)
{
    auto args = std::make_shared<ProfileArgs>();
    CLI::App* cmd = app.add_subcommand(
        "profile", "The profile drawing of a vessel or a sherd: the section through its axis of rotation, as SVG at a "
                   "stated scale (the section, the axis dash-dot, the rim diameter, a scale bar) and as CSV (line,x,y: "
                   "x from the axis, y the height from the lowest point); --plane cuts any plane.");
    cmd->add_option("input", args->input, "Mesh or feature PLY (PLY, OBJ, OFF, STL)")->required();
    cmd->add_option("-o,--output", args->output, "Output SVG (default <input stem>.profile.svg; the CSV beside it)");
    cmd->add_option("--axis", args->axis,
                    "auto (fit it, as msii axis), PX,PY,PZ:DX,DY,DZ (a point and a direction) or an axis record "
                    "of msii axis (default auto)");
    cmd->add_option("--through", args->through,
                    "The plane goes through the axis and this point X,Y,Z; x is positive on its side (default: a "
                    "sherd's centroid, else the world axis most across the axis)");
    cmd->add_option("--plane", args->plane, "Any plane instead, PX,PY,PZ:NX,NY,NZ (a point and its normal)");
    cmd->add_option("--scale", args->scale, "The drawing's scale 1:K (default 1:1; the SVG's size is in mm)");
    cmd->add_option("--units", args->units,
                    "Units of the mesh, for the labels (default: what the PLY states, else mm)");
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runProfile(*args);
    };
}

}  // namespace msii::tools
