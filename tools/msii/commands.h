#pragma once
// The subcommands of the msii program; each registers its options on a CLI11 app and runs.
#include <CLI/CLI.hpp>
#include <msii/core/terminal_progress.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <tbb/global_control.h>

namespace msii::tools {

/// What every command takes (addCommonOptions): -j/--threads, -q/--quiet, --overwrite, and,
/// for the commands that write a PLY, --property-names (addPropertyNamesOption).
struct CommonArgs {
    int threads = 0;             ///< 0 = all cores
    bool quiet = false;          ///< no progress line, no summary; errors only
    bool progressLines = false;  ///< progress as lines for a program that runs msii, terminal or not
    bool overwrite = false;      ///< replace existing outputs
    std::string propertyPrefix;  ///< --property-names: "" or "scalar_"
};

/// Registers -j/--threads, -q/--quiet, --overwrite and --progress-lines on @p cmd, into @p args.
void addCommonOptions(CLI::App* cmd, CommonArgs& args);

/// How the command shows its progress: --progress-lines, else a line on a terminal unless --quiet.
TerminalProgress::Style progressStyle(const CommonArgs& args);

/// A check of a number option for CLI11's check(): "" where @p allowed(value) holds, else
/// @p message (CLI11 itself refuses text that is not a number).
std::function<std::string(const std::string&)> numberCheck(std::function<bool(double)> allowed, std::string message);

/// Checks that each of @p paths may be written: it does not exist yet, or @p overwrite is
/// set, and its folder is writable.
/// @throw IOError naming the path (and --overwrite where it exists).
void checkOutputs(const std::vector<std::string>& paths, bool overwrite);

/// --threads N: 0 = all cores (null), else a TBB limit held for the returned object's life.
/// @throw InvalidInputError if N < 0.
std::unique_ptr<tbb::global_control> limitThreads(int threads);

/// --property-names msii|cloudcompare on @p cmd, into @p prefix: "" or "scalar_", which
/// WritePlyOptions::propertyPrefix puts before every vertex property's name (CloudCompare's
/// command line loads PLY vertex properties as scalar fields only when so named).
void addPropertyNamesOption(CLI::App* cmd, std::string& prefix);

/// Adds `msii compute`; the returned function runs it (after parsing) and returns the exit code.
std::function<int()> addComputeCommand(CLI::App& app);
/// Adds `msii metric` (metrics of feature vectors, paper Sec. 3.1).
std::function<int()> addMetricCommand(CLI::App& app);
/// Adds `msii smooth` (fast 1-ring smoothing, paper Sec. 3.2).
std::function<int()> addSmoothCommand(CLI::App& app);
/// Adds `msii map` (OpenEXR feature maps).
std::function<int()> addMapCommand(CLI::App& app);
/// Adds `msii render` (PNG pictures).
std::function<int()> addRenderCommand(CLI::App& app);
/// Adds `msii segment` (connected components of a thresholded value).
std::function<int()> addSegmentCommand(CLI::App& app);
/// Adds `msii outline` (isolines as SVG).
std::function<int()> addOutlineCommand(CLI::App& app);
/// Adds `msii merge` (joins tiles computed separately).
std::function<int()> addMergeCommand(CLI::App& app);
/// Adds `msii view` (a web page of the features, served on 127.0.0.1).
std::function<int()> addViewCommand(CLI::App& app);
/// Adds `msii axis` (the axis of rotation of a vessel, a sherd or a seal).
std::function<int()> addAxisCommand(CLI::App& app);
/// Adds `msii profile` (the section through the axis, or any plane: SVG and CSV).
std::function<int()> addProfileCommand(CLI::App& app);
/// Adds `msii unroll` (the surface laid onto the plane around its axis).
std::function<int()> addUnrollCommand(CLI::App& app);

} // namespace msii::tools
