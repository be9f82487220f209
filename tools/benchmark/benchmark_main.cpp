/// @file benchmark_main.cpp
/// @brief `msii-benchmark`: times the compute job on a generated tablet-like open surface
/// (default: ~1.1M vertices at 0.03 mm spacing, R = 1 mm, N = 16) and prints a table of
/// median stage timings over several runs, vertices/s, peak memory and the machine.
/// Each run does what `msii compute` does: read the mesh from a binary PLY file (written
/// once beforehand), compute, and write the result PLY; the total is that whole wall time.
#include <msii/core/stopwatch.h>
#include <msii/invariants/compute.h>
#include <msii/io/feature_properties.h>
#include <msii/io/feature_table.h>
#include <msii/metrics/feature_metrics.h>
#include <msii/smoothing/ring_smoothing.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/read_mesh.h>
#include <msii/samples/generators.h>
#include <msii/map/feature_map.h>
#include <msii/tiling/tiled_compute.h>
#include <msii/render/annotate.h>
#include <msii/render/picture.h>

#include <CLI/CLI.hpp>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

using namespace msii;

namespace {
double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}
std::string cpuModel()
{
    std::ifstream in("/proc/cpuinfo");
    for (std::string line; std::getline(in, line);)
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}
} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"msii-benchmark: stage timings of msii compute on a generated tablet surface"};
    double spacing = 0.03, size = 31.6, radius = 1.0, precision = 6.0, voxel = 0;
    int scales = 16, runs = 3;
    std::string invariants = "V,S,P,L";
    app.add_option("--spacing", spacing, "vertex spacing, mm (default 0.03)");
    app.add_option("--size", size, "width = height of the tablet, mm (default 31.6 → 1.1M vertices)");
    app.add_option("--radius", radius, "largest radius R, mm (default 1)");
    app.add_option("--scales", scales, "N (default 16)");
    app.add_option("--precision", precision, "voxels per radius (default 6)");
    app.add_option("--voxel-size", voxel, "finest voxel (default automatic)");
    app.add_option("--runs", runs, "runs; medians are reported (default 3)");
    app.add_option("--invariants", invariants, "which invariants, e.g. V,S (default V,S,P,L)");
    int mapPixels = 4096, picturePixels = 2048, tiles = 2;
    app.add_option("--tiles", tiles, "also time the compute in K x K tiles (default 2; 0: skip)");
    app.add_option("--map-pixels", mapPixels, "longer side of the EXR map, pixels (default 4096)");
    app.add_option("--picture-pixels", picturePixels, "longer side of the PNG picture, pixels (default 2048)");
    CLI11_PARSE(app, argc, argv);

    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = ho.height = size;
    ho.spacing = spacing;
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("msii-benchmark-" + std::to_string(getpid()));
    fs::create_directories(dir);
    const std::string input = (dir / "tablet.ply").string(), output = (dir / "tablet.msii.ply").string();
    const Stopwatch generating;
    {
        const TriMesh mesh = samples::makeHeightField(ho);
        writePly(input, mesh, {});
    }
    const double gen = generating.seconds();

    std::vector<double> read, check, ls, occ, st, interp, samp, pl, compute, write, total, tiled;
    std::size_t tiledLargest = 0;
    const auto has = [&](char c) { return invariants.find(c) != std::string::npos; };
    ComputeResult last;
    TriMesh lastMesh;
    std::size_t nv = 0;
    for (int run = 0; run < runs; ++run) {
        const Stopwatch wall;
        TriMesh mesh = readMesh(input).mesh;
        read.push_back(wall.seconds());
        nv = mesh.numVertices();
        ComputeOptions o;
        o.radius = radius;
        o.scales = scales;
        o.minVoxelsPerRadius = precision;
        o.voxelSize = voxel;
        o.computeVolume = has('V');
        o.computeSphere = has('S');
        o.computePatch = has('P');
        o.computeLine = has('L');
        last = computeInvariants(mesh, o);
        const Stopwatch writing;
        writePly(output, mesh, featureProperties(featuresOf(last.invariants, last.patchLine)));
        write.push_back(writing.seconds());
        total.push_back(wall.seconds());
        check.push_back(last.timings.check);
        ls.push_back(last.timings.levelSet);
        occ.push_back(last.timings.occupancy);
        st.push_back(last.timings.stencils);
        interp.push_back(last.timings.interpolation);
        samp.push_back(last.timings.samples);
        pl.push_back(last.timings.patchLine);
        compute.push_back(last.timings.total);
        if (tiles > 0) {
            TilingOptions to;
            to.tilesPerAxis = tiles;
            TiledComputeInfo info;
            const Stopwatch tiledWall;
            const ComputeResult t = computeTiled(mesh, o, to, &info);
            tiled.push_back(tiledWall.seconds());
            tiledLargest = info.largestTileVertices;
        }
        if (run + 1 == runs) lastMesh = std::move(mesh);
    }
    fs::remove_all(dir);

    // After compute: every metric over all computed features (4 × N with V,S,P,L) against a
    // vertex's vector, and 30 passes of each 1-ring filter on quality (issue 4's stages).
    const std::vector<VertexProperty> props = featureProperties(featuresOf(last.invariants, last.patchLine));
    std::vector<Invariant> all;
    for (const auto& [c, inv] : {std::pair{'V', Invariant::Volume}, std::pair{'S', Invariant::Sphere},
                                 std::pair{'P', Invariant::Patch}, std::pair{'L', Invariant::Line}})
        if (has(c)) all.push_back(inv);
    const FeatureTable table = featureTableOf(props, nv, all);
    std::size_t refVertex = nv / 2;  // a vertex with no masked element, near the middle
    for (std::size_t i = nv / 2; i < nv; ++i) {
        const float* row = table.values.data() + i * table.dimension();
        if (std::none_of(row, row + table.dimension(), [](float v) { return std::isnan(v); })) {
            refVertex = i;
            break;
        }
    }
    const std::vector<double> reference = vertexReference(table, refVertex);
    struct MetricRow {
        std::string name;
        MetricOptions options;
        std::vector<double> seconds;
    };
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<MetricRow> metricRows{
        {"l1", {MetricKind::PNorm, 1, false}, {}},   {"l2w", {MetricKind::PNorm, 2, true}, {}},
        {"linfw", {MetricKind::PNorm, inf, true}, {}}, {"lp (p = 3)", {MetricKind::PNorm, 3, false}, {}},
        {"mahalanobis", {MetricKind::Mahalanobis, 2, false}, {}}, {"cosine", {MetricKind::Cosine, 2, false}, {}},
        {"correlation", {MetricKind::Correlation, 2, false}, {}},
        {"autocorrelation", {MetricKind::AutoCorrelation, 2, false}, {}},
        {"tanimoto", {MetricKind::Tanimoto, 2, false}, {}},
        {"neuclid", {MetricKind::NormalizedEuclidean, 2, false}, {}}};
    std::vector<double> ringSetupMean, ringMean, ringSetupMedian, ringMedian;
    std::vector<float> quality = props.back().values;
    for (int run = 0; run < runs; ++run) {
        for (MetricRow& m : metricRows) {
            const Stopwatch t;
            const MetricResult r = computeMetric(table, reference, m.options);
            m.seconds.push_back(t.seconds());
        }
        for (const SmoothingFilter filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
            SmoothingOptions so;
            so.filter = filter;
            so.iterations = 30;
            std::vector<float> values = quality;
            const Stopwatch setup;
            const RingSmoother smoother(lastMesh, so);
            const double setupSeconds = setup.seconds();
            const Stopwatch passes;
            smoother.smooth(values);
            (filter == SmoothingFilter::Mean ? ringSetupMean : ringSetupMedian).push_back(setupSeconds);
            (filter == SmoothingFilter::Mean ? ringMean : ringMedian).push_back(passes.seconds());
        }
    }
    // Issue 5's stages: the EXR feature map (every feature and quality; default PIZ float,
    // and the variants) and a PNG picture (rasterise, colour, shade, isolines, bars, write).
    struct MapRow {
        std::string name;
        FeatureMapOptions options;
        std::vector<double> seconds;
        double megabytes = 0;
    };
    std::vector<MapRow> mapRows(3);
    mapRows[0].name = "float, piz (default)";
    mapRows[1].name = "float, none";
    mapRows[1].options.compression = ExrCompression::None;
    mapRows[2].name = "half, piz";
    mapRows[2].options.half = true;
    std::vector<double> pictureSeconds;
    MapFrame mapFrame, pictureFrame;
    {
        fs::create_directories(dir);
        MapFrameOptions fo;
        fo.longerSidePixels = mapPixels;
        mapFrame = makeMapFrame(lastMesh, fo);
        fo.longerSidePixels = picturePixels;
        pictureFrame = makeMapFrame(lastMesh, fo);
        const std::string exr = (dir / "map.exr").string(), png = (dir / "picture.png").string();
        for (int run = 0; run < runs; ++run) {
            for (MapRow& m : mapRows) {
                const Stopwatch t;
                writeFeatureMap(exr, lastMesh, mapFrame, props, m.options);
                m.seconds.push_back(t.seconds());
                m.megabytes = double(fs::file_size(exr)) / 1e6;
                fs::remove(exr);
            }
            const Stopwatch t;
            const PixelHits hits = rasterize(lastMesh, pictureFrame);
            const std::vector<float> value = interpolateToPixels(lastMesh, hits, quality), mask = coverageMask(hits);
            const std::array<std::vector<float>, 3> normals = vertexNormalsInFrame(lastMesh, pictureFrame);
            std::vector<float> n3[3];
            for (std::size_t a = 0; a < 3; ++a) n3[a] = interpolateToPixels(lastMesh, hits, normals[a]);
            PictureChannels pc;
            pc.width = hits.width, pc.height = hits.height;
            pc.value = &value, pc.mask = &mask, pc.nx = &n3[0], pc.ny = &n3[1], pc.nz = &n3[2];
            PictureOptions po;
            po.shade = true;
            po.isolineCount = 5;
            const PictureResult pic = renderPicture(pc, po);
            FigureOptions fig;
            fig.range = pic.range;
            fig.isolines = pic.isolineLevels;
            fig.pixelSize = pictureFrame.pixelSize;
            writePng(png, composeFigure(pic.image, fig));
            pictureSeconds.push_back(t.seconds());
        }
        fs::remove_all(dir);
    }

    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf("msii-benchmark: tablet %.1f x %.1f mm, spacing %.3f mm, %zu vertices, R = %g, N = %d, "
                "%s, precision %g, voxel %.4f mm, %d levels, %d runs (medians)\n",
                size, size, spacing, nv, radius, scales, invariants.c_str(), precision, last.voxelSize,
                last.invariants.numLevels, runs);
    std::printf("machine: %s, %u hardware threads\n\n", cpuModel().c_str(), std::thread::hardware_concurrency());
    std::printf("| %-62s | %8s |\n|%s|%s|\n", "stage", "seconds", std::string(64, '-').c_str(), std::string(10, '-').c_str());
    const auto row = [](const char* name, double value, const char* format) {
        std::printf("| %-62s | ", name);
        std::printf(format, value);
        std::printf(" |\n");
    };
    row("generate + write input (not counted)", gen, "%8.2f");
    row("read PLY", median(read), "%8.2f");
    row("check + statistics", median(check), "%8.2f");
    row("level set", median(ls), "%8.2f");
    row("occupancy pyramid", median(occ), "%8.2f");
    row("stencils (V and S)", median(st), "%8.2f");
    row("interpolation to vertices", median(interp), "%8.2f");
    row("P, L: surface samples", median(samp), "%8.2f");
    row("P, L: kernel sums", median(pl), "%8.2f");
    row("compute (the stages above but reading)", median(compute), "%8.2f");
    row("write result PLY", median(write), "%8.2f");
    row("**total wall, read to write**", median(total), "%8.2f");
    row("vertices per second", nv / median(total), "%8.0f");
    if (tiles > 0)
        row(("compute in " + std::to_string(tiles) + " x " + std::to_string(tiles) + " tiles (largest " +
             std::to_string(tiledLargest) + " vertices with halo; bit-identical)")
                .c_str(),
            median(tiled), "%8.2f");
    const std::string features = std::to_string(table.dimension()) + " features";
    for (const MetricRow& m : metricRows)
        row(("metric " + m.name + ", " + features).c_str(), median(m.seconds), "%8.2f");
    row("1-ring set-up (mean)", median(ringSetupMean), "%8.2f");
    row("1-ring mean, 30 passes", median(ringMean), "%8.2f");
    row("1-ring set-up (median)", median(ringSetupMedian), "%8.2f");
    row("1-ring median, 30 passes", median(ringMedian), "%8.2f");
    for (const MapRow& m : mapRows)
        row(("EXR map " + std::to_string(mapFrame.width) + " x " + std::to_string(mapFrame.height) + ", " +
             std::to_string(props.size() + 5) + " ch, " + m.name + ", " + std::to_string(int(m.megabytes)) + " MB")
                .c_str(),
            median(m.seconds), "%8.2f");
    row(("PNG picture " + std::to_string(pictureFrame.width) + " x " + std::to_string(pictureFrame.height) +
         " (shaded colour, isolines, bars)")
            .c_str(),
        median(pictureSeconds), "%8.2f");
    row("peak memory (MB)", usage.ru_maxrss / 1024.0, "%8.0f");
    return 0;
}
