/// @file benchmark_main.cpp
/// @brief `msii-benchmark`: times the compute job on a generated tablet-like open surface
/// (default: ~1.1M vertices at 0.03 mm spacing, R = 1 mm, N = 16) and prints a table of
/// median stage timings over several runs, vertices/s, peak memory and the machine.
#include <msii/invariants/compute.h>
#include <msii/samples/generators.h>

#include <CLI/CLI.hpp>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
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
    app.add_option("--spacing", spacing, "vertex spacing, mm (default 0.03)");
    app.add_option("--size", size, "width = height of the tablet, mm (default 31.6 → 1.1M vertices)");
    app.add_option("--radius", radius, "largest radius R, mm (default 1)");
    app.add_option("--scales", scales, "N (default 16)");
    app.add_option("--precision", precision, "voxels per radius (default 6)");
    app.add_option("--voxel-size", voxel, "finest voxel (default automatic)");
    app.add_option("--runs", runs, "runs; medians are reported (default 3)");
    CLI11_PARSE(app, argc, argv);

    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = ho.height = size;
    ho.spacing = spacing;
    std::vector<double> gen, check, ls, occ, st, interp, total;
    ComputeResult last;
    std::size_t nv = 0;
    for (int run = 0; run < runs; ++run) {
        const auto t0 = std::chrono::steady_clock::now();
        TriMesh mesh = samples::makeHeightField(ho);
        gen.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        nv = mesh.numVertices();
        ComputeOptions o;
        o.radius = radius;
        o.scales = scales;
        o.minVoxelsPerRadius = precision;
        o.voxelSize = voxel;
        last = computeInvariants(mesh, o);
        check.push_back(last.timings.check);
        ls.push_back(last.timings.levelSet);
        occ.push_back(last.timings.occupancy);
        st.push_back(last.timings.stencils);
        interp.push_back(last.timings.interpolation);
        total.push_back(last.timings.total);
    }
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf("msii-benchmark: tablet %.1f x %.1f mm, spacing %.3f mm, %zu vertices, R = %g, N = %d, "
                "V and S, precision %g, voxel %.4f mm, %d levels, %d runs (medians)\n",
                size, size, spacing, nv, radius, scales, precision, last.voxelSize,
                last.invariants.numLevels, runs);
    std::printf("machine: %s, %u hardware threads\n\n", cpuModel().c_str(), std::thread::hardware_concurrency());
    std::printf("| stage                      | seconds |\n|----------------------------|---------|\n");
    std::printf("| generate mesh (not counted)| %7.2f |\n", median(gen));
    std::printf("| check + statistics         | %7.2f |\n", median(check));
    std::printf("| level set (OpenVDB + exact)| %7.2f |\n", median(ls));
    std::printf("| occupancy pyramid          | %7.2f |\n", median(occ));
    std::printf("| stencils (V and S)         | %7.2f |\n", median(st));
    std::printf("| interpolation to vertices  | %7.2f |\n", median(interp));
    std::printf("| total compute              | %7.2f |\n", median(total));
    std::printf("| vertices per second        | %7.0f |\n", nv / median(total));
    std::printf("| peak memory (MB)           | %7.0f |\n", usage.ru_maxrss / 1024.0);
    return 0;
}
