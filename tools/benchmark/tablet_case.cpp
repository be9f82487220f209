/// @file tablet_case.cpp
/// @brief The tablet: times the compute job on a generated tablet-like open surface
/// (default: ~1.1M vertices at 0.03 mm spacing, R = 1 mm, N = 16) and prints a table of
/// median stage timings over several runs, vertices/s, peak memory and the machine.
/// Each run does what `msii compute` does: read the mesh from a binary PLY file (written
/// once beforehand), compute, and write the result PLY; the total is that whole wall time.
/// Each run also times the same computation in tiles and the preparation of the tablet with
/// pin-holes. The table holds the rows of the cases timed on the tablet's results as well.
#include "benchmark.h"

#include <msii/core/stopwatch.h>
#include <msii/invariants/invariants.h>
#include <msii/io/feature_properties.h>
#include <msii/io/read_mesh.h>
#include <msii/io/write_ply.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/samples/generators.h>

#include <sys/resource.h>

#include <cstring>
#include <fstream>
#include <thread>

namespace msii::benchmark {

namespace {
std::string cpuModel()
{
    std::ifstream in("/proc/cpuinfo");
    for (std::string line; std::getline(in, line);)
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

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

} // namespace

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
    printExactRows(report, s, x.exact, t.nv, x.slabVertices);
    printMetricRows(report, x.metrics, x.numFeatures);
    printMapRows(report, x.maps, x.numProperties);
    row(report, "peak memory (MB)", usage.ru_maxrss / 1024.0, "%8.0f");
    printProcessRows(report, x.processes);
    if (s.sheets) printSheetRows(report, s, x.sheets, t.nv);
    if (s.vessels) printVesselRows(report, x.vessels);
}

} // namespace msii::benchmark
