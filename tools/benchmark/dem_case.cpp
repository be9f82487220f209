/// @file dem_case.cpp
/// @brief The DEM (--dem-cells): a generated GeoTIFF DEM of 0.5 m cells computed by msii
/// compute in windows, R = 15 m, N = 16, the default bands; each program in a process of
/// its own, for its time and peak memory.
#include "benchmark.h"

#include <cmath>
#include <cstdio>
#include <fstream>

namespace msii::benchmark {

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

} // namespace msii::benchmark
