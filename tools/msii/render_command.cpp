/// `msii render INPUT`: PNG pictures of a feature PLY, an EXR feature map or a georeferenced
/// raster (a DEM or msii compute's GeoTIFF, one picture cell per raster cell or block): false
/// colour of a value with isolines, shaded relief (virtual illumination), the height map of
/// the paper's Fig. 7c, with a colour bar and a scale bar.
#include "commands.h"
#include "feature_input.h"
#include "compute_args.h"
#include "map_input.h"
#include "render_args.h"

#include <msii/core/terminal_progress.h>
#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/featuremap/feature_map.h>
#include <msii/featuremap/rasterize.h>
#include <msii/render/annotate.h>
#include <msii/render/typeface.h>
#include <msii/render/picture.h>
#include <msii/terrain/raster_output.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <memory>
#include <sstream>

namespace msii::tools {

namespace {

namespace fs = std::filesystem;

/// The channels of the picture, from an EXR map or a rasterised mesh.
struct Channels {
    int width = 0, height = 0;
    double pixelSize = 0;
    std::string units = "mm";
    std::map<std::string, std::vector<float>> data;
};

std::string available(const std::vector<std::string>& names)
{
    std::string s;
    for (const auto& n : names) s += (s.empty() ? "" : " ") + n;
    return s.empty() ? "none" : s;
}

/// The channels of an EXR map: mask, @p value (unless empty) and, if asked, the normals.
/// With @p orRelief a missing value is no error: the normals are read instead, for the relief.
Channels channelsFromMap(const std::string& path, const std::string& value, bool needNormals, bool orRelief = false)
{
    std::vector<std::string> wanted{"mask"};
    if (!value.empty()) wanted.push_back(value);
    if (needNormals || orRelief) wanted.insert(wanted.end(), {"normal.x", "normal.y", "normal.z"});
    FeatureMapImage map = readFeatureMap(path, wanted);
    Channels c;
    c.width = map.width, c.height = map.height;
    c.pixelSize = map.frame.pixelSize;  // also a sheet's, which has no single frame
    if (!map.units.empty()) c.units = map.units;
    const std::vector<std::string>& names = map.channelNames;
    for (const std::string& w : wanted) {
        auto it = map.channels.find(w);
        if (it == map.channels.end()) {
            if (w == "mask" || (orRelief && w == value)) continue;
            throw InvalidInputError("the map has no channel '" + w + "' (it has: " + available(names) + ")");
        }
        c.data[w] = std::move(it->second);
    }
    return c;
}

/// The same channels from a mesh rasterised into the frame the view options ask for.
Channels channelsFromMesh(const std::string& path, const std::vector<std::string>& matFiles, const ViewArgs& view,
                          const std::string& value, bool needNormals, RunContext* progress, bool orRelief = false)
{
    const MapFrameOptions frameOpts = frameOptions(view, kDefaultPixels);
    FeatureMesh in = readFeatureMesh(path, matFiles);
    const VertexProperty* property = nullptr;
    if (!value.empty() && value != "height") {
        const bool present = std::any_of(in.properties.begin(), in.properties.end(),
                                         [&](const VertexProperty& p) { return p.name == value; });
        if (present || !orRelief) property = &in.properties[findProperty(in, value)];
        else needNormals = true;  // the relief instead
    }
    const MapFrame frame = makeMapFrame(in.mesh, frameOpts);
    const PixelHits hits = rasterize(in.mesh, frame, progress);
    Channels c;
    c.width = frame.width, c.height = frame.height, c.pixelSize = frame.pixelSize;
    if (const std::string units = unitsFromComments(in.comments); !units.empty()) c.units = units;
    c.data["mask"] = coverageMask(hits);
    if (value == "height") c.data["height"] = hits.depth;
    if (property) c.data[value] = interpolateToPixels(in.mesh, hits, property->values);
    if (needNormals) {
        const std::array<std::vector<float>, 3> normals = vertexNormalsInFrame(in.mesh, frame);
        const char* names[3] = {"normal.x", "normal.y", "normal.z"};
        for (std::size_t a = 0; a < 3; ++a) c.data[names[a]] = interpolateToPixels(in.mesh, hits, normals[a]);
    }
    return c;
}

/// The same channels from a georeferenced raster (a DEM, or the GeoTIFF msii compute writes
/// for one): @p value is a band by its description; the normals, for shading, come from a
/// band named "height" (or the only band), else from the DEM the GeoTIFF names. Rasters larger
/// than @p pixels on their longer side are reduced by averaging blocks of cells; those at
/// most half of it are enlarged.
Channels channelsFromRaster(const std::string& path, const std::string& value, bool needNormals, int pixels,
                            bool orRelief, bool quiet)
{
    const RasterInput in = readRasterInput(path, needNormals || orRelief);
    printWarnings(path, in.warnings, quiet);
    const RasterGeoreference& g = in.raster.georeference;
    std::vector<std::string> names;
    for (const RasterBand& b : in.raster.bands) names.push_back(b.name.empty() ? "(unnamed)" : b.name);
    const std::vector<float>* heights = in.heights.empty() ? nullptr : &in.heights;
    const std::vector<float>* shown = value.empty() || value == "height" ? heights : nullptr;
    for (const RasterBand& b : in.raster.bands)
        if (!shown && b.name == value) shown = &b.values;
    if (!value.empty() && !shown && !(orRelief && heights))
        throw InvalidInputError("the raster has no band '" + value + "' (it has: " + available(names) + ")");
    if ((needNormals || (orRelief && !shown)) && !heights)
        throw InvalidInputError("shading needs heights: the raster has no band 'height' and its DEM (MSII_INPUT) is not "
                                "where it was (msii compute --bands ...,height writes them; it has: " +
                                available(names) + ")");
    // Block averages, NaN-aware, to at most `pixels` on the longer side.
    const int step = std::max(1, (std::max(g.width, g.height) + pixels - 1) / pixels);
    const int w = (g.width + step - 1) / step, h = (g.height + step - 1) / step;
    const auto reduce = [&](const std::vector<float>& in) {
        std::vector<float> out(std::size_t(w) * std::size_t(h), std::numeric_limits<float>::quiet_NaN());
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                double sum = 0;
                int n = 0;
                for (int yy = y * step; yy < std::min(g.height, (y + 1) * step); ++yy)
                    for (int xx = x * step; xx < std::min(g.width, (x + 1) * step); ++xx) {
                        const float v = in[std::size_t(yy) * std::size_t(g.width) + std::size_t(xx)];
                        if (!std::isnan(v)) sum += v, ++n;
                    }
                if (n > 0) out[std::size_t(y) * std::size_t(w) + std::size_t(x)] = float(sum / n);
            }
        return out;
    };
    // Rasters much smaller than `pixels` are enlarged by a whole factor, bilinearly (nearest
    // next to nodata), so that small DEMs give pictures of a useful size.
    const int zoom = step == 1 ? std::max(1, pixels / std::max(w, h)) : 1;
    const int pw = w * zoom, ph = h * zoom;
    const auto enlarge = [&](std::vector<float> in) {
        if (zoom == 1) return in;
        std::vector<float> out(std::size_t(pw) * std::size_t(ph));
        const auto at = [&](int x, int y) {
            return in[std::size_t(std::clamp(y, 0, h - 1)) * std::size_t(w) + std::size_t(std::clamp(x, 0, w - 1))];
        };
        for (int y = 0; y < ph; ++y)
            for (int x = 0; x < pw; ++x) {
                const double u = (x + 0.5) / zoom - 0.5, v = (y + 0.5) / zoom - 0.5;
                const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
                const double fx = u - x0, fy = v - y0;
                const float a = at(x0, y0), b = at(x0 + 1, y0), c = at(x0, y0 + 1), d = at(x0 + 1, y0 + 1);
                float r;
                if (std::isnan(a) || std::isnan(b) || std::isnan(c) || std::isnan(d))
                    r = at(int(std::lround(u)), int(std::lround(v)));
                else
                    r = float((1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * c + fx * d));
                out[std::size_t(y) * std::size_t(pw) + std::size_t(x)] = r;
            }
        return out;
    };
    Channels c;
    c.width = pw, c.height = ph;
    const double cellX = std::hypot(g.transform[1], g.transform[4]), cellY = std::hypot(g.transform[2], g.transform[5]);
    c.pixelSize = step * std::sqrt(cellX * cellY) / zoom;
    c.units = in.units.empty() ? "units" : in.units;
    std::vector<float> valueCells = shown ? enlarge(reduce(*shown)) : std::vector<float>{};
    std::vector<float>& mask = c.data["mask"];
    const std::vector<float> heightCells = heights ? enlarge(reduce(*heights)) : std::vector<float>{};
    const std::vector<float>& coverage = shown ? valueCells : heightCells;
    mask.resize(coverage.size());
    for (std::size_t k = 0; k < mask.size(); ++k) mask[k] = std::isnan(coverage[k]) ? 0.0f : 1.0f;
    if (shown) c.data[value.empty() ? "height" : value] = std::move(valueCells);
    if (needNormals || (orRelief && !shown)) {
        // Normals of the height field (x right, y up on the picture; rows run down), by central
        // differences over the reduced cells, one-sided at edges and next to nodata.
        std::vector<float> nx(heightCells.size()), ny(heightCells.size()), nz(heightCells.size());
        const double dx = step * cellX / zoom, dy = step * cellY / zoom;
        const auto at = [&](int x, int y) { return heightCells[std::size_t(y) * std::size_t(pw) + std::size_t(x)]; };
        for (int y = 0; y < ph; ++y)
            for (int x = 0; x < pw; ++x) {
                const std::size_t k = std::size_t(y) * std::size_t(pw) + std::size_t(x);
                const float z = at(x, y);
                if (std::isnan(z)) {
                    nx[k] = ny[k] = nz[k] = std::numeric_limits<float>::quiet_NaN();
                    continue;
                }
                const auto slope = [&](int x0, int y0, int x1, int y1, double d) {
                    const bool a = x0 >= 0 && y0 >= 0 && x0 < pw && y0 < ph && !std::isnan(at(x0, y0));
                    const bool b = x1 >= 0 && y1 >= 0 && x1 < pw && y1 < ph && !std::isnan(at(x1, y1));
                    if (a && b) return (at(x1, y1) - at(x0, y0)) / (2.0 * d);
                    if (b) return (at(x1, y1) - z) / d;
                    if (a) return (z - at(x0, y0)) / d;
                    return 0.0;
                };
                const double gx = slope(x - 1, y, x + 1, y, dx), gy = -slope(x, y - 1, x, y + 1, dy);
                const double len = std::sqrt(gx * gx + gy * gy + 1.0);
                nx[k] = float(-gx / len), ny[k] = float(-gy / len), nz[k] = float(1.0 / len);
            }
        c.data["normal.x"] = std::move(nx), c.data["normal.y"] = std::move(ny), c.data["normal.z"] = std::move(nz);
    }
    return c;
}

} // namespace

