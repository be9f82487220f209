/// @file processes_case.cpp
/// @brief msii compute and the Python module's msii.compute on the tablet, each run once
/// in a process of its own: their time, and their peak memory as each process measures it;
/// a Python result should cost its arrays on top of the engine's own peak, no more.
#include "benchmark.h"

#include <cstdlib>
#include <fstream>

namespace msii::benchmark {

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

void printProcessRows(Report& report, const ProcessRuns& p)
{
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

} // namespace msii::benchmark
