/// @file shading.cpp
/// @brief Lambert shading of a normal map, plain or of the normals' local deviations.
///
/// High contrast: the box mean of the usable (masked-in, finite) normals over (2r+1)²
/// pixels, clipped to the image, is computed separably with running sums, so the cost is
/// O(pixels) whatever the radius. The rows are cut into fixed blocks (their size depends on
/// the radius only); a task sums the windows along x for its block's rows plus r rows above
/// and below into a scratch buffer, then runs the column sums down the block and shades.
/// Every output value is thus computed by one fixed sequence of operations, and the result
/// does not depend on the number of threads. The 1st and 99th percentiles for the final
/// stretch are selected exactly by two histogram passes over the values' bit patterns
/// (radix selection), without copying or sorting the values.

#include <msii/render/shading.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace msii {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Rows per task for the per-pixel loops.
constexpr int kRowGrain = 16;

/// The unit vector towards the light, and the ambient term.
struct Light {
    float x, y, z;
    float ambient;
};

/// The azimuth is the direction the light travels in the picture plane (counter-clockwise
/// from +x, y up), so 315° comes from the top left and the vector towards the light is
/// (−cos az · cos el, −sin az · cos el, sin el).
Light lightFrom(const ShadingOptions& o)
{
    const double az = o.azimuthDeg * kPi / 180, el = o.elevationDeg * kPi / 180;
    return {float(-std::cos(el) * std::cos(az)), float(-std::cos(el) * std::sin(az)),
            float(std::sin(el)), float(o.ambient)};
}

/// Lambert brightness of the direction (x, y, z), normalised here; NaN if it has no length.
inline float lambert(float x, float y, float z, const Light& l)
{
    const float len2 = x * x + y * y + z * z;
    if (!(len2 > 0) || !(len2 < std::numeric_limits<float>::infinity())) return kNaN;
    const float d = (x * l.x + y * l.y + z * l.z) / std::sqrt(len2);
    return l.ambient + (1 - l.ambient) * std::max(0.0f, d);
}

inline bool usable(float m, float x, float y, float z)
{
    return m != 0 && std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
}

void checkInputs(int width, int height, const std::vector<float>& nx, const std::vector<float>& ny,
                 const std::vector<float>& nz, const std::vector<float>& mask,
                 const ShadingOptions& o)
{
    if (width < 0 || height < 0)
        throw InvalidInputError("shading: the image size cannot be negative (" +
                                std::to_string(width) + " x " + std::to_string(height) + ").");
    const std::size_t n = std::size_t(width) * std::size_t(height);
    if (nx.size() != n || ny.size() != n || nz.size() != n || mask.size() != n)
        throw InvalidInputError("shading: the normal and mask arrays must each hold " +
                                std::to_string(n) + " values for a " + std::to_string(width) +
                                " x " + std::to_string(height) + " image.");
    if (!std::isfinite(o.azimuthDeg))
        throw InvalidInputError("shading: the light azimuth must be a finite angle.");
    if (!(o.elevationDeg > 0 && o.elevationDeg <= 90))
        throw InvalidInputError("shading: the light elevation must be in (0, 90] degrees (got " +
                                std::to_string(o.elevationDeg) + ").");
    if (!(o.ambient >= 0 && o.ambient < 1))
        throw InvalidInputError("shading: the ambient brightness must be in [0, 1) (got " +
                                std::to_string(o.ambient) + ").");
    if (o.highContrast && o.contrastRadius < 1)
        throw InvalidInputError("shading: the contrast radius must be at least 1 pixel (got " +
                                std::to_string(o.contrastRadius) + ").");
}

void shadePlain(int width, int height, const std::vector<float>& nx, const std::vector<float>& ny,
                const std::vector<float>& nz, const std::vector<float>& mask, const Light& l,
                std::vector<float>& out)
{
    const std::size_t w = std::size_t(width);
    tbb::parallel_for(tbb::blocked_range<int>(0, height, kRowGrain), [&](const auto& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            const std::size_t row = std::size_t(y) * w;
            for (std::size_t i = row; i < row + w; ++i)
                out[i] = mask[i] != 0 ? lambert(nx[i], ny[i], nz[i], l) : kNaN;
        }
    });
}

/// Per-thread buffers of the high-contrast pass.
struct Scratch {
    std::vector<float> weighted;  ///< one row: x, y, z, 1 of usable normals, zeros otherwise
    std::vector<float> rowSums;   ///< the block's rows: window sums along x (x, y, z, count)
    std::vector<double> acc;      ///< window sums along x and y, per column (x, y, z, count)
};

