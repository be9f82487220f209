/// @file large_terrain_case.cpp
/// @brief The streamed terrain (--large-vertices): runs the `msii-samples` and `msii`
/// programs themselves on a streamed terrain of that size, each in its own process so that
/// its peak memory is its own, and prints their time, memory and time per vertex against
/// the tablet's.
#include "benchmark.h"

#include <cmath>
#include <cstdio>
#include <fstream>

namespace msii::benchmark {

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

} // namespace msii::benchmark
