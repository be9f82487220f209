/// `msii compute` on collections: folders and several inputs (compute_args.h).
#include "compute_args.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/core/terminal_progress.h>
#include <msii/core/version.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <new>

namespace fs = std::filesystem;

namespace msii::tools {

namespace {

/// Mesh files msii reads, by extension (case-insensitive).

bool isMeshFile(const fs::path& p)
{
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl") return false;
    // Not msii's own outputs (a rerun into the input folder must not take them as inputs):
    // compute's <name>.msii.ply, GigaMesh's <name>.gigamesh.ply, and what the other commands
    // make of them, <name>.msii.metric.ply, <name>.msii.metric.smooth.ply,
    // <name>.msii.segments.ply: any name with a part ".msii." or ".gigamesh.".
    const std::string name = p.filename().string();
    const std::string stem = p.stem().string();
    for (const char* suffix : {".msii", ".gigamesh"}) {
        const std::string s(suffix);
        if (stem.size() > s.size() && stem.compare(stem.size() - s.size(), s.size(), s) == 0) return false;
        if (name.find(s + ".") != std::string::npos) return false;
    }
    return name.front() != '.';  // nor hidden or temporary files
}

} // namespace

std::vector<std::string> expandInputs(const ComputeArgs& args, bool& collection)
{
    std::vector<std::string> out;
    collection = args.inputs.size() > 1;
    for (const std::string& input : args.inputs) {
        std::error_code ec;
        if (!fs::is_directory(input, ec)) {
            out.push_back(input);
            continue;
        }
        collection = true;
        std::vector<std::string> found;
        const auto visit = [&](const fs::directory_entry& e) {
            std::error_code fec;
            if (e.is_regular_file(fec) && isMeshFile(e.path())) found.push_back(e.path().string());
        };
        if (args.recursive)
            for (const auto& e : fs::recursive_directory_iterator(input, fs::directory_options::skip_permission_denied, ec)) visit(e);
        else
            for (const auto& e : fs::directory_iterator(input, ec)) visit(e);
        if (ec) throw IOError("cannot read the folder " + input + ": " + ec.message());
        if (found.empty())
            throw InvalidInputError("the folder " + input + " has no mesh files (.ply, .obj, .off, .stl)" +
                                    (args.recursive ? "" : "; --recursive looks into subfolders"));
        std::sort(found.begin(), found.end());
        out.insert(out.end(), found.begin(), found.end());
    }
    return out;
}

namespace {

/// Empty if the JSON record @p sidecar was written with the parameters of @p args that shape
/// the features (radius, scales, precision, voxel size, invariants, exact); else which differ.
std::string differentParameters(const std::string& sidecar, const ComputeArgs& args)
{
    try {
        std::ifstream in(sidecar);
        const nlohmann::json j = nlohmann::json::parse(in);
        const auto& p = j.at("parameters");
        std::string differs;
        const auto check = [&](const char* name, double had, double want) {
            if (std::abs(had - want) > 1e-12 * std::max(1.0, std::abs(want)))
                differs += std::string(differs.empty() ? "" : ", ") + name + " " + std::to_string(had) +
                           " instead of " + std::to_string(want);
        };
        check("radius", p.at("radius").get<double>(), args.radius);
        check("scales", p.at("scales").get<double>(), args.scales);
        check("precision", p.at("precision_voxels_per_radius").get<double>(), args.precision);
        check("P and L precision", p.value("precision_patch_line", args.precision), plPrecisionOf(args));
        check("voxel size", p.at("voxel_size_requested").get<double>(), args.voxelSize);
        if ((p.at("mode").get<std::string>() == "exact") != args.exact) differs += (differs.empty() ? "" : ", ") + std::string("mode");
        std::string had;
        for (const auto& c : p.at("invariants")) had += c.get<std::string>();
        InvariantsOptions wanted;
        wanted.select(invariantsOf(args));
        const std::string want = invariantLetters(wanted.selected());
        if (had != want) differs += (differs.empty() ? "" : ", ") + std::string("invariants ") + had + " instead of " + want;
        return differs;
    } catch (const std::exception&) {
        return "its JSON record cannot be read";
    }
}

/// Appends one JSON line per input to the manifest, flushed at once, so an interrupted run
/// keeps the lines of what it finished.
class Manifest {
public:
    explicit Manifest(const std::string& path) : mPath(path)
    {
        if (path.empty()) return;
        mFile = std::fopen(path.c_str(), "a");
        if (!mFile) throw IOError("cannot write the manifest " + path);
    }
    ~Manifest()
    {
        if (mFile) std::fclose(mFile);
    }
    Manifest(const Manifest&) = delete;
    Manifest& operator=(const Manifest&) = delete;
    void add(const nlohmann::json& line)
    {
        if (!mFile) return;
        const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
        if (std::fwrite(text.data(), 1, text.size(), mFile) != text.size() || std::fflush(mFile) != 0)
            throw IOError("cannot write the manifest " + mPath);
    }

private:
    std::string mPath;
    std::FILE* mFile = nullptr;
};

std::string nowUtc()
{
    const std::time_t t = std::time(nullptr);
    char buffer[32];
    std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
    return buffer;
}

} // namespace

int computeCollection(const ComputeArgs& args, const std::vector<std::string>& inputs)
{
    // A collection: each input on its own; a failure is reported and the rest go on;
    // finished outputs are skipped unless --overwrite, so an interrupted run resumes.
    // Two inputs must not share an output (same name in two folders, or x.ply and x.obj).
    {
        std::map<std::string, std::string> owner;
        for (const std::string& input : inputs) {
            const std::string out = fs::absolute(outputPathFor(args, input)).lexically_normal().string();
            const auto [it, fresh] = owner.emplace(out, input);
            if (!fresh)
                throw InvalidInputError("'" + it->second + "' and '" + input + "' would both write " + out +
                                        "; rename one or process them into different --output-dir folders");
        }
    }
    std::string manifestPath = args.manifest;
    if (manifestPath.empty())
        manifestPath = ((args.outputDir.empty() ? fs::path(outputPathFor(args, inputs.front())).parent_path()
                                                 : fs::path(args.outputDir)) /
                        "msii-manifest.jsonl")
                           .string();
    Manifest manifest(manifestPath);
    const Stopwatch all;
    const nlohmann::json parameters = {{"radius", args.radius},       {"scales", args.scales},
                                       {"precision", args.precision}, {"pl_precision", args.plPrecision},
                                       {"voxel_size", args.voxelSize},
                                       {"invariants", args.invariants}, {"exact", args.exact},
                                       {"strict", args.strict},
                                       {"fill_holes", args.fillHoles},
                                       {"border", args.border}};
    std::size_t done = 0, skipped = 0;
    std::vector<std::string> failed;
    const bool terminal = !args.quiet && stderrIsTerminal();
    // A failed input: one error line, and the reason in its manifest line.
    const auto fail = [&](const std::string& input, nlohmann::json& line, const std::string& why) {
        failed.push_back(input);
        std::fprintf(stderr, "msii: error: %s: %s\n", input.c_str(), printableLine(why).c_str());
        line["status"] = "failed";
        line["error"] = why;
    };
    for (std::size_t k = 0; k < inputs.size(); ++k) {
        const std::string& input = inputs[k];
        const std::string output = outputPathFor(args, input);
        if (terminal)
            std::fprintf(stderr, "msii: [%zu/%zu] %s (%zu done, %zu skipped, %zu failed, %.0f s)\n", k + 1,
                         inputs.size(), input.c_str(), done, skipped, failed.size(), all.seconds());
        nlohmann::json line = {{"input", fs::absolute(input).string()},
                               {"output", fs::absolute(output).string()},
                               {"parameters", parameters},
                               {"version", versionString()},
                               {"time", nowUtc()}};
        std::error_code ec;
        const bool finished = fs::exists(output, ec) && fs::exists(sidecarPathFor(output), ec);
        if (!args.overwrite && finished) {
            // Skip it only if it was made with the same parameters.
            const std::string differs = differentParameters(sidecarPathFor(output), args);
            if (differs.empty()) {
                ++skipped;
                line["status"] = "skipped";
                line["reason"] = "output exists (--overwrite replaces it)";
                manifest.add(line);
                continue;
            }
            fail(input, line, "'" + output + "' exists with other parameters (" + differs +
                                  "); use --overwrite or another --output-dir");
            manifest.add(line);
            continue;
        }
        try {
            // An output without its JSON record (or the reverse) is from an interrupted
            // run or was removed on purpose: redo it.
            ComputeArgs redo = args;
            redo.overwrite = args.overwrite || !finished;
            const OneResult r = computeOne(redo, input, output);
            ++done;
            line["status"] = "done";
            line["vertices"] = r.vertices;
            line["voxel_size"] = r.voxelSize;
            line["seconds"] = r.seconds;
        } catch (const std::bad_alloc&) {
            fail(input, line, "out of memory (try a larger --voxel-size)");
        } catch (const std::exception& e) {  // msii's errors, and anything else: go on
            fail(input, line, e.what());
        }
        manifest.add(line);
    }
    if (!args.quiet || !failed.empty()) {
        std::fprintf(stderr, "msii: %zu inputs: %zu done, %zu skipped (outputs exist), %zu failed, %.1f s; manifest %s\n",
                     inputs.size(), done, skipped, failed.size(), all.seconds(), manifestPath.c_str());
        for (const std::string& f : failed) std::fprintf(stderr, "msii: failed: %s\n", f.c_str());
    }
    return failed.empty() ? 0 : 1;
}

} // namespace msii::tools
