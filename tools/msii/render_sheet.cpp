/// `msii render INPUT… --layout fat-cross`: the figure tablet researchers
/// publish, the six orthographic views on one sheet at one scale (engine:
/// figures/fat_cross.h), with its JSON record beside it; for several inputs,
/// one sheet each at a common scale and a contact sheet (index.html) in the
/// output folder (docs/figures.md).
#include "compute_args.h"
#include "feature_input.h"
#include "render_args.h"
#include "sheet_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/core/terminal_progress.h>
#include <msii/featuremap/rasterize.h>
#include <msii/figures/sheet_raster.h>
#include <msii/io/atomic_file.h>
#include <msii/io/read_mesh.h>
#include <msii/mesh/vertex_normals.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace msii::tools {
namespace {

namespace fs = std::filesystem;

constexpr Rgb8 kBlankFrame{200, 200, 200};
/// Thumbnails in the contact sheet: the largest sheet's longer side, in pixels.
constexpr int kThumbnailPixels = 320;

/// Where one input's sheet goes.
struct SheetPaths {
    std::string png, json;
    std::vector<std::string> views;  ///< --views-separately, in SheetView order
};

/// What the contact sheet lists of one sheet.
struct SheetEntry {
    std::string input, png, units;
    Vec3 size;
    double pixelSize = 0;
    int width = 0, height = 0;
};

/// What every sheet of a run shares: the options as parsed, the font and the
/// scale.
struct SheetRun {
    const RenderArgs& args;
    SheetOrientationOptions orientation;
    FatCrossOptions scale;
    FontResult font;
};

SheetPaths sheetPaths(const RenderArgs& args, const std::string& input, const std::string& shown)
{
    SheetPaths p;
    if (!args.output.empty()) {
        p.png = args.output;
    } else {
        const fs::path in(input);
        const fs::path folder = args.outputDir.empty() ? in.parent_path() : fs::path(args.outputDir);
        p.png = (folder / (in.stem().string() + "." + shown + ".sheet.png")).string();
    }
    if (fs::path(p.png).extension() != ".png")
        throw InvalidInputError("the output '" + p.png + "' must be a .png file");
    const std::string stem = p.png.substr(0, p.png.size() - 4);
    p.json = stem + ".json";
    if (args.viewsSeparately)
        for (int k = 0; k < kSheetViews; ++k) p.views.push_back(stem + "." + sheetViewName(SheetView(k)) + ".png");
    std::vector<std::string> all{p.png, p.json};
    all.insert(all.end(), p.views.begin(), p.views.end());
    checkOutputs(all, args.overwrite);
    return p;
}

/// One error line for coordinates that are not numbers (the layout would be
/// meaningless).
void checkFinite(const TriMesh& mesh)
{
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t)
            if (!isFinite(mesh.points[i]))
                throw InvalidInputError("the mesh has coordinates that are not finite "
                                        "numbers (NaN or infinite)");
}

/// The captions: with --labels the views' names, and "not scanned" under a
/// blank view.
std::array<std::string, kSheetViews> captionsOf(const RenderArgs& args, const SheetSides& sides)
{
    std::array<std::string, kSheetViews> text;
    for (std::size_t k = 0; k < kSheetViews; ++k) {
        if (args.labels) text[k] = sheetViewLabel(SheetView(k));
        if (!sides.scanned[k]) text[k] += args.labels ? " (not scanned)" : "not scanned";
    }
    return text;
}

int captionWidth(const FontResult& font, const std::string& text, int lineHeight)
{
    if (text.empty()) return 0;
    return font.typeface.isBuiltIn() ? textWidth(text, std::max(1, lineHeight / 9))
                                     : font.typeface.textWidth(text, lineHeight);
}

/// The sheet laid out (layOutSheet) and, where it has captions (--labels, "not
/// scanned"), laid out again with room for them, whose size follows the
/// sheet's; its views rasterised again only if that changed the scale.
SheetViews layOutWithCaptions(const TriMesh& mesh, const std::vector<Vec3>& normals,
                              const SheetOrientation& orientation, const SheetRun& run,
                              std::array<std::string, kSheetViews>& captions, RunContext* progress)
{
    SheetViews s = layOutSheet(mesh, normals, orientation, run.scale, progress);
    captions = captionsOf(run.args, s.sides);
    if (std::all_of(captions.begin(), captions.end(), [](const std::string& c) { return c.empty(); })) return s;
    FatCrossOptions options = run.scale;
    options.captionHeight = labelLineHeight(s.layout.height);
    for (std::size_t k = 0; k < kSheetViews; ++k)
        options.captionWidth[k] = captionWidth(run.font, captions[k], options.captionHeight);
    const double pixelSize = s.layout.pixelSize;
    s.layout = layoutFatCross(mesh, orientation, options);
    if (s.layout.pixelSize != pixelSize) s.views = rasterizeViews(mesh, s.layout, progress);
    markScanned(s.layout, s.sides);
    return s;
}

