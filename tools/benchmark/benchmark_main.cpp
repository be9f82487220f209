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
#include <msii/core/errors.h>
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
#include <cstdlib>
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
  25 m wide and 4 m high, 200 small nodata patches), R = 15 m, N = 16, the default bands
  (quality and V at R/4, R/2, 3R/4 and R: V alone is computed, from the height field), in
  windows of 2,048 cells, in a process of its own with its peak memory
  ([terrain.md](terrain.md#large-areas)).
- **Terrain tools' case** (`--terrain-peer`): a 1000 × 1000 DEM of 1 m at R = 10 and 30
  cells, on the height field and on the mesh (`--engine mesh`), and with `--rvt PATH`
  RVT_py's sky-view factor and openness (16 directions) and multi-scale topographic
  position at the same radius ([terrain.md](terrain.md#large-areas)).

This machine's timings vary from one sitting to the next, by 15–20 % within a day and by up
to 2× between days, also in stages whose code did not change: compare builds in alternating
runs. The accuracy of the same settings is in [accuracy.md](accuracy.md); P and L use
8 cells per radius by default (`--pl-precision 6` is faster and less exact at sharp edges).
)";
    return page;
}

std::string number(double v)
{
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    return std::string(text);
}

namespace fs = std::filesystem;

/// What to measure and how: the command line.
struct Settings {
    double spacing = 0.03, size = 31.6, radius = 1.0, precision = 6.0, plPrecision = 0, voxel = 0;
    int scales = 16, runs = 3;
    std::string invariants = "V,S,P,L";
    int mapPixels = 4096, picturePixels = 2048, tiles = 2;
    double largeVertices = 0;
    std::string largeBudget = "8G", msiiProgram = MSII_PROGRAM, samplesProgram = MSII_SAMPLES_PROGRAM;
    double demCells = 0;
    bool terrainPeer = false;  ///< the 1000 × 1000 DEM of 1 m at R = 10 and 30 cells, both routes
    std::string rvt;           ///< a folder holding RVT_py's package rvt, for the peer's rows
    int exactVertices = 2000;
    bool exactSlab = true, processes = true;
    std::string markdown;

    /// Whether the invariant with letter @p c is computed.
    /// Whether --invariants (read as msii compute reads it) selects the invariant of letter @p c.
    bool has(char c) const
    {
        const std::vector<Invariant> list = parseInvariantList(invariants);
        return std::find(list.begin(), list.end(), *invariantOfLetter(c)) != list.end();
    }
};

void addOptions(CLI::App& app, Settings& s)
{
    app.add_option("--spacing", s.spacing, "vertex spacing, mm (default 0.03)");
    app.add_option("--size", s.size, "width = height of the tablet, mm (default 31.6 → 1.1M vertices)");
    app.add_option("--radius", s.radius, "largest radius R, mm (default 1)");
    app.add_option("--scales", s.scales, "N (default 16)");
    app.add_option("--precision", s.precision, "voxels per radius (default 6)");
    app.add_option("--pl-precision", s.plPrecision, "cells per radius for P and L (default: 4/3 of --precision)");
    app.add_option("--voxel-size", s.voxel, "finest voxel (default automatic)");
    app.add_option("--runs", s.runs, "runs; medians are reported (default 3)");
    app.add_option("--invariants", s.invariants, "which invariants, e.g. V,S (default V,S,P,L)");
    app.add_option("--tiles", s.tiles, "also time the compute in K x K tiles (default 2; 0: skip)");
    app.add_option("--map-pixels", s.mapPixels, "longer side of the EXR map, pixels (default 4096; 0: skip maps and pictures)");
    app.add_option("--picture-pixels", s.picturePixels, "longer side of the PNG picture, pixels (default 2048)");
    app.add_option("--large-vertices", s.largeVertices,
                   "also run msii compute --memory-budget on a streamed terrain of about this many vertices "
                   "(e.g. 50e6; same spacing, R and N; default 0: skip)");
    app.add_option("--large-budget", s.largeBudget, "--memory-budget of that run (default 8G)");
    app.add_option("--dem-cells", s.demCells,
                   "also run msii compute on a generated GeoTIFF DEM of about this many cells (e.g. 1e8: 10,000 x "
                   "10,000 cells of 0.5 m), R = 15 m, N = 16, default bands, in windows (default 0: skip)");
    app.add_option("--terrain-peer", s.terrainPeer,
                   "also run msii compute on a generated 1000 x 1000 DEM of 1 m cells at R = 10 and 30 cells, default "
                   "bands, 2 threads, on the height field and on the mesh (--engine mesh) (default false)");
    app.add_option("--rvt", s.rvt,
                   "with --terrain-peer (implied), also time RVT_py's sky-view factor (16 directions) and multi-scale "
                   "topographic position at the same radii on the same DEM: PATH is a folder holding its package rvt "
                   "(it is not installed by msii)")
        ->type_name("PATH");
    app.add_option("--msii", s.msiiProgram, "the msii program (default: the one built with this benchmark)");
    app.add_option("--msii-samples", s.samplesProgram, "the msii-samples program (default: the one built with this benchmark)");
    app.add_option("--processes", s.processes,
                   "also run msii compute and the Python module's msii.compute on the tablet, each in its own "
                   "process, for their time and peak memory (default true)");
    app.add_option("--exact-vertices", s.exactVertices,
                   "also time the exact mode (--exact) on this many consecutive vertices in the middle of the tablet "
                   "(default 2000; 0: skip)");
    app.add_option("--exact-slab", s.exactSlab,
                   "also time the exact mode on every vertex of a closed 7 x 5 x 3 mm tablet slab with long wall and bottom "
                   "triangles (39k vertices, same spacing, R and N; default true)");
    app.add_option("--markdown", s.markdown,
                   "also write the results as the Markdown page docs/performance.md (machine, build, command, "
                   "tables)");
}

/// The command as given, without --markdown FILE, for the page.
std::string commandLine(int argc, char** argv, const std::string& markdown)
{
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
    return command;
}

/// What the cases share: the settings, and the work folder with the tablet's input and
/// output files.
struct Bench {
    const Settings& settings;
    fs::path dir;
    std::string input, output;
};

/// The streamed terrain: generated and computed by the programs, each in its own process.
struct LargeRun {
    ChildRun generate, compute;
    double side = 0, inputBytes = 0, outputBytes = 0;
    nlohmann::json json;
    bool ok = false;
};

/// A terrain far larger than the tablet, generated streamed to disk and computed by msii
/// compute in tiles sized from the memory budget; one run (it takes long). Returns false,
/// having said why and removed the work folder, if a program failed.
bool runLargeTerrain(const Bench& bench, LargeRun& large)
{
    const Settings& s = bench.settings;
    const fs::path& dir = bench.dir;
    const double side = std::sqrt(s.largeVertices) * s.spacing;
    fs::create_directories(dir);
    const std::string terrain = (dir / "terrain.ply").string(), terrainOut = (dir / "terrain.msii.ply").string();
    large.side = side;
    large.generate = runChild({s.samplesProgram, "terrain", "--width", number(side), "--height", number(side),
                               "--spacing", number(s.spacing), "-q", "--output", terrain});
    if (!large.generate.ok) {
        std::fprintf(stderr, "msii-benchmark: error: %s could not write the terrain\n", s.samplesProgram.c_str());
        fs::remove_all(dir);
        return false;
    }
    large.inputBytes = double(fs::file_size(terrain));
    std::vector<std::string> args{s.msiiProgram, "compute", terrain, "-r", number(s.radius), "-n", std::to_string(s.scales),
                                  "--precision", number(s.precision), "--invariants", s.invariants, "--memory-budget",
                                  s.largeBudget, "-q", "--output", terrainOut};
    if (s.plPrecision > 0) args.insert(args.end(), {"--pl-precision", number(s.plPrecision)});
    large.compute = runChild(args);
    if (!large.compute.ok) {
        std::fprintf(stderr, "msii-benchmark: error: msii compute failed on the terrain\n");
        fs::remove_all(dir);
        return false;
    }
    large.outputBytes = double(fs::file_size(terrainOut));
    std::ifstream sidecar((dir / "terrain.msii.json").string());
    large.json = nlohmann::json::parse(sidecar);
    large.ok = true;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return true;
}

/// The DEM: generated and computed by the programs, each in its own process.
struct DemRun {
    ChildRun generate, compute;
    int side = 0;
    double outputBytes = 0;
    nlohmann::json json;
    bool ok = false;
};

/// A DEM as landscape archaeologists have them: 0.5 m cells in UTM coordinates
/// (EPSG:25832), hills about 25 m wide and 4 m high, 200 small nodata patches; computed by
/// msii compute in windows, one run in a process of its own (it takes long). Returns false,
/// having said why and removed the work folder, if a program failed.
bool runDem(const Bench& bench, DemRun& dem)
{
    const Settings& s = bench.settings;
    const fs::path& dir = bench.dir;
    dem.side = int(std::lround(std::sqrt(s.demCells)));
    const std::string tif = (dir / "dem.tif").string(), out = (dir / "dem.msii.tif").string();
    dem.generate = runChild({s.samplesProgram, "terrain", "--geotiff", "--width", number(0.5 * dem.side), "--height",
                             number(0.5 * dem.side), "--spacing", "0.5", "--relief", "4", "--hill-width", "25",
                             "--holes", "200", "--hole-size", "2", "-q", "--output", tif});
    if (!dem.generate.ok) {
        std::fprintf(stderr, "msii-benchmark: error: %s could not write the DEM\n", s.samplesProgram.c_str());
        fs::remove_all(dir);
        return false;
    }
    dem.compute = runChild({s.msiiProgram, "compute", tif, "-r", "15", "-n", "16", "-q", "--raster-output", out});
    if (!dem.compute.ok) {
        std::fprintf(stderr, "msii-benchmark: error: msii compute failed on the DEM\n");
        fs::remove_all(dir);
        return false;
    }
    dem.outputBytes = double(fs::file_size(out));
    std::ifstream sidecar((dir / "dem.msii.json").string());
    dem.json = nlohmann::json::parse(sidecar);
    dem.ok = true;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return true;
}

/// The terrain tools' case: a 1000 × 1000 DEM of 1 m, msii on both routes and RVT_py.
struct PeerRun {
    struct Row {
        std::string what;
        double seconds = 0, peakBytes = 0;
    };
    std::vector<Row> rows;  ///< per radius: heights, mesh, then RVT's two if given
    bool ok = false;
};

/// RVT_py's sky-view factor (16 directions, r_max = R cells) and multi-scale topographic
/// position (local, meso and broad scales splitting 1 … R cells in thirds), timed inside one
/// Python process (the imports and the reading excluded), printed as "svf SECONDS" and
/// "mstp SECONDS".
const char* kRvtScript = R"(import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from osgeo import gdal
import rvt.vis
dem = gdal.Open(sys.argv[2]).GetRasterBand(1).ReadAsArray().astype(np.float32)
R = int(sys.argv[3]); a, b = max(1, R // 3), max(2, 2 * R // 3)
t = time.perf_counter()
rvt.vis.sky_view_factor(dem=dem, resolution=1, compute_svf=True, compute_opns=True, svf_n_dir=16, svf_r_max=R, svf_noise=0)
print("svf", time.perf_counter() - t)
t = time.perf_counter()
rvt.vis.mstp(dem=dem, local_scale=(1, a, 1), meso_scale=(a, b, 1), broad_scale=(b, R, 1))
print("mstp", time.perf_counter() - t)
)";

bool runTerrainPeer(const Bench& bench, PeerRun& peer)
{
    const Settings& s = bench.settings;
    const fs::path& dir = bench.dir;
    const std::string tif = (dir / "peer.tif").string(), out = (dir / "peer.msii.tif").string();
    if (!runChild({s.samplesProgram, "terrain", "--geotiff", "--width", "1000", "--height", "1000", "--spacing", "1",
                   "--relief", "4", "--hill-width", "25", "--holes", "20", "--hole-size", "2", "-q", "--output", tif})
             .ok) {
        std::fprintf(stderr, "msii-benchmark: error: %s could not write the DEM\n", s.samplesProgram.c_str());
        return false;
    }
    for (const int R : {10, 30}) {
        for (const std::string engine : {"heights", "mesh"}) {
            const ChildRun r = runChild({s.msiiProgram, "compute", tif, "-r", std::to_string(R), "-j", "2", "-q",
                                         "--overwrite", "--engine", engine, "--raster-output", out});
            if (!r.ok) {
                std::fprintf(stderr, "msii-benchmark: error: msii compute --engine %s failed on the DEM\n", engine.c_str());
                return false;
            }
            peer.rows.push_back({"msii compute -r " + std::to_string(R) + " -j 2 --engine " + engine, r.seconds, r.peakBytes});
        }
        if (s.rvt.empty()) continue;
        const std::string script = (dir / "rvt_peer.py").string(), times = (dir / "rvt_times.txt").string();
        std::ofstream(script) << kRvtScript;
        const std::string command = "python3 '" + script + "' '" + s.rvt + "' '" + tif + "' " + std::to_string(R) + " > '" + times + "'";
        if (std::system(command.c_str()) != 0) {
            std::fprintf(stderr, "msii-benchmark: error: RVT_py from %s did not run (%s)\n", s.rvt.c_str(), command.c_str());
            return false;
        }
        std::ifstream in(times);
        std::string name;
        double seconds = 0;
        while (in >> name >> seconds)
            peer.rows.push_back({std::string(name == "svf" ? "RVT_py sky-view factor and openness, 16 directions"
                                                           : "RVT_py multi-scale topographic position") +
                                     ", r = " + std::to_string(R),
                                 seconds, 0});
    }
    peer.ok = true;
    return true;
}

void printPeerTable(Report& report, const PeerRun& peer)
{
    report.print("\nTerrain tools' case: a generated 1000 x 1000 DEM of 1 m cells (hills 25 m wide, 4 m high, 20 small "
                 "nodata patches), default bands, one run each, separate processes (RVT_py: its functions' time in "
                 "one Python process)\n\n");
    report.print("| %-62s | %8s | %8s |\n|%s|%s|%s|\n", "run", "seconds", "peak MB", std::string(64, '-').c_str(),
                 std::string(10, '-').c_str(), std::string(10, '-').c_str());
    for (const PeerRun::Row& r : peer.rows)
        report.print("| %-62s | %8.2f | %8s |\n", r.what.c_str(), r.seconds,
                     r.peakBytes > 0 ? std::to_string(int(r.peakBytes / 1e6)).c_str() : "");
    for (std::size_t k = 0; k + 1 < peer.rows.size(); ++k)
        if (peer.rows[k].what.find("--engine heights") != std::string::npos)
            report.print("| %-62s | %8.3f | %8s |\n", ("  heights / mesh, " + peer.rows[k].what.substr(13, 6)).c_str(),
                         peer.rows[k].seconds / peer.rows[k + 1].seconds, "");
}

/// Generates the tablet and writes it as the input PLY; returns the seconds taken.
double writeTablet(const Bench& bench)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = ho.height = bench.settings.size;
    ho.spacing = bench.settings.spacing;
    const Stopwatch generating;
    {
        const TriMesh mesh = samples::makeHeightField(ho);
        writePly(bench.input, mesh, {});
    }
    return generating.seconds();
}

/// The tablet's runs: seconds per run of each stage, and the last run's result and mesh,
/// on which the other commands are timed.
struct TabletRuns {
    std::vector<double> read, prepare, prepareHoles, check, ls, occ, st, interp, samp, pl, plCheck, plExact, compute, write,
        total, tiled;
    std::size_t holesFilled = 0;
    std::size_t tiledLargest = 0, tiledDiffering = 0;
    ComputeResult last;
    TriMesh lastMesh;
    std::size_t nv = 0;
};

ComputeOptions computeOptions(const Settings& s)
{
    InvariantsOptions o;
    o.radius = s.radius;
    o.scales = s.scales;
    o.minVoxelsPerRadius = s.precision;
    o.patchLinePrecision = s.plPrecision;
    o.voxelSize = s.voxel;
    o.select(parseInvariantList(s.invariants));
    ComputeOptions co;
    co.invariants = o;
    return co;
}

/// One run of the pipeline as msii compute runs it (preparation: checks, repair, holes; the
/// invariants; the values mapped to the input's vertices), on the clean tablet: read,
/// compute, write. Returns the mesh read.
TriMesh timeComputeRun(const Bench& bench, const ComputeOptions& co, TabletRuns& t)
{
    const Stopwatch wall;
    TriMesh mesh = readMesh(bench.input).mesh;
    t.read.push_back(wall.seconds());
    t.nv = mesh.numVertices();
    t.last = msii::compute(mesh, co);
    t.prepare.push_back(t.last.preparation.seconds);
    const Stopwatch writing;
    writePly(bench.output, mesh, outputProperties(t.last.features, t.last.filledShare));
    t.write.push_back(writing.seconds());
    t.total.push_back(wall.seconds());
    t.check.push_back(t.last.cost.check);
    t.ls.push_back(t.last.cost.levelSet);
    t.occ.push_back(t.last.cost.occupancy);
    t.st.push_back(t.last.cost.stencils);
    t.interp.push_back(t.last.cost.interpolation);
    t.samp.push_back(t.last.cost.samples);
    t.pl.push_back(t.last.cost.patchLine);
    t.plCheck.push_back(t.last.cost.patchLineCheck);
    t.plExact.push_back(t.last.cost.patchLineExact);
    t.compute.push_back(t.last.cost.total);
    return mesh;
}

/// One run of the same computation in K x K tiles, its values checked, not assumed: every
/// value against the untiled run's, bit for bit.
void timeTiledRun(const TriMesh& mesh, const ComputeOptions& co, int tiles, TabletRuns& t)
{
    ComputeOptions tco = co;
    tco.tiling.tilesPerAxis = tiles;
    const Stopwatch tiledWall;
    const ComputeResult tiled = msii::compute(mesh, tco);
    t.tiled.push_back(tiledWall.seconds());
    t.tiledLargest = tiled.tiling.largestTileVertices;
    const auto differing = [](const std::vector<std::vector<float>>& a, const std::vector<std::vector<float>>& b) {
        std::size_t count = 0;
        for (std::size_t j = 0; j < a.size(); ++j)
            for (std::size_t i = 0; i < a[j].size(); ++i)
                count += std::memcmp(&a[j][i], &b[j][i], sizeof(float)) != 0;
        return count;
    };
    t.tiledDiffering = 0;
    for (Invariant i : kAllInvariants) t.tiledDiffering += differing(tiled.features[i], t.last.features[i]);
}

/// One run of preparation alone, not counted in the total, on the tablet with 100 seeded
/// pin-holes, up to one spacing around.
void timePrepareWithHoles(const TriMesh& mesh, const Settings& s, TabletRuns& t)
{
    TriMesh holed = mesh;
    samples::HoleOptions holes;
    holes.count = 100;
    holes.minSize = 0.5 * s.spacing;
    holes.maxSize = s.spacing;
    samples::punchHoles(holed, holes);
    const Stopwatch preparing;
    PrepareMeshOptions po;
    po.maxHolePerimeter = defaultMaxHolePerimeter(s.radius);
    po.radius = s.radius;
    t.holesFilled = prepareMesh(holed, po).holes.numFilled;
    t.prepareHoles.push_back(preparing.seconds());
}

/// The tablet computed run after run; each run also times the tiled computation and the
/// preparation of the tablet with holes.
TabletRuns timeTablet(const Bench& bench)
{
    const Settings& s = bench.settings;
    TabletRuns t;
    for (int run = 0; run < s.runs; ++run) {
        const ComputeOptions co = computeOptions(s);
        TriMesh mesh = timeComputeRun(bench, co, t);
        if (s.tiles > 0) timeTiledRun(mesh, co, s.tiles, t);
        timePrepareWithHoles(mesh, s, t);
        if (run + 1 == s.runs) t.lastMesh = std::move(mesh);
    }
    return t;
}

/// msii compute and the Python module's msii.compute, each run once in its own process.
struct ProcessRuns {
    ChildRun cli, python;
    double pythonArrays = 0;  ///< bytes of the arrays a Python result holds
};

/// Memory of the program and of the Python module on the same input, each in its own
/// process (one run each): a Python result costs its arrays on top of the engine's own
/// peak, no more.
ProcessRuns runProcesses(const Bench& bench, const TabletRuns& tablet)
{
    const Settings& s = bench.settings;
    const fs::path& dir = bench.dir;
    ProcessRuns p;
    std::vector<std::string> args{s.msiiProgram, "compute", bench.input, "-r", number(s.radius), "-n", std::to_string(s.scales),
                                  "--precision", number(s.precision), "--invariants", s.invariants, "-q",
                                  "--overwrite", "--output", (dir / "process.msii.ply").string()};
    if (s.plPrecision > 0) args.insert(args.end(), {"--pl-precision", number(s.plPrecision)});
    p.cli = runChild(args);
    // Peaks as the processes measure them (VmHWM): wait4's counts the memory this
    // benchmark held when it started them.
    if (p.cli.ok) {
        std::ifstream record((dir / "process.msii.json").string());
        p.cli.peakBytes = nlohmann::json::parse(record).value("peak_memory_bytes", 0.0);
    }
#ifdef MSII_PYTHON
    if (s.precision == 6.0 && s.plPrecision == 0 && s.voxel == 0) {  // msii.compute's defaults
        ::setenv("PYTHONPATH", MSII_PYTHON_DIR, 1);
        p.python = runChild({MSII_PYTHON, "-c",
                             "import sys, msii\n"
                             "v, f = msii.read_mesh(sys.argv[1])\n"
                             "r = msii.compute(v, f, float(sys.argv[2]), scales=int(sys.argv[3]), "
                             "invariants=sys.argv[4])\n"
                             "peak = [l for l in open('/proc/self/status') if l.startswith('VmHWM:')][0]\n"
                             "open(sys.argv[5], 'w').write(str(float(peak.split()[1]) * 1024))\n",
                             bench.input, number(s.radius), std::to_string(s.scales), s.invariants,
                             (dir / "python-peak.txt").string()});
        if (p.python.ok) {
            std::ifstream peak((dir / "python-peak.txt").string());
            peak >> p.python.peakBytes;
        }
        std::size_t letters = 0;
        for (const char c : std::string("VSPL")) letters += s.has(c) ? 1 : 0;
        p.pythonArrays = double(tablet.nv) * (double(s.scales) * 4.0 * double(letters) + 24.0) +
                         double(tablet.lastMesh.numTriangles()) * 12.0;
    }
#else
    (void)tablet;
#endif
    return p;
}

/// A closed 7 x 5 x 3 mm tablet slab whose walls and bottom are a few long triangles.
TriMesh makeSlab(const Settings& s)
{
    samples::HeightFieldOptions so;
    so.kind = samples::HeightFieldKind::Tablet;
    so.width = 7;
    so.height = 5;
    so.spacing = s.spacing;
    so.closed = true;
    so.thickness = 3;
    so.wallStep = 1.5;
    return samples::makeHeightField(so);
}

/// The exact mode's runs: on a block of the tablet's vertices, and on every vertex of the slab.
struct ExactRuns {
    std::vector<double> vertexSeconds, slabSeconds;
};

/// The exact mode's options for the vertices [first, first + count).
ExactOptions exactOptions(const Settings& s, std::size_t first, std::size_t count)
{
    ExactOptions eo;
    eo.radii = equidistantRadii(s.radius, s.scales);
    eo.computeVolumeSphere = s.has('V') || s.has('S');
    eo.computePatchLine = s.has('P') || s.has('L');
    for (std::size_t i = first; i < first + count; ++i) eo.vertices.push_back(std::uint32_t(i));
    return eo;
}

/// One run of the exact mode on --exact-vertices consecutive vertices in the middle of the
/// tablet, setting up the whole mesh included; returns its seconds.
double timeExactOnVertices(const Settings& s, const TriMesh& tablet)
{
    const std::size_t count = std::min<std::size_t>(std::size_t(s.exactVertices), tablet.numVertices());
    const ExactOptions eo = exactOptions(s, (tablet.numVertices() - count) / 2, count);
    const Stopwatch t;
    computeExact(tablet, eo);
    return t.seconds();
}

/// One run of the exact mode on every vertex of @p slab; returns its seconds.
double timeExactOnSlab(const Settings& s, const TriMesh& slab)
{
    const Stopwatch t;
    computeExact(slab, exactOptions(s, 0, slab.numVertices()));
    return t.seconds();
}

/// Every feature of the invariants computed, as a table of one row per vertex.
FeatureTable featureTable(const Settings& s, const std::vector<VertexProperty>& props, std::size_t nv)
{
    std::vector<Invariant> all;
    for (const auto& [c, inv] : {std::pair{'V', Invariant::Volume}, std::pair{'S', Invariant::Sphere},
                                 std::pair{'P', Invariant::Patch}, std::pair{'L', Invariant::Line}})
        if (s.has(c)) all.push_back(inv);
    return featureTableOf(props, nv, all);
}

struct MetricRow {
    std::string name;
    MetricOptions options;
    std::vector<double> seconds;
};

/// The runs of every metric and of the 1-ring filters.
struct MetricRuns {
    std::vector<MetricRow> metricRows;
    std::vector<double> ringSetupMean, ringMean, ringSetupMedian, ringMedian;
};

/// One run of every metric over all computed features against a vertex's vector.
void timeMetrics(const FeatureTable& table, const std::vector<double>& reference, MetricRuns& m)
{
    for (MetricRow& row : m.metricRows) {
        const Stopwatch t;
        const MetricResult r = computeMetric(table, reference, row.options);
        row.seconds.push_back(t.seconds());
    }
}

/// One run of 30 passes of each 1-ring filter on @p quality, and of its set-up.
void timeSmoothing(const TriMesh& mesh, const std::vector<float>& quality, MetricRuns& m)
{
    for (const SmoothingFilter filter : {SmoothingFilter::Mean, SmoothingFilter::Median}) {
        SmoothingOptions so;
        so.filter = filter;
        so.iterations = 30;
        std::vector<float> values = quality;
        const Stopwatch setup;
        const RingSmoother smoother(mesh, so);
        const double setupSeconds = setup.seconds();
        const Stopwatch passes;
        smoother.smooth(values);
        (filter == SmoothingFilter::Mean ? m.ringSetupMean : m.ringSetupMedian).push_back(setupSeconds);
        (filter == SmoothingFilter::Mean ? m.ringMean : m.ringMedian).push_back(passes.seconds());
    }
}

/// After compute: every metric over all computed features (4 × N with V,S,P,L) against a
/// vertex's vector, and 30 passes of each 1-ring filter on quality, run after run.
MetricRuns timeMetricsAndSmoothing(const Settings& s, const FeatureTable& table, std::size_t nv, const TriMesh& mesh,
                                   const std::vector<float>& quality)
{
    std::size_t refVertex = nv / 2;  // a vertex with no masked element, near the middle
    for (std::size_t i = nv / 2; i < nv; ++i) {
        const float* row = table.values.data() + i * table.dimension();
        if (std::none_of(row, row + table.dimension(), [](float v) { return std::isnan(v); })) {
            refVertex = i;
            break;
        }
    }
    const std::vector<double> reference = vertexReference(table, refVertex);
    const double inf = std::numeric_limits<double>::infinity();
    MetricRuns m;
    m.metricRows = {
        {"l1", {MetricKind::PNorm, 1, false}, {}},   {"l2w", {MetricKind::PNorm, 2, true}, {}},
        {"linfw", {MetricKind::PNorm, inf, true}, {}}, {"lp (p = 3)", {MetricKind::PNorm, 3, false}, {}},
        {"mahalanobis", {MetricKind::Mahalanobis, 2, false}, {}}, {"cosine", {MetricKind::Cosine, 2, false}, {}},
        {"correlation", {MetricKind::Correlation, 2, false}, {}},
        {"autocorrelation", {MetricKind::AutoCorrelation, 2, false}, {}},
        {"tanimoto", {MetricKind::Tanimoto, 2, false}, {}},
        {"neuclid", {MetricKind::NormalizedEuclidean, 2, false}, {}}};
    for (int run = 0; run < s.runs; ++run) {
        timeMetrics(table, reference, m);
        timeSmoothing(mesh, quality, m);
    }
    return m;
}

struct MapRow {
    std::string name;
    FeatureMapOptions options;
    std::vector<double> seconds;
    double megabytes = 0;
};

/// The runs of the EXR feature map, in its variants, and of the PNG picture.
struct MapRuns {
    std::vector<MapRow> mapRows;
    std::vector<double> pictureSeconds;
    MapFrame mapFrame, pictureFrame;
};

/// One run of a PNG picture as msii render makes it: rasterise, colour, shade, isolines,
/// bars, write; returns its seconds.
double timePicture(const TriMesh& mesh, const MapFrame& frame, const std::vector<float>& quality,
                   const std::string& png)
{
    const Stopwatch t;
    const PixelHits hits = rasterize(mesh, frame);
    const std::vector<float> value = interpolateToPixels(mesh, hits, quality), mask = coverageMask(hits);
    const std::array<std::vector<float>, 3> normals = vertexNormalsInFrame(mesh, frame);
    std::vector<float> n3[3];
    for (std::size_t a = 0; a < 3; ++a) n3[a] = interpolateToPixels(mesh, hits, normals[a]);
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
    fig.pixelSize = frame.pixelSize;
    writePng(png, composeFigure(pic.image, fig));
    return t.seconds();
}

/// The EXR feature map (every feature and quality; default PIZ float, and the variants) and
/// a PNG picture, run after run.
MapRuns timeMapsAndPictures(const Bench& bench, const TriMesh& mesh, const std::vector<VertexProperty>& props,
                            const std::vector<float>& quality)
{
    const Settings& s = bench.settings;
    MapRuns m;
    m.mapRows.resize(3);
    m.mapRows[0].name = "float, piz (default)";
    m.mapRows[1].name = "float, none";
    m.mapRows[1].options.compression = ExrCompression::None;
    m.mapRows[2].name = "half, piz";
    m.mapRows[2].options.half = true;
    if (!(s.mapPixels > 0 && s.picturePixels > 0)) return m;
    fs::create_directories(bench.dir);
    MapFrameOptions fo;
    fo.longerSidePixels = s.mapPixels;
    m.mapFrame = makeMapFrame(mesh, fo);
    fo.longerSidePixels = s.picturePixels;
    m.pictureFrame = makeMapFrame(mesh, fo);
    const std::string exr = (bench.dir / "map.exr").string(), png = (bench.dir / "picture.png").string();
    for (int run = 0; run < s.runs; ++run) {
        for (MapRow& row : m.mapRows) {
            const Stopwatch t;
            writeFeatureMap(exr, mesh, m.mapFrame, props, row.options);
            row.seconds.push_back(t.seconds());
            row.megabytes = double(fs::file_size(exr)) / 1e6;
            fs::remove(exr);
        }
        m.pictureSeconds.push_back(timePicture(mesh, m.pictureFrame, quality, png));
    }
    fs::remove_all(bench.dir);
    return m;
}

/// A row of the tablet's table: @p value printed with @p format.
void row(Report& report, const char* name, double value, const char* format)
{
    report.print("| %-62s | ", name);
    report.print(format, value);
    report.print(" |\n");
}

/// What the tablet's table prints beyond the runs themselves.
struct TabletExtras {
    double generateSeconds = 0;
    const ExactRuns& exact;
    std::size_t slabVertices = 0;
    const MetricRuns& metrics;
    std::size_t numFeatures = 0, numProperties = 0;
    const MapRuns& maps;
    const ProcessRuns& processes;
};

/// The tablet's table: the line that says what was measured, the machine, and the stages.
void printTabletTable(Report& report, const Settings& s, const TabletRuns& t, const TabletExtras& x)
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    InvariantsOptions precision;
    precision.minVoxelsPerRadius = s.precision;
    precision.patchLinePrecision = s.plPrecision;
    report.print("msii-benchmark: tablet %.1f x %.1f mm, spacing %.3f mm, %zu vertices, R = %g, N = %d, "
                 "%s, precision %g (P, L: %g), voxel %.4f mm, %d levels, %d runs (medians)\n",
                 s.size, s.size, s.spacing, t.nv, s.radius, s.scales, s.invariants.c_str(), s.precision,
                 patchLinePrecision(precision), t.last.plan.voxelSize, t.last.plan.numVolumeSphereLevels(), s.runs);
    report.print("machine: %s, %u hardware threads\n\n", cpuModel().c_str(), std::thread::hardware_concurrency());
    report.print("| %-62s | %8s |\n|%s|%s|\n", "stage", "seconds", std::string(64, '-').c_str(), std::string(10, '-').c_str());
    row(report, "generate + write input (not counted)", x.generateSeconds, "%8.2f");
    row(report, "read PLY", median(t.read), "%8.2f");
    row(report, "prepare (checks, repair, holes; clean mesh)", median(t.prepare), "%8.2f");
    row(report, "check + statistics", median(t.check), "%8.2f");
    row(report, "level set", median(t.ls), "%8.2f");
    row(report, "occupancy pyramid", median(t.occ), "%8.2f");
    row(report, "stencils (V and S)", median(t.st), "%8.2f");
    row(report, "interpolation to vertices", median(t.interp), "%8.2f");
    row(report, "P, L: surface samples", median(t.samp), "%8.2f");
    row(report, "P, L: kernel sums", median(t.pl), "%8.2f");
    row(report, "  of which the check (kernels 1.5 times narrower)", median(t.plCheck), "%8.2f");
    {
        const InvariantsCost& c = t.last.cost;
        char label[96];
        std::snprintf(label, sizeof(label), "P, L: exact sums where the kernels blur (%.1f %% of values)",
                      100.0 * double(c.patchLinePairsExact) / double(std::max<std::size_t>(1, c.patchLinePairs)));
        row(report, label, median(t.plExact), "%8.2f");
    }
    row(report, "compute (the stages above but reading)", median(t.compute), "%8.2f");
    row(report, "write result PLY", median(t.write), "%8.2f");
    row(report, "**total wall, read to write**", median(t.total), "%8.2f");
    row(report, "vertices per second", t.nv / median(t.total), "%8.0f");
    row(report, "prepare, share of the total (target <= 10 %)", 100.0 * median(t.prepare) / median(t.total), "%7.1f%%");
    row(report, ("prepare with 100 pin-holes (" + std::to_string(t.holesFilled) + " filled; not in the total)").c_str(),
        median(t.prepareHoles), "%8.2f");
    row(report, "the same, share of the total (target <= 10 %)", 100.0 * median(t.prepareHoles) / median(t.total),
        "%7.1f%%");
    if (s.tiles > 0)
        row(report,
            ("compute in " + std::to_string(s.tiles) + " x " + std::to_string(s.tiles) + " tiles (largest " +
             std::to_string(t.tiledLargest) + " vertices with halo; " +
             (t.tiledDiffering == 0 ? std::string("bit-identical") : std::to_string(t.tiledDiffering) + " values differ") +
             ")")
                .c_str(),
            median(t.tiled), "%8.2f");
    if (!x.exact.vertexSeconds.empty()) {
        const std::size_t count = std::min<std::size_t>(std::size_t(s.exactVertices), t.nv);
        row(report, ("exact mode (--exact), " + std::to_string(count) + " vertices of the tablet, set-up included").c_str(),
            median(x.exact.vertexSeconds), "%8.2f");
    }
    if (!x.exact.slabSeconds.empty()) {
        row(report, ("exact mode, 7 x 5 x 3 mm slab, long walls, all " + std::to_string(x.slabVertices) + " vertices").c_str(),
            median(x.exact.slabSeconds), "%8.2f");
        row(report, "the same, milliseconds per vertex", 1e3 * median(x.exact.slabSeconds) / double(x.slabVertices), "%8.3f");
    }
    const std::string features = std::to_string(x.numFeatures) + " features";
    for (const MetricRow& m : x.metrics.metricRows)
        row(report, ("metric " + m.name + ", " + features).c_str(), median(m.seconds), "%8.2f");
    row(report, "1-ring set-up (mean)", median(x.metrics.ringSetupMean), "%8.2f");
    row(report, "1-ring mean, 30 passes", median(x.metrics.ringMean), "%8.2f");
    row(report, "1-ring set-up (median)", median(x.metrics.ringSetupMedian), "%8.2f");
    row(report, "1-ring median, 30 passes", median(x.metrics.ringMedian), "%8.2f");
    const MapRuns& maps = x.maps;
    for (const MapRow& m : maps.mapRows)
        if (!m.seconds.empty())
            row(report,
                ("EXR map " + std::to_string(maps.mapFrame.width) + " x " + std::to_string(maps.mapFrame.height) + ", " +
                 std::to_string(x.numProperties + 5) + " ch, " + m.name + ", " + std::to_string(int(m.megabytes)) + " MB")
                    .c_str(),
                median(m.seconds), "%8.2f");
    if (!maps.pictureSeconds.empty())
        row(report,
            ("PNG picture " + std::to_string(maps.pictureFrame.width) + " x " + std::to_string(maps.pictureFrame.height) +
             " (shaded colour, isolines, bars)")
                .c_str(),
            median(maps.pictureSeconds), "%8.2f");
    row(report, "peak memory (MB)", usage.ru_maxrss / 1024.0, "%8.0f");
    const ProcessRuns& p = x.processes;
    if (p.cli.ok) {
        row(report, "msii compute, own process: read to write", p.cli.seconds, "%8.2f");
        row(report, "the same, peak memory (MB)", p.cli.peakBytes / 1e6, "%8.0f");
    }
    if (p.python.ok) {
        row(report, "Python msii.compute, own process: import, read, compute", p.python.seconds, "%8.2f");
        row(report, "the same, peak memory (MB)", p.python.peakBytes / 1e6, "%8.0f");
        row(report, "arrays it holds: vertices, faces, V, S, P, L (MB)", p.pythonArrays / 1e6, "%8.0f");
        row(report, "its peak beyond msii compute's and the arrays (MB, target <= 0)",
            (p.python.peakBytes - p.cli.peakBytes - p.pythonArrays) / 1e6, "%8.0f");
    }
}

