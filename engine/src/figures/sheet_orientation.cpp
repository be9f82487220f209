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

/// What decides the signs, in one pass over the triangles: along the front axis, per side
/// (by the triangle's centroid) the surface facing along it (within 60°) with its area and the
/// first and second moments of its height, and the projected area; along each axis, the
/// second and third central moments of the surface (triangle centroids, area-weighted).
struct SignMeasures {
    double projected = 0, area[2] = {0, 0}, sum[2] = {0, 0}, sum2[2] = {0, 0};
    double m2[2] = {0, 0}, m3[2] = {0, 0};  ///< along the front axis [0] and the up axis [1]

    /// The third moment along axis @p k relative to area · σ³: positive where the surface
    /// has its longer tail of area.
    double skew(int k, double totalArea) const
    {
        const double sigma = std::sqrt(m2[k] / totalArea);
        return sigma > 0 ? m3[k] / (totalArea * sigma * sigma * sigma) : 0.0;
    }
};

SignMeasures signMeasures(const TriMesh& mesh, const SurfaceMoments& m, const Vec3& frontAxis, const Vec3& upAxis)
{
    SignMeasures s;
    for (const Triangle& t : mesh.triangles) {
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const Vec3 n = cross(b - a, c - a) * 0.5, centre = (a + b + c) / 3.0 - m.centroid;
        const double A = norm(n), along = std::abs(dot(n, frontAxis));
        const double h[2] = {dot(centre, frontAxis), dot(centre, upAxis)};
        for (int k = 0; k < 2; ++k) s.m2[k] += A * h[k] * h[k], s.m3[k] += A * h[k] * h[k] * h[k];
        s.projected += along;
        if (!(A > 0) || along < 0.5 * A) continue;
        const int side = h[0] >= 0 ? 0 : 1;
        s.area[side] += A, s.sum[side] += A * h[0], s.sum2[side] += A * h[0] * h[0];
    }
    return s;
}

/// The sign of the front axis @p axis: the side an open scan faces, else the flatter of the
/// two large sides (its height varies less), else the third moment's tail (the bulge goes
/// to the reverse), else the sign convention.
Vec3 frontSide(const SignMeasures& s, const SurfaceMoments& m, const Vec3& axis, std::string& rule)
{
    const double facing = dot(m.vectorArea, axis);
    if (std::abs(facing) > 0.5 * s.projected) {
        rule = "the scan's side";
        return facing > 0 ? axis : -axis;
    }
    const auto variance = [&](int k) {
        return s.area[k] > 0 ? s.sum2[k] / s.area[k] - (s.sum[k] / s.area[k]) * (s.sum[k] / s.area[k]) : 0.0;
    };
    const double plus = variance(0), minus = variance(1);
    if (std::abs(plus - minus) > kUndecided * std::max(plus, minus)) {
        rule = "the flatter side";
        return plus < minus ? axis : -axis;
    }
    const double skew = s.skew(0, m.area);
    if (std::abs(skew) > kUndecided) {
        rule = "third moment";
        return skew < 0 ? axis : -axis;
    }
    rule = "sign convention";
    return canonicalSign(axis);
}

/// The sign of the up axis @p axis: towards the third moment's tail, else the convention.
Vec3 upSide(const SignMeasures& s, const SurfaceMoments& m, const Vec3& axis, std::string& rule)
{
    const double skew = s.skew(1, m.area);
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
    // The two axes' lines first (a given direction, or the principal axis across it), then
    // their signs from one pass over the surface.
    const PrincipalAxes p = principalAxes(m.covariance);
    const Vec3 frontAxis = front ? *front : up ? firstAcross({p.axes[0], p.axes[1]}, *up) : normalized(p.axes[0]);
    const Vec3 upAxis = up ? across(*up, frontAxis) : firstAcross({p.axes[2], p.axes[1]}, frontAxis);
    const SignMeasures s = signMeasures(mesh, m, frontAxis, upAxis);
    if (front)
        o.front = *front, o.frontRule = "given";
    else
        o.front = frontSide(s, m, frontAxis, o.frontRule);
    if (up)
        o.up = *up, o.upRule = "given";
    else
        o.up = upSide(s, m, upAxis, o.upRule);
    return o;
}

}  // namespace msii
