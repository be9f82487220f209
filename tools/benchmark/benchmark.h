/// @file benchmark.h
/// @brief What the cases of `msii-benchmark` share: the settings (the command line), the
/// work folder, the report that is printed and kept for the performance page, a few helpers,
/// and each case's entry points. Each case has a file of its own, named after it:
/// tablet_case.cpp, processes_case.cpp, exact_case.cpp, metrics_case.cpp, maps_case.cpp, sheets_case.cpp,
/// vessels_case.cpp,
/// large_terrain_case.cpp, dem_case.cpp and terrain_peer_case.cpp; benchmark_main.cpp runs
/// them in order and writes the page.
#pragma once
#include <msii/core/feature_set.h>
#include <msii/featuremap/feature_map.h>
#include <msii/featuremap/map_frame.h>
#include <msii/mesh/trimesh.h>
#include <msii/metrics/feature_metrics.h>
#include <msii/pipeline/compute.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace msii::benchmark {

namespace fs = std::filesystem;

/// The median of @p v; 0 if it is empty.
double median(std::vector<double> v);
/// @p v as the programs' options take it (%.6g).
std::string number(double v);

/// A child program's wall time, peak resident memory and exit status.
struct ChildRun {
    double seconds = 0, peakBytes = 0;
    bool ok = false;
};

/// Runs @p args (the program's path first) in a process of its own and waits for it.
ChildRun runChild(const std::vector<std::string>& args, const std::string& log = "");

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

/// A row of the tablet's table: @p value printed with @p format.
void row(Report& report, const char* name, double value, const char* format);

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
    bool scans = true;         ///< the scans case: scan-like slabs of ~38k and ~300k vertices, and the tablet
    bool sheets = true;        ///< the sheets case: the fat cross beside one view, on the tablet and a closed tablet
    double sheetDpi = 600;     ///< the sheets case's scale
    bool vessels = true;       ///< the vessels case: msii axis, profile and unroll on a vase of ~1M vertices
    double vesselSpacing = 0.245;  ///< its spacing, mm
    std::string before;        ///< an earlier msii program, run beside --msii on the scans case
    std::string gigamesh;      ///< a folder holding GigaMesh's gigamesh-featurevectors and -sl
    std::string markdown;

    /// Whether --invariants (read as msii compute reads it) selects the invariant of letter @p c.
    bool has(char c) const
    {
        const std::vector<Invariant> list = parseInvariantList(invariants);
        return std::find(list.begin(), list.end(), *invariantOfLetter(c)) != list.end();
    }
};

/// What the cases share: the settings, and the work folder with the tablet's input and
/// output files.
struct Bench {
    const Settings& settings;
    fs::path dir;
    std::string input, output;
};

// The tablet (tablet_case.cpp).

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

/// Generates the tablet and writes it as the input PLY; returns the seconds taken.
double writeTablet(const Bench& bench);

/// The tablet computed run after run; each run also times the tiled computation and the
/// preparation of the tablet with holes.
TabletRuns timeTablet(const Bench& bench);

// msii compute and the Python module in their own processes (processes_case.cpp).

/// msii compute and the Python module's msii.compute, each run once in its own process.
struct ProcessRuns {
    ChildRun cli, python;
    double pythonArrays = 0;  ///< bytes of the arrays a Python result holds
};

/// Memory of the program and of the Python module on the same input, each in its own
/// process (one run each): a Python result costs its arrays on top of the engine's own
/// peak, no more.
ProcessRuns runProcesses(const Bench& bench, const TabletRuns& tablet);

/// The rows of the tablet's table for the processes that ran.
void printProcessRows(Report& report, const ProcessRuns& p);

// The exact mode (exact_case.cpp).

/// A closed 7 x 5 x 3 mm tablet slab whose walls and bottom are a few long triangles.
TriMesh makeSlab(const Settings& s);