void printDemTable(Report& report, const DemRun& dem)
{
    const nlohmann::json& d = dem.json;
    const double cells = double(dem.side) * dem.side;
    const nlohmann::json& windows = d["raster"]["windows"];
    report.print("\nDEM %d x %d cells of 0.5 m (GeoTIFF, EPSG:25832, %.0f cells with heights); msii compute -r 15 "
                 "-n 16 (default bands): %d x %d windows of %d cells, halo %d cells (%d where no nodata gap "
                 "crosses it, in %d windows); one run each, separate processes\n\n",
                 dem.side, dem.side, d["raster"]["cells_with_height"].get<double>(), windows["per_row"].get<int>(),
                 windows["per_column"].get<int>(), windows["cells"].get<int>(), windows["halo_cells"].get<int>(),
                 windows["narrow_halo_cells"].get<int>(),
                 windows["per_row"].get<int>() * windows["per_column"].get<int>() -
                     windows["windows_with_wide_halo"].get<int>());
    report.print("| %-62s | %8s | %8s |\n|%s|%s|%s|\n", "stage", "seconds", "peak MB", std::string(64, '-').c_str(),
                 std::string(10, '-').c_str(), std::string(10, '-').c_str());
    report.print("| %-62s | %8.1f | %8.0f |\n", "msii-samples terrain --geotiff", dem.generate.seconds,
                 dem.generate.peakBytes / 1e6);
    report.print("| %-62s | %8.1f | %8.0f |\n",
                 ("**msii compute, read to write** (" + std::to_string(int(dem.outputBytes / 1e6)) + " MB)").c_str(),
                 dem.compute.seconds, dem.compute.peakBytes / 1e6);
    const auto& t = d["timings_seconds"];
    for (const char* stage : {"read", "prepare", "height_field", "level_set", "occupancy", "stencils", "interpolation", "write"})
        report.print("| %-62s | %8.1f | %8s |\n", ("  of which " + std::string(stage)).c_str(), t[stage].get<double>(), "");
    report.print("| %-62s | %8.2f | %8s |\n", "microseconds per cell", 1e6 * dem.compute.seconds / cells, "");
    report.print("| %-62s | %8.0f | %8s |\n", "cells per second", cells / dem.compute.seconds, "");
    report.print("| %-62s | %8s | %8s |\n", "targets", "1200", "4000");
}

