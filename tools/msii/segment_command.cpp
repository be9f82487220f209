/// `msii segment INPUT.ply --threshold T`: connected components of a thresholded per-vertex
/// value (labels and a table), e.g. the wedges of a tablet.
#include "commands.h"
#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/write_ply.h>
#include <msii/segmentation/components.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

namespace msii::tools {

namespace {

namespace fs = std::filesystem;

struct SegmentArgs : CommonArgs {
    std::string input, output, table;
    std::vector<std::string> matFiles;
    std::string property = "quality";
    double threshold = NAN;
    bool below = false;
    long long minVertices = 1;
    double minArea = 0;
};

int runSegment(const SegmentArgs& args)
{
    const Stopwatch total;
    if (!std::isfinite(args.threshold)) throw InvalidInputError("--threshold must be a finite number");
    if (args.minVertices < 1) throw InvalidInputError("--min-vertices must be at least 1");
    if (!(args.minArea >= 0) || !std::isfinite(args.minArea)) throw InvalidInputError("--min-area must be 0 or more");
    const std::string output = outputPath(args.input, args.output, "segments", args.overwrite);
    std::string table = args.table;
    if (table.empty()) table = (fs::path(output).parent_path() / (fs::path(output).stem().string() + ".csv")).string();
    if (fs::path(table).extension() != ".csv") throw InvalidInputError("the table '" + table + "' must be a .csv file");
    checkOutputs({table}, args.overwrite);
    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);
    const VertexProperty& f = in.properties[findProperty(in, args.property)];

    ComponentOptions options;
    options.threshold = args.threshold;
    options.below = args.below;
    options.minVertices = std::size_t(args.minVertices);
    options.minArea = args.minArea;
    const ComponentResult result = findComponents(in.mesh, f.values, options);

    std::ostringstream csv;
    csv.precision(9);
    csv << "label,vertices,area,centroid_x,centroid_y,centroid_z,min_x,min_y,min_z,max_x,max_y,max_z\n";
    for (const Component& c : result.components)
        csv << c.label << ',' << c.vertices << ',' << c.area << ',' << c.centroid.x << ',' << c.centroid.y << ','
            << c.centroid.z << ',' << c.boxMin.x << ',' << c.boxMin.y << ',' << c.boxMin.z << ',' << c.boxMax.x
            << ',' << c.boxMax.y << ',' << c.boxMax.z << '\n';

    VertexProperty label{"label", std::vector<float>(in.mesh.numVertices()), /*integer=*/true};
    for (std::size_t i = 0; i < label.values.size(); ++i) label.values[i] = float(result.label[i]);
    for (auto it = in.properties.begin(); it != in.properties.end(); ++it)
        if (it->name == "label") {
            in.properties.erase(it);
            break;
        }
    in.properties.push_back(std::move(label));
    WritePlyOptions plyOptions;
    plyOptions.propertyPrefix = args.propertyPrefix;
    std::ostringstream comment;
    comment << "msii " << versionString() << " segment --property " << args.property << " --threshold "
            << args.threshold << (args.below ? " --below" : "") << " --min-vertices " << args.minVertices
            << " --min-area " << args.minArea << "; label = component (1 = largest area), 0 = none";
    plyOptions.comments = in.comments;  // keep the provenance (e.g. compute's R and N)
    plyOptions.comments.push_back(comment.str());
    writeTextFileAtomic(table, csv.str());
    qualityWithoutNaN(in.properties);
    writePly(output, in.mesh, in.properties, plyOptions);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s, %s (%zu components, %zu smaller ones dropped, %.1f s)\n",
                     args.input.c_str(), output.c_str(), table.c_str(), result.components.size(),
                     result.droppedComponents, total.seconds());
    return 0;
}

} // namespace

std::function<int()> addSegmentCommand(CLI::App& app)
{
    auto args = std::make_shared<SegmentArgs>();
    CLI::App* cmd = app.add_subcommand(
        "segment", "Connected components of the vertices whose value passes a threshold (e.g. the "
                   "wedges of a tablet): a PLY with a per-vertex label (1 = largest) and a CSV table "
                   "of the components (vertices, area, centroid, bounding box).");
    cmd->add_option("input", args->input, "PLY with per-vertex values (e.g. from msii compute or metric)")->required();
    cmd->add_option("-o,--output", args->output, "Output PLY (default <input stem>.segments.ply)");
    cmd->add_option("--table", args->table, "Output CSV (default: the output PLY's name with .csv)");
    cmd->add_option("--mat", args->matFiles, "GigaMesh feature file(s) for the input mesh");
    cmd->add_option("--property", args->property, "Vertex property to threshold (default quality)");
    cmd->add_option("--threshold", args->threshold, "Vertices with value >= this are selected")->required();
    cmd->add_flag("--below", args->below, "Select value <= threshold instead");
    cmd->add_option("--min-vertices", args->minVertices, "Drop components with fewer vertices (default 1)");
    cmd->add_option("--min-area", args->minArea, "Drop components with less area, mesh units^2 (default 0)");
    addCommonOptions(cmd, *args);
    addPropertyNamesOption(cmd, args->propertyPrefix);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runSegment(*args);
    };
}

} // namespace msii::tools