void shadeDeviations(int width, int height, const std::vector<float>& nx,
                     const std::vector<float>& ny, const std::vector<float>& nz,
                     const std::vector<float>& mask, const Light& l, int radius,
                     std::vector<float>& out)
{
    const std::size_t w = std::size_t(width);
    const std::size_t len = 4 * w;
    const int blockRows = std::max(128, 4 * radius);
    const int blocks = (height + blockRows - 1) / blockRows;
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<int>(0, blocks, 1), [&](const auto& range) {
        Scratch& buf = scratch.local();
        for (int b = range.begin(); b < range.end(); ++b) {
            const int y0 = b * blockRows, y1 = std::min(height, y0 + blockRows);
            const int ya = std::max(0, y0 - radius), yb = std::min(height, y1 + radius);
            buf.weighted.resize(len);
            buf.rowSums.resize(len * std::size_t(yb - ya));
            buf.acc.assign(len, 0.0);

            // Window sums along x.
            float* const wt = buf.weighted.data();
            for (int y = ya; y < yb; ++y) {
                const std::size_t row = std::size_t(y) * w;
                for (std::size_t x = 0; x < w; ++x) {
                    const std::size_t i = row + x;
                    const bool ok = usable(mask[i], nx[i], ny[i], nz[i]);
                    wt[4 * x] = ok ? nx[i] : 0.0f;
                    wt[4 * x + 1] = ok ? ny[i] : 0.0f;
                    wt[4 * x + 2] = ok ? nz[i] : 0.0f;
                    wt[4 * x + 3] = ok ? 1.0f : 0.0f;
                }
                float* const o = buf.rowSums.data() + len * std::size_t(y - ya);
                double s[4] = {0, 0, 0, 0};
                for (int x = 0; x < std::min(radius, width); ++x)
                    for (int k = 0; k < 4; ++k) s[k] += wt[4 * x + k];
                for (int x = 0; x < width; ++x) {
                    if (x + radius < width)
                        for (int k = 0; k < 4; ++k) s[k] += wt[4 * (x + radius) + k];
                    if (x - radius - 1 >= 0)
                        for (int k = 0; k < 4; ++k) s[k] -= wt[4 * (x - radius - 1) + k];
                    for (int k = 0; k < 4; ++k) o[4 * x + k] = float(s[k]);
                }
            }

            // Window sums along y, then the shading of n − mean + (0, 0, 1).
            double* const acc = buf.acc.data();
            const auto rowAt = [&](int y) {
                return buf.rowSums.data() + len * std::size_t(y - ya);
            };
            for (int y = ya; y < std::min(y0 + radius, height); ++y) {
                const float* in = rowAt(y);
                for (std::size_t k = 0; k < len; ++k) acc[k] += in[k];
            }
            for (int y = y0; y < y1; ++y) {
                // The window moves down: row y + radius enters, row y − radius − 1 leaves.
                const float* entering = y + radius < height ? rowAt(y + radius) : nullptr;
                const float* leaving = y - radius - 1 >= ya ? rowAt(y - radius - 1) : nullptr;
                if (entering && leaving)
                    for (std::size_t k = 0; k < len; ++k)
                        acc[k] += double(entering[k]) - double(leaving[k]);
                else if (entering)
                    for (std::size_t k = 0; k < len; ++k) acc[k] += entering[k];
                else if (leaving)
                    for (std::size_t k = 0; k < len; ++k) acc[k] -= leaving[k];
                const std::size_t row = std::size_t(y) * w;
                for (std::size_t x = 0; x < w; ++x) {
                    const std::size_t i = row + x;
                    if (!usable(mask[i], nx[i], ny[i], nz[i])) {
                        out[i] = kNaN;
                        continue;
                    }
                    const double* a = acc + 4 * x;
                    const double inv = 1 / std::max(a[3], 1.0);
                    out[i] = lambert(float(nx[i] - a[0] * inv), float(ny[i] - a[1] * inv),
                                     float(nz[i] - a[2] * inv + 1.0), l);
                }
            }
        }
    });
}

inline std::uint32_t bitsOf(float v)
{
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return bits;
}

constexpr std::size_t kDigits = 1u << 16;  ///< values of one 16-bit half of a float's bits

/// How many non-NaN values (all >= 0, @p w per row) have each upper half of their bits.
std::vector<std::size_t> upperHistogram(const std::vector<float>& values, std::size_t w)
{
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> upper(
        [] { return std::vector<std::uint32_t>(kDigits, 0); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size() / w, 64),
                      [&](const auto& rows) {
                          std::vector<std::uint32_t>& h = upper.local();
                          for (std::size_t i = rows.begin() * w; i < rows.end() * w; ++i)
                              if (!std::isnan(values[i])) ++h[bitsOf(values[i]) >> 16];
                      });
    std::vector<std::size_t> countUpper(kDigits, 0);
    for (const auto& h : upper)
        for (std::size_t d = 0; d < kDigits; ++d) countUpper[d] += h[d];
    return countUpper;
}

