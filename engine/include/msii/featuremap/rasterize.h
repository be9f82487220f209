#pragma once
/// @file rasterize.h
/// @brief Which triangle each pixel of a map frame sees (the nearest surface towards the
/// viewer) and where: triangle index and barycentric coordinates, so that any per-vertex value
/// can be interpolated at each pixel.

#include <msii/core/run_context.h>
#include <msii/featuremap/map_frame.h>
#include <msii/mesh/vertex_normals.h>
#include <msii/mesh/trimesh.h>

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace msii {

struct PixelHits {
    static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    int width = 0, height = 0;
    std::vector<std::uint32_t> triangle;  ///< per pixel (row-major, row 0 at the top); kNone = background
    std::vector<float> b1, b2;            ///< barycentric weights of the triangle's 2nd and 3rd vertex
    std::vector<float> depth;             ///< height over the plane (towards the viewer), NaN = background
    std::size_t covered = 0;              ///< pixels that see the mesh

    std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
    /// The value of a per-vertex field at pixel @p k (NaN for background or NaN vertices).
    float interpolate(const TriMesh& mesh, const std::vector<float>& perVertex, std::size_t k) const
    {
        const std::uint32_t t = triangle[k];
        if (t == kNone) return std::numeric_limits<float>::quiet_NaN();
        const Triangle& tri = mesh.triangles[t];
        return (1.0f - b1[k] - b2[k]) * perVertex[tri[0]] + b1[k] * perVertex[tri[1]] + b2[k] * perVertex[tri[2]];
    }
};

/// Which triangles a picture draws, by their orientation (the order of their corners).
enum class RasterFaces {
    Both,     ///< all: open scans seen from behind still show
    Towards,  ///< those whose normal points towards the viewer (a closed surface facing outward hides the others)
    Away,     ///< those whose normal points away (a closed surface facing inward)
};

/// Rasterises the triangles of @p mesh into @p frame: a pixel belongs to the triangles whose
/// closed projection contains its centre, and shows the one with the largest height (towards
/// the viewer; ties go to the lower triangle index). @p faces chooses the triangles by their
/// orientation (all by default). Parallel over bands of rows; the result does not depend on
/// the thread count.
PixelHits rasterize(const TriMesh& mesh, const MapFrame& frame, RunContext* context = nullptr,
                    RasterFaces faces = RasterFaces::Both);

/// Unit vertex normals (mesh/vertex_normals.h) in the map frame: x along axisU, y along
/// axisV, z towards the viewer; zero for vertices without area.
std::array<std::vector<float>, 3> vertexNormalsInFrame(const TriMesh& mesh, const MapFrame& frame);

/// A per-vertex field at every pixel (PixelHits::interpolate; NaN for background).
std::vector<float> interpolateToPixels(const TriMesh& mesh, const PixelHits& hits, const std::vector<float>& perVertex);

/// 1 where the pixel sees the mesh, 0 elsewhere.
std::vector<float> coverageMask(const PixelHits& hits);

} // namespace msii
