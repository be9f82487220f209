#include <msii/vessels/unroll.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace msii {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// How a point goes to the plane: its angle from the seam in [0, 2π) and where that puts it.
struct Development {
    AxisFrame frame;
    UnrollShape shape;
    double radius = 0;  // cylinder
    double apex = 0, sinA = 0, cosA = 1, up = 1;  // cone: apex height, half-angle, +1 if it opens along the axis
    double seam = 0;

    double turn(const Vec3& p) const
    {
        double t = frame.angle(p) - seam;
        while (t < 0) t += 2 * kPi;
        while (t >= 2 * kPi) t -= 2 * kPi;
        return t;
    }
    /// The point at angle @p t (from the seam) in the plane, with its relief.
    Vec3 place(const Vec3& p, double t) const
    {
        const double h = frame.height(p), r = frame.radius(p);
        if (shape == UnrollShape::Cylinder) return {radius * t, h, r - radius};
        // Along the generatrix from the apex (s) and off the cone (z, outward), in the (r, h) plane.
        const double dh = (h - apex) * up;
        const double s = r * sinA + dh * cosA, z = r * cosA - dh * sinA;
        const double psi = t * sinA - kPi * sinA;  // the development, centred on the seam's opposite
        return {s * std::sin(psi), up * s * std::cos(psi), z};  // y grows with the height
    }
};

/// The default seam: the middle of the widest span of angles around the axis where the
/// surface has no vertex, if it spans at least 5° (a sherd, a partial scan: the seam then cuts
/// nothing); else angle 0 (AxisFrame::e1). @p angle: each vertex's, NaN for those in no
/// triangle or on the axis.
double openSide(const std::vector<double>& angle)
{
    constexpr int kBins = 3600;  // a tenth of a degree
    std::vector<char> filled(kBins, 0);
    for (const double a : angle)
        if (std::isfinite(a)) filled[std::size_t(std::clamp(int((a + kPi) / (2 * kPi) * kBins), 0, kBins - 1))] = 1;
    int bestStart = 0, bestLength = 0;
    for (int start = 0; start < kBins; ++start) {  // runs of empty bins, round the circle
        if (filled[std::size_t(start)] || !filled[std::size_t((start + kBins - 1) % kBins)]) continue;
        int length = 0;
        while (length < kBins && !filled[std::size_t((start + length) % kBins)]) ++length;
        if (length > bestLength) bestStart = start, bestLength = length;
    }
    if (bestLength < kBins / 72) return 0;
    return (bestStart + 0.5 * bestLength) / kBins * 2 * kPi - kPi;
}

/// Each vertex's angle about the axis (AxisFrame::angle); NaN for vertices in no triangle
/// or on the axis.
std::vector<double> anglesOf(const TriMesh& mesh, const AxisFrame& frame)
{
    std::vector<char> used(mesh.numVertices(), 0);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t) used[i] = 1;
    std::vector<double> angle(mesh.numVertices());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, angle.size()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
            angle[i] = used[i] && frame.radius(mesh.points[i]) > 0 ? frame.angle(mesh.points[i]) : std::nan("");
    });
    return angle;
}

Development developmentOf(const TriMesh& mesh, const AxisOfRotation& axis, const UnrollOptions& o)
{
    Development d{AxisFrame(axis.point, axis.direction), o.shape};
    if (o.shape == UnrollShape::Cylinder) {
        d.radius = axis.cylinderRadius;
    } else {
        if (!(std::abs(axis.coneSlope) > 1e-6))
            throw InvalidInputError(
                "the surface has no slope along its axis to unroll as a cone: unroll it as a cylinder");
        d.apex = -axis.coneRadius0 / axis.coneSlope;
        const double alpha = std::atan(std::abs(axis.coneSlope));
        d.sinA = std::sin(alpha), d.cosA = std::cos(alpha), d.up = axis.coneSlope > 0 ? 1 : -1;
    }
    if (o.cutThrough) {
        if (!(d.frame.radius(*o.cutThrough) > 0)) throw InvalidInputError("the seam's point lies on the axis");
        d.seam = d.frame.angle(*o.cutThrough);
    } else {
        d.seam = openSide(anglesOf(mesh, d.frame));
    }
    return d;
}