/// The streamed terrain's table; @p smallPerVertex: the tablet's seconds per vertex.
void printLargeTable(Report& report, const Settings& s, const LargeRun& large, double smallPerVertex)
{
    const nlohmann::json& j = large.json;
    const double largeNv = j["mesh"]["vertices"].get<double>();
    const int perAxis = j["tiling"]["tiles_per_axis"].get<int>();
    const double perVertex = large.compute.seconds / largeNv;
    report.print("\nstreamed terrain %s x %s mm, spacing %.3f mm, %.0f vertices, %.0f triangles; "
                 "msii compute -r %g -n %d --invariants %s --memory-budget %s: %d x %d tiles (largest %.0f "
                 "vertices with halo, halo %.2f mm); one run each, separate processes\n\n",
                 number(large.side).c_str(), number(large.side).c_str(), s.spacing, largeNv,
                 j["mesh"]["faces"].get<double>(), s.radius, s.scales, s.invariants.c_str(), s.largeBudget.c_str(),
                 perAxis, perAxis, j["tiling"]["largest_tile_vertices"].get<double>(), j["tiling"]["halo"].get<double>());
    report.print("| %-62s | %8s | %8s |\n|%s|%s|%s|\n", "stage", "seconds", "peak MB", std::string(64, '-').c_str(),
                 std::string(10, '-').c_str(), std::string(10, '-').c_str());
    report.print("| %-62s | %8.1f | %8.0f |\n",
                 ("msii-samples terrain, streamed (" + std::to_string(int(large.inputBytes / 1e6)) + " MB)").c_str(),
                 large.generate.seconds, large.generate.peakBytes / 1e6);
    report.print("| %-62s | %8.1f | %8.0f |\n",
                 ("**msii compute, read to write** (" + std::to_string(int(large.outputBytes / 1e6)) + " MB)").c_str(),
                 large.compute.seconds, large.compute.peakBytes / 1e6);
    const auto& t = j["timings_seconds"];
    for (const char* stage : {"read", "check", "level_set", "stencils", "samples", "patch_line", "patch_line_exact", "write"})
        report.print("| %-62s | %8.1f | %8s |\n", ("  of which " + std::string(stage)).c_str(), t[stage].get<double>(), "");
    report.print("| %-62s | %8.2f | %8s |\n", "microseconds per vertex", 1e6 * perVertex, "");
    report.print("| %-62s | %8.2f | %8s |\n", "the same for the tablet above (total wall / vertices)", 1e6 * smallPerVertex, "");
    report.print("| %-62s | %8.2f | %8s |\n", "ratio (target <= 1.5)", perVertex / smallPerVertex, "");
}

