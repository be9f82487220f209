/// @file vessels_case.cpp
/// @brief Vessels: `msii axis`, `msii profile` and `msii unroll` on a generated vase of about
/// a million vertices (msii-samples vessel), each in a process of its own as a user runs
/// them, reading the mesh included.
#include "benchmark.h"

namespace msii::benchmark {

VesselRuns timeVessels(const Bench& bench)
{
    const Settings& s = bench.settings;
    VesselRuns r;
    const std::string vase = (bench.dir / "vase.ply").string();
    const ChildRun made = runChild({s.samplesProgram, "vessel", "--profile", "vase", "--spacing",
                                    number(s.vesselSpacing), "--roughness", "0.01", "-q", "-o", vase});
    if (!made.ok) return r;
    const std::string axis = (bench.dir / "vase.axis.json").string();
    const std::vector<std::vector<std::string>> commands = {
        {s.msiiProgram, "axis", vase, "-q", "--overwrite", "-o", axis},
        {s.msiiProgram, "profile", vase, "-q", "--overwrite", "--axis", axis, "-o",
         (bench.dir / "vase.profile.svg").string()},
        {s.msiiProgram, "unroll", vase, "-q", "--overwrite", "--axis", axis, "-o",
         (bench.dir / "vase.roll.ply").string()},
    };
    for (int run = 0; run < s.runs; ++run)
        for (std::size_t k = 0; k < commands.size(); ++k) {
            const ChildRun c = runChild(commands[k], (bench.dir / "vessel.log").string());
            r.ok = r.ok && c.ok;
            r.seconds[k].push_back(c.seconds);
        }
    r.vertices = readVertexCount(vase);
    return r;
}

void printVesselRows(Report& report, const VesselRuns& r)
{
    if (r.seconds[0].empty() || !r.ok) return;
    const std::string vase = "vase of " + std::to_string(r.vertices / 1000) + "k vertices";
    row(report, ("msii axis, " + vase + ", own process (target <= 2 s)").c_str(), median(r.seconds[0]), "%8.2f");
    row(report, "msii profile, the axis given (target <= 1 s)", median(r.seconds[1]), "%8.2f");
    row(report, "msii unroll, the axis given (target <= 3 s)", median(r.seconds[2]), "%8.2f");
}

}  // namespace msii::benchmark
