/// @file terrain_peer_case.cpp
/// @brief The terrain tools' case (--terrain-peer, --rvt): a generated 1000 × 1000 DEM of
/// 1 m at R = 10 and 30 cells, msii compute on the height field and on the mesh (--engine
/// mesh), each run in a process of its own; with --rvt, RVT_py's sky-view factor and
/// openness and its multi-scale topographic position at the same radii, and the former as a
/// whole process as well.
#include "benchmark.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace msii::benchmark {

namespace {
/// RVT_py's sky-view factor (16 directions, r_max = R cells) and multi-scale topographic
/// position (local, meso and broad scales splitting 1 … R cells in thirds), timed inside one
/// Python process (the imports and the reading excluded), printed as "svf SECONDS" and
/// "mstp SECONDS".
const char* kRvtScript = R"(import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from osgeo import gdal
import rvt.vis
ds = gdal.Open(sys.argv[2])  # kept while its band is read: a band of a freed dataset crashes
dem = ds.GetRasterBand(1).ReadAsArray().astype(np.float32)
R = int(sys.argv[3]); a, b = max(1, R // 3), max(2, 2 * R // 3)
t = time.perf_counter()
rvt.vis.sky_view_factor(dem=dem, resolution=1, compute_svf=True, compute_opns=True, svf_n_dir=16, svf_r_max=R, svf_noise=0)
print("svf", time.perf_counter() - t)
t = time.perf_counter()
rvt.vis.mstp(dem=dem, local_scale=(1, a, 1), meso_scale=(a, b, 1), broad_scale=(b, R, 1))
print("mstp", time.perf_counter() - t)
)";

/// RVT_py as a user runs it: a Python process that imports it, reads the DEM, computes the
/// sky-view factor and openness (16 directions, r_max = R cells) and writes both as GeoTIFFs
/// (its own save function), as msii compute reads, computes and writes.
const char* kRvtWholeScript = R"(import sys
sys.path.insert(0, sys.argv[1])
import rvt.default
d = rvt.default.DefaultValues()
d.svf_n_dir, d.svf_r_max, d.svf_noise, d.overwrite = 16, int(sys.argv[3]), 0, 1
d.save_sky_view_factor(sys.argv[2], save_svf=True, save_opns=True, custom_dir=sys.argv[4], save_float=True, save_8bit=False)
)";
} // namespace

bool runTerrainPeer(const Bench& bench, PeerRun& peer)
{
    const Settings& s = bench.settings;
    const fs::path& dir = bench.dir;
    const std::string tif = (dir / "peer.tif").string(), out = (dir / "peer.msii.tif").string();
    // A failure ends the benchmark: the work folder goes with it, as in the other cases.
    const auto fail = [&] {
        fs::remove_all(dir);
        return false;
    };
    if (!runChild({s.samplesProgram, "terrain", "--geotiff", "--width", "1000", "--height", "1000", "--spacing", "1",
                   "--relief", "4", "--hill-width", "25", "--holes", "20", "--hole-size", "2", "-q", "--output", tif})
             .ok) {
        std::fprintf(stderr, "msii-benchmark: error: %s could not write the DEM\n", s.samplesProgram.c_str());
        return fail();
    }
    for (const int R : {10, 30}) {
        for (const std::string engine : {"heights", "mesh"}) {
            const ChildRun r = runChild({s.msiiProgram, "compute", tif, "-r", std::to_string(R), "-j", "2", "-q",
                                         "--overwrite", "--engine", engine, "--raster-output", out});
            if (!r.ok) {
                std::fprintf(stderr, "msii-benchmark: error: msii compute --engine %s failed on the DEM\n", engine.c_str());
                return fail();
            }
            peer.rows.push_back({"msii compute -r " + std::to_string(R) + " -j 2 --engine " + engine, r.seconds, r.peakBytes});
        }
        if (s.rvt.empty()) continue;
        const std::string script = (dir / "rvt_peer.py").string(), times = (dir / "rvt_times.txt").string();
        std::ofstream(script) << kRvtScript;
        const std::string command = "python3 '" + script + "' '" + s.rvt + "' '" + tif + "' " + std::to_string(R) + " > '" + times + "'";
        if (std::system(command.c_str()) != 0) {
            std::fprintf(stderr, "msii-benchmark: error: RVT_py from %s did not run (%s)\n", s.rvt.c_str(), command.c_str());
            return fail();
        }
        std::ifstream in(times);
        std::string name;
        double seconds = 0;
        while (in >> name >> seconds)
            peer.rows.push_back({std::string(name == "svf" ? "RVT_py sky-view factor and openness, 16 directions"
                                                           : "RVT_py multi-scale topographic position") +
                                     ", r = " + std::to_string(R),
                                 seconds, 0});
        const std::string whole = (dir / "rvt_whole.py").string(), written = (dir / "rvt_out").string();
        std::ofstream(whole) << kRvtWholeScript;
        fs::create_directories(written);
        const ChildRun w = runChild({"/usr/bin/env", "python3", whole, s.rvt, tif, std::to_string(R), written});
        if (!w.ok) {
            std::fprintf(stderr, "msii-benchmark: error: RVT_py's save_sky_view_factor from %s did not run\n", s.rvt.c_str());
            return fail();
        }
        peer.rows.push_back({"RVT_py sky-view factor and openness, whole process, r = " + std::to_string(R), w.seconds,
                             w.peakBytes});
    }
    peer.ok = true;
    return true;
}

void printPeerTable(Report& report, const PeerRun& peer)
{
    report.print("\nTerrain tools' case: a generated 1000 x 1000 DEM of 1 m cells (hills 25 m wide, 4 m high, 20 small "
                 "nodata patches), default bands, one run each, separate processes (RVT_py: its functions' time in "
                 "one Python process, and its sky-view factor and openness as a whole process of their own)\n\n");
    report.print("| %-62s | %8s | %8s |\n|%s|%s|%s|\n", "run", "seconds", "peak MB", std::string(64, '-').c_str(),
                 std::string(10, '-').c_str(), std::string(10, '-').c_str());
    for (const PeerRun::Row& r : peer.rows)
        report.print("| %-62s | %8.2f | %8s |\n", r.what.c_str(), r.seconds,
                     r.peakBytes > 0 ? std::to_string(int(r.peakBytes / 1e6)).c_str() : "");
    for (std::size_t k = 0; k + 1 < peer.rows.size(); ++k)
        if (peer.rows[k].what.find("--engine heights") != std::string::npos) {
            // "-r R" of the row's command, whatever R's digits.
            const std::string& what = peer.rows[k].what;
            const std::size_t from = what.find("-r "), to = what.find(' ', from + 3);
            report.print("| %-62s | %8.3f | %8s |\n", ("  heights / mesh, " + what.substr(from, to - from)).c_str(),
                         peer.rows[k].seconds / peer.rows[k + 1].seconds, "");
        }
}

} // namespace msii::benchmark