/// --markdown: the report as the performance page.
void writeMarkdown(const Settings& s, const std::string& command, const Report& report)
{
    if (s.markdown.empty()) return;
    const std::string header = "Measured on " + todayUtc() + " with msii " + versionString() + " (" +
                               MSII_BUILD_TYPE + " build).\n";
    writeTextFileAtomic(s.markdown, performancePage(command, header, report.text));
    std::fprintf(stderr, "msii-benchmark: wrote %s\n", s.markdown.c_str());
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"msii-benchmark: stage timings of msii compute on a generated tablet surface"};
    Settings settings;
    addOptions(app, settings);
    CLI11_PARSE(app, argc, argv);
    try {
        parseInvariantList(settings.invariants);
    } catch (const InvalidInputError& e) {
        std::fprintf(stderr, "msii-benchmark: error: --invariants: %s\n", e.what());
        return 2;
    }
    const std::string command = commandLine(argc, argv, settings.markdown);
    Report report;

    const fs::path dir = fs::temp_directory_path() / ("msii-benchmark-" + std::to_string(getpid()));
    fs::create_directories(dir);
    const Bench bench{settings, dir, (dir / "tablet.ply").string(), (dir / "tablet.msii.ply").string()};
    // The separate processes first, while this process is small: a spawned child starts out
    // sharing this process's memory, which would count in its peak.
    LargeRun large;
    if (settings.largeVertices > 0 && !runLargeTerrain(bench, large)) return 1;
    DemRun dem;
    if (settings.demCells > 0 && !runDem(bench, dem)) return 1;
    PeerRun peer;
    if ((settings.terrainPeer || !settings.rvt.empty()) && !runTerrainPeer(bench, peer)) return 1;

    const double generateSeconds = writeTablet(bench);
    const TabletRuns tablet = timeTablet(bench);
    ProcessRuns processes;
    if (settings.processes) processes = runProcesses(bench, tablet);
    fs::remove_all(dir);

    // The exact mode (V, S, P, L from the triangles): on a block of the tablet's vertices,
    // and on every vertex of a closed slab with long wall and bottom triangles.
    ExactRuns exact;
    const TriMesh slab = settings.exactSlab ? makeSlab(settings) : TriMesh();
    for (int run = 0; run < settings.runs; ++run) {
        if (settings.exactVertices > 0) exact.vertexSeconds.push_back(timeExactOnVertices(settings, tablet.lastMesh));
        if (settings.exactSlab) exact.slabSeconds.push_back(timeExactOnSlab(settings, slab));
    }

    const std::vector<VertexProperty> props = featureProperties(tablet.last.features);
    const FeatureTable table = featureTable(settings, props, tablet.nv);
    const std::vector<float> quality = props.back().values;
    const MetricRuns metrics = timeMetricsAndSmoothing(settings, table, tablet.nv, tablet.lastMesh, quality);
    const MapRuns maps = timeMapsAndPictures(bench, tablet.lastMesh, props, quality);

    const TabletExtras extras{generateSeconds, exact, slab.numVertices(), metrics, table.dimension(), props.size(),
                              maps, processes};
    printTabletTable(report, settings, tablet, extras);
    std::fflush(stdout);
    if (dem.ok) printDemTable(report, dem);
    if (peer.ok) printPeerTable(report, peer);
    if (large.ok) printLargeTable(report, settings, large, median(tablet.total) / double(tablet.nv));
    writeMarkdown(settings, command, report);
    return 0;
}
