/// What the subcommands share: their common options and the check of their outputs.
#include "commands.h"

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>

#include <filesystem>
#include <map>

namespace msii::tools {

void addCommonOptions(CLI::App* cmd, CommonArgs& args)
{
    cmd->add_option("-j,--threads", args.threads, "Worker threads (default: all cores)");
    cmd->add_flag("-q,--quiet", args.quiet, "No progress, no summary; errors only");
    cmd->add_flag("--overwrite", args.overwrite, "Replace existing outputs");
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