PictureOptions pictureOptionsOf(const RenderArgs& args)
{
    PictureOptions options;
    if (!args.colorMap.empty()) options.colorMap = parseColorMap(args.colorMap);
    const std::vector<double> light = parseNumberList(args.light, "--light");
    if (light.size() != 2) throw InvalidInputError("--light takes AZIMUTH,ELEVATION in degrees");
    // --light uses the map-makers' convention (azimuth clockwise from up, where the light
    // comes from); ShadingOptions measures the direction of travel counter-clockwise from +x.
    options.shading.azimuthDeg = std::fmod(-90.0 - light[0] + 720.0, 360.0);
    options.shading.elevationDeg = light[1];
    options.shading.highContrast = args.highContrast;
    options.shading.contrastRadius = args.contrastRadius;
    options.shadeStrength = args.shadeStrength;
    if (args.isolines < 0) throw InvalidInputError("--isolines must be 0 or more");
    options.isolineCount = args.isolines;
    if (!args.levels.empty()) options.isolineLevels = parseNumberList(args.levels, "--levels");
    if (!args.range.empty()) {
        const auto r = parseNumberList(args.range, "--range");
        if (r.size() != 2 || !(r[0] < r[1])) throw InvalidInputError("--range takes LOW,HIGH with LOW < HIGH");
        options.fixedRange = true;
        options.range = {r[0], r[1]};
    } else {
        const auto p = parseNumberList(args.percentiles, "--percentiles");
        if (p.size() != 2) throw InvalidInputError("--percentiles takes LOW,HIGH (0 to 100)");
        options.loPercentile = p[0], options.hiPercentile = p[1];
    }
    if (args.centerOption && args.centerOption->count() > 0) {
        if (!std::isfinite(args.center)) throw InvalidInputError("--center must be a finite number");
        options.centered = true, options.center = args.center;
    }
    return options;
}

