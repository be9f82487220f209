#pragma once
// The rasterizer's parts (featuremap/rasterize.h), for rasterize() and for the six views of a
// figure sheet (figures/sheet_raster.cpp), which lists the triangles of all its views in one
// pass over the mesh: the rows of pixels in bands, the triangles that may cover a pixel centre
// in each band, and the drawing of a band's triangles.
#include <msii/core/run_context.h>
#include <msii/featuremap/rasterize.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace msii::raster {

constexpr int kBandRows = 16;

struct Projected {
    double x, y, h;  // continuous pixel coordinates and height
};

/// A triangle's bands (first and last; first > last: none).
using BandRange = std::array<std::uint16_t, 2>;
constexpr BandRange kNoBands{1, 0};

/// The bands whose rows hold pixel centres inside the box [xMin, xMax] × [yMin, yMax] (pixel
/// coordinates, centres at +½) of a picture @p width × @p height; none where the box holds no
/// pixel centre (most triangles of a mesh finer than the pixels) or is not finite.
inline BandRange bandsOfBox(double xMin, double xMax, double yMin, double yMax, int width, int height)
{
    if (!(xMin >= -1e9 && xMax <= 1e9 && yMin >= -1e9 && yMax <= 1e9)) return kNoBands;
    const int lo = std::max(0, int(std::ceil(yMin - 0.5))), hi = std::min(height - 1, int(std::floor(yMax - 0.5)));
    const int left = std::max(0, int(std::ceil(xMin - 0.5))), right = std::min(width - 1, int(std::floor(xMax - 0.5)));
    if (lo > hi || left > right) return kNoBands;
    return {std::uint16_t(lo / kBandRows), std::uint16_t(hi / kBandRows)};
}

/// As bandsOfBox, for a box found another way than from the projected corners (products
/// instead of quotients): a millionth of a pixel wider on each side, so that rounding never
/// leaves out a band the corners' box reaches (a band too many is harmless: drawBands clips
/// each triangle to its own box).
inline BandRange bandsOfWiderBox(double xMin, double xMax, double yMin, double yMax, int width, int height)
{
    constexpr double kSlack = 1e-6;
    return bandsOfBox(xMin - kSlack, xMax + kSlack, yMin - kSlack, yMax + kSlack, width, height);
}

/// Per band, the triangles that may cover one of its pixel centres, in index order (so that
/// ties in height go to the lower index).
struct Bands {
    std::vector<std::size_t> start;  ///< band b lists triangles[start[b] .. start[b + 1])
    std::vector<std::uint32_t> triangles;
};

/// The band lists of @p K pictures (@p numBands each) in one pass over the triangles:
/// @p rangesOf(t) gives triangle t's BandRange in each. Counted and filled in chunks of
/// triangles in parallel; each chunk fills its share of a band after the earlier chunks'
/// shares, so a band lists its triangles in index order.
template <std::size_t K, class RangesOf>
std::array<Bands, K> listBands(std::size_t numTriangles, const std::array<int, K>& numBands, const RangesOf& rangesOf)
{
    constexpr std::size_t kChunk = 1 << 15;
    const std::size_t numChunks = (numTriangles + kChunk - 1) / kChunk;
    std::vector<std::array<BandRange, K>> ranges(numTriangles);  // found once, for both passes
    std::array<std::vector<std::size_t>, K> counts;                // per picture: per chunk, per band
    for (std::size_t v = 0; v < K; ++v) counts[v].assign(numChunks * std::size_t(numBands[v]), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numChunks), [&](const auto& r) {
        for (std::size_t c = r.begin(); c < r.end(); ++c)
            for (std::size_t t = c * kChunk; t < std::min(numTriangles, (c + 1) * kChunk); ++t) {
                ranges[t] = rangesOf(t);
                for (std::size_t v = 0; v < K; ++v)
                    for (int b = ranges[t][v][0]; b <= ranges[t][v][1]; ++b)
                        ++counts[v][c * std::size_t(numBands[v]) + std::size_t(b)];
            }
    });
    std::array<Bands, K> lists;
    for (std::size_t v = 0; v < K; ++v) {
        const std::size_t bands = std::size_t(numBands[v]);
        lists[v].start.assign(bands + 1, 0);
        for (std::size_t b = 0; b < bands; ++b) {
            std::size_t at = lists[v].start[b];
            for (std::size_t c = 0; c < numChunks; ++c) {
                const std::size_t n = counts[v][c * bands + b];
                counts[v][c * bands + b] = at;  // now where chunk c starts in band b
                at += n;
            }
            lists[v].start[b + 1] = at;
        }
        lists[v].triangles.resize(lists[v].start.back());
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numChunks), [&](const auto& r) {
        for (std::size_t c = r.begin(); c < r.end(); ++c)
            for (std::size_t t = c * kChunk; t < std::min(numTriangles, (c + 1) * kChunk); ++t)
                for (std::size_t v = 0; v < K; ++v)
                    for (int b = ranges[t][v][0]; b <= ranges[t][v][1]; ++b)
                        lists[v].triangles[counts[v][c * std::size_t(numBands[v]) + std::size_t(b)]++] =
                            std::uint32_t(t);
    });
    return lists;
}

/// A picture's pixels, none of them seeing the mesh yet.
PixelHits emptyHits(int width, int height);

/// Draws the triangles of @p bands (projected to @p p) into @p hits, band by band in
/// parallel; counts the pixels that see the mesh.
void drawBands(const TriMesh& mesh, const std::vector<Projected>& p, const Bands& bands, PixelHits& hits,
               RunContext* progress);

/// Whether a triangle, turning as its projected corners a, b, c do (rows run down, so one
/// facing the viewer turns clockwise), is drawn for @p faces.
inline bool drawn(RasterFaces faces, double signedArea)
{
    return faces == RasterFaces::Both || (faces == RasterFaces::Towards ? signedArea < 0 : signedArea > 0);
}

} // namespace msii::raster
