#pragma once
/// @file map_frame.h
/// @brief The orthographic frame of a feature map or picture: a plane (origin, right axis u,
/// up axis v, normal w towards the viewer) and a pixel grid on it. The plane is the mesh's
/// least-squares plane or a view the user names.
///
/// Map coordinates of a point p: (u, v, height) = ((p − origin)·u, (p − origin)·v,
/// (p − origin)·w). Pixel (x, y), row 0 at the top, has its centre at
/// u = minU + (x + ½)·pixelSize, v = maxV − (y + ½)·pixelSize.

#include <msii/mesh/trimesh.h>

#include <string>

namespace msii {

enum class MapView {
    BestFit,    ///< least-squares plane of the surface (area-weighted); u along its longest extent (along x, else y, when the two in-plane extents are within 10 %)
    PlusX, MinusX, PlusY, MinusY, PlusZ, MinusZ,  ///< seen from that side, e.g. +z: looking down −z, u = +x, v = +y
    Direction,  ///< seen from `direction` (a vector from the object towards the viewer)
};

struct MapFrameOptions {
    MapView view = MapView::BestFit;
    Vec3 direction{0, 0, 1};  ///< for MapView::Direction; any length > 0
    bool flip = false;        ///< BestFit: look at the other side of the plane
    /// Resolution, one of: the longer side in pixels, or the pixel size in mesh units, or
    /// dots per inch for meshes in millimetres (pixel size 25.4 / dpi).
    int longerSidePixels = 0;
    double pixelSize = 0;
    double dpi = 0;
    /// Largest allowed side in pixels (the pixel buffers cost 16 bytes per pixel).
    int maxSidePixels = 16384;
    /// The surface's extent grown by this on every side (mesh units): half a cell for a
    /// raster's mesh, whose vertices are the cells' centres, so that W × H cells give W × H
    /// pixels, one per cell.
    double margin = 0;
};

struct MapFrame {
    MapView view = MapView::BestFit;
    Vec3 origin;                  ///< the plane's origin: the surface's area-weighted centroid (every view)
    Vec3 axisU, axisV, normal;    ///< orthonormal, right-handed (axisU × axisV = normal)
    double pixelSize = 0;         ///< mesh units per pixel
    int width = 0, height = 0;    ///< pixels
    double minU = 0, maxV = 0;    ///< map coordinates of the image's top-left corner

    Vec3 toMap(const Vec3& p) const;          ///< (u, v, height)
    double pixelX(double u) const { return (u - minU) / pixelSize; }  ///< continuous, pixel centres at +½
    double pixelY(double v) const { return (maxV - v) / pixelSize; }
};

/// "best", "+x", "-x", "+y", "-y", "+z", "-z", or "X,Y,Z" (a direction towards the viewer).
/// @throw InvalidInputError for anything else or a zero-length direction.
void parseMapView(const std::string& text, MapFrameOptions& options);
std::string mapViewName(const MapFrame& frame);

/// The frame of @p mesh for the given view and resolution: the projected mesh fits the image
/// exactly (no margin).
/// @throw InvalidInputError for an empty mesh, a resolution that is not given exactly once or
/// is not positive, an image side beyond maxSidePixels, or an empty projection (the mesh seen
/// edge-on: projected area below 1e-9 of its area).
MapFrame makeMapFrame(const TriMesh& mesh, const MapFrameOptions& options);

} // namespace msii
