/// @file scans_case.cpp
/// @brief Scans of the sizes most users have: scan-like closed slabs of about 38k and 300k
/// vertices (triangles of aspect 3 : 1, vertex density varying 4×, white scanner noise of
/// about a tenth of an edge, walls and bottom of a few long triangles) at R = 25 median
/// edges, and the benchmark's 1.1M-vertex tablet. Each is computed by the msii program in a
/// process of its own, as a user runs it, with all four invariants and with V and S alone;
/// the stages come from the run's JSON record. With --before, an earlier build's program
/// runs in turn with it on the same inputs (pairs of runs, so that the machine's drift
/// falls on both alike). With --gigamesh, the established tool's programs run on the
/// smallest scan.
#include "benchmark.h"

#include <msii/io/write_ply.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/samples/generators.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace msii::benchmark {

namespace {

/// The stages of msii compute's JSON record, in the pipeline's order, with their rows' names.
const std::pair<const char*, const char*> kStages[] = {
    {"read", "read PLY"},
    {"prepare", "prepare (checks, repair, holes, continuation)"},
    {"check", "check + statistics"},
    {"level_set", "level set"},
    {"occupancy", "occupancy pyramid"},
    {"stencils", "stencils (V and S)"},
    {"interpolation", "interpolation to vertices"},
    {"samples", "P, L: surface samples"},
    {"patch_line", "P, L: kernel sums"},
    {"patch_line_check", "  of which the check"},
    {"patch_line_exact", "P, L: exact sums where the kernels blur"},
    {"write", "write result PLY"},
    {"total", "total, read to write (the record's)"},
};

/// Splits @p command as a shell splits plain words (no quotes): "PROGRAM [ARGS...]".
std::vector<std::string> words(const std::string& command)
{
    std::istringstream in(command);
    std::vector<std::string> out;
    for (std::string w; in >> w;) out.push_back(w);
    return out;
}

/// A scan-like closed slab of @p width × @p height mm at the benchmark's spacing, written to
/// @p path; fills @p c's size and median edge.
void writeScanLikeSlab(const Settings& s, double width, double height, const std::string& path, ScanCase& c)
{
    samples::HeightFieldOptions so;
    so.kind = samples::HeightFieldKind::Tablet;
    so.width = width, so.height = height, so.spacing = s.spacing;
    so.closed = true, so.thickness = 3, so.wallStep = 1.5;
    so.anisotropy = 3, so.densityVariation = 4;
    so.roughness = 0.133 * s.spacing;  // about a tenth of the median edge
    const TriMesh mesh = samples::makeHeightField(so);
    writePly(path, mesh, {});
    c.input = path;
    c.vertices = mesh.numVertices();
    c.medianEdge = computeMeshStats(mesh).medianEdge;
}

/// One run of @p program (its words) on scan @p c with @p invariants into @p t; the output
/// and its record go to @p dir. A scan not generated here (the tablet) takes its size and
/// median edge from the record.
void runOnce(const std::vector<std::string>& program, ScanCase& c, const Settings& s, const std::string& invariants,
             const fs::path& dir, ScanTimings& t)
{
    const std::string output = (dir / "scan.msii.ply").string(), record = (dir / "scan.msii.json").string();
    fs::remove(record);
    std::vector<std::string> args = program;
    for (const std::string& a : {std::string("compute"), c.input, std::string("-r"), number(c.radius), std::string("-n"),
                                 std::to_string(s.scales), std::string("-j"), std::to_string(c.threads),
                                 std::string("--invariants"), invariants, std::string("-q"), std::string("--overwrite"),
                                 std::string("-o"), output})
        args.push_back(a);
    const ChildRun run = runChild(args, (dir / "scan.log").string());
    std::ifstream in(record);
    if (!run.ok || !in) {
        t.ok = false;
        return;
    }
    const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
    if (json.is_discarded() || !json.contains("timings_seconds")) {
        t.ok = false;
        return;
    }
    for (const auto& [key, value] : json["timings_seconds"].items())
        if (value.is_number()) t.stages[key].push_back(value.get<double>());
    if (c.vertices == 0 && json.contains("mesh")) {  // the tablet, written by its own case
        c.vertices = json["mesh"].value("vertices", std::size_t(0));
        c.medianEdge = json["mesh"]["edge_length"].value("median", 0.0);
    }
    if (json.contains("patch_line") && json["patch_line"].contains("share_exact"))
        t.shareExact = json["patch_line"]["share_exact"].get<double>();
    t.wall.push_back(run.seconds);
    t.peakBytes.push_back(run.peakBytes);
}

/// GigaMesh on scan @p c, confined to one CPU (taskset): gigamesh-featurevectors once for V
/// and P at the N radii (2^4 = 16 by default: -n is log2 N), and gigamesh-featurevectors-sl
/// once per radius for S (its algorithm sphere_volume) and once for L (sphere_surface),
/// one run each (they take long). Their outputs and logs go to @p dir.
GigaMeshRun runGigaMesh(const Settings& s, const ScanCase& c, const fs::path& dir)
{
    GigaMeshRun g;
    g.ran = true;
    const fs::path folder(s.gigamesh), featureVectors = folder / "gigamesh-featurevectors",
                                       sphereLine = folder / "gigamesh-featurevectors-sl";
    for (const fs::path& p : {featureVectors, sphereLine})
        if (!fs::exists(p)) {
            g.error = p.string() + " not found";
            return g;
        }
    const std::string taskset = fs::exists("/usr/bin/taskset") ? "/usr/bin/taskset" : "";
    const auto oneCpu = [&](std::vector<std::string> args) {
        if (!taskset.empty()) args.insert(args.begin(), {taskset, "-c", "0"});
        return args;
    };
    const std::string log = (dir / "gigamesh.log").string();
    // Its files go next to its input: a copy of the scan in the work folder.
    const std::string input = (dir / "gigamesh-input.ply").string();
    fs::copy_file(c.input, input, fs::copy_options::overwrite_existing);
    const int log2Scales = int(std::lround(std::log2(double(s.scales))));
    const ChildRun vp = runChild(oneCpu({featureVectors.string(), "-r", number(c.radius), "-n", std::to_string(log2Scales),
                                         "-k", input}),
                                 log);
    if (!vp.ok) {
        g.error = "gigamesh-featurevectors failed (its output: " + log + ")";
        return g;
    }
    g.volumePatch = vp.seconds;
    g.peakBytes = vp.peakBytes;
    for (int j = 1; j <= s.scales; ++j) {
        const double r = c.radius * j / s.scales;
        for (const char* algorithm : {"sphere_volume", "sphere_surface"}) {
            const std::string output = (dir / "gigamesh-sl.ply").string();
            fs::remove(output);
            const ChildRun sl = runChild(oneCpu({sphereLine.string(), "-input", input, "-format", "ply", "-radius",
                                                 number(r), "-algorithm", algorithm, "-output", output, "-threads", "1",
                                                 "-max_load", "1000"}),
                                         log);
            // It exits with 0 also when its arguments are wrong: its output file says whether it ran.
            if (!sl.ok || !fs::exists(output)) {
                g.error = std::string("gigamesh-featurevectors-sl -algorithm ") + algorithm + " failed (its output: " + log + ")";
                return g;
            }
            g.sphereLine += sl.seconds;
            g.peakBytes = std::max(g.peakBytes, sl.peakBytes);
        }
    }
    g.ok = true;
    return g;
}

/// "1.23" or "–" where a stage was not run.
std::string cell(const ScanTimings& t, const char* key, const char* format = "%.2f")
{
    const auto it = t.stages.find(key);
    if (!t.ok || it == t.stages.end() || it->second.empty()) return "–";
    char text[32];
    std::snprintf(text, sizeof(text), format, median(it->second));
    return text;
}

std::string ratioCell(const ScanTimings& after, const ScanTimings& before, const char* key)
{
    const auto a = after.stages.find(key), b = before.stages.find(key);
    if (!after.ok || !before.ok || a == after.stages.end() || b == before.stages.end()) return "–";
    const double x = median(a->second), y = median(b->second);
    if (!(y > 0.005) || !(x > 0.005)) return "–";  // too short to compare
    char text[32];
    std::snprintf(text, sizeof(text), "%.2f", x / y);
    return text;
}

/// @p text right-aligned in @p width columns (counting characters, not bytes: "–" is one).
std::string pad(const std::string& text, std::size_t width)
{
    std::size_t n = 0;
    for (const unsigned char ch : text) n += (ch & 0xC0) != 0x80;
    return n >= width ? text : std::string(width - n, ' ') + text;
}

std::string format(const char* f, double v)
{
    char text[64];
    std::snprintf(text, sizeof(text), f, v);
    return text;
}

} // namespace