void drawCaptions(RgbImage& image, const FatCrossLayout& layout, const FontResult& font,
                  const std::array<std::string, kSheetViews>& captions)
{
    const int lineHeight = layout.captionHeight;
    for (const SheetViewBox& box : layout.views) {
        const std::string& text = captions[std::size_t(box.view)];
        if (!box.scanned) {  // the blank view's place, framed in light grey
            const int x0 = box.x0, y0 = box.y0, x1 = box.x0 + box.frame.width, y1 = box.y0 + box.frame.height;
            fillRect(image, x0, y0, x1, y0 + 1, kBlankFrame), fillRect(image, x0, y1 - 1, x1, y1, kBlankFrame);
            fillRect(image, x0, y0, x0 + 1, y1, kBlankFrame), fillRect(image, x1 - 1, y0, x1, y1, kBlankFrame);
        }
        if (text.empty()) continue;
        const int x = box.captionX - captionWidth(font, text, lineHeight) / 2;
        if (font.typeface.isBuiltIn())
            drawText(image, x, box.captionY, text, {0, 0, 0}, std::max(1, lineHeight / 9));
        else
            font.typeface.drawText(image, x, box.captionY, text, {0, 0, 0}, lineHeight);
    }
}

/// The picture of the sheet's views (before the colour and scale bars).
PictureResult sheetPicture(const FeatureMesh& in, const std::vector<Vec3>& normals, const SheetViews& s,
                           const std::string& value, const PictureOptions& options)
{
    const SheetPixels sheet = composeSheet(s.layout, s.views);
    if (sheet.hits.covered == 0) throw InvalidInputError("no view sees the mesh");
    const std::vector<float> mask = coverageMask(sheet.hits);
    PictureChannels pc;
    pc.width = s.layout.width, pc.height = s.layout.height;
    pc.mask = &mask;
    std::vector<float> values;
    if (value == "height")
        pc.value = &sheet.hits.depth;
    else if (!value.empty())
        pc.value = &(values = interpolateToPixels(in.mesh, sheet.hits, in.properties[findProperty(in, value)].values));
    std::array<std::vector<float>, 3> shading;
    if (options.shade) {
        shading = sheetNormals(in.mesh, normals, s.layout, sheet);
        pc.nx = &shading[0], pc.ny = &shading[1], pc.nz = &shading[2];
    }
    return renderPicture(pc, options);
}

/// Each view on its own: its box cut out of the picture.
void writeViews(const RgbImage& picture, const FatCrossLayout& layout, const SheetPaths& paths)
{
    for (std::size_t k = 0; k < paths.views.size(); ++k) {
        const SheetViewBox& box = layout.views[k];
        RgbImage view(box.frame.width, box.frame.height);
        for (int y = 0; y < view.height; ++y)
            std::copy_n(picture.rgb.begin() + std::ptrdiff_t(3 * (std::size_t(box.y0 + y) * picture.width + box.x0)),
                        3 * view.width, view.rgb.begin() + std::ptrdiff_t(3 * std::size_t(y) * view.width));
        writePng(paths.views[k], view);
    }
}