/// The exact mode's runs: on a block of the tablet's vertices, and on every vertex of the slab.
struct ExactRuns {
    std::vector<double> vertexSeconds, slabSeconds;
};

/// One run of the exact mode on --exact-vertices consecutive vertices in the middle of the
/// tablet, setting up the whole mesh included; returns its seconds.
double timeExactOnVertices(const Settings& s, const TriMesh& tablet);

/// One run of the exact mode on every vertex of @p slab; returns its seconds.
double timeExactOnSlab(const Settings& s, const TriMesh& slab);

/// The rows of the tablet's table for the exact mode's runs; @p tabletVertices and
/// @p slabVertices: the two meshes' vertices.
void printExactRows(Report& report, const Settings& s, const ExactRuns& exact, std::size_t tabletVertices,
                    std::size_t slabVertices);

// Metrics and 1-ring smoothing (metrics_case.cpp).

/// Every feature of the invariants computed, as a table of one row per vertex.
FeatureTable featureTable(const Settings& s, const std::vector<VertexProperty>& props, std::size_t nv);

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

/// After compute: every metric over all computed features (4 × N with V,S,P,L) against a
/// vertex's vector, and 30 passes of each 1-ring filter on quality, run after run.
MetricRuns timeMetricsAndSmoothing(const Settings& s, const FeatureTable& table, std::size_t nv, const TriMesh& mesh,
                                   const std::vector<float>& quality);

/// The rows of the tablet's table for every metric over @p numFeatures features and for the
/// 1-ring filters.
void printMetricRows(Report& report, const MetricRuns& metrics, std::size_t numFeatures);

// EXR maps and the PNG picture (maps_case.cpp).

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

// The six views on one sheet beside one view (sheets_case.cpp).

/// One view's picture and the sheet of the same input at the same pixel size, in turn.
struct SheetPair {
    std::vector<double> view, sheet;
    bool ok = true;
};
struct SheetRuns {
    SheetPair tablet, closed;
    std::size_t closedVertices = 0;
};

/// `msii render` (one view) and `msii render --layout fat-cross` in processes of their own,
/// in turn: on the tablet's results (bench.output) and on a closed tablet of about
/// @p tabletVertices vertices.
SheetRuns timeSheets(const Bench& bench, std::size_t tabletVertices);

/// The rows of the tablet's table for the sheets' runs.
void printSheetRows(Report& report, const Settings& s, const SheetRuns& r, std::size_t tabletVertices);

// Vessels: axis, profile and rollout (vessels_case.cpp).

struct VesselRuns {
    std::array<std::vector<double>, 3> seconds;  ///< msii axis, profile, unroll
    std::size_t vertices = 0;
    bool ok = true;
};

/// `msii axis`, `msii profile` and `msii unroll` on a generated vase, each in a process of its
/// own, run after run.
VesselRuns timeVessels(const Bench& bench);

/// The rows of the tablet's table for the vessels' runs.
void printVesselRows(Report& report, const VesselRuns& r);

/// The vertex count a PLY's header states (0 if it cannot be read).
std::size_t readVertexCount(const std::string& ply);

/// The EXR feature map (every feature and quality; default PIZ float, and the variants) and
/// a PNG picture, run after run.
MapRuns timeMapsAndPictures(const Bench& bench, const TriMesh& mesh, const std::vector<VertexProperty>& props,
                            const std::vector<float>& quality);

/// The rows of the tablet's table for the EXR maps (a channel for each of @p numProperties
/// properties, and height, normal and mask) and the PNG picture, where they were made.
void printMapRows(Report& report, const MapRuns& maps, std::size_t numProperties);

// The tablet's table (tablet_case.cpp), with the rows of the cases above.

/// What the tablet's table prints beyond the runs themselves.
struct TabletExtras {
    double generateSeconds = 0;
    const ExactRuns& exact;
    std::size_t slabVertices = 0;
    const MetricRuns& metrics;
    std::size_t numFeatures = 0, numProperties = 0;
    const MapRuns& maps;
    const ProcessRuns& processes;
    const SheetRuns& sheets;
    const VesselRuns& vessels;
};

