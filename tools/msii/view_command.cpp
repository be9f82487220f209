/// `msii view FEATURES [--open] [--no-serve] [--port P]`: writes `<stem>.view/` beside a
/// feature PLY or a DEM's feature GeoTIFF (a web page that shows it, view_folder.h) and
/// serves that folder on 127.0.0.1 until Ctrl-C (view_server.h).
#include "commands.h"
#include "compute_args.h"
#include "feature_input.h"
#include "map_input.h"
#include "view_folder.h"
#include "view_server.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/featuremap/map_frame.h>
#include <msii/mesh/vertex_normals.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <thread>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace msii::tools {

namespace {

namespace fs = std::filesystem;

/// The largest raster side the page draws: textures of 8192 texels are what WebGL 2 offers
/// everywhere (and a browser tab holds some GB at most).
constexpr int kMaxRasterSide = 8192;

struct ViewCommandArgs : CommonArgs {
    std::string input;
    bool open = false;
    bool noServe = false;
    int port = 0;
};

// Ctrl-C, kill and a closed terminal stop the server, or a write under way (which then
// removes its temporary folder): the handler only sets this flag.
std::atomic<bool> gStop{false};
std::atomic<int> gSignal{0};

extern "C" void onStopSignal(int sig)
{
    gSignal = sig;
    gStop = true;
}

/// Installs onStopSignal for SIGINT, SIGTERM and SIGHUP while it lives.
class StopOnSignals {
public:
    StopOnSignals()
    {
        for (int k = 0; k < 3; ++k) {
            struct sigaction action {};
            action.sa_handler = onStopSignal;
            sigemptyset(&action.sa_mask);
            ::sigaction(kSignals[k], &action, &mOld[k]);
        }
    }
    ~StopOnSignals()
    {
        for (int k = 0; k < 3; ++k) ::sigaction(kSignals[k], &mOld[k], nullptr);
    }
    StopOnSignals(const StopOnSignals&) = delete;
    StopOnSignals& operator=(const StopOnSignals&) = delete;

private:
    static constexpr int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
    struct sigaction mOld[3] {};
};

/// Ends the process by the signal that interrupted it, as the other commands end.
[[noreturn]] void dieBySignal()
{
    const int sig = gSignal.load() ? gSignal.load() : SIGINT;
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    std::_Exit(128 + sig);
}

std::array<double, 3> toArray(const Vec3& v) { return {v.x, v.y, v.z}; }

/// A feature mesh (PLY) as the page's mesh and columns.
ViewInput meshInput(FeatureMesh& in)
{
    if (in.mesh.triangles.empty()) throw InvalidInputError("the mesh has no triangles to draw");
    ViewInput view;
    ViewMesh m;
    Vec3 lo = in.mesh.points.front(), hi = lo;
    for (const Vec3& p : in.mesh.points) {
        lo = Vec3(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
        hi = Vec3(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
    }
    const Vec3 c = (lo + hi) * 0.5;
    m.center = toArray(c), m.bboxMin = toArray(lo), m.bboxMax = toArray(hi);
    m.positions.reserve(in.mesh.points.size() * 3);
    for (const Vec3& p : in.mesh.points)
        for (double v : {p.x - c.x, p.y - c.y, p.z - c.z}) m.positions.push_back(float(v));
    const std::vector<Vec3> normals = vertexNormals(in.mesh);
    m.normals.reserve(normals.size() * 3);
    for (const Vec3& n : normals)
        for (double v : {n.x, n.y, n.z}) m.normals.push_back(std::int8_t(std::lround(std::clamp(v, -1.0, 1.0) * 127)));
    m.triangles.reserve(in.mesh.triangles.size() * 3);
    for (const Triangle& t : in.mesh.triangles)
        for (int k = 0; k < 3; ++k) m.triangles.push_back(std::uint32_t(t[k]));
    try {  // the first view: msii render's default picture, the best-fit plane
        MapFrameOptions frame;
        frame.longerSidePixels = 256;
        const MapFrame f = makeMapFrame(in.mesh, frame);
        m.right = toArray(f.axisU), m.up = toArray(f.axisV), m.normal = toArray(f.normal);
    } catch (const InvalidInputError&) {
        // seen edge-on or degenerate: the default frame (from +z) will do
    }
    view.mesh = std::move(m);
    for (const VertexProperty& p : in.properties) view.columns.push_back({p.name, &p.values, p.integer});
    view.units = unitsFromComments(in.comments);
    view.radii = radiiFromComments(in.comments);
    view.comments = in.comments;
    return view;
}

/// A DEM's feature GeoTIFF (or any raster GDAL reads) as the page's grid and columns.
ViewInput rasterInput(const RasterInput& in)
{
    const RasterGeoreference& g = in.raster.georeference;
    if (g.width > kMaxRasterSide || g.height > kMaxRasterSide)
        throw InvalidInputError("the raster has " + std::to_string(g.width) + " x " + std::to_string(g.height) +
                                " cells; the page draws at most " + std::to_string(kMaxRasterSide) +
                                " on a side (cut a part out with gdal_translate -srcwin, or compute with msii "
                                "compute --tile-of-mosaic)");
    ViewInput view;
    ViewRaster r;
    r.width = g.width, r.height = g.height, r.transform = g.transform;
    r.crs = !g.epsg.empty() ? "EPSG:" + g.epsg : g.crsName;
    r.cellX = std::hypot(g.transform[1], g.transform[4]);
    r.cellY = std::hypot(g.transform[2], g.transform[5]);
    r.heights = in.heights;
    view.raster = std::move(r);
    for (std::size_t k = 0; k < in.raster.bands.size(); ++k) {
        const RasterBand& b = in.raster.bands[k];
        view.columns.push_back({b.name.empty() ? "band_" + std::to_string(k + 1) : b.name, &b.values, false});
    }
    view.units = in.units.empty() ? "units" : in.units;
    for (const auto& [key, value] : in.raster.metadata) {
        if (key == "MSII_RADII") view.radii = parseNumberList(value, "MSII_RADII");
        if (key == "TIFFTAG_IMAGEDESCRIPTION") view.comments.push_back(value);
    }
    return view;
}

/// Whether @p path is a folder msii view wrote (it is then served as it is).
bool isViewFolder(const fs::path& path)
{
    return fs::is_directory(path) && fs::is_regular_file(path / "data.json") && fs::is_regular_file(path / "index.html");
}

/// Opens @p url in the user's browser (xdg-open), without waiting for it.
void openBrowser(const std::string& url, bool quiet)
{
    pid_t pid = 0;
    const char* argv[] = {"xdg-open", url.c_str(), nullptr};
    if (::posix_spawnp(&pid, "xdg-open", nullptr, nullptr, const_cast<char* const*>(argv), environ) != 0) {
        if (!quiet) std::fprintf(stderr, "msii: warning: cannot run xdg-open; open %s yourself\n", url.c_str());
        return;
    }
    std::thread([pid] { ::waitpid(pid, nullptr, 0); }).detach();
}

void serve(const fs::path& folder, const ViewCommandArgs& args)
{
    StopOnSignals signals;
    ServeOptions options;
    options.port = args.port;
    options.stop = &gStop;
    options.onListening = [&](int port) {
        const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
        // The address on stdout (for scripts), the rest on stderr as every command does.
        std::printf("%s\n", url.c_str());
        std::fflush(stdout);
        if (!args.quiet) std::fprintf(stderr, "msii: serving %s on %s (Ctrl-C stops)\n", folder.string().c_str(), url.c_str());
        if (args.open) openBrowser(url, args.quiet);
    };
    serveFolder(folder.string(), options);
    if (!args.quiet) std::fprintf(stderr, "msii: stopped serving %s\n", folder.string().c_str());
}

std::string megabytes(std::uint64_t bytes)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.3g MB", double(bytes) / 1e6);
    return text;
}

int runView(const ViewCommandArgs& args)
{
    const Stopwatch total;
    const fs::path input(args.input);
    if (isViewFolder(input)) {  // a folder written before: serve it as it is
        if (args.noServe) throw InvalidInputError("'" + args.input + "' is a view folder already; --no-serve has nothing to do");
        serve(input, args);
        return 0;
    }
    if (fs::is_directory(input))
        throw InvalidInputError("'" + args.input + "' is a folder, but not one msii view wrote (it has no data.json)");
    const fs::path folder = input.parent_path() / (input.stem().string() + ".view");
    if (fs::exists(fs::symlink_status(folder)) && !args.overwrite)
        throw IOError("'" + folder.string() + "' exists already (use --overwrite to replace it)");
    ViewFolderOptions options;
    options.assets = findViewAssets(fs::read_symlink("/proc/self/exe").string());
    options.overwrite = args.overwrite;
    options.cancel = &gStop;

    // Read the input (Ctrl-C ends the process here: nothing is written yet).
    FeatureMesh mesh;
    RasterInput raster;
    ViewInput view;
    if (isRasterInput(args.input)) {
        raster = readRasterInput(args.input, true);
        printWarnings(args.input, raster.warnings, args.quiet);
        if (raster.heights.empty())
            printWarnings(args.input,
                          {"no heights (no band 'height', and its DEM, MSII_INPUT, is not where it was): the map has "
                           "no hillshade"},
                          args.quiet);
        view = rasterInput(raster);
    } else {
        mesh = readFeatureMesh(args.input, {});
        printWarnings(args.input, mesh.warnings, args.quiet);
        view = meshInput(mesh);
    }
    view.source = input.filename().string();

    ViewFolderResult written;
    {
        StopOnSignals signals;
        try {
            written = writeViewFolder(view, folder.string(), options);
        } catch (const Interrupted&) {
            dieBySignal();
        }
    }
    if (gStop) dieBySignal();
    if (!args.quiet) {
        const std::size_t items = view.mesh ? view.mesh->positions.size() / 3
                                            : std::size_t(view.raster->width) * std::size_t(view.raster->height);
        std::fprintf(stderr, "msii: %s -> %s (%zu %s, %zu columns, %s with data.bin %s; feature values within %.2g; %.1f s)\n",
                     args.input.c_str(), folder.string().c_str(), items, view.mesh ? "vertices" : "cells",
                     written.columns, megabytes(written.folderBytes).c_str(), megabytes(written.dataBytes).c_str(),
                     written.largestError, total.seconds());
    }
    if (!args.noServe) serve(folder, args);
    return 0;
}

} // namespace

std::function<int()> addViewCommand(CLI::App& app)
{
    auto args = std::make_shared<ViewCommandArgs>();
    CLI::App* cmd = app.add_subcommand(
        "view", "A web page that shows a feature PLY or a DEM's feature GeoTIFF: colour by any invariant at any "
                "radius, click a vertex for its feature vectors and the feature distance of every other one to it. "
                "Writes <stem>.view/ beside the input and serves it on 127.0.0.1 until Ctrl-C.");
    cmd->add_option("input", args->input,
                    "Feature PLY (msii compute, metric, smooth) or feature GeoTIFF of a DEM; or a .view folder "
                    "written before, to serve it again")
        ->required();
    cmd->add_flag("--open", args->open, "Also open the page in the browser (xdg-open)");
    cmd->add_flag("--no-serve", args->noServe, "Only write the folder (it works from any static web server)");
    cmd->add_option("--port", args->port, "Port on 127.0.0.1 (default 0: a free one, printed)")
        ->check(CLI::Range(0, 65535));
    addCommonOptions(cmd, *args);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runView(*args);
    };
}

} // namespace msii::tools