/// One input's sheet, its record and (--views-separately) its views.
SheetEntry renderOneSheet(const SheetRun& run, const std::string& input)
{
    const RenderArgs& args = run.args;
    const Stopwatch total;
    if (fs::path(input).extension() == ".exr" || isRasterInput(input))
        throw InvalidInputError("a sheet of six views needs a mesh (PLY, OBJ, OFF "
                                "or STL), not a map or a raster");
    PictureOptions options = pictureOptionsOf(args);
    FeatureMesh in = readFeatureMesh(input, args.matFiles);
    printWarnings(input, in.warnings, args.quiet);
    checkFinite(in.mesh);
    const bool hasQuality = std::any_of(in.properties.begin(), in.properties.end(),
                                        [](const VertexProperty& p) { return p.name == "quality"; });
    const std::string value = shownValue(args, hasQuality, options);
    if (!value.empty() && value != "height") findProperty(in, value);  // names what there is
    const std::string shown = value.empty() ? "relief" : value;
    const SheetPaths paths = sheetPaths(args, input, shown);
    const std::string units = !args.units.empty()                       ? args.units
                              : !unitsFromComments(in.comments).empty() ? unitsFromComments(in.comments)
                                                                        : "mm";

    const SheetOrientation orientation = orientSheet(in.mesh, run.orientation);
    const std::vector<Vec3> normals = vertexNormals(in.mesh);
    TerminalProgress terminal(progressStyle(args));
    RunContext progress(terminal.listener());
    std::array<std::string, kSheetViews> captions;
    const SheetViews views = layOutWithCaptions(in.mesh, normals, orientation, run, captions, &progress);
    const FatCrossLayout& layout = views.layout;
    PictureResult picture = sheetPicture(in, normals, views, value, options);
    drawCaptions(picture.image, layout, run.font, captions);

    FigureOptions figure;
    setLabelsFont(figure, run.font, layout.height);
    figure.colorBar = options.colour && !args.noColorBar;
    figure.colorMap = options.colorMap;
    figure.range = picture.range;
    figure.label = value == "height" ? "height (" + units + ")" : value;
    figure.isolines = picture.isolineLevels;
    figure.scaleBar = !args.noScaleBar;
    figure.pixelSize = layout.pixelSize;
    figure.units = units;
    const RgbImage image = (figure.colorBar || figure.scaleBar) ? composeFigure(picture.image, figure) : picture.image;

    nlohmann::json record = sheetRecord(layout, units);
    record["input"] = fs::absolute(input).string();
    record["shows"] = shown;
    record["width"] = image.width, record["height"] = image.height;
    if (options.colour) record["colour_range"] = {picture.range.lo, picture.range.hi};
    if (figure.scaleBar) {
        const double length = scaleBarLength(picture.image.width, layout.pixelSize);
        record["scale_bar"] = {
            {"length", length}, {"units", units}, {"pixels", std::lround(length / layout.pixelSize)}};
    }
    if (!paths.views.empty()) writeViews(picture.image, layout, paths);
    writeTextFileAtomic(paths.json, record.dump(2) + "\n");
    writePng(paths.png, image);
    if (!args.quiet)
        std::fprintf(stderr,
                     "msii: %s -> %s (%d x %d pixels, %.4g %s per pixel, obverse "
                     "%s, up %s, %.1f s)\n",
                     input.c_str(), paths.png.c_str(), image.width, image.height, layout.pixelSize, units.c_str(),
                     orientation.frontRule.c_str(), orientation.upRule.c_str(), total.seconds());
    return {input, paths.png, units, layout.size, layout.pixelSize, image.width, image.height};
}

/// A collection's common scale for --pixels (or the default): the largest pixel
/// size any of its sheets needs to fit, so that all are at one scale and sizes
/// compare.
FatCrossOptions commonScale(const SheetRun& run, const std::vector<std::string>& inputs)
{
    if (run.scale.longerSidePixels == 0) return run.scale;
    double largest = 0;
    for (const std::string& input : inputs) {
        try {
            const TriMesh mesh = readMesh(input).mesh;
            checkFinite(mesh);
            const SheetOrientation orientation = orientSheet(mesh, run.orientation);
            largest = std::max(largest, layoutFatCross(mesh, orientation, run.scale).pixelSize);
        } catch (const Error&) {  // said when its sheet is made
        }
    }
    FatCrossOptions common;
    common.pixelSize = largest > 0 ? largest : 1.0;
    return common;
}

std::string escapeHtml(const std::string& text)
{
    std::string out;
    for (char c : text)
        out += c == '&' ? "&amp;" : c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '"' ? "&quot;" : std::string(1, c);
    return out;
}

/// A length as a reader wants it: three significant digits, whole units from 100 on.
std::string length(double value)
{
    char text[32];
    std::snprintf(text, sizeof text, value >= 100 ? "%.0f" : "%.3g", value);
    return text;
}

/// A thumbnail of @p image @p factor times its size (box-filtered).
RgbImage thumbnail(const RgbImage& image, double factor)
{
    const int w = std::max(1, int(std::lround(image.width * factor))),
              h = std::max(1, int(std::lround(image.height * factor)));
    RgbImage out(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int x0 = int(x / factor), x1 = std::max(x0 + 1, std::min(image.width, int((x + 1) / factor)));
            const int y0 = int(y / factor), y1 = std::max(y0 + 1, std::min(image.height, int((y + 1) / factor)));
            double sum[3] = {0, 0, 0};
            for (int yy = y0; yy < y1; ++yy)
                for (int xx = x0; xx < x1; ++xx)
                    for (int c = 0; c < 3; ++c) sum[c] += image.rgb[3 * (std::size_t(yy) * image.width + xx) + c];
            const double n = double(x1 - x0) * (y1 - y0);
            out.set(x, y,
                    {std::uint8_t(std::lround(sum[0] / n)), std::uint8_t(std::lround(sum[1] / n)),
                     std::uint8_t(std::lround(sum[2] / n))});
        }
    return out;
}

