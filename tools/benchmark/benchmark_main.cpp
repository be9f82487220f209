/// @file benchmark_main.cpp
/// @brief `msii-benchmark`: times msii on generated inputs and prints a table per case: the
/// tablet's stages, with the cases run on the tablet or on its results in the same table
/// (msii compute and Python in their own processes, the exact mode, metrics and 1-ring
/// smoothing, EXR maps and the PNG picture), and, where asked for, the DEM, the terrain
/// tools' case and the streamed terrain. Here: the options, the order the cases run in,
/// and the performance page (--markdown). Each case has a file of its own (benchmark.h).
#include "benchmark.h"

#include <msii/core/errors.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <ctime>

namespace msii::benchmark {

namespace {
std::string todayUtc()
{
    const std::time_t now = std::time(nullptr);
    char text[32];
    std::strftime(text, sizeof(text), "%Y-%m-%d", std::gmtime(&now));
    return text;
}

/// The page's head: what is measured and its targets, and the start of the command's block.
const char* pageIntro()
{
    return R"(# Performance

<!-- Written by msii-benchmark --markdown; do not edit by hand: run the command below. -->

Stage timings of `msii compute` on a generated tablet surface (the benchmark's own input: an
irregular, scanner-like triangulation with cuneiform wedges), medians of the runs, with the
other commands' costs on its results. Targets: 30 s and 4 GB for the 1.1M-vertex tablet, and
at most 10 % of the total for mesh preparation. With `--dem-cells`, also a DEM computed in
windows: 20 minutes (1,200 s) and 4 GB for 100M cells.

```bash
)";
}

/// What each row of the tables measures, and how.
const char* rowsExplained()
{
    return R"(
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
- **Scans** (`--scans`, on by default): `msii compute`, in a process of its own as a user
  runs it, on scan-like closed slabs of about 38k vertices (one thread) and 300k vertices
  (two threads), and on the tablet (two threads). The slabs have triangles of aspect 3 : 1,
  vertex density varying 4×, white scanner noise of about a tenth of an edge, and walls and
  bottom of a few long triangles; R is 25 median edges. Each stage comes from the run's JSON
  record, with all four invariants and with V and S alone. With `--before "PROGRAM"` an
  earlier build runs in turn with this one on the same inputs, and the table gives both and
  their ratio (an earlier build: `git worktree add ../msii-old COMMIT`, then build it as the
  README says and pass `../msii-old/build/tools/msii`). With `--gigamesh PATH`, GigaMesh's
  `gigamesh-featurevectors` (V and P at the N radii) and `gigamesh-featurevectors-sl` (S and
  L, one radius per run) run on the 38k-vertex slab on one CPU, against `msii compute -j 1`.
  Build them from GigaMesh's public repository with CMake (`-DBUILD_GUI=OFF
  -DENABLE_TESTS=OFF`, targets `gigamesh-featurevectors` and `gigamesh-featurevectors-sl`);
  they take hours there.
- **DEM**: `msii compute` on a generated GeoTIFF DEM (0.5 m cells in EPSG:25832, hills about
  25 m wide and 4 m high, 200 small nodata patches), R = 15 m, N = 16, the default bands
  (quality and V at R/4, R/2, 3R/4 and R: V alone is computed, from the height field), in
  windows of 2,048 cells, in a process of its own with its peak memory
  ([terrain.md](terrain.md#large-areas)).
- **Terrain tools' case** (`--terrain-peer`): a 1000 × 1000 DEM of 1 m at R = 10 and 30
  cells, on the height field and on the mesh (`--engine mesh`), and with `--rvt PATH`
  RVT_py's sky-view factor and openness (16 directions) and multi-scale topographic
  position at the same radius, their functions' time in one Python process, and the
  sky-view factor and openness once more as a user runs them: a process of its own that
  imports RVT_py, reads the DEM and writes both GeoTIFFs (`save_sky_view_factor`)
  ([terrain.md](terrain.md#large-areas)).
)";
}

/// Where the time goes now, stage by stage, and what would make each faster.
const char* speedLimits()
{
    return R"(
What limits the speed now, and the next steps:
- **P and L's exact sums** (the check's flagged pairs, evaluated from the triangles) are the
  largest stage on the slabs, and with the kernel sums they take most of the time of all four
  invariants on every scan (tables above). The walk opens only the blocks and cells along the
  flagged spheres, adds the others whole, and clips only the triangles a flagged sphere
  cuts, so it already visits about the shell of a kernel's width around each sphere, not
  the ball: on the Stanford bunny at R = 27 median edges (one thread), a flagged pair's ball
  holds 2,796 triangles on average, the walk tests 659 of them and clips 259; the stage is
  about 55 % testing triangles, 25 % clipping and 20 % walking the blocks and cells (perf),
  and it is bound by computation, not memory (a vertex walked twice takes twice as long).
  Each pair therefore costs about its sphere's circumference in triangles (the clips are
  the sphere's own cuts: 2 % of them find nothing), and the total follows the number of pairs
  flagged: 27 % of the Stanford bunny's pairs at R = 27 median edges, against 10–11 % on the
  slabs, where all four invariants take 1.40 times 7764c7f's time, and 7 % on the tablet
  (1.22 times; tables above). Counting the flagged radii per triangle in loops that
  vectorise helped a little (values bit-identical); cells of 1, 3 or 4 median edges instead
  of 2, the tests compiled for AVX2 through run-time dispatch (slower: the calls cost more
  than the wider lanes gain), the clips' corners stored per triangle, or the whole areas
  summed per radius did not help. On the
  39k slab, 81 % of the vertices are flagged at the smallest radius checked (3.1 median
  edges) and 25 % at the next, where under 1 % of the flagged pairs had kernel values beyond
  the stated bounds, yet those small balls cost 45 % of the stage: cells of two median edges
  hold up to 45 triangles where the vertices are densest, and a small ball tests about as
  many triangles as it holds. At larger radii, 25–35 % of the bunny's flagged pairs are
  beyond the bounds and 50–60 % beyond half of them, so those flags are mostly needed. A
  check that allows for the narrow kernels' noise (thresholds raised by half of its median
  at 6 cells, falling as (6 h_0/r)²) spares a fifth of the slab's exact sums but leaves 4
  pairs beyond the bounds unflagged (1 with today's check, L̂ off by 0.015), so the check
  stays ([method.md](method.md#exact-where-the-kernels-blur)). Even a check that knew the
  errors would send a quarter of today's flagged pairs on the bunny (23.5 %, those beyond
  the bounds) to the exact sums, so the exact sums per pair, or the kernels' own errors near
  a sphere's tangencies and creases, must fall before scans like it cost little more than
  the kernels. On the tablet the check's other cost is in the kernel sums (13.26 s against
  10.10 s, table above): the fitted vertices whose fit bends beyond the check's thresholds
  are evaluated where they are (about eight times as many as without the check), which
  halves the pairs flagged there.
  Next: clips that share a triangle's frame over its flagged radii, and kernels that err
  less where a sphere becomes tangent to a sheet or meets a crease.
- **P and L's kernel sums**: per vertex, the histograms of the samples within reach, over
  distance (binning 26 %, adding into the histograms 50 % of the stage, callgrind on the 39k
  slab). Neither the continuation's vertices (past open borders) nor samples that no
  vertex's fit reads are evaluated, nor V and S's nodes around those vertices: on a tablet of
  111k vertices, where the continuation is a quarter of the vertices, that takes the kernel
  sums to 0.72 and the stencils to 0.63 of their time, values identical
  ([method.md](method.md#where-p-and-l-are-evaluated)); on the 1.1M tablet it is a smaller
  share. Next: histograms shared by neighbouring vertices.
- **V and S**: the level set and the stencils. The level set's cost follows the surface's
  area over the finest voxel squared, not the vertices: a slab whose walls and bottom are a
  few long triangles pays for their area as for the top's. Most of it is the band's
  approximate distances, a row of eight voxels against a triangle at once (about 30
  voxel-triangle pairs per band voxel on the 39k slab, where a row costs about 40 ns); in
  vector lanes of floats, two rows at once, it was no faster. It includes loading OpenVDB's
  libraries (about 0.04 s; twice that while GDAL's were loaded into every run,
  [architecture.md](architecture.md)). The stencils' largest part is now their entries'
  additions, one per voxel of the largest ball per row of nodes; the coarser levels' nodes
  each take an exact distance from the mesh (a descent, then a grid of triangles; about a
  tenth of V and S), which the band's rasterization done at those levels would not make
  cheaper (their reach, in triangles, is larger). Next: a coarser level set where no vertex
  is near.
- **DEMs** on the height field: the kernel is most of the time (reading, filling,
  continuing and writing the rest). It sums sixteen cells at a time (one AVX-512 register
  where the processor has it, two AVX2 registers elsewhere), its products fused into its
  sums. The clamps of the chords near the disc's rim are most of the kernel: a lane sums a
  piece only where its largest |z − z₀| over the piece's quadrant of the disc (from squares
  of 2 × 2 cells) reaches the piece's half-chord, which on a 1000² DEM at R = 10 cells takes
  0.86 of the time of one bound for the whole disc (eight or sixteen sectors cost more in
  their bounds than they save in pieces). Next: the rim's pieces as annular sectors with
  h(ρ) integrated in closed form, so that they can be longer. On a 1000 × 1000 DEM at
  R = 10 cells (0.29 s), the kernel is 0.09 s; a fixed 0.12 s is starting the process,
  loading GDAL's libraries and reading the coordinate system (PROJ's database, 0.06 s
  together), and writing the Cloud-Optimized GeoTIFF (0.055 s, ZSTD at level 1 hardly
  faster), which RVT_py's function's time does not include (its whole process: 0.66 s;
  [terrain.md](terrain.md#large-areas)).
)";
}

/// How far this machine's timings can be trusted, and where the accuracy is.
const char* timingNote()
{
    return R"(
This machine's timings vary from one sitting to the next, by 15–20 % within a day and by up
to 2× between days, also in stages whose code did not change: compare builds in alternating
runs. The accuracy of the same settings is in [accuracy.md](accuracy.md); P and L use
8 cells per radius by default (`--pl-precision 6` is less exact at sharp edges, and no faster).
)";
}

/// docs/performance.md: what is measured, the command that measures it again, the machine
/// and build, and the tables; generated whole, so that the page cannot drift from the program.
std::string performancePage(const std::string& command, const std::string& header, const std::string& tables)
{
    std::string page = pageIntro();
    page += command + "\n```\n\n" + header + "\n" + tables;
    page += rowsExplained();
    page += speedLimits();
    page += timingNote();
    return page;
}

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
    app.add_option("--scans", s.scans,
                   "also time msii compute, in a process of its own and per stage, on scan-like closed slabs of ~38k "
                   "(one thread) and ~300k vertices (two threads) at R = 25 median edges and on the tablet (two "
                   "threads), with all four invariants and with V and S alone (default true)");
    app.add_option("--sheets", s.sheets,
                   "also time msii render --layout fat-cross beside one view's msii render at the same pixel size, "
                   "each in its own process, on the tablet's results and on a closed tablet of as many vertices "
                   "(default true)");
    app.add_option("--sheet-dpi", s.sheetDpi, "the sheets' scale, dots per inch (default 600)");
    app.add_option("--vessels", s.vessels,
                   "also time msii axis, msii profile and msii unroll, each in its own process, on a generated vase "
                   "of about a million vertices (default true)");
    app.add_option("--vessel-spacing", s.vesselSpacing, "the vase's vertex spacing, mm (default 0.245: about 1M vertices)");
    app.add_option("--before", s.before,
                   "with the scans: an earlier msii build's program (\"PROGRAM [ARGS...]\"), run in turn with --msii "
                   "on the same inputs, for before/after columns and their ratio")
        ->type_name("COMMAND");
    app.add_option("--gigamesh", s.gigamesh,
                   "with the scans: also time GigaMesh's gigamesh-featurevectors (V, P) and gigamesh-featurevectors-sl "
                   "(S, L: a run per radius each) on the ~38k-vertex scan on one CPU, against msii compute -j 1: PATH is "
                   "the folder holding both programs (built from GigaMesh's repository with -DBUILD_GUI=OFF; not "
                   "installed by msii; it takes hours)")
        ->type_name("PATH");
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
        command += a.find(' ') == std::string::npos ? " " + a : " \"" + a + "\"";
    }
    command += markdown.empty() ? "" : " --markdown docs/performance.md";
    return command;
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

} // namespace msii::benchmark

using namespace msii;
using namespace msii::benchmark;

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
    ScanRuns scans;
    if (settings.scans || !settings.before.empty() || !settings.gigamesh.empty()) scans = runScans(bench);
    const TabletRuns tablet = timeTablet(bench);
    ProcessRuns processes;
    if (settings.processes) processes = runProcesses(bench, tablet);
    SheetRuns sheets;
    if (settings.sheets) sheets = timeSheets(bench, tablet.nv);
    VesselRuns vessels;
    if (settings.vessels) vessels = timeVessels(bench);
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
                              maps, processes, sheets, vessels};
    printTabletTable(report, settings, tablet, extras);
    std::fflush(stdout);
    if (!scans.cases.empty()) printScanTables(report, settings, scans);
    std::fflush(stdout);
    if (dem.ok) printDemTable(report, dem);
    if (peer.ok) printPeerTable(report, peer);
    if (large.ok) printLargeTable(report, settings, large, median(tablet.total) / double(tablet.nv));
    writeMarkdown(settings, command, report);
    return 0;
}
