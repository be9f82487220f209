#include <msii/featuremap/map_frame.h>

#include <msii/core/errors.h>
#include <msii/mesh/principal_axes.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

namespace msii {
namespace {

void axesOfView(MapView view, const Vec3& direction, Vec3& u, Vec3& v, Vec3& w)
{
    switch (view) {
    case MapView::PlusZ: u = {1, 0, 0}, v = {0, 1, 0}; break;
    case MapView::MinusZ: u = {-1, 0, 0}, v = {0, 1, 0}; break;
    case MapView::PlusX: u = {0, 1, 0}, v = {0, 0, 1}; break;
    case MapView::MinusX: u = {0, -1, 0}, v = {0, 0, 1}; break;
    case MapView::PlusY: u = {-1, 0, 0}, v = {0, 0, 1}; break;
    case MapView::MinusY: u = {1, 0, 0}, v = {0, 0, 1}; break;
    case MapView::Direction: {
        w = normalized(direction);
        // Up on the picture: +z projected into the plane, or +y when looking along z.
        const Vec3 up = std::abs(w.z) < 0.99 ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
        v = normalized(up - w * dot(up, w));
        u = cross(v, w);
        return;
    }
    case MapView::BestFit: break;
    }
    w = cross(u, v);
}

} // namespace

Vec3 MapFrame::toMap(const Vec3& p) const
{
    const Vec3 d = p - origin;
    return {dot(d, axisU), dot(d, axisV), dot(d, normal)};
}

void parseMapView(const std::string& text, MapFrameOptions& options)
{
    static const std::pair<const char*, MapView> names[] = {
        {"best", MapView::BestFit}, {"+x", MapView::PlusX}, {"-x", MapView::MinusX},
        {"+y", MapView::PlusY},     {"-y", MapView::MinusY}, {"+z", MapView::PlusZ},
        {"-z", MapView::MinusZ}};
    for (const auto& [name, view] : names)
        if (text == name) {
            options.view = view;
            return;
        }
    std::stringstream in(text);
    double c[3];
    char comma1 = 0, comma2 = 0;
    if ((in >> c[0] >> comma1 >> c[1] >> comma2 >> c[2]) && comma1 == ',' && comma2 == ',' && (in >> std::ws).eof()) {
        const Vec3 d(c[0], c[1], c[2]);
        if (!isFinite(d) || !(norm(d) > 0))
            throw InvalidInputError("the view direction '" + text + "' has zero length or is not finite");
        options.view = MapView::Direction;
        options.direction = d;
        return;
    }
    throw InvalidInputError("unknown view '" + text + "' (use best, +x, -x, +y, -y, +z, -z or a direction X,Y,Z)");
}

std::string mapViewName(const MapFrame& frame)
{
    switch (frame.view) {
    case MapView::BestFit: return "best-fit plane";
    case MapView::PlusX: return "+x";
    case MapView::MinusX: return "-x";
    case MapView::PlusY: return "+y";
    case MapView::MinusY: return "-y";
    case MapView::PlusZ: return "+z";
    case MapView::MinusZ: return "-z";
    case MapView::Direction: break;
    }
    std::ostringstream s;
    s.precision(6);
    s << "direction " << frame.normal.x << "," << frame.normal.y << "," << frame.normal.z;
    return s.str();
}

MapFrame makeMapFrame(const TriMesh& mesh, const MapFrameOptions& options)
{
    if (mesh.empty()) throw InvalidInputError("the mesh is empty: nothing to project");
    const int given = (options.longerSidePixels != 0) + (options.pixelSize != 0) + (options.dpi != 0);
    if (given != 1)
        throw InvalidInputError("give the resolution exactly once: as pixels, as a pixel size or as DPI");
    if (options.longerSidePixels < 0 || options.pixelSize < 0 || options.dpi < 0 ||
        !std::isfinite(options.pixelSize) || !std::isfinite(options.dpi))
        throw InvalidInputError("the resolution must be positive");
    if (options.view == MapView::Direction && (!isFinite(options.direction) || !(norm(options.direction) > 0)))
        throw InvalidInputError("the view direction has zero length or is not finite");

    // Area, centroid and covariance of the surface; the vector area for the side the
    // surface faces.
    const SurfaceMoments moments = surfaceMoments(mesh);
    const double area = moments.area;
    if (!(area > 0)) throw InvalidInputError("the mesh has no area: nothing to project");

    MapFrame frame;
    frame.view = options.view;
    frame.origin = moments.centroid;
    if (options.view == MapView::BestFit) {
        const PrincipalAxes principal = principalAxes(moments.covariance);
        const std::array<double, 3>& values = principal.variances;
        const std::array<Vec3, 3>& vectors = principal.axes;
        const Vec3& vectorArea = moments.vectorArea;
        Vec3 w = normalized(vectors[0]);
        // Face the side the surface faces: its vector area, when that is most of the
        // projected area (open scans); closed meshes (vector area about 0, also with a small
        // hole) take the deterministic sign of canonicalSign.
        double projectedArea = 0;
        for (const Triangle& t : mesh.triangles) {
            const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
            projectedArea += 0.5 * std::abs(dot(cross(b - a, c - a), w));
        }
        if (std::abs(dot(vectorArea, w)) > 0.5 * projectedArea) {
            if (dot(vectorArea, w) < 0) w = -w;
        } else {
            w = canonicalSign(w);
        }
        if (options.flip) w = -w;
        // u along the longest extent; when the two in-plane extents are about equal (square
        // or round objects) that direction is noise, so take the world axis closest to the
        // plane instead (x, else y), for a stable picture.
        Vec3 longest = vectors[2];
        if (values[2] < 1.1 * values[1]) {
            longest = std::abs(w.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
        }
        Vec3 u = normalized(longest - w * dot(longest, w));
        if (values[2] >= 1.1 * values[1]) u = canonicalSign(u);
        frame.normal = w;
        frame.axisU = u;
        frame.axisV = cross(w, u);
    } else {
        // The origin stays at the centroid, so that heights are small numbers (floats)
        // even for meshes far from the world origin.
        axesOfView(options.view, options.direction, frame.axisU, frame.axisV, frame.normal);
    }

    // Projected area (empty when seen edge-on) and extent.
    double projected = 0;
    for (const Triangle& t : mesh.triangles) {
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        projected += std::abs(dot(cross(b - a, c - a), frame.normal)) * 0.5;
    }
    if (!(projected > 1e-9 * area))
        throw InvalidInputError("the projection is empty: the mesh is seen edge-on from this view");
    double minU = std::numeric_limits<double>::max(), maxU = -minU, minV = minU, maxV = -minU;
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t) {
            const Vec3 m = frame.toMap(mesh.points[i]);
            minU = std::min(minU, m.x), maxU = std::max(maxU, m.x);
            minV = std::min(minV, m.y), maxV = std::max(maxV, m.y);
        }
    minU -= options.margin, maxU += options.margin, minV -= options.margin, maxV += options.margin;
    const double extent = std::max(maxU - minU, maxV - minV);
    if (options.longerSidePixels > 0) frame.pixelSize = extent / options.longerSidePixels;
    else if (options.pixelSize > 0) frame.pixelSize = options.pixelSize;
    else frame.pixelSize = 25.4 / options.dpi;
    if (!(frame.pixelSize > 0)) throw InvalidInputError("the projection is empty: the mesh has no extent");
    const double w = std::ceil((maxU - minU) / frame.pixelSize - 1e-9);
    const double h = std::ceil((maxV - minV) / frame.pixelSize - 1e-9);
    if (w > options.maxSidePixels || h > options.maxSidePixels) {
        std::ostringstream s;
        s << "the image would be " << w << " x " << h << " pixels; the largest allowed side is "
          << options.maxSidePixels << " (choose a larger pixel size or fewer pixels)";
        throw InvalidInputError(s.str());
    }
    frame.width = std::max(1, int(w));
    frame.height = std::max(1, int(h));
    // Centre the mesh in the image (it fits exactly along the longer side).
    frame.minU = 0.5 * (minU + maxU) - 0.5 * frame.width * frame.pixelSize;
    frame.maxV = 0.5 * (minV + maxV) + 0.5 * frame.height * frame.pixelSize;
    return frame;
}

} // namespace msii