/// The contact sheet: each scan's name, its size and a thumbnail linking to its
/// sheet, the thumbnails at one scale as the sheets are.
void writeContactSheet(const fs::path& folder, const std::vector<SheetEntry>& entries)
{
    const std::string& units = entries.front().units;
    const double pixelSize = entries.front().pixelSize;
    int longest = 1;
    for (const SheetEntry& e : entries) longest = std::max({longest, e.width, e.height});
    const double factor = std::min(1.0, double(kThumbnailPixels) / longest);
    fs::create_directories(folder / "thumbs");
    std::ostringstream html;
    html.precision(4);
    html << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta "
            "charset=\"utf-8\">\n<title>msii sheets</title>\n"
         << "<style>body{font-family:sans-serif;margin:1.5em}main{display:flex;"
            "flex-wrap:wrap;gap:1.5em;"
         << "align-items:flex-end}figure{margin:0}figcaption{font-size:0.9em;"
            "margin-top:0.3em}"
         << "img{border:1px solid #ccc}</style>\n</head>\n<body>\n<h1>msii "
            "sheets</h1>\n<p>"
         << entries.size() << " scans, six views each, all at " << pixelSize << " " << escapeHtml(units)
         << " per pixel";
    if (units == "mm") html << " (" << 25.4 / pixelSize << " dpi)";
    html << "; the thumbnails share one scale. Size: width &times; height "
            "&times; thickness as laid out.</p>\n<main>\n";
    for (const SheetEntry& e : entries) {
        const fs::path png(e.png);
        const std::string thumb = "thumbs/" + png.filename().string();
        const RgbImage small = thumbnail(readPng(e.png), factor);
        writePng((folder / thumb).string(), small);
        html << "<figure><a href=\"" << escapeHtml(fs::relative(png, folder).string()) << "\"><img src=\""
             << escapeHtml(thumb) << "\" width=\"" << small.width << "\" height=\"" << small.height << "\" alt=\""
             << escapeHtml(fs::path(e.input).filename().string()) << "\"></a><figcaption><strong>"
             << escapeHtml(fs::path(e.input).filename().string()) << "</strong><br>" << length(e.size.x) << " &times; "
             << length(e.size.y) << " &times; " << length(e.size.z) << " " << escapeHtml(units)
             << "</figcaption></figure>\n";
    }
    html << "</main>\n</body>\n</html>\n";
    writeTextFileAtomic((folder / "index.html").string(), html.str());
}

}  // namespace

int runSheets(const RenderArgs& args)
{
    const std::vector<std::string>& inputs = args.inputs;
    const bool collection = inputs.size() > 1;
    if (collection && !args.output.empty())
        throw InvalidInputError("several inputs give several sheets: name their "
                                "folder with --output-dir, not -o");
    if (collection && args.outputDir.empty())
        throw InvalidInputError("several inputs: give --output-dir FOLDER for "
                                "their sheets and the contact sheet");
    if (!args.output.empty() && !args.outputDir.empty()) throw InvalidInputError("give -o or --output-dir, not both");
    double recordPixelSize = 0;
    SheetRun run{args, sheetOrientationOptions(args.front, args.up, args.orientationFile, recordPixelSize),
                 sheetScale(args.view, kDefaultPixels, recordPixelSize), labelsFont(args)};
    if (!args.outputDir.empty()) fs::create_directories(args.outputDir);
    if (collection) run.scale = commonScale(run, inputs);
    std::vector<SheetEntry> entries;
    int failed = 0;
    for (const std::string& input : inputs) {
        try {
            entries.push_back(renderOneSheet(run, input));
        } catch (const Error& e) {
            if (!collection) throw;
            std::fprintf(stderr, "msii: error: %s: %s\n", input.c_str(), e.what());
            ++failed;
        }
    }
    if (collection && !entries.empty()) writeContactSheet(args.outputDir, entries);
    return failed > 0 ? 1 : 0;
}

}  // namespace msii::tools