std::string shownValue(const RenderArgs& args, bool hasQuality, PictureOptions& options)
{
    const std::string show = args.show.empty() ? (hasQuality ? "quality" : "relief") : args.show;
    if (show == "relief") {
        if (!args.show.empty() && (args.isolines > 0 || !args.levels.empty() || !args.range.empty() ||
                                   !args.colorMap.empty() || options.centered || args.shade))
            throw InvalidInputError("--show relief is grey shading: --isolines, --levels, --range, --colormap, "
                                    "--center and --shade apply to values (e.g. --show quality --shade)");
        options.colour = false;
        options.shade = true;
        return "";
    }
    options.shade = args.shade;
    return show;
}

FontResult labelsFont(const RenderArgs& args)
{
    FontOptions fo;
    fo.file = args.font;
    FontResult font = findFont(fo);
    if (!font.warning.empty() && !args.quiet)
        std::fprintf(stderr, "msii: warning: %s (--font FILE names a font)\n", font.warning.c_str());
    return font;
}

void setLabelsFont(FigureOptions& figure, const FontResult& font, int pictureHeight)
{
    if (!font.typeface.isBuiltIn()) {
        figure.typeface = &font.typeface;
        figure.lineHeight = labelLineHeight(pictureHeight);
    } else {
        figure.fontScale = std::max(1, labelLineHeight(pictureHeight) / 9);
    }
}

