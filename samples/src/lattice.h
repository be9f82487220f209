#pragma once
/// @file lattice.h
/// @brief Private to the sample generators (generators.cpp, vessels.cpp): the counter-based
/// randomness, the option checks with their "sample mesh: ..." wording, and the jittered
/// lattice's triangulation, shared so that every generator follows the same conventions
/// (generators.h: spacing, irregularity, determinism).

#include <msii/core/errors.h>
#include <msii/mesh/trimesh.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace msii::samples::detail {

// ---------------------------------------------------------------------------------------
// Tunables
// ---------------------------------------------------------------------------------------

/// Maximum jitter, in lattice steps. A triangle of a square lattice has heights >= step/sqrt(2);
/// moving each vertex by at most r changes a height by at most 2r, so r < 0.354 keeps all
/// triangles non-degenerate and correctly oriented (the equilateral sphere lattice allows
/// r < 0.433).
constexpr double kJitter = 0.25;
/// Probability that a quad takes its shorter diagonal.
constexpr double kShortDiagonalProbability = 0.9;
/// Guard against absurd requests (memory, 32-bit indices).
constexpr double kMaxVertices = 200e6;

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------
// Deterministic randomness
// ---------------------------------------------------------------------------------------

/// The splitmix64 output function: a bijective avalanche mix of 64 bits.
constexpr std::uint64_t mix64(std::uint64_t z)
{
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/// Counter-based random bits for (seed, stream, a, b): the same key gives the same bits
/// wherever and in whatever order it is evaluated, so parallel loops stay deterministic.
constexpr std::uint64_t hashKey(std::uint64_t seed, std::uint64_t stream, std::uint64_t a,
                                std::uint64_t b = 0)
{
    return mix64(mix64(mix64(mix64(seed) ^ stream) ^ a) ^ b);
}

/// Uniform in [0, 1) from the top 53 bits.
constexpr double unitInterval(std::uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }

/// Uniform in [-1, 1).
constexpr double signedUnit(std::uint64_t bits) { return 2.0 * unitInterval(bits) - 1.0; }

/// Uniform in the closed unit disc, by rejection from the square (accepts with p = pi/4).
inline std::array<double, 2> unitDiscPoint(std::uint64_t key)
{
    for (std::uint64_t attempt = 0;; ++attempt) {
        const std::uint64_t h = mix64(key + attempt * 0xd1b54a32d192ed03ULL);
        const double u = double(h >> 40) * 0x1.0p-23 - 1.0;               // 24 bits
        const double v = double((h >> 8) & 0xffffffULL) * 0x1.0p-23 - 1.0;  // 24 bits
        if (u * u + v * v <= 1.0) return {u, v};
    }
}

// ---------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------

/// Shortest readable form of a number for messages ("0.01", not "0.010000").
inline std::string formatNumber(double value)
{
    std::ostringstream out;
    out << std::setprecision(6) << value;
    return out.str();
}

inline void requirePositive(double value, const char* what)
{
    if (!(std::isfinite(value) && value > 0.0))
        throw InvalidInputError(std::string("sample mesh: ") + what +
                                " must be a positive finite number (got " + formatNumber(value) + ").");
}

inline void requireNonNegative(double value, const char* what)
{
    if (!(std::isfinite(value) && value >= 0.0))
        throw InvalidInputError(std::string("sample mesh: ") + what +
                                " must be a finite number >= 0 (got " + formatNumber(value) + ").");
}

inline void requireVertexCount(double count)
{
    if (count > kMaxVertices)
        throw InvalidInputError("sample mesh: " + formatNumber(count) +
                                " vertices requested (limit 200 million); increase the spacing.");
}

// ---------------------------------------------------------------------------------------
// Lattice triangulation
// ---------------------------------------------------------------------------------------

/// The two triangles of quad q with corners a, b, c, d (counter-clockwise in the lattice,
/// reversed if flip): its shorter diagonal (in 3D) with probability
/// kShortDiagonalProbability, decided by hash(seed, stream, q).
inline void quadTriangles(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d, const Vec3& pa,
                          const Vec3& pb, const Vec3& pc, const Vec3& pd, std::uint64_t seed, std::uint64_t stream,
                          std::uint64_t q, bool flip, Triangle* out)
{
    const bool acShorter = squaredNorm(pc - pa) <= squaredNorm(pd - pb);
    const bool preferShort = unitInterval(hashKey(seed, stream, q)) < kShortDiagonalProbability;
    Triangle t0, t1;
    if (acShorter == preferShort) {
        t0 = {a, b, c};
        t1 = {a, c, d};
    } else {
        t0 = {a, b, d};
        t1 = {b, c, d};
    }
    if (flip) {
        std::swap(t0[1], t0[2]);
        std::swap(t1[1], t1[2]);
    }
    out[0] = t0;
    out[1] = t1;
}

/// Triangulates the quads of an (nu + 1) x (nv + 1) vertex grid, two triangles per quad at
/// out[2 q], out[2 q + 1] with q = j * nu + i; index(i, j) gives a grid vertex (see
/// quadTriangles).
template <class IndexFn>
void triangulateGrid(const std::vector<Vec3>& points, int nu, int nv, const IndexFn& index,
                     std::uint64_t seed, std::uint64_t stream, bool flip, Triangle* out)
{
    tbb::parallel_for(tbb::blocked_range<int>(0, nv), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            for (int i = 0; i < nu; ++i) {
                const std::size_t q = std::size_t(j) * std::size_t(nu) + std::size_t(i);
                const std::uint32_t a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1),
                                    d = index(i, j + 1);
                quadTriangles(a, b, c, d, points[a], points[b], points[c], points[d], seed, stream, q, flip,
                              out + 2 * q);
            }
        }
    });
}

} // namespace msii::samples::detail