ScanRuns runScans(const Bench& bench)
{
    const Settings& s = bench.settings;
    ScanRuns scans;
    scans.before = !s.before.empty();
    const fs::path dir = bench.dir / "scans";
    fs::create_directories(dir);
    // The slabs at R = 25 median edges (rounded to 3 digits), as a user sizes R for wedges.
    const std::pair<double, double> sizes[] = {{7, 5}, {19.5, 14}};
    const int threads[] = {1, 2};
    for (int k = 0; k < 2; ++k) {
        ScanCase c;
        writeScanLikeSlab(s, sizes[k].first, sizes[k].second, (dir / ("slab" + std::to_string(k) + ".ply")).string(), c);
        c.radius = std::stod(format("%.3g", 25 * c.medianEdge));
        c.threads = threads[k];
        c.name = "scan-like slab";
        scans.cases.push_back(c);
    }
    ScanCase tablet;
    tablet.name = "tablet";
    tablet.input = bench.input;
    tablet.radius = s.radius;
    tablet.threads = 2;
    scans.cases.push_back(tablet);

    const std::vector<std::string> programs[2] = {words(s.msiiProgram), words(s.before)};
    const char* invariantSets[2] = {"V,S,P,L", "V,S"};
    for (int run = 0; run < s.runs; ++run)
        for (ScanCase& c : scans.cases)
            for (int i = 0; i < 2; ++i)
                for (int p = 0; p < (scans.before ? 2 : 1); ++p) runOnce(programs[p], c, s, invariantSets[i], dir, c.runs[i][p]);
    if (!s.gigamesh.empty()) {
        scans.gigamesh = runGigaMesh(s, scans.cases.front(), dir);
        if (scans.gigamesh.ok) {
            ScanCase one = scans.cases.front();
            for (int run = 0; run < s.runs; ++run) {
                ScanTimings vp;
                runOnce(programs[0], one, s, "V,P", dir, vp);
                if (vp.ok) scans.gigamesh.msiiVolumePatch.push_back(vp.wall.front());
            }
        }
    }
    fs::remove_all(dir);
    return scans;
}