namespace {

int runRender(const RenderArgs& args)
{
    const Stopwatch total;
    const std::string& input = args.inputs.front();
    const bool isMap = fs::path(input).extension() == ".exr";
    const bool isRaster = !isMap && isRasterInput(input);
    // What to show: relief (grey shading), height (Fig. 7c) or a value; default quality for
    // feature files, relief for plain meshes.
    std::string show = args.show;
    PictureOptions options = pictureOptionsOf(args);

    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    std::string value;
    // Default: quality when the input has it, else the relief (read in one go).
    const bool automatic = show.empty();
    const std::string wanted = automatic ? "quality" : show == "relief" ? "" : show;
    const bool needNormals = show == "relief" || args.shade;
    Channels ch = isMap      ? channelsFromMap(input, wanted, needNormals, automatic)
                  : isRaster ? channelsFromRaster(input, wanted, needNormals,
                                                  args.view.pixels > 0 ? args.view.pixels : kDefaultPixels, automatic,
                                                  args.quiet)
                             : channelsFromMesh(input, args.matFiles, args.view, wanted, needNormals, &progress, automatic);
    value = shownValue(args, ch.data.count("quality") > 0, options);
    show = value.empty() ? "relief" : value;
    if (!args.units.empty()) ch.units = args.units;
    const std::string output = outputPath(input, args.output, show, args.overwrite, ".png");

    PictureChannels pc;
    pc.width = ch.width, pc.height = ch.height;
    const auto get = [&](const char* name) -> const std::vector<float>* {
        auto it = ch.data.find(name);
        return it == ch.data.end() ? nullptr : &it->second;
    };
    pc.mask = get("mask");
    pc.nx = get("normal.x"), pc.ny = get("normal.y"), pc.nz = get("normal.z");
    if (!value.empty()) pc.value = get(value.c_str());
    const PictureResult picture = renderPicture(pc, options);

    FigureOptions figure;
    FontResult font;
    if (!args.noColorBar || !args.noScaleBar) {
        font = labelsFont(args);
        setLabelsFont(figure, font, picture.image.height);
    }
    figure.colorBar = options.colour && !args.noColorBar;
    figure.colorMap = options.colorMap;
    figure.range = picture.range;
    figure.label = value == "height" ? "height (" + ch.units + ")" : value;
    figure.isolines = picture.isolineLevels;
    figure.scaleBar = !args.noScaleBar && ch.pixelSize > 0;
    figure.pixelSize = ch.pixelSize;
    figure.units = ch.units;
    const RgbImage image = (figure.colorBar || figure.scaleBar) ? composeFigure(picture.image, figure) : picture.image;
    writePng(output, image);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %s -> %s (%d x %d pixels, %s%s, %.1f s)\n", input.c_str(), output.c_str(),
                     image.width, image.height, show.c_str(),
                     options.colour ? (" in [" + std::to_string(picture.range.lo) + ", " +
                                       std::to_string(picture.range.hi) + "]").c_str()
                                    : "",
                     total.seconds());
    return 0;
}

} // namespace