/// Of the edges near the fitted surface (both ends within 1 % of the radius of it, where the relief's own depth stretches lengths along the circle by at most 1 %), the
/// largest and the 99th percentile of |unrolled length / length − 1|.
void measureDistortion(const TriMesh& in, const TriMesh& out, double radius, Unrolled& u)
{
    std::vector<double> ratios;
    for (const Triangle& t : out.triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t i = t[std::size_t(k)], j = t[std::size_t((k + 1) % 3)];
            if (i > j) continue;  // each inner edge once (its other triangle has it the other way)
            const Vec3 &a = out.points[i], &b = out.points[j];
            if (std::abs(a.z) > 0.01 * radius || std::abs(b.z) > 0.01 * radius) continue;
            const std::uint32_t ia = i < in.numVertices() ? i : u.copyOf[i - in.numVertices()];
            const std::uint32_t ib = j < in.numVertices() ? j : u.copyOf[j - in.numVertices()];
            const double length = norm(in.points[ia] - in.points[ib]);
            if (length > 0) ratios.push_back(std::abs(norm(a - b) / length - 1));
        }
    u.edgesMeasured = ratios.size();
    if (ratios.empty()) return;
    u.maxDistortion = *std::max_element(ratios.begin(), ratios.end());
    const std::size_t k = std::min(ratios.size() - 1, std::size_t(0.99 * double(ratios.size())));
    std::nth_element(ratios.begin(), ratios.begin() + std::ptrdiff_t(k), ratios.end());
    u.distortion99 = ratios[k];
}

}  // namespace

Unrolled unrollSurface(const TriMesh& mesh, const AxisOfRotation& axis, const UnrollOptions& o)
{
    const Development d = developmentOf(mesh, axis, o);
    Unrolled u;
    u.shape = o.shape, u.radius = d.radius, u.seamAngle = d.seam;
    u.apexHeight = d.apex, u.halfAngle = std::asin(d.sinA);
    const double mid = 0.5 * axis.height,
                 seamR = o.shape == UnrollShape::Cylinder ? d.radius : axis.coneRadius0 + axis.coneSlope * mid;
    u.seamPoint = d.frame.point + d.frame.direction * mid +
                  (d.frame.e1 * std::cos(d.seam) + d.frame.e2 * std::sin(d.seam)) * seamR;
    const std::size_t n = mesh.numVertices();
    std::vector<double> turn(n);
    u.mesh.points.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            turn[i] = d.turn(mesh.points[i]);
            u.mesh.points[i] = d.place(mesh.points[i], turn[i]);
        }
    });
    // A triangle across the seam (its angles spanning more than half a turn) takes copies of
    // its corners near the seam's start, placed a full turn on. Triangles still spanning more
    // than an eighth of a turn lie at the axis (a base, a lid): they have no place in a
    // rollout and are left out (their vertices stay, in no triangle).
    std::vector<std::uint32_t> copy(n, UINT32_MAX);
    u.mesh.triangles.reserve(mesh.numTriangles());
    for (Triangle t : mesh.triangles) {
        double a[3] = {turn[t[0]], turn[t[1]], turn[t[2]]};
        const bool seam = std::max({a[0], a[1], a[2]}) - std::min({a[0], a[1], a[2]}) > kPi;
        for (int k = 0; k < 3 && seam; ++k)
            if (a[k] < kPi) a[k] += 2 * kPi;
        if (std::max({a[0], a[1], a[2]}) - std::min({a[0], a[1], a[2]}) > 0.25 * kPi) {
            ++u.trianglesLeftOut;
            continue;
        }
        for (int k = 0; k < 3 && seam; ++k) {
            std::uint32_t& i = t[std::size_t(k)];
            if (turn[i] >= kPi) continue;
            if (copy[i] == UINT32_MAX) {
                copy[i] = std::uint32_t(u.mesh.points.size());
                u.mesh.points.push_back(d.place(mesh.points[i], turn[i] + 2 * kPi));
                u.copyOf.push_back(i);
            }
            i = copy[i];
        }
        u.mesh.triangles.push_back(t);
    }
    if (u.mesh.triangles.empty())
        throw InvalidInputError("nothing to unroll: every triangle spans more than an eighth of a turn about the axis "
                                "(a surface at the axis, or one of fewer than eight sides)");
    if (o.impression)
        for (Vec3& p : u.mesh.points) p.x = -p.x, p.z = -p.z;
    if (o.impression)  // mirrored: the triangles turn the other way
        for (Triangle& t : u.mesh.triangles) std::swap(t[1], t[2]);
    measureDistortion(mesh, u.mesh, o.shape == UnrollShape::Cylinder ? d.radius : std::max(axis.meanRadius, 1e-300), u);
    return u;
}

}  // namespace msii
