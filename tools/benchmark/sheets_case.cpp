/// @file sheets_case.cpp
/// @brief The six views on one sheet (`msii render --layout fat-cross`) beside one view's
/// picture (`msii render`) at the same pixel size, each in a process of its own as a user
/// runs them, in turn: on the tablet's results (an open scan, quality shaded) and on a closed
/// tablet of as many vertices (msii-samples rounded-tablet, its relief).
#include "benchmark.h"

#include <cmath>

namespace msii::benchmark {

namespace {

/// One view's picture and the sheet of @p input, in turn, run after run. (Their peak memory
/// is not reported: a child spawned by this process, large by now, counts its size.)
void timePair(const Settings& s, const std::vector<std::string>& view, const std::vector<std::string>& sheet,
              SheetPair& pair)
{
    for (int run = 0; run < s.runs; ++run) {
        const ChildRun v = runChild(view), h = runChild(sheet);
        pair.ok = pair.ok && v.ok && h.ok;
        pair.view.push_back(v.seconds), pair.sheet.push_back(h.seconds);
    }
}

std::vector<std::string> renderArgs(const Settings& s, const std::string& input, const std::string& png,
                                    std::vector<std::string> more)
{
    std::vector<std::string> args{s.msiiProgram, "render",      input, "--dpi", number(s.sheetDpi),
                                  "-q",          "--overwrite", "-o",  png};
    args.insert(args.end(), more.begin(), more.end());
    return args;
}

}  // namespace

SheetRuns timeSheets(const Bench& bench, std::size_t tabletVertices)
{
    const Settings& s = bench.settings;
    SheetRuns r;
    const std::string view = (bench.dir / "view.png").string(), sheet = (bench.dir / "sheet.png").string();
    timePair(s, renderArgs(s, bench.output, view, {"--shade"}),
             renderArgs(s, bench.output, sheet, {"--shade", "--layout", "fat-cross"}), r.tablet);
    // A closed tablet of about as many vertices: 24 × 32 × 10 mm has about 2,600 mm² of surface.
    const std::string closed = (bench.dir / "closed.ply").string();
    const double spacing = std::sqrt(2600.0 / double(std::max<std::size_t>(tabletVertices, 1)));
    const ChildRun made = runChild({s.samplesProgram, "rounded-tablet", "--spacing", number(spacing), "--roughness",
                                    number(0.1 * spacing), "-q", "-o", closed});
    r.closedVertices = made.ok ? std::size_t(2600.0 / (spacing * spacing)) : 0;
    if (made.ok)
        timePair(s, renderArgs(s, closed, view, {}), renderArgs(s, closed, sheet, {"--layout", "fat-cross"}), r.closed);
    return r;
}

void printSheetRows(Report& report, const Settings& s, const SheetRuns& r, std::size_t tabletVertices)
{
    const auto rows = [&](const SheetPair& p, const std::string& what) {
        if (p.view.empty() || !p.ok) return;
        const double v = median(p.view), h = median(p.sheet);
        row(report, ("render one view, " + number(s.sheetDpi) + " dpi, " + what + ", own process").c_str(), v, "%8.2f");
        row(report, ("render the fat cross (6 views), same pixel size, " + what).c_str(), h, "%8.2f");
        row(report, "  sheet / one view (target at most 2.5 for a closed scan)", h / v, "%8.2f");
    };
    rows(r.tablet, "the tablet's quality (" + std::to_string(tabletVertices / 1000) + "k, open)");
    rows(r.closed, "a closed tablet's relief (~" + std::to_string(r.closedVertices / 1000) + "k)");
}

}  // namespace msii::benchmark