std::function<int()> addRenderCommand(CLI::App& app)
{
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand(
        "render", "PNG picture of a feature PLY, a GeoTIFF from msii compute on a DEM, or an EXR map: "
                  "false colour of a value with isolines, "
                  "shaded relief (virtual illumination) or the height map, with colour bar and scale bar.");
    cmd->add_option("input", args->inputs,
                    "Mesh or feature PLY, a GeoTIFF from msii compute on a DEM, or an EXR map from msii map; "
                    "with --layout fat-cross, any number of meshes (a collection)")
        ->required();
    cmd->add_option("-o,--output", args->output,
                    "Output PNG (default <input stem>.<what>.png; a sheet: <input stem>.<what>.sheet.png)");
    cmd->add_option("--output-dir", args->outputDir,
                    "With --layout fat-cross: the folder for the sheets, their records and index.html");
    cmd->add_option("--mat", args->matFiles, "GigaMesh feature file(s) for the input mesh");
    cmd->add_option("--show", args->show,
                    "What to show: a vertex property or map channel (quality, V_16, f_cosine ...), "
                    "height (height over the plane, paper Fig. 7c) or relief (virtual illumination). "
                    "Default: quality if present, else relief");
    cmd->add_option("--colormap", args->colorMap,
                    "viridis (default), cividis, gray (sequential) or coolwarm (diverging)");
    cmd->add_option("--range", args->range, "Colour range LOW,HIGH (default: --percentiles)");
    cmd->add_option("--percentiles", args->percentiles, "Colour range from percentiles LOW,HIGH (default 1,99)");
    args->centerOption = cmd->add_option("--center", args->center,
                    "Make the range symmetric about this value (e.g. 0.5 for V, the flat surface)");
    cmd->add_option("--isolines", args->isolines, "Draw this many isolines evenly inside the range");
    cmd->add_option("--levels", args->levels, "Draw isolines at these values, comma-separated");
    cmd->add_flag("--shade", args->shade, "Modulate the colours by the shaded relief");
    cmd->add_option("--shade-strength", args->shadeStrength, "With --shade: 0 (none) to 1 (full), default 0.6");
    cmd->add_option("--light", args->light,
                    "Light AZIMUTH,ELEVATION in degrees: azimuth clockwise from the top of the picture, "
                    "where the light comes from (default 315,45: from the top left)");
    cmd->add_flag("--high-contrast", args->highContrast,
                  "Shade the normal's deviation from its local mean: shallow strokes become visible");
    cmd->add_option("--contrast-radius", args->contrastRadius, "Radius of the local mean in pixels (default 16)");
    cmd->add_flag("--no-colorbar", args->noColorBar, "No colour bar");
    cmd->add_flag("--no-scalebar", args->noScaleBar, "No scale bar");
    cmd->add_option("--units", args->units,
                    "Units for the scale bar (default: those the input states: a raster's coordinate system, a map's "
                    "header, msii compute --units; else mm)");
    cmd->add_option("--font", args->font,
                    "Font file (TrueType/OpenType) for the labels (default: environment MSII_FONT, then "
                    "DejaVu Sans through fontconfig, else a built-in pixel font with a warning)");
    addViewOptions(cmd, args->view, kDefaultPixels);
    cmd->add_option("--layout", args->layout,
                    "fat-cross: the six orthographic views on one sheet at one scale, the obverse in the centre, the "
                    "edges folded out around it and the reverse below (docs/figures.md); with --pixels, the "
                    "sheet's longer side")
        ->check(CLI::IsMember({"fat-cross"}));
    cmd->add_flag("--labels", args->labels, "With --layout: name the views obv., rev., t.e., b.e., l.e., r.e.");
    cmd->add_option("--front", args->front,
                    "With --layout: the direction X,Y,Z from the object towards a viewer of the obverse "
                    "(default: along the axis of least extent, the flatter side)");
    cmd->add_option("--up", args->up,
                    "With --layout: the direction X,Y,Z that is up on the obverse (default: the longest axis)");
    cmd->add_option("--orientation", args->orientationFile,
                    "With --layout: take front, up (and, without a resolution, the pixel size) from a sheet's "
                    "JSON record, to redo a sheet the same way");
    cmd->add_flag("--views-separately", args->viewsSeparately,
                  "With --layout: also write each view as its own PNG (<sheet>.obverse.png ...)");
    addCommonOptions(cmd, *args);
    return [args, cmd]() {
        const auto limit = limitThreads(args->threads);
        if (!args->layout.empty()) return runSheets(*args);
        if (args->inputs.size() > 1)
            throw InvalidInputError("render takes one input, or several with --layout fat-cross (one sheet each)");
        for (const char* option : {"--labels", "--front", "--up", "--orientation", "--views-separately", "--output-dir"})
            if (cmd->count(option) > 0)
                throw InvalidInputError(std::string(option) + " needs --layout fat-cross");
        return runRender(*args);
    };
}

} // namespace msii::tools
