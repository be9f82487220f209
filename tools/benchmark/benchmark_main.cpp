/// @file benchmark_main.cpp
/// @brief `msii-benchmark`: times the compute job on a generated tablet-like open surface
/// (default: ~1.1M vertices at 0.03 mm spacing, R = 1 mm, N = 16) and prints a table of
/// median stage timings over several runs, vertices/s, peak memory and the machine.
/// Each run does what `msii compute` does: read the mesh from a binary PLY file (written
/// once beforehand), compute, and write the result PLY; the total is that whole wall time.
/// With --large-vertices it then runs the `msii-samples` and `msii` programs themselves on
/// a streamed terrain of that size, each in its own process so that its peak
/// memory is its own, and prints their time, memory and time per vertex against the above.
/// It also times the exact mode (--exact): on a block of the tablet's vertices, and on every
/// vertex of a closed slab whose walls and bottom are a few long triangles.
#include <msii/core/stopwatch.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/invariants/invariants.h>
#include <msii/invariants/exact.h>
#include <msii/invariants/scales.h>
#include <msii/io/feature_properties.h>
#include <msii/io/feature_table.h>
#include <msii/metrics/feature_metrics.h>
#include <msii/smoothing/ring_smoothing.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/io/read_mesh.h>
#include <msii/samples/generators.h>
#include <msii/featuremap/feature_map.h>
#include <msii/pipeline/compute.h>
#include <msii/render/annotate.h>
#include <msii/render/typeface.h>
#include <msii/render/picture.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <ctime>
#include <cstdio>
#include <cstring>
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
/// A child program's wall time, peak resident memory and exit status.
struct ChildRun {
    double seconds = 0, peakBytes = 0;
    bool ok = false;
};

ChildRun runChild(const std::vector<std::string>& args)
{
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ChildRun r;
    const Stopwatch wall;
    pid_t pid = 0;
    if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return r;
    int status = 0;
    rusage usage{};
    if (wait4(pid, &status, 0, &usage) != pid) return r;
    r.seconds = wall.seconds();
    r.peakBytes = double(usage.ru_maxrss) * 1024.0;
    r.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    return r;
}

/// What the benchmark prints, kept as well: `msii-benchmark --markdown FILE` writes it into
/// the performance page.
struct Report {
    std::string text;
    __attribute__((format(printf, 2, 3))) void print(const char* format, ...)
    {
        char buffer[1024];
        va_list args;
        va_start(args, format);
        std::vsnprintf(buffer, sizeof(buffer), format, args);
        va_end(args);
        std::fputs(buffer, stdout);
        text += buffer;
    }
};

std::string todayUtc()
{
    const std::time_t now = std::time(nullptr);
    char text[32];
    std::strftime(text, sizeof(text), "%Y-%m-%d", std::gmtime(&now));
    return text;
}

