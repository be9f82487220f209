#include <msii/figures/sheet_orientation.h>

#include <msii/core/errors.h>
#include <msii/mesh/principal_axes.h>

#include <cmath>

namespace msii {
namespace {

/// Relative differences below this are rounding: the rule does not decide.
constexpr double kUndecided = 1e-9;

Vec3 checkedDirection(const Vec3& d, const char* what)
{
    if (!isFinite(d) || !(norm(d) > 0))
        throw InvalidInputError(std::string("the ") + what + " direction has zero length or is not finite");
    return normalized(d);
}

/// @p axis with the part along @p unit dropped, normalised; zero if (nearly)
/// parallel.
Vec3 across(const Vec3& axis, const Vec3& unit)
{
    const Vec3 a = axis - unit * dot(axis, unit);
    return norm(a) > 1e-6 * norm(axis) ? normalized(a) : Vec3{};
}

/// The first of @p candidates that has a part across @p unit, made orthogonal
/// to it.
Vec3 firstAcross(std::initializer_list<Vec3> candidates, const Vec3& unit)
{
    for (const Vec3& c : candidates) {
        const Vec3 a = across(c, unit);
        if (norm(a) > 0.1) return a;
    }
    return across(*candidates.begin(), unit);
}

/// Area-weighted third central moment of the surface along @p axis (triangle
/// centroids), relative to area · σ³: positive where the surface has its longer
/// tail of area.
double thirdMoment(const TriMesh& mesh, const SurfaceMoments& m, const Vec3& axis)
{
    double m2 = 0, m3 = 0;
    for (const Triangle& t : mesh.triangles) {
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const double A = 0.5 * norm(cross(b - a, c - a));
        const double h = dot((a + b + c) / 3.0 - m.centroid, axis);
        m2 += A * h * h;
        m3 += A * h * h * h;
    }
    const double sigma = std::sqrt(m2 / m.area);
    return sigma > 0 ? m3 / (m.area * sigma * sigma * sigma) : 0.0;
}

/// The sign of the front axis @p axis: the side an open scan faces, else the
/// flatter of the two large sides, else the third moment's tail (the bulge),
/// else the sign convention.
Vec3 frontSide(const TriMesh& mesh, const SurfaceMoments& m, const Vec3& axis, std::string& rule)
{
    // Per side (by the triangle's centroid), the surface facing along the axis
    // (within 60°): area, and the first and second moments of its height along
    // the axis.
    double projected = 0, area[2] = {0, 0}, sum[2] = {0, 0}, sum2[2] = {0, 0};
    for (const Triangle& t : mesh.triangles) {
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const Vec3 n = cross(b - a, c - a) * 0.5;
        const double A = norm(n), along = std::abs(dot(n, axis));
        projected += along;
        if (!(A > 0) || along < 0.5 * A) continue;
        const double h = dot((a + b + c) / 3.0 - m.centroid, axis);
        const int s = h >= 0 ? 0 : 1;
        area[s] += A, sum[s] += A * h, sum2[s] += A * h * h;
    }
    const double facing = dot(m.vectorArea, axis);
    if (std::abs(facing) > 0.5 * projected) {
        rule = "the scan's side";
        return facing > 0 ? axis : -axis;
    }
    const auto variance = [&](int s) {
        return area[s] > 0 ? sum2[s] / area[s] - (sum[s] / area[s]) * (sum[s] / area[s]) : 0.0;
    };
    const double plus = variance(0), minus = variance(1);
    if (std::abs(plus - minus) > kUndecided * std::max(plus, minus)) {
        rule = "the flatter side";
        return plus < minus ? axis : -axis;
    }
    const double skew = thirdMoment(mesh, m, axis);
    if (std::abs(skew) > kUndecided) {
        rule = "third moment";
        return skew < 0 ? axis : -axis;  // the bulge (the tail) goes to the reverse
    }
    rule = "sign convention";
    return canonicalSign(axis);
}

/// The sign of the up axis @p axis: towards the third moment's tail, else the
/// convention.
Vec3 upSide(const TriMesh& mesh, const SurfaceMoments& m, const Vec3& axis, std::string& rule)
{
    const double skew = thirdMoment(mesh, m, axis);
    if (std::abs(skew) > kUndecided) {
        rule = "third moment";
        return skew > 0 ? axis : -axis;
    }
    rule = "sign convention";
    return canonicalSign(axis);
}

}  // namespace

SheetOrientation orientSheet(const TriMesh& mesh, const SheetOrientationOptions& options)
{
    const std::optional<Vec3> front =
        options.front ? std::optional(checkedDirection(*options.front, "front")) : std::nullopt;
    const std::optional<Vec3> up = options.up ? std::optional(checkedDirection(*options.up, "up")) : std::nullopt;
    const SurfaceMoments m = surfaceMoments(mesh, !(front && up));
    if (!(m.area > 0)) throw InvalidInputError("the mesh has no area: nothing to lay out");
    SheetOrientation o;
    o.centre = m.centroid;
    o.closed = norm(m.vectorArea) <= 0.01 * m.area;
    if (front && up) {
        o.front = *front;
        o.up = across(*up, *front);
        if (!(norm(o.up) > 0))
            throw InvalidInputError("the front and up directions are parallel: up needs a part across the front");
        o.frontRule = o.upRule = "given";
        return o;
    }
    const PrincipalAxes p = principalAxes(m.covariance);
    if (front) {
        o.front = *front;
        o.frontRule = "given";
        o.up = upSide(mesh, m, firstAcross({p.axes[2], p.axes[1]}, o.front), o.upRule);
        return o;
    }
    if (up) {
        o.up = *up;
        o.upRule = "given";
        o.front = frontSide(mesh, m, firstAcross({p.axes[0], p.axes[1]}, o.up), o.frontRule);
        return o;
    }
    o.front = frontSide(mesh, m, normalized(p.axes[0]), o.frontRule);
    o.up = upSide(mesh, m, across(p.axes[2], o.front), o.upRule);
    return o;
}

}  // namespace msii
