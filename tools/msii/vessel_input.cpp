#include "vessel_input.h"

#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/mesh/vertex_normals.h>

#include <array>
#include <cmath>
#include <fstream>

namespace msii::tools {
namespace {

nlohmann::json vectorJson(const Vec3& v)
{
    return nlohmann::json::array({v.x, v.y, v.z});
}

Vec3 vectorOf(const nlohmann::json& j, const char* key)
{
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
        throw InvalidInputError(std::string("its ") + key + " is not a vector of three numbers");
    return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

/// Along a given line: the object's extent and its outer wall's best cylinder and cone (what
/// unroll needs of an axis it did not fit). The outer wall: the vertices of triangles whose
/// normals are mostly radial (within 45°), of the side (facing away from the axis or towards
/// it) with the larger mean radius, so that an inner wall, a base or a rim do not pull it.
AxisOfRotation describedAlong(const TriMesh& mesh, const Vec3& point, const Vec3& direction)
{
    const AxisFrame f(point, direction);
    const std::vector<Vec3> normals = vertexNormals(mesh);
    std::vector<char> used(mesh.numVertices(), 0);
    double lo = 1e300, hi = -1e300;
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t) {
            used[i] = 1;
            lo = std::min(lo, f.height(mesh.points[i])), hi = std::max(hi, f.height(mesh.points[i]));
        }
    // Per side: count, Σh, Σr, Σh², Σhr, Σr².
    std::array<std::array<double, 6>, 2> sums{};
    for (std::size_t i = 0; i < mesh.numVertices(); ++i) {
        const Vec3& p = mesh.points[i];
        const double r = f.radius(p);
        if (!used[i] || !(r > 0)) continue;
        const Vec3 radial = (p - f.point - f.direction * f.height(p)) / r;
        const double along = dot(normals[i], radial);
        if (std::abs(along) < 0.7071) continue;
        const double h = f.height(p) - lo;
        std::array<double, 6>& s = sums[along > 0 ? 0 : 1];
        s[0] += 1, s[1] += h, s[2] += r, s[3] += h * h, s[4] += h * r, s[5] += r * r;
    }
    const auto meanR = [&](int k) { return sums[k][0] > 0 ? sums[k][2] / sums[k][0] : -1.0; };
    const std::array<double, 6>& s = sums[meanR(0) >= meanR(1) ? 0 : 1];
    if (!(s[0] > 2))
        throw InvalidInputError("the surface has no wall around the given axis (no part of it faces away from it)");
    const double W = s[0], Sh = s[1], Sr = s[2], Shh = s[3], Shr = s[4], Srr = s[5];
    AxisOfRotation a;
    a.point = point + f.direction * lo;
    a.direction = f.direction;
    a.height = hi - lo;
    a.meanRadius = a.cylinderRadius = Sr / W;
    const double d = W * Shh - Sh * Sh;
    a.coneSlope = d > 0 ? (W * Shr - Sh * Sr) / d : 0;
    a.coneRadius0 = (Sr - a.coneSlope * Sh) / W;
    // The misfits from the sums: Σ(r − c)² and Σ(r − c0 − k h)².
    const double cylinder = Srr - Sr * Sr / W;
    const double cone = Srr + W * a.coneRadius0 * a.coneRadius0 + a.coneSlope * a.coneSlope * Shh -
                        2 * a.coneRadius0 * Sr - 2 * a.coneSlope * Shr + 2 * a.coneRadius0 * a.coneSlope * Sh;
    a.cylinderMisfit = std::sqrt(std::max(0.0, cylinder) / W), a.coneMisfit = std::sqrt(std::max(0.0, cone) / W);
    a.shape = a.coneMisfit < 0.8 * a.cylinderMisfit ? RevolutionShape::Cone : RevolutionShape::Cylinder;
    return a;
}

RevolutionShape shapeNamed(const std::string& name)
{
    for (const RevolutionShape s : {RevolutionShape::Cylinder, RevolutionShape::Cone, RevolutionShape::General})
        if (name == revolutionShapeName(s)) return s;
    throw InvalidInputError("its shape '" + name + "' is none of cylinder, cone, surface of revolution");
}

/// An axis record of `msii axis`: the axis and what the fit found, as it found it. A record
/// with only a point and a direction (written by hand) is described along its line.
AxisOfRotation axisOfRecord(const TriMesh& mesh, const nlohmann::json& r)
{
    const Vec3 point = vectorOf(r.at("point"), "point"), direction = vectorOf(r.at("direction"), "direction");
    if (!(norm(direction) > 0)) throw InvalidInputError("its direction has no length");
    if (!r.contains("cylinder") || !r.contains("cone") || !r.contains("mean_radius"))
        return describedAlong(mesh, point, direction);
    AxisOfRotation a;
    a.point = point, a.direction = normalized(direction);
    a.shape = shapeNamed(r.at("shape").get<std::string>());
    a.residual = r.value("residual", 0.0);
    a.inlierShare = r.value("inlier_share", 0.0);
    a.meanRadius = r.at("mean_radius").get<double>();
    a.height = r.at("height").get<double>();
    a.directionUncertainty = r.value("direction_uncertainty_degrees", 0.0);
    a.cylinderRadius = r.at("cylinder").at("radius").get<double>();
    a.cylinderMisfit = r.at("cylinder").at("misfit").get<double>();
    a.coneRadius0 = r.at("cone").at("radius_at_point").get<double>();
    a.coneSlope = r.at("cone").at("slope").get<double>();
    a.coneMisfit = r.at("cone").at("misfit").get<double>();
    if (r.contains("rim_diameter") && r["rim_diameter"].is_number()) a.rimDiameter = r["rim_diameter"].get<double>();
    for (const double v : {a.meanRadius, a.height, a.cylinderRadius, a.coneRadius0, a.coneSlope})
        if (!std::isfinite(v)) throw InvalidInputError("it holds a number that is not finite");
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
        return axisOfRecord(mesh, r);
    } catch (const InvalidInputError& e) {
        throw InvalidInputError("--axis " + option + " is not a usable axis record: " + e.what());
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
