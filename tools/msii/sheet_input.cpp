#include "sheet_input.h"

#include "feature_input.h"

#include <msii/core/errors.h>

#include <cmath>
#include <fstream>

namespace msii::tools {
namespace {

Vec3 parseDirection(const std::string& text, const char* option)
{
    const std::vector<double> c = parseNumberList(text, option);
    if (c.size() != 3) throw InvalidInputError(std::string(option) + " takes a direction X,Y,Z (got '" + text + "')");
    const Vec3 d(c[0], c[1], c[2]);
    if (!(norm(d) > 0))
        throw InvalidInputError(std::string(option) + " must be a direction of non-zero length (got '" + text + "')");
    return d;
}

Vec3 vectorOf(const nlohmann::json& j)
{
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
        throw InvalidInputError("not a vector");
    return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

nlohmann::json vectorJson(const Vec3& v)
{
    return nlohmann::json::array({v.x, v.y, v.z});
}

}  // namespace

SheetOrientationOptions sheetOrientationOptions(const std::string& front, const std::string& up,
                                                const std::string& orientationFile, double& recordPixelSize)
{
    SheetOrientationOptions o;
    recordPixelSize = 0;
    if (!orientationFile.empty()) {
        if (!front.empty() || !up.empty()) throw InvalidInputError("give --orientation or --front and --up, not both");
        std::ifstream in(orientationFile);
        if (!in) throw InvalidInputError("cannot read --orientation " + orientationFile);
        try {
            const nlohmann::json record = nlohmann::json::parse(in);
            o.front = vectorOf(record.at("front"));
            o.up = vectorOf(record.at("up"));
            if (record.contains("pixel_size") && record["pixel_size"].is_number())
                recordPixelSize = record["pixel_size"].get<double>();
        } catch (const std::exception&) {
            throw InvalidInputError("--orientation " + orientationFile +
                                    " is not a sheet's record (a JSON file with "
                                    "front and up, as msii render "
                                    "--layout fat-cross writes)");
        }
    }
    if (!front.empty()) o.front = parseDirection(front, "--front");
    if (!up.empty()) o.up = parseDirection(up, "--up");
    if (o.front && o.up) {
        const Vec3 f = normalized(*o.front), u = normalized(*o.up);
        if (!(norm(cross(f, u)) > 1e-6))
            throw InvalidInputError(
                (orientationFile.empty() ? std::string("--front and --up are") : "the record's front and up are") +
                " parallel: up must have a part across the front direction");
    }
    return o;
}

FatCrossOptions sheetScale(const ViewArgs& view, int defaultPixels, double recordPixelSize)
{
    if ((view.viewOption && view.viewOption->count() > 0) || view.flip)
        throw InvalidInputError("a sheet shows every side: --view and --flip do "
                                "not apply to --layout fat-cross "
                                "(--front and --up orient it)");
    const auto given = [](const CLI::Option* o) { return o && o->count() > 0; };
    const bool any = given(view.pixelsOption) || given(view.pixelSizeOption) || given(view.dpiOption);
    const MapFrameOptions frame = frameOptions(view, defaultPixels);  // checks the values
    FatCrossOptions o;
    if (!any && recordPixelSize > 0) {
        o.pixelSize = recordPixelSize;
        return o;
    }
    o.longerSidePixels = frame.longerSidePixels;
    o.pixelSize = frame.pixelSize;
    o.dpi = frame.dpi;
    return o;
}

SheetViews layOutSheet(const TriMesh& mesh, const std::vector<Vec3>& normals, const SheetOrientation& orientation,
                       const FatCrossOptions& scale, RunContext* progress)
{
    SheetViews s;
    s.layout = layoutFatCross(mesh, orientation, scale);
    s.views = rasterizeViews(mesh, s.layout, progress);
    s.sides = sheetSides(mesh, normals, s.layout, s.views);
    markScanned(s.layout, s.sides);
    return s;
}

nlohmann::json sheetViewsRecord(const FatCrossLayout& layout)
{
    nlohmann::json views = nlohmann::json::array();
    for (const SheetViewBox& box : layout.views) {
        nlohmann::json matrix = nlohmann::json::array();
        for (const auto& row : box.toPixel()) matrix.push_back(row);
        views.push_back({{"name", sheetViewName(box.view)},
                         {"label", sheetViewLabel(box.view)},
                         {"scanned", box.scanned},
                         {"box", {box.x0, box.y0, box.x0 + box.frame.width, box.y0 + box.frame.height}},
                         {"to_pixel", matrix}});
    }
    return views;
}

nlohmann::json sheetRecord(const FatCrossLayout& layout, const std::string& units)
{
    const SheetOrientation& o = layout.orientation;
    nlohmann::json r;
    r["layout"] = "fat-cross";
    r["pixel_size"] = layout.pixelSize;
    r["units"] = units;
    if (units == "mm") r["dpi"] = 25.4 / layout.pixelSize;
    r["front"] = vectorJson(o.front);
    r["up"] = vectorJson(o.up);
    r["right"] = vectorJson(o.right());
    r["orientation_rule"] = {{"front", o.frontRule}, {"up", o.upRule}};
    r["size"] = vectorJson(layout.size);
    r["sheet"] = {layout.width, layout.height};
    r["views"] = sheetViewsRecord(layout);
    return r;
}

}  // namespace msii::tools
