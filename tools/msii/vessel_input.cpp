#include "vessel_input.h"

#include "feature_input.h"

#include <msii/core/errors.h>

#include <cmath>
#include <fstream>

namespace msii::tools {
namespace {

nlohmann::json vectorJson(const Vec3& v)
{
    return nlohmann::json::array({v.x, v.y, v.z});
}

Vec3 vectorOf(const nlohmann::json& j)
{
    if (!j.is_array() || j.size() != 3) throw InvalidInputError("not a vector");
    return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

/// Along a given axis: the object's extent and its outer wall's best cylinder and cone, from
/// the surface's points (what unroll needs of an axis it did not fit).
AxisOfRotation describedAlong(const TriMesh& mesh, const Vec3& point, const Vec3& direction)
{
    const AxisFrame f(point, direction);
    double lo = 1e300, hi = -1e300, W = 0, Sh = 0, Sr = 0, Shh = 0, Shr = 0;
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t)
            lo = std::min(lo, f.height(mesh.points[i])), hi = std::max(hi, f.height(mesh.points[i]));
    for (const Vec3& p : mesh.points) {
        const double h = f.height(p) - lo, r = f.radius(p);
        W += 1, Sh += h, Sr += r, Shh += h * h, Shr += h * r;
    }
    AxisOfRotation a;
    a.point = point + f.direction * lo;
    a.direction = f.direction;
    a.height = hi - lo;
    a.meanRadius = a.cylinderRadius = Sr / W;
    const double d = W * Shh - Sh * Sh;
    a.coneSlope = d > 0 ? (W * Shr - Sh * Sr) / d : 0;
    a.coneRadius0 = (Sr - a.coneSlope * Sh) / W;
    double cylinder = 0, cone = 0;
    for (const Vec3& p : mesh.points) {
        const double h = f.height(p) - lo, r = f.radius(p), c = r - a.cylinderRadius,
                     k = r - a.coneRadius0 - a.coneSlope * h;
        cylinder += c * c, cone += k * k;
    }
    a.cylinderMisfit = std::sqrt(cylinder / W), a.coneMisfit = std::sqrt(cone / W);
    return a;
}

}  // namespace

AxisOfRotation axisFromOption(const TriMesh& mesh, const std::string& option, std::string& said)
{
    if (option.empty() || option == "auto") {
        said = "fitted";
        return fitAxisOfRotation(mesh);
    }
    const std::size_t colon = option.find(':');
    if (colon != std::string::npos) {
        const std::vector<double> p = parseNumberList(option.substr(0, colon), "--axis");
        const std::vector<double> d = parseNumberList(option.substr(colon + 1), "--axis");
        if (p.size() != 3 || d.size() != 3 || !(std::hypot(d[0], d[1], d[2]) > 0))
            throw InvalidInputError("--axis takes auto, PX,PY,PZ:DX,DY,DZ (a point and a direction of non-zero length) "
                                    "or an axis record of msii axis (got '" +
                                    option + "')");
        said = "given";
        return describedAlong(mesh, Vec3(p[0], p[1], p[2]), Vec3(d[0], d[1], d[2]));
    }
    std::ifstream in(option);
    if (!in)
        throw InvalidInputError("--axis " + option + ": no such file (give auto, PX,PY,PZ:DX,DY,DZ or an axis record)");
    try {
        const nlohmann::json r = nlohmann::json::parse(in);
        said = "from " + option;
        AxisOfRotation a = describedAlong(mesh, vectorOf(r.at("point")), vectorOf(r.at("direction")));
        if (r.contains("rim_diameter") && r["rim_diameter"].is_number())
            a.rimDiameter = r["rim_diameter"].get<double>();
        return a;
    } catch (const InvalidInputError&) {
        throw;
    } catch (const std::exception&) {
        throw InvalidInputError("--axis " + option +
                                " is not an axis record (a JSON file with point and direction, as "
                                "msii axis writes)");
    }
}

nlohmann::json axisRecord(const AxisOfRotation& a, const std::string& units)
{
    nlohmann::json r;
    r["point"] = vectorJson(a.point);
    r["direction"] = vectorJson(a.direction);
    r["shape"] = revolutionShapeName(a.shape);
    r["residual"] = a.residual;
    r["rim_diameter"] = a.rimDiameter ? nlohmann::json(*a.rimDiameter) : nlohmann::json(nullptr);
    r["units"] = units;
    r["height"] = a.height;
    r["mean_radius"] = a.meanRadius;
    r["inlier_share"] = a.inlierShare;
    r["direction_uncertainty_degrees"] = a.directionUncertainty;
    r["cylinder"] = {{"radius", a.cylinderRadius}, {"misfit", a.cylinderMisfit}};
    r["cone"] = {{"radius_at_point", a.coneRadius0},
                 {"slope", a.coneSlope},
                 {"misfit", a.coneMisfit},
                 {"half_angle_degrees", std::atan(std::abs(a.coneSlope)) * 180.0 / 3.14159265358979323846}};
    return r;
}

}  // namespace msii::tools
