#include <msii/vessels/profile_section.h>

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>
#include <msii/mesh/principal_axes.h>
#include <msii/outline/isolines.h>
#include <msii/render/annotate.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace msii {
namespace {

/// The isoline at 0 of the signed distance from the plane (point, normal), in the frame
/// (origin, xAxis, yAxis).
Section sectionInFrame(const TriMesh& mesh, const Vec3& point, const Vec3& normal, Section frame)
{
    std::vector<float> distance(mesh.numVertices());
    for (std::size_t i = 0; i < distance.size(); ++i) distance[i] = float(dot(mesh.points[i] - point, normal));
    const std::vector<Polyline> lines = computeIsolines(mesh, distance, {0.0});
    Section s = frame;
    s.xMin = s.yMin = 1e300, s.xMax = s.yMax = -1e300;
    for (const Polyline& l : lines) {
        SectionLine out;
        out.closed = l.closed;
        for (const Vec3& p : l.points) {
            const Vec3 d = p - s.origin;
            out.points.push_back({dot(d, s.xAxis), dot(d, s.yAxis)});
            s.xMin = std::min(s.xMin, out.points.back()[0]), s.xMax = std::max(s.xMax, out.points.back()[0]);
            s.yMin = std::min(s.yMin, out.points.back()[1]), s.yMax = std::max(s.yMax, out.points.back()[1]);
        }
        for (std::size_t k = 1; k < out.points.size() + (out.closed ? 1 : 0); ++k) {
            const auto& a = out.points[k - 1];
            const auto& b = out.points[k % out.points.size()];
            s.length += std::hypot(b[0] - a[0], b[1] - a[1]);
        }
        s.lines.push_back(std::move(out));
    }
    if (s.lines.empty()) throw InvalidInputError("the section's plane misses the mesh");
    return s;
}

}  // namespace

Section axisSection(const TriMesh& mesh, const AxisOfRotation& axis, const Vec3& through)
{
    const Vec3 a = normalized(axis.direction), d = through - axis.point;
    const Vec3 radial = d - a * dot(d, a);
    if (!(norm(radial) > 1e-9 * (1 + norm(d))))
        throw InvalidInputError("the point the profile's plane goes through lies on the axis");
    Section frame;
    frame.xAxis = normalized(radial);
    frame.yAxis = a;
    frame.normal = cross(frame.xAxis, frame.yAxis);
    double lowest = 1e300;  // y from the object's lowest point along the axis
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t) lowest = std::min(lowest, dot(mesh.points[i] - axis.point, a));
    frame.origin = axis.point + a * lowest;
    return sectionInFrame(mesh, axis.point, frame.normal, frame);
}