void printScanTables(Report& report, const Settings& s, const ScanRuns& scans)
{
    for (const ScanCase& c : scans.cases) {
        const std::string vertices = std::to_string(c.vertices) + " vertices";
        report.print("\n%s, %s, R = %s%s, N = %d, %d thread%s; msii compute in a process of its own, medians of %d "
                     "runs%s\n\n",
                     c.name.c_str(), vertices.c_str(), number(c.radius).c_str(),
                     c.medianEdge > 0 ? format(" (%.0f median edges)", c.radius / c.medianEdge).c_str() : "", s.scales,
                     c.threads, c.threads == 1 ? "" : "s", s.runs,
                     scans.before ? (", before: " + s.before + ", in turn with it").c_str() : "");
        const ScanTimings& all = c.runs[0][0];
        const ScanTimings& vs = c.runs[1][0];
        if (scans.before) {
            const ScanTimings& allBefore = c.runs[0][1];
            const ScanTimings& vsBefore = c.runs[1][1];
            report.print("| %-48s | all four: before | after | ratio | V, S: before | after | ratio |\n", "stage (s)");
            report.print("|%s|------------------|-------|-------|--------------|-------|-------|\n", std::string(50, '-').c_str());
            const auto line = [&](const char* name, const std::string& a, const std::string& b, const std::string& c1,
                                  const std::string& d, const std::string& e, const std::string& f) {
                report.print("| %-48s | %s | %s | %s | %s | %s | %s |\n", name, pad(a, 16).c_str(), pad(b, 5).c_str(),
                             pad(c1, 5).c_str(), pad(d, 12).c_str(), pad(e, 5).c_str(), pad(f, 5).c_str());
            };
            for (const auto& [key, name] : kStages)
                line(name, cell(allBefore, key), cell(all, key), ratioCell(all, allBefore, key), cell(vsBefore, key),
                     cell(vs, key), ratioCell(vs, vsBefore, key));
            const auto process = [&](const ScanTimings& t, bool peak) {
                if (!t.ok || t.wall.empty()) return std::string("–");
                return peak ? format("%.0f", median(t.peakBytes) / 1e6) : format("%.2f", median(t.wall));
            };
            const auto ratio = [&](const ScanTimings& a, const ScanTimings& b, bool peak) {
                if (!a.ok || !b.ok || a.wall.empty() || b.wall.empty()) return std::string("–");
                return peak ? format("%.2f", median(a.peakBytes) / median(b.peakBytes))
                            : format("%.2f", median(a.wall) / median(b.wall));
            };
            for (const bool peak : {false, true})
                line(peak ? "**peak memory (MB)**" : "**wall, the whole process**", process(allBefore, peak),
                     process(all, peak), ratio(all, allBefore, peak), process(vsBefore, peak), process(vs, peak),
                     ratio(vs, vsBefore, peak));
        } else {
            report.print("| %-48s | all four | V, S |\n", "stage (s)");
            report.print("|%s|----------|------|\n", std::string(50, '-').c_str());
            for (const auto& [key, name] : kStages)
                report.print("| %-48s | %s | %s |\n", name, pad(cell(all, key), 8).c_str(), pad(cell(vs, key), 4).c_str());
            report.print("| %-48s | %s | %s |\n", "**wall, the whole process**",
                         pad(all.ok ? format("%.2f", median(all.wall)) : "–", 8).c_str(),
                         pad(vs.ok ? format("%.2f", median(vs.wall)) : "–", 4).c_str());
            report.print("| %-48s | %s | %s |\n", "**peak memory (MB)**",
                         pad(all.ok ? format("%.0f", median(all.peakBytes) / 1e6) : "–", 8).c_str(),
                         pad(vs.ok ? format("%.0f", median(vs.peakBytes) / 1e6) : "–", 4).c_str());
        }
        if (all.shareExact >= 0)
            report.print("\nP and L values evaluated exactly (all four, after): %.1f %%\n", 100 * all.shareExact);
        for (int i = 0; i < 2; ++i)
            for (int p = 0; p < (scans.before ? 2 : 1); ++p)
                if (!c.runs[i][p].ok)
                    report.print("\n%s failed on this scan with --invariants %s\n", p == 0 ? "msii" : "the earlier msii",
                                 i == 0 ? "V,S,P,L" : "V,S");
    }
    const GigaMeshRun& g = scans.gigamesh;
    if (!g.ran) return;
    const ScanCase& c = scans.cases.front();
    report.print("\nGigaMesh (%s) on the %zu-vertex scan, R = %s, N = %d, one CPU (taskset -c 0), one run\n\n",
                 s.gigamesh.c_str(), c.vertices, number(c.radius).c_str(), s.scales);
    if (!g.ok) {
        report.print("not measured: %s\n", g.error.c_str());
        return;
    }
    const double msiiAll = median(c.runs[0][0].wall), msiiVP = median(g.msiiVolumePatch);
    report.print("| %-62s |  seconds |\n|%s|----------|\n", "program", std::string(64, '-').c_str());
    row(report, "gigamesh-featurevectors (V and P at the N radii)", g.volumePatch, "%8.1f");
    row(report, "gigamesh-featurevectors-sl (S and L, a run per radius each)", g.sphereLine, "%8.1f");
    row(report, "msii compute --invariants V,P -j 1 (process, median)", msiiVP, "%8.2f");
    row(report, "msii compute, all four, -j 1 (process, median)", msiiAll, "%8.2f");
    row(report, "GigaMesh / msii, V and P", msiiVP > 0 ? g.volumePatch / msiiVP : 0, "%8.1f");
    row(report, "GigaMesh / msii, all four", msiiAll > 0 ? (g.volumePatch + g.sphereLine) / msiiAll : 0, "%8.1f");
    row(report, "GigaMesh's peak memory (MB)", g.peakBytes / 1e6, "%8.0f");
}

} // namespace msii::benchmark
