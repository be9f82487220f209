/// What the subcommands share: their common options and the check of their outputs.
#include "commands.h"

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>

#include <cstdlib>
#include <filesystem>
#include <map>

namespace msii::tools {

void addCommonOptions(CLI::App* cmd, CommonArgs& args)
{
    cmd->add_option("-j,--threads", args.threads, "Worker threads (default: all cores)");
    cmd->add_flag("-q,--quiet", args.quiet, "No progress, no summary; errors only");
    cmd->add_flag("--overwrite", args.overwrite, "Replace existing outputs");
    cmd->add_flag("--progress-lines", args.progressLines,
                  "Progress as lines 'msii: progress PERCENT STAGE' on stderr, also when it is not a terminal "
                  "(for programs that run msii and show its progress, such as the QGIS plugin)");
}

TerminalProgress::Style progressStyle(const CommonArgs& args)
{
    if (args.progressLines) return TerminalProgress::Style::Lines;
    return !args.quiet && stderrIsTerminal() ? TerminalProgress::Style::Line : TerminalProgress::Style::Off;
}

void addPropertyNamesOption(CLI::App* cmd, std::string& prefix)
{
    static const std::map<std::string, std::string> styles{{"msii", ""}, {"cloudcompare", "scalar_"}};
    cmd->add_option("--property-names", prefix,
                    "Names of the output PLY's vertex properties: msii (V_01 ... quality; default) or "
                    "cloudcompare (scalar_V_01 ... scalar_quality, which CloudCompare's command line "
                    "loads as scalar fields)")
        ->transform(CLI::CheckedTransformer(styles, CLI::ignore_case));
}

std::function<std::string(const std::string&)> numberCheck(std::function<bool(double)> allowed, std::string message)
{
    return [allowed = std::move(allowed), message = std::move(message)](const std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str()) return {};  // not a number: CLI11 says so
        return allowed(v) ? std::string() : message;
    };
}

void checkOutputs(const std::vector<std::string>& paths, bool overwrite)
{
    for (const std::string& path : paths) {
        if (!overwrite && std::filesystem::exists(path))
            throw IOError("'" + path + "' exists already (use --overwrite to replace it)");
        checkWritable(path);
    }
}

std::unique_ptr<tbb::global_control> limitThreads(int threads)
{
    if (threads < 0) throw InvalidInputError("--threads must be 0 (all cores) or more");
    if (threads == 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 std::size_t(threads));
}

} // namespace msii::tools