/// The values at the given 0-based ranks (in ascending order) of the non-NaN entries of
/// @p values, all >= 0, found exactly by radix selection: for non-negative floats the bit
/// pattern orders like the value, so the histogram of the upper 16 bits (@p countUpper, from
/// upperHistogram) gives each rank's upper half, and a histogram of the lower 16 bits among
/// the values sharing it gives the rest. Counts are integers, so the result does not depend
/// on how the passes are split.
std::vector<float> valuesAtRanks(const std::vector<float>& values, std::size_t w,
                                 const std::vector<std::size_t>& countUpper,
                                 const std::vector<std::size_t>& ranks)
{
    const std::size_t height = values.size() / w;

    std::vector<std::uint32_t> tops;  // distinct upper halves of the ranks
    std::vector<std::size_t> topIndex, localRank;
    for (std::size_t r : ranks) {
        std::size_t below = 0, d = 0;
        while (below + countUpper[d] <= r) below += countUpper[d++];
        const auto it = std::find(tops.begin(), tops.end(), std::uint32_t(d));
        topIndex.push_back(std::size_t(it - tops.begin()));
        if (it == tops.end()) tops.push_back(std::uint32_t(d));
        localRank.push_back(r - below);
    }

    // Pass 2: the lower halves among the values with those upper halves.
    const std::size_t m = tops.size();
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> lower(
        [m] { return std::vector<std::uint32_t>(m * kDigits, 0); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, height, 64), [&](const auto& rows) {
        std::vector<std::uint32_t>& h = lower.local();
        for (std::size_t i = rows.begin() * w; i < rows.end() * w; ++i) {
            if (std::isnan(values[i])) continue;
            const std::uint32_t bits = bitsOf(values[i]);
            for (std::size_t j = 0; j < m; ++j)
                if (bits >> 16 == tops[j]) ++h[j * kDigits + (bits & 0xFFFF)];
        }
    });
    std::vector<std::size_t> countLower(m * kDigits, 0);
    for (const auto& h : lower)
        for (std::size_t k = 0; k < m * kDigits; ++k) countLower[k] += h[k];

    std::vector<float> result;
    for (std::size_t k = 0; k < ranks.size(); ++k) {
        const std::size_t* c = countLower.data() + topIndex[k] * kDigits;
        std::size_t below = 0, d = 0;
        while (below + c[d] <= localRank[k]) below += c[d++];
        const std::uint32_t bits = (tops[topIndex[k]] << 16) | std::uint32_t(d);
        float v;
        std::memcpy(&v, &bits, sizeof v);
        result.push_back(v);
    }
    return result;
}

/// Maps the 1st–99th percentile of the non-NaN values (all >= 0) to [0, 1], clamped;
/// percentile p is at rank p/100·(count − 1), linear between order statistics. Leaves the
/// values as they are if that range is empty.
void stretchPercentiles(std::vector<float>& out, std::size_t w)
{
    const std::vector<std::size_t> countUpper = upperHistogram(out, w);
    std::size_t count = 0;
    for (std::size_t c : countUpper) count += c;
    if (count == 0) return;
    const double r1 = 0.01 * double(count - 1), r99 = 0.99 * double(count - 1);
    const auto k1 = std::size_t(std::floor(r1)), k99 = std::size_t(std::floor(r99));
    const std::vector<float> v = valuesAtRanks(
        out, w, countUpper, {k1, std::min(k1 + 1, count - 1), k99, std::min(k99 + 1, count - 1)});
    const double p1 = v[0] + (r1 - double(k1)) * (double(v[1]) - v[0]);
    const double p99 = v[2] + (r99 - double(k99)) * (double(v[3]) - v[2]);
    if (!(p99 - p1 > 1e-9)) return;

    const double scale = 1 / (p99 - p1);
    const std::size_t height = out.size() / w;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, height, kRowGrain), [&](const auto& rows) {
        for (std::size_t i = rows.begin() * w; i < rows.end() * w; ++i)
            if (!std::isnan(out[i])) out[i] = float(std::clamp((out[i] - p1) * scale, 0.0, 1.0));
    });
}

} // namespace

std::vector<float> shadeRelief(int width, int height, const std::vector<float>& nx,
                               const std::vector<float>& ny, const std::vector<float>& nz,
                               const std::vector<float>& mask, const ShadingOptions& options)
{
    checkInputs(width, height, nx, ny, nz, mask, options);
    std::vector<float> out(std::size_t(width) * std::size_t(height));
    if (out.empty()) return out;
    const Light l = lightFrom(options);
    if (options.highContrast) {
        // A box wider than the image covers all of it: the radius need not grow beyond that.
        const int radius = std::min(options.contrastRadius, std::max(width, height));
        shadeDeviations(width, height, nx, ny, nz, mask, l, radius, out);
        stretchPercentiles(out, std::size_t(width));
    } else {
        shadePlain(width, height, nx, ny, nz, mask, l, out);
    }
    return out;
}

} // namespace msii