/// The tablet's table: the line that says what was measured, the machine, and the stages.
void printTabletTable(Report& report, const Settings& s, const TabletRuns& t, const TabletExtras& x);

// Scans of the sizes most users have, and the established tool on one (scans_case.cpp).
/// One program's runs of msii compute on one scan with one set of invariants: each stage's
/// seconds per run (the JSON record's timings), the process's wall time and peak memory.
struct ScanTimings {
    std::map<std::string, std::vector<double>> stages;
    std::vector<double> wall, peakBytes;
    double shareExact = -1;  ///< the share of P, L values evaluated exactly (-1: not said)
    bool ok = true;
};
/// A scan of the case: its PLY, size, radius and threads, and the runs with all four
/// invariants ([0]) and with V and S alone ([1]), of --msii ([·][0]) and --before ([·][1]).
struct ScanCase {
    std::string name, input;
    std::size_t vertices = 0;
    double radius = 0, medianEdge = 0;
    int threads = 1;
    ScanTimings runs[2][2];
};
/// GigaMesh's tools on the smallest scan, one CPU: gigamesh-featurevectors (V and P at the N
/// radii) and gigamesh-featurevectors-sl (S, then L, one radius per run, at each radius).
struct GigaMeshRun {
    bool ran = false, ok = false;
    std::string error;
    double volumePatch = 0, sphereLine = 0, peakBytes = 0;
    std::vector<double> msiiVolumePatch;  ///< msii compute --invariants V,P on the same scan, one thread
};
struct ScanRuns {
    std::vector<ScanCase> cases;
    bool before = false;
    GigaMeshRun gigamesh;
};
/// The scans case: scan-like closed slabs of about 38k (one thread) and 300k vertices (two
/// threads) at R = 25 median edges, and the tablet (bench.input, written already; two
/// threads, R = --radius), each computed by msii compute in a process of its own, run after
/// run, with all four invariants and with V and S alone; with --before, the earlier program
/// in turn with --msii on every run; with --gigamesh, GigaMesh's tools on the smallest scan.
ScanRuns runScans(const Bench& bench);
/// A table per scan: each stage's median seconds, and with --before both programs and their
/// ratio; then GigaMesh's times and their ratio to msii's.
void printScanTables(Report& report, const Settings& s, const ScanRuns& scans);

// The DEM (dem_case.cpp).

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
bool runDem(const Bench& bench, DemRun& dem);

/// The DEM's table: its windows, and the time and peak memory of each program.
void printDemTable(Report& report, const DemRun& dem);

// The terrain tools' case (terrain_peer_case.cpp).

/// The terrain tools' case: a 1000 × 1000 DEM of 1 m, msii on both routes and RVT_py.
struct PeerRun {
    struct Row {
        std::string what;
        double seconds = 0, peakBytes = 0;
    };
    std::vector<Row> rows;  ///< per radius: heights, mesh, then RVT's two if given
    bool ok = false;
};

/// Generates the 1000 × 1000 DEM and times msii compute on it at R = 10 and 30 cells on both
/// routes, and RVT_py with --rvt. Returns false, having said why, if a program failed.
bool runTerrainPeer(const Bench& bench, PeerRun& peer);
/// The terrain tools' table: a row per run, and the height field's time over the mesh's.
void printPeerTable(Report& report, const PeerRun& peer);

// The streamed terrain (large_terrain_case.cpp).

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
bool runLargeTerrain(const Bench& bench, LargeRun& large);

/// The streamed terrain's table; @p smallPerVertex: the tablet's seconds per vertex.
void printLargeTable(Report& report, const Settings& s, const LargeRun& large, double smallPerVertex);

} // namespace msii::benchmark