/// docs/performance.md: what is measured, the command that measures it again, the machine
/// and build, and the tables; generated whole, so that the page cannot drift from the program.
std::string performancePage(const std::string& command, const std::string& header, const std::string& tables)
{
    std::string page = R"(# Performance

<!-- Written by msii-benchmark --markdown; do not edit by hand: run the command below. -->

Stage timings of `msii compute` on a generated tablet surface (the benchmark's own input: an
irregular, scanner-like triangulation with cuneiform wedges), medians of the runs, with the
other commands' costs on its results. Targets: 30 s and 4 GB for the 1.1M-vertex tablet, and
at most 10 % of the total for mesh preparation. With `--dem-cells`, also a DEM computed in
windows: 20 minutes (1,200 s) and 4 GB for 100M cells.

```bash
)";
    page += command + "\n```\n\n" + header + "\n" + tables;
    page += R"(
What the rows are:
- **total wall, read to write**: reading the PLY, preparing the mesh (checks, repair, hole
  filling), the computation and writing the result, as `msii compute` does them.
- **compute in K x K tiles**: the same computation with `--tiles K`; its values are compared
  with the untiled run's, bit for bit.
- **exact mode**: `msii compute --exact` on 2,000 consecutive vertices of the tablet (setting
  up the whole mesh is most of that time) and on every vertex of a closed 7 × 5 × 3 mm tablet
  slab whose walls and bottom are a few long triangles (R = 1 mm, N = 16, 2 threads); the
  per-vertex rate comes from the slab.
- **metric, 1-ring, EXR map, PNG picture**: `msii metric`, `msii smooth`, `msii map` and
  `msii render` on the tablet's results.
- **own process**: `msii compute` and the Python module's `msii.compute` on the same tablet,
  each run once in a process of its own, with that process's peak memory. The Python
  result holds its arrays (vertices, faces and the (n, N) float32 arrays of V, S, P, L) on
  top of the engine's own peak, and should cost no more than that sum.
- **DEM**: `msii compute` on a generated GeoTIFF DEM (0.5 m cells in EPSG:25832, hills about
  25 m wide and 4 m high, 200 small nodata patches), R = 15 m, N = 16, V and S, in windows
  sized to the default 3 GB budget, in a process of its own with its peak memory
  ([terrain.md](terrain.md#large-areas)).

This machine's timings vary from one sitting to the next, by 15–20 % within a day and by up
to 2× between days, also in stages whose code did not change: compare builds in alternating
runs. The accuracy of the same settings is in [accuracy.md](accuracy.md); P and L use
8 cells per radius by default (`--pl-precision 6` is faster and less exact at sharp edges).
)";
    return page;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"msii-benchmark: stage timings of msii compute on a generated tablet surface"};
    double spacing = 0.03, size = 31.6, radius = 1.0, precision = 6.0, plPrecision = 0, voxel = 0;
    int scales = 16, runs = 3;
    std::string invariants = "V,S,P,L";
    app.add_option("--spacing", spacing, "vertex spacing, mm (default 0.03)");
    app.add_option("--size", size, "width = height of the tablet, mm (default 31.6 → 1.1M vertices)");
    app.add_option("--radius", radius, "largest radius R, mm (default 1)");
    app.add_option("--scales", scales, "N (default 16)");
    app.add_option("--precision", precision, "voxels per radius (default 6)");
    app.add_option("--pl-precision", plPrecision, "cells per radius for P and L (default: 4/3 of --precision)");
    app.add_option("--voxel-size", voxel, "finest voxel (default automatic)");
    app.add_option("--runs", runs, "runs; medians are reported (default 3)");
    app.add_option("--invariants", invariants, "which invariants, e.g. V,S (default V,S,P,L)");
    int mapPixels = 4096, picturePixels = 2048, tiles = 2;
    app.add_option("--tiles", tiles, "also time the compute in K x K tiles (default 2; 0: skip)");
    app.add_option("--map-pixels", mapPixels, "longer side of the EXR map, pixels (default 4096; 0: skip maps and pictures)");
    app.add_option("--picture-pixels", picturePixels, "longer side of the PNG picture, pixels (default 2048)");
    double largeVertices = 0;
    std::string largeBudget = "8G", msiiProgram = MSII_PROGRAM, samplesProgram = MSII_SAMPLES_PROGRAM;
    app.add_option("--large-vertices", largeVertices,
                   "also run msii compute --memory-budget on a streamed terrain of about this many vertices "
                   "(e.g. 50e6; same spacing, R and N; default 0: skip)");
    app.add_option("--large-budget", largeBudget, "--memory-budget of that run (default 8G)");
    double demCells = 0;
    app.add_option("--dem-cells", demCells,
                   "also run msii compute on a generated GeoTIFF DEM of about this many cells (e.g. 1e8: 10,000 x "
                   "10,000 cells of 0.5 m), R = 15 m, N = 16, V and S, in windows (default 0: skip)");
    app.add_option("--msii", msiiProgram, "the msii program (default: the one built with this benchmark)");
    app.add_option("--msii-samples", samplesProgram, "the msii-samples program (default: the one built with this benchmark)");
    int exactVertices = 2000;
    bool exactSlab = true, processes = true;
    app.add_option("--processes", processes,
                   "also run msii compute and the Python module's msii.compute on the tablet, each in its own "
                   "process, for their time and peak memory (default true)");
    app.add_option("--exact-vertices", exactVertices,
                   "also time the exact mode (--exact) on this many consecutive vertices in the middle of the tablet "
                   "(default 2000; 0: skip)");
    app.add_option("--exact-slab", exactSlab,
                   "also time the exact mode on every vertex of a closed 7 x 5 x 3 mm tablet slab with long wall and bottom "
                   "triangles (39k vertices, same spacing, R and N; default true)");
    std::string markdown;
    app.add_option("--markdown", markdown,
                   "also write the results as the Markdown page docs/performance.md (machine, build, command, "
                   "tables)");
    CLI11_PARSE(app, argc, argv);
    // The command as given, without --markdown FILE, for the page.
    std::string command = "build/tools/msii-benchmark";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--markdown") {
            ++i;
            continue;
        }
        if (a.rfind("--markdown=", 0) == 0) continue;
        command += " " + a;
    }
    command += markdown.empty() ? "" : " --markdown docs/performance.md";
    Report report;

    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = ho.height = size;
    ho.spacing = spacing;
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("msii-benchmark-" + std::to_string(getpid()));
    fs::create_directories(dir);
    const std::string input = (dir / "tablet.ply").string(), output = (dir / "tablet.msii.ply").string();
    const auto number = [](double v) {
        char text[32];
        std::snprintf(text, sizeof(text), "%.6g", v);
        return std::string(text);
    };
    struct LargeRun {
        ChildRun generate, compute;
        double side = 0, inputBytes = 0, outputBytes = 0;
        nlohmann::json json;
        bool ok = false;
    } large;
    if (largeVertices > 0) {
        // A terrain far larger than the tablet, generated streamed to disk and computed
        // by msii compute in tiles sized from the memory budget; one run (it takes long). Run
        // first, while this process is small: a spawned child starts out sharing this process's
        // memory, which would count in its peak.
        const double side = std::sqrt(largeVertices) * spacing;
        fs::create_directories(dir);
        const std::string terrain = (dir / "terrain.ply").string(), terrainOut = (dir / "terrain.msii.ply").string();
        large.side = side;
        large.generate = runChild({samplesProgram, "terrain", "--width", number(side), "--height", number(side),
                                       "--spacing", number(spacing), "-q", "--output", terrain});
        if (!large.generate.ok) {
            std::fprintf(stderr, "msii-benchmark: error: %s could not write the terrain\n", samplesProgram.c_str());
            fs::remove_all(dir);
            return 1;
        }
        large.inputBytes = double(fs::file_size(terrain));
        std::vector<std::string> args{msiiProgram, "compute", terrain, "-r", number(radius), "-n", std::to_string(scales),
                                      "--precision", number(precision), "--invariants", invariants, "--memory-budget",
                                      largeBudget, "-q", "--output", terrainOut};
        if (plPrecision > 0) args.insert(args.end(), {"--pl-precision", number(plPrecision)});
        large.compute = runChild(args);
        if (!large.compute.ok) {
            std::fprintf(stderr, "msii-benchmark: error: msii compute failed on the terrain\n");
            fs::remove_all(dir);
            return 1;
        }
        large.outputBytes = double(fs::file_size(terrainOut));
        std::ifstream sidecar((dir / "terrain.msii.json").string());
        large.json = nlohmann::json::parse(sidecar);
        large.ok = true;
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    struct DemRun {
        ChildRun generate, compute;
        int side = 0;
        double outputBytes = 0;
        nlohmann::json json;
        bool ok = false;
    } dem;
    if (demCells > 0) {
        // A DEM as landscape archaeologists have them: 0.5 m cells in UTM coordinates
        // (EPSG:25832), hills about 25 m wide and 4 m high, 200 small nodata patches; computed
        // by msii compute in windows, one run in a process of its own (it takes long).
        dem.side = int(std::lround(std::sqrt(demCells)));
        const std::string tif = (dir / "dem.tif").string(), out = (dir / "dem.msii.tif").string();
        dem.generate = runChild({samplesProgram, "terrain", "--geotiff", "--width", number(0.5 * dem.side), "--height",
                                 number(0.5 * dem.side), "--spacing", "0.5", "--relief", "4", "--hill-width", "25",
                                 "--holes", "200", "--hole-size", "2", "-q", "--output", tif});
        if (!dem.generate.ok) {
            std::fprintf(stderr, "msii-benchmark: error: %s could not write the DEM\n", samplesProgram.c_str());
            fs::remove_all(dir);
            return 1;
        }
        dem.compute = runChild({msiiProgram, "compute", tif, "-r", "15", "-n", "16", "--invariants", "V,S", "-q",
                                "--raster-output", out});
        if (!dem.compute.ok) {
            std::fprintf(stderr, "msii-benchmark: error: msii compute failed on the DEM\n");
            fs::remove_all(dir);
            return 1;
        }
        dem.outputBytes = double(fs::file_size(out));
        std::ifstream sidecar((dir / "dem.msii.json").string());
        dem.json = nlohmann::json::parse(sidecar);
        dem.ok = true;
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    const Stopwatch generating;
    {
        const TriMesh mesh = samples::makeHeightField(ho);
        writePly(input, mesh, {});
    }
    const double gen = generating.seconds();

    std::vector<double> read, prepare, prepareHoles, check, ls, occ, st, interp, samp, pl, compute, write, total, tiled;
    std::size_t holesFilled = 0;
    std::size_t tiledLargest = 0, tiledDiffering = 0;
    const auto has = [&](char c) { return invariants.find(c) != std::string::npos; };
    ComputeResult last;
    TriMesh lastMesh;
    std::size_t nv = 0;
    for (int run = 0; run < runs; ++run) {
        const Stopwatch wall;
        TriMesh mesh = readMesh(input).mesh;
        read.push_back(wall.seconds());
        nv = mesh.numVertices();
        InvariantsOptions o;
        o.radius = radius;
        o.scales = scales;
        o.minVoxelsPerRadius = precision;
        o.patchLinePrecision = plPrecision;
        o.voxelSize = voxel;
        o.computeVolume = has('V');
        o.computeSphere = has('S');
        o.computePatch = has('P');
        o.computeLine = has('L');
        // The pipeline as msii compute runs it (preparation: checks, repair, holes; the
        // invariants; the values mapped to the input's vertices), on the clean tablet; then
        // preparation alone, not counted in the total, on the same tablet with 100 pin-holes.
        ComputeOptions co;
        co.invariants = o;
        last = msii::compute(mesh, co);
        prepare.push_back(last.preparation.seconds);
        const Stopwatch writing;
        writePly(output, mesh, outputProperties(last.features, last.filledShare));
        write.push_back(writing.seconds());
        total.push_back(wall.seconds());
        check.push_back(last.cost.check);
        ls.push_back(last.cost.levelSet);
        occ.push_back(last.cost.occupancy);
        st.push_back(last.cost.stencils);
        interp.push_back(last.cost.interpolation);
        samp.push_back(last.cost.samples);
        pl.push_back(last.cost.patchLine);
        compute.push_back(last.cost.total);
        if (tiles > 0) {
            ComputeOptions tco = co;
            tco.tiling.tilesPerAxis = tiles;
            const Stopwatch tiledWall;
            const ComputeResult t = msii::compute(mesh, tco);
            tiled.push_back(tiledWall.seconds());
            tiledLargest = t.tiling.largestTileVertices;
            // Checked, not assumed: every value against the untiled run, bit for bit.
            const auto differing = [](const std::vector<std::vector<float>>& a, const std::vector<std::vector<float>>& b) {
                std::size_t count = 0;
                for (std::size_t j = 0; j < a.size(); ++j)
                    for (std::size_t i = 0; i < a[j].size(); ++i)
                        count += std::memcmp(&a[j][i], &b[j][i], sizeof(float)) != 0;
                return count;
            };
            tiledDiffering = 0;
            for (Invariant i : kAllInvariants) tiledDiffering += differing(t.features[i], last.features[i]);
        }
        {
            TriMesh holed = mesh;
            samples::HoleOptions holes;  // 100 seeded pin-holes, up to one spacing around
            holes.count = 100;
            holes.minSize = 0.5 * spacing;
            holes.maxSize = spacing;
            samples::punchHoles(holed, holes);
            const Stopwatch preparing;
            PrepareMeshOptions po;
            po.maxHolePerimeter = defaultMaxHolePerimeter(radius);
            po.radius = radius;
            holesFilled = prepareMesh(holed, po).holes.numFilled;
            prepareHoles.push_back(preparing.seconds());
        }
        if (run + 1 == runs) lastMesh = std::move(mesh);
    }
    // Memory of the program and of the Python module on the same input, each in its own
    // process (one run each): a Python result costs its arrays on top of the engine's own
    // peak, no more.
    ChildRun cliRun, pythonRun;
    double pythonArrays = 0;
    if (processes) {
        std::vector<std::string> args{msiiProgram, "compute", input, "-r", number(radius), "-n", std::to_string(scales),
                                      "--precision", number(precision), "--invariants", invariants, "-q",
                                      "--overwrite", "--output", (dir / "process.msii.ply").string()};
        if (plPrecision > 0) args.insert(args.end(), {"--pl-precision", number(plPrecision)});
        cliRun = runChild(args);
        // Peaks as the processes measure them (VmHWM): wait4's counts the memory this
        // benchmark held when it started them.
        if (cliRun.ok) {
            std::ifstream record((dir / "process.msii.json").string());
            cliRun.peakBytes = nlohmann::json::parse(record).value("peak_memory_bytes", 0.0);
        }
#ifdef MSII_PYTHON
        if (precision == 6.0 && plPrecision == 0 && voxel == 0) {  // msii.compute's defaults
            ::setenv("PYTHONPATH", MSII_PYTHON_DIR, 1);
            pythonRun = runChild({MSII_PYTHON, "-c",
                                  "import sys, msii\n"
                                  "v, f = msii.read_mesh(sys.argv[1])\n"
                                  "r = msii.compute(v, f, float(sys.argv[2]), scales=int(sys.argv[3]), "
                                  "invariants=sys.argv[4])\n"
                                  "peak = [l for l in open('/proc/self/status') if l.startswith('VmHWM:')][0]\n"
                                  "open(sys.argv[5], 'w').write(str(float(peak.split()[1]) * 1024))\n",
                                  input, number(radius), std::to_string(scales), invariants,
                                  (dir / "python-peak.txt").string()});
            if (pythonRun.ok) {
                std::ifstream peak((dir / "python-peak.txt").string());
                peak >> pythonRun.peakBytes;
            }
            std::size_t letters = 0;
            for (const char c : std::string("VSPL")) letters += has(c) ? 1 : 0;
            pythonArrays = double(nv) * (double(scales) * 4.0 * double(letters) + 24.0) +
                           double(lastMesh.numTriangles()) * 12.0;
        }
#endif
    }

    fs::remove_all(dir);

    // The exact mode (V, S, P, L from the triangles): on a block of the tablet's vertices,
    // and on every vertex of a closed slab with long wall and bottom triangles.
    std::vector<double> exactSeconds, exactSlabSeconds;
    std::size_t exactSlabVertices = 0;
    const auto exactOptions = [&](std::size_t first, std::size_t count) {
        ExactOptions eo;
        eo.radii = equidistantRadii(radius, scales);
        eo.computeVolumeSphere = has('V') || has('S');
        eo.computePatchLine = has('P') || has('L');
        for (std::size_t i = first; i < first + count; ++i) eo.vertices.push_back(std::uint32_t(i));
        return eo;
    };
    TriMesh slab;
    if (exactSlab) {
        samples::HeightFieldOptions so;
        so.kind = samples::HeightFieldKind::Tablet;
        so.width = 7;
        so.height = 5;
        so.spacing = spacing;
        so.closed = true;
        so.thickness = 3;
        so.wallStep = 1.5;
        slab = samples::makeHeightField(so);
        exactSlabVertices = slab.numVertices();
    }
    for (int run = 0; run < runs; ++run) {
        if (exactVertices > 0) {
            const std::size_t count = std::min<std::size_t>(std::size_t(exactVertices), lastMesh.numVertices());
            const ExactOptions eo = exactOptions((lastMesh.numVertices() - count) / 2, count);
            const Stopwatch t;
            computeExact(lastMesh, eo);
            exactSeconds.push_back(t.seconds());
        }
        if (exactSlab) {
            const Stopwatch t;
            computeExact(slab, exactOptions(0, slab.numVertices()));
            exactSlabSeconds.push_back(t.seconds());
        }
    }

    // After compute: every metric over all computed features (4 × N with V,S,P,L) against a
    // vertex's vector, and 30 passes of each 1-ring filter on quality.
    const std::vector<VertexProperty> props = featureProperties(last.features);
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
    // The EXR feature map (every feature and quality; default PIZ float,
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
    if (mapPixels > 0 && picturePixels > 0) {
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
            static const FontResult font = findFont();  // as msii render: DejaVu Sans if installed
            if (!font.typeface.isBuiltIn()) fig.typeface = &font.typeface;
            fig.lineHeight = labelLineHeight(pic.image.height);
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
    report.print("msii-benchmark: tablet %.1f x %.1f mm, spacing %.3f mm, %zu vertices, R = %g, N = %d, "
                "%s, precision %g (P, L: %g), voxel %.4f mm, %d levels, %d runs (medians)\n",
                size, size, spacing, nv, radius, scales, invariants.c_str(), precision,
                [&] {
                    InvariantsOptions o;
                    o.minVoxelsPerRadius = precision;
                    o.patchLinePrecision = plPrecision;
                    return patchLinePrecision(o);
                }(),
                last.plan.voxelSize,
                last.plan.numVolumeSphereLevels(), runs);
    report.print("machine: %s, %u hardware threads\n\n", cpuModel().c_str(), std::thread::hardware_concurrency());
    report.print("| %-62s | %8s |\n|%s|%s|\n", "stage", "seconds", std::string(64, '-').c_str(), std::string(10, '-').c_str());
    const auto row = [&report](const char* name, double value, const char* format) {
        report.print("| %-62s | ", name);
        report.print(format, value);
        report.print(" |\n");
    };
    row("generate + write input (not counted)", gen, "%8.2f");
    row("read PLY", median(read), "%8.2f");
    row("prepare (checks, repair, holes; clean mesh)", median(prepare), "%8.2f");
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
    row("prepare, share of the total (target <= 10 %)", 100.0 * median(prepare) / median(total), "%7.1f%%");
    row(("prepare with 100 pin-holes (" + std::to_string(holesFilled) + " filled; not in the total)").c_str(),
        median(prepareHoles), "%8.2f");
    row("the same, share of the total (target <= 10 %)", 100.0 * median(prepareHoles) / median(total), "%7.1f%%");
    if (tiles > 0)
        row(("compute in " + std::to_string(tiles) + " x " + std::to_string(tiles) + " tiles (largest " +
             std::to_string(tiledLargest) + " vertices with halo; " +
             (tiledDiffering == 0 ? std::string("bit-identical") : std::to_string(tiledDiffering) + " values differ") + ")")
                .c_str(),
            median(tiled), "%8.2f");
    if (!exactSeconds.empty()) {
        const std::size_t count = std::min<std::size_t>(std::size_t(exactVertices), nv);
        row(("exact mode (--exact), " + std::to_string(count) + " vertices of the tablet, set-up included").c_str(),
            median(exactSeconds), "%8.2f");
    }
    if (!exactSlabSeconds.empty()) {
        row(("exact mode, 7 x 5 x 3 mm slab, long walls, all " + std::to_string(exactSlabVertices) + " vertices").c_str(),
            median(exactSlabSeconds), "%8.2f");
        row("the same, milliseconds per vertex", 1e3 * median(exactSlabSeconds) / double(exactSlabVertices), "%8.3f");
    }
    const std::string features = std::to_string(table.dimension()) + " features";
    for (const MetricRow& m : metricRows)
        row(("metric " + m.name + ", " + features).c_str(), median(m.seconds), "%8.2f");
    row("1-ring set-up (mean)", median(ringSetupMean), "%8.2f");
    row("1-ring mean, 30 passes", median(ringMean), "%8.2f");
    row("1-ring set-up (median)", median(ringSetupMedian), "%8.2f");
    row("1-ring median, 30 passes", median(ringMedian), "%8.2f");
    for (const MapRow& m : mapRows)
        if (!m.seconds.empty()) row(("EXR map " + std::to_string(mapFrame.width) + " x " + std::to_string(mapFrame.height) + ", " +
             std::to_string(props.size() + 5) + " ch, " + m.name + ", " + std::to_string(int(m.megabytes)) + " MB")
                .c_str(),
            median(m.seconds), "%8.2f");
    if (!pictureSeconds.empty())
        row(("PNG picture " + std::to_string(pictureFrame.width) + " x " + std::to_string(pictureFrame.height) +
             " (shaded colour, isolines, bars)")
                .c_str(),
            median(pictureSeconds), "%8.2f");
    row("peak memory (MB)", usage.ru_maxrss / 1024.0, "%8.0f");
    if (cliRun.ok) {
        row("msii compute, own process: read to write", cliRun.seconds, "%8.2f");
        row("the same, peak memory (MB)", cliRun.peakBytes / 1e6, "%8.0f");
    }
    if (pythonRun.ok) {
        row("Python msii.compute, own process: import, read, compute", pythonRun.seconds, "%8.2f");
        row("the same, peak memory (MB)", pythonRun.peakBytes / 1e6, "%8.0f");
        row("arrays it holds: vertices, faces, V, S, P, L (MB)", pythonArrays / 1e6, "%8.0f");
        row("its peak beyond msii compute's and the arrays (MB, target <= 0)",
            (pythonRun.peakBytes - cliRun.peakBytes - pythonArrays) / 1e6, "%8.0f");
    }
    std::fflush(stdout);

    const auto finish = [&] {
        if (markdown.empty()) return 0;
        const std::string header = "Measured on " + todayUtc() + " with msii " + versionString() + " (" +
                                   MSII_BUILD_TYPE + " build).\n";
        writeTextFileAtomic(markdown, performancePage(command, header, report.text));
        std::fprintf(stderr, "msii-benchmark: wrote %s\n", markdown.c_str());
        return 0;
    };
    if (dem.ok) {
        const nlohmann::json& d = dem.json;
        const double cells = double(dem.side) * dem.side;
        report.print("\nDEM %d x %d cells of 0.5 m (GeoTIFF, EPSG:25832, %.0f cells with heights); msii compute -r 15 "
                     "-n 16 --invariants V,S: %d x %d windows of %d cells, halo %d cells (%d where no nodata gap "
                     "crosses it, in %d windows); one run each, separate processes\n\n",
                     dem.side, dem.side, d["raster"]["cells_with_height"].get<double>(),
                     d["raster"]["windows"]["per_row"].get<int>(), d["raster"]["windows"]["per_column"].get<int>(),
                     d["raster"]["windows"]["cells"].get<int>(), d["raster"]["windows"]["halo_cells"].get<int>(),
                     d["raster"]["windows"]["narrow_halo_cells"].get<int>(),
                     d["raster"]["windows"]["per_row"].get<int>() * d["raster"]["windows"]["per_column"].get<int>() -
                         d["raster"]["windows"]["windows_with_wide_halo"].get<int>());
        report.print("| %-62s | %8s | %8s |\n|%s|%s|%s|\n", "stage", "seconds", "peak MB", std::string(64, '-').c_str(),
                     std::string(10, '-').c_str(), std::string(10, '-').c_str());
        report.print("| %-62s | %8.1f | %8.0f |\n", "msii-samples terrain --geotiff", dem.generate.seconds,
                     dem.generate.peakBytes / 1e6);
        report.print("| %-62s | %8.1f | %8.0f |\n",
                     ("**msii compute, read to write** (" + std::to_string(int(dem.outputBytes / 1e6)) + " MB)").c_str(),
                     dem.compute.seconds, dem.compute.peakBytes / 1e6);
        const auto& t = d["timings_seconds"];
        for (const char* stage : {"read", "prepare", "level_set", "occupancy", "stencils", "interpolation", "write"})
            report.print("| %-62s | %8.1f | %8s |\n", ("  of which " + std::string(stage)).c_str(), t[stage].get<double>(), "");
        report.print("| %-62s | %8.2f | %8s |\n", "microseconds per cell", 1e6 * dem.compute.seconds / cells, "");
        report.print("| %-62s | %8s | %8s |\n", "targets", "1200", "4000");
    }
    if (!large.ok) return finish();
    const nlohmann::json& j = large.json;
    const double largeNv = j["mesh"]["vertices"].get<double>();
    const int perAxis = j["tiling"]["tiles_per_axis"].get<int>();
    const double perVertex = large.compute.seconds / largeNv, smallPerVertex = median(total) / double(nv);
    report.print("\nstreamed terrain %s x %s mm, spacing %.3f mm, %.0f vertices, %.0f triangles; "
                "msii compute -r %g -n %d --invariants %s --memory-budget %s: %d x %d tiles (largest %.0f "
                "vertices with halo, halo %.2f mm); one run each, separate processes\n\n",
                number(large.side).c_str(), number(large.side).c_str(), spacing, largeNv, j["mesh"]["faces"].get<double>(),
                radius, scales, invariants.c_str(), largeBudget.c_str(), perAxis, perAxis,
                j["tiling"]["largest_tile_vertices"].get<double>(), j["tiling"]["halo"].get<double>());
    report.print("| %-62s | %8s | %8s |\n|%s|%s|%s|\n", "stage", "seconds", "peak MB", std::string(64, '-').c_str(),
                std::string(10, '-').c_str(), std::string(10, '-').c_str());
    report.print("| %-62s | %8.1f | %8.0f |\n",
                ("msii-samples terrain, streamed (" + std::to_string(int(large.inputBytes / 1e6)) + " MB)").c_str(),
                large.generate.seconds, large.generate.peakBytes / 1e6);
    report.print("| %-62s | %8.1f | %8.0f |\n",
                ("**msii compute, read to write** (" + std::to_string(int(large.outputBytes / 1e6)) + " MB)").c_str(),
                large.compute.seconds, large.compute.peakBytes / 1e6);
    const auto& t = j["timings_seconds"];
    for (const char* stage : {"read", "check", "level_set", "stencils", "samples", "patch_line", "write"})
        report.print("| %-62s | %8.1f | %8s |\n", ("  of which " + std::string(stage)).c_str(), t[stage].get<double>(), "");
    report.print("| %-62s | %8.2f | %8s |\n", "microseconds per vertex", 1e6 * perVertex, "");
    report.print("| %-62s | %8.2f | %8s |\n", "the same for the tablet above (total wall / vertices)", 1e6 * smallPerVertex, "");
    report.print("| %-62s | %8.2f | %8s |\n", "ratio (target <= 1.5)", perVertex / smallPerVertex, "");
    return finish();
}
