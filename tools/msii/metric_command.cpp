/// `msii metric INPUT.ply [--invariants V] [--metric mahalanobis] [--reference flat]`: one
/// value f per vertex from its feature vectors (paper §3.1), written as `quality`.
#include "commands.h"
#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/io/feature_table.h>
#include <msii/io/write_ply.h>
#include <msii/metrics/feature_metrics.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>

namespace msii::tools {

namespace {

namespace fs = std::filesystem;

struct MetricArgs : CommonArgs {
    std::string input, output;
    std::vector<std::string> matFiles;
    std::string invariants = "V";
    std::string metrics = "mahalanobis";
    double p = 2.0;
    std::string reference = "flat";
};

struct NamedMetric {
    std::string name;
    MetricOptions options;
};

/// "l1,l2w,mahalanobis" → metric options; see the --metric help for the names.
std::vector<NamedMetric> parseMetrics(const MetricArgs& args)
{
    if (!(args.p > 0) || std::isnan(args.p))
        throw InvalidInputError("--p must be a positive number (or inf), not " + std::to_string(args.p));
    std::vector<NamedMetric> out;
    std::stringstream in(args.metrics);
    std::string name;
    while (std::getline(in, name, ',')) {
        name.erase(0, name.find_first_not_of(" \t"));
        name.erase(name.find_last_not_of(" \t") + 1);
        if (name.empty()) continue;
        out.push_back({name, metricOptionsByName(name, args.p)});
    }
    if (out.empty()) throw InvalidInputError("--metric names no metric");
    return out;
}

/// A whole number from @p text, or an error naming @p what.
double parseNumber(const std::string& text, const std::string& what)
{
    std::size_t used = 0;
    double v = std::numeric_limits<double>::quiet_NaN();
    try {
        v = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || text.find_first_not_of(" \t", used) != std::string::npos || !std::isfinite(v))
        throw InvalidInputError(what + ": '" + text + "' is not a number");
    return v;
}

std::vector<double> parseNumbers(const std::string& text, const std::string& what)
{
    std::vector<double> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) out.push_back(parseNumber(item, what));
    return out;
}

/// --reference: flat | vertex:I | point:X,Y,Z | vector:v1,v2,...
std::vector<double> parseReference(const std::string& text, const FeatureTable& table, const TriMesh& mesh,
                                   std::string& described)
{
    const std::string kind = text.substr(0, text.find(':'));
    const std::string value = text.find(':') == std::string::npos ? "" : text.substr(text.find(':') + 1);
    if (text == "flat") {
        described = "the flat surface";
        return flatReference(table);
    }
    if (kind == "vertex") {
        std::size_t used = 0;
        long long v = -1;
        try {
            v = std::stoll(value, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != value.size() || v < 0)
            throw InvalidInputError("--reference vertex:" + value + ": not a vertex index");
        if (std::size_t(v) >= table.numVertices)
            throw InvalidInputError("--reference vertex:" + value + ": the mesh has " +
                                    std::to_string(table.numVertices) + " vertices (0 to " +
                                    std::to_string(table.numVertices - 1) + ")");
        described = "vertex " + value;
        return vertexReference(table, std::size_t(v));
    }
    if (kind == "point") {
        const std::vector<double> xyz = parseNumbers(value, "--reference point");
        if (xyz.size() != 3) throw InvalidInputError("--reference point:X,Y,Z takes three numbers");
        const std::size_t v = nearestVertex(mesh, Vec3(xyz[0], xyz[1], xyz[2]));
        described = "vertex " + std::to_string(v) + " (nearest to the point)";
        return vertexReference(table, v);
    }
    if (kind == "vector") {
        std::vector<double> ref = parseNumbers(value, "--reference vector");
        if (ref.size() != table.dimension())
            throw InvalidInputError("--reference vector has " + std::to_string(ref.size()) +
                                    " values; the selected features have " + std::to_string(table.dimension()));
        described = "the given vector";
        return ref;
    }
    throw InvalidInputError("--reference '" + text +
                            "': use flat, vertex:INDEX, point:X,Y,Z or vector:V1,V2,...");
}

int runMetric(const MetricArgs& args)
{
    const Stopwatch total;
    const std::vector<NamedMetric> metrics = parseMetrics(args);
    const std::vector<Invariant> invariants = parseInvariantList(args.invariants);
    const std::string output = outputPath(args.input, args.output, "metric", args.overwrite,
                                          featureOutputExtension(args.input, args.output));

    FeatureMesh in = readFeatureMesh(args.input, args.matFiles);
    printWarnings(args.input, in.warnings, args.quiet);
    const FeatureTable table = [&] {
        try {
            return featureTableOf(in.properties, in.mesh.numVertices(), invariants);
        } catch (const InvalidInputError& e) {
            if (!in.raster || std::string(e.what()).find("some radii only") == std::string::npos) throw;
            throw InvalidInputError(std::string(e.what()) + " (msii compute --bands quality," + args.invariants +
                                    " writes every radius)");
        }
    }();
    std::string referenceText;
    const std::vector<double> reference = parseReference(args.reference, table, in.mesh, referenceText);

    std::vector<VertexProperty> add;
    std::ostringstream summary;
    for (const NamedMetric& m : metrics) {
        const MetricResult r = computeMetric(table, reference, m.options);
        add.push_back({"f_" + m.name, r.values});
        summary << "  " << m.name << ": " << r.numUndefined << " vertices undefined (NaN)";
        if (m.options.kind == MetricKind::Mahalanobis)
            summary << ", " << r.numNegativeForms << " with a negative form (f = -sqrt(-q))";
        summary << "\n";
        if (add.size() == 1) {
            summary << "  scale weights (Eq. 4-6), error of their sum (Eq. 7):";
            for (std::size_t b = 0; b < table.blocks.size(); ++b)
                summary << " " << invariantLetter(table.blocks[b].invariant) << " (n = "
                        << table.blocks[b].count << ") eps = " << r.weightErrors[b];
            summary << "\n";
        }
    }
    add.push_back({"quality", add.front().values});
    std::vector<std::string> written{"quality"};
    for (const NamedMetric& m : metrics) written.push_back("f_" + m.name);
    mergeProperties(in.properties, std::move(add));

    std::ostringstream comment;
    comment << "msii " << versionString() << " metric " << args.metrics << " of " << args.invariants
            << " against " << referenceText << "; quality = f_" << metrics.front().name;
    if (fs::path(output).extension() == ".tif") {
        // On the raster's grid: quality and each metric, NaN where undefined (GIS show nodata).
        std::vector<const VertexProperty*> bands;
        for (const std::string& name : written) bands.push_back(&in.properties[findProperty(in, name)]);
        writeFeatureRaster(output, in, bands, comment.str());
    } else {
        WritePlyOptions options;
        options.propertyPrefix = args.propertyPrefix;
        options.comments = in.comments;  // keep the provenance (e.g. compute's R and N)
        options.comments.push_back(comment.str() + " (0 where NaN)");
        qualityWithoutNaN(in.properties);
        writePly(output, in.mesh, in.properties, options);
    }
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%zu vertices, %zu features, reference %s, %.1f s)\n%s",
                     args.input.c_str(), output.c_str(), table.numVertices, table.dimension(),
                     referenceText.c_str(), total.seconds(), summary.str().c_str());
    return 0;
}

} // namespace