Vec3 defaultThrough(const TriMesh& mesh, const AxisOfRotation& axis)
{
    const SurfaceMoments m = surfaceMoments(mesh, false);
    const AxisFrame f(axis.point, axis.direction);
    if (f.radius(m.centroid) > 0.05 * std::max(axis.meanRadius, 1e-300)) return m.centroid;
    const Vec3 world[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    Vec3 best = world[0];
    for (const Vec3& w : world)
        if (std::abs(dot(w, f.direction)) < std::abs(dot(best, f.direction)) - 1e-12) best = w;
    return axis.point + best * std::max(axis.meanRadius, 1.0);
}

Section planeSection(const TriMesh& mesh, const Vec3& point, const Vec3& normal)
{
    if (!isFinite(normal) || !(norm(normal) > 0))
        throw InvalidInputError("the section's plane needs a normal of non-zero length");
    Section frame;
    frame.normal = normalized(normal);
    const Vec3 x = std::abs(frame.normal.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    frame.xAxis = normalized(x - frame.normal * dot(x, frame.normal));
    frame.yAxis = cross(frame.normal, frame.xAxis);
    frame.origin = point;
    Section s = sectionInFrame(mesh, point, frame.normal, frame);
    // From the section's lowest and leftmost point.
    for (SectionLine& l : s.lines)
        for (auto& p : l.points) p[0] -= s.xMin, p[1] -= s.yMin;
    s.origin = point + s.xAxis * s.xMin + s.yAxis * s.yMin;
    s.xMax -= s.xMin, s.yMax -= s.yMin, s.xMin = 0, s.yMin = 0;
    return s;
}

void writeProfileSvg(const std::string& path, const Section& s, const ProfileDrawingOptions& o)
{
    const double k = o.scale, margin = 12.0, labels = 14.0;  // mm on paper
    // The drawing's extent: the section, the axis, and the rim's dimension line across it (a
    // rim sherd's section lies on one side of the axis; its rim diameter spans both).
    const double reach = o.rimDiameter && o.axisX ? 0.5 * *o.rimDiameter : 0;
    const double x0 = std::min(s.xMin, o.axisX ? *o.axisX - reach : s.xMin);
    const double x1 = std::max(s.xMax, o.axisX ? *o.axisX + reach : s.xMax);
    const double width = std::max((x1 - x0) * k + 2 * margin, 80.0);
    const double height = (s.yMax - s.yMin) * k + 2 * margin + 2 * labels + (o.title.empty() ? 0 : 5);
    const auto X = [&](double x) { return margin + (x - x0) * k; };
    const auto Y = [&](double y) { return margin + labels + (s.yMax - y) * k; };  // y up on paper
    std::ostringstream svg;
    svg.precision(6);
    svg << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width
        << "mm\" height=\"" << height << "mm\" viewBox=\"0 0 " << width << " " << height << "\">\n"
        << "<g fill=\"none\" stroke=\"black\" stroke-width=\"0.25\" stroke-linejoin=\"round\">\n";
    for (const SectionLine& l : s.lines) {
        svg << "<path" << (l.closed ? " fill=\"#222\"" : "") << " d=\"";
        for (std::size_t i = 0; i < l.points.size(); ++i)
            svg << (i ? " L" : "M") << X(l.points[i][0]) << "," << Y(l.points[i][1]);
        svg << (l.closed ? " Z" : "") << "\"/>\n";
    }
    svg << "</g>\n";
    if (o.axisX)  // dash-dot, past the drawing a little at both ends
        svg << "<line class=\"axis\" x1=\"" << X(*o.axisX) << "\" y1=\"" << Y(s.yMax) - 6 << "\" x2=\"" << X(*o.axisX)
            << "\" y2=\"" << Y(s.yMin) + 6
            << "\" stroke=\"black\" stroke-width=\"0.2\" stroke-dasharray=\"6 1.5 1 1.5\"/>\n";
    char text[96];
    if (o.rimDiameter && o.axisX) {  // the dimension line at the top
        const double r = 0.5 * *o.rimDiameter, y = Y(s.yMax) - 4;
        std::snprintf(text, sizeof text, "&#216; %.1f %s", *o.rimDiameter, o.units.c_str());
        svg << "<g class=\"rim\" stroke=\"black\" stroke-width=\"0.2\"><line x1=\"" << X(*o.axisX - r) << "\" y1=\""
            << y << "\" x2=\"" << X(*o.axisX + r) << "\" y2=\"" << y << "\"/><line x1=\"" << X(*o.axisX - r)
            << "\" y1=\"" << y - 1.5 << "\" x2=\"" << X(*o.axisX - r) << "\" y2=\"" << y + 1.5 << "\"/><line x1=\""
            << X(*o.axisX + r) << "\" y1=\"" << y - 1.5 << "\" x2=\"" << X(*o.axisX + r) << "\" y2=\"" << y + 1.5
            << "\"/></g>\n"
            << "<text x=\"" << X(*o.axisX) << "\" y=\"" << y - 2 << "\" font-family=\"DejaVu Sans, sans-serif\" "
            << "font-size=\"3.5\" text-anchor=\"middle\">" << text << "</text>\n";
    }
    // The scale bar: a nice length near a fifth of the drawing, and the scale.
    const double bar = scaleBarLength(1000, std::max({x1 - x0, s.yMax - s.yMin, 1e-12}) / 1000);
    const double yb = height - margin;
    std::snprintf(text, sizeof text, "%g %s; scale 1:%g", bar, o.units.c_str(), 1.0 / k);
    svg << "<g class=\"scale\"><rect x=\"" << margin << "\" y=\"" << yb - 1 << "\" width=\"" << bar * k
        << "\" height=\"1\" fill=\"black\"/><text x=\"" << margin << "\" y=\"" << yb + 4.5
        << "\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"3.5\">" << text << "</text></g>\n";
    if (!o.title.empty()) {
        std::string title;
        for (char c : o.title) title += c == '&' ? "&amp;" : c == '<' ? "&lt;" : c == '>' ? "&gt;" : std::string(1, c);
        svg << "<text x=\"" << margin << "\" y=\"" << yb + 9.5 << "\" font-family=\"DejaVu Sans, sans-serif\" "
            << "font-size=\"3\">" << title << "</text>\n";
    }
    svg << "</svg>\n";
    writeTextFileAtomic(path, svg.str());
}

}  // namespace msii