std::function<int()> addMetricCommand(CLI::App& app)
{
    auto args = std::make_shared<MetricArgs>();
    CLI::App* cmd = app.add_subcommand(
        "metric", "One value f per vertex from its feature vectors (distance or similarity to a "
                  "reference, paper Sec. 3.1); writes a PLY with quality = f, f_<metric> per "
                  "metric, and every property of the input; for a GeoTIFF from msii compute on a "
                  "DEM, a GeoTIFF on its grid with the bands quality and f_<metric> (float32).");
    cmd->add_option("input", args->input,
                    "Feature PLY or GeoTIFF written by msii compute (or any mesh with --mat)")
        ->required();
    cmd->add_option("-o,--output", args->output,
                    "Output PLY (default <input stem>.metric.ply), or for a GeoTIFF input a GeoTIFF "
                    "(default <input stem>.metric.tif; a .ply name gives the DEM's mesh)");
    cmd->add_option("--mat", args->matFiles,
                    "GigaMesh feature file(s) for the input mesh: *.volume.mat (V), *.surface.mat "
                    "(P); they replace the PLY's V or P features");
    cmd->add_option("-i,--invariants", args->invariants,
                    "Features to use, e.g. V or V,P (concatenated) (default V)");
    cmd->add_option("-m,--metric", args->metrics,
                    "Metric(s), comma-separated; the first becomes quality (default mahalanobis): "
                    "l1, l2, linf, lp (p-norms of x - o), l1w, l2w, linfw, lpw (weighted by the "
                    "scale dependency, Eq. 4-6), mahalanobis (Eq. 11), cosine, correlation, "
                    "autocorrelation, tanimoto, neuclid (normalised Euclidean)");
    cmd->add_option("--p", args->p, "p of lp and lpw (> 0; default 2)");
    cmd->add_option("--reference", args->reference,
                    "o: flat (the ideal flat surface, default), vertex:INDEX, point:X,Y,Z (the "
                    "nearest vertex) or vector:V1,V2,...");
    addCommonOptions(cmd, *args);
    addPropertyNamesOption(cmd, args->propertyPrefix);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runMetric(*args);
    };
}

} // namespace msii::tools
