/// @file generators.cpp
/// @brief Sample meshes: jittered lattices with random diagonals (height fields, cube
/// faces), a jittered geodesic sphere, and the analytic height functions. See generators.h
/// for the spacing / vertex-count relations and the determinism contract.

#include <msii/samples/generators.h>

#include "lattice.h"

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace msii::samples {

using namespace detail;

namespace {

// ---------------------------------------------------------------------------------------
// Tunables
// ---------------------------------------------------------------------------------------

/// Value-noise wavelength, in spacings.
constexpr double kNoiseWavelength = 5.0;
/// Tablet: wedge creases are rounded over min(spacing, this), mm.
constexpr double kMaxBlendLength = 0.1;

/// Independent random streams: every random quantity is hash(seed, stream, key...).
enum Stream : std::uint64_t {
    kStreamJitter = 1,
    kStreamDiagonal,
    kStreamBottomJitter,
    kStreamBottomDiagonal,
    kStreamWallJitter,
    kStreamWallDiagonal,
    kStreamCubeDiagonal,  // + face number
    kStreamHills = 16,
    kStreamWedges,
    kStreamNoise,
    kStreamHoles,
    kStreamRoughness,
    kStreamMarks,
};

/// Sequential generator for the few global layout choices (hills, wedges).
class SplitMix64 {
public:
    explicit SplitMix64(std::uint64_t seed) : mState(seed) {}
    std::uint64_t next()
    {
        const std::uint64_t out = mix64(mState);
        mState += 0x9e3779b97f4a7c15ULL;
        return out;
    }
    double uniform() { return unitInterval(next()); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    /// A random unit vector in the plane (uniform direction).
    std::array<double, 2> direction()
    {
        for (;;) {
            const double u = 2.0 * uniform() - 1.0, v = 2.0 * uniform() - 1.0;
            const double r2 = u * u + v * v;
            if (r2 <= 1.0 && r2 >= 1e-4) {
                const double r = std::sqrt(r2);
                return {u / r, v / r};
            }
        }
    }

private:
    std::uint64_t mState;
};

// ---------------------------------------------------------------------------------------
// Lattice helpers
// ---------------------------------------------------------------------------------------

/// Number of lattice cells along an extent, round(extent / spacing), at least 1.
int latticeCells(double extent, double spacing)
{
    const double cells = std::round(extent / spacing);
    if (!(cells <= kMaxVertices))
        throw InvalidInputError("sample mesh: spacing " + formatNumber(spacing) +
                                " is far too fine for a size of " + formatNumber(extent) + ".");
    return std::max(1, int(cells));
}

/// Coordinate of lattice line i of n over [0, extent]; the last line is exactly extent.
double latticeCoord(int i, int n, double extent) { return i == n ? extent : extent * i / n; }

// ---------------------------------------------------------------------------------------
// Smooth min / max (quadratic polynomial blend, C1): equal to min / max when |a - b| >= k,
// so far-away features contribute exactly nothing.
// ---------------------------------------------------------------------------------------

double smoothMin(double a, double b, double k)
{
    const double h = std::max(k - std::abs(a - b), 0.0) / k;
    return std::min(a, b) - 0.25 * h * h * k;
}

double smoothMax(double a, double b, double k)
{
    const double h = std::max(k - std::abs(a - b), 0.0) / k;
    return std::max(a, b) + 0.25 * h * h * k;
}

// ---------------------------------------------------------------------------------------
// Height functions
// ---------------------------------------------------------------------------------------

struct Box {
    double xmin, xmax, ymin, ymax;
    bool contains(double x, double y) const { return x >= xmin && x <= xmax && y >= ymin && y <= ymax; }
};

/// A uniform grid of buckets over a rectangle listing, per cell, the items whose box
/// overlaps it, in increasing item order (so sums and blends run in a fixed order).
/// Queries outside the rectangle use the nearest cell, which is still correct: box ranges
/// are clamped the same way.
class BucketGrid {
public:
    BucketGrid() = default;
    BucketGrid(const Box& domain, double cell, const std::vector<Box>& boxes)
        : mX0(domain.xmin), mY0(domain.ymin), mCell(cell)
    {
        mNx = std::clamp(int(std::ceil((domain.xmax - domain.xmin) / cell)), 1, 4096);
        mNy = std::clamp(int(std::ceil((domain.ymax - domain.ymin) / cell)), 1, 4096);
        std::vector<std::vector<std::uint32_t>> cells(std::size_t(mNx) * std::size_t(mNy));
        for (std::size_t n = 0; n < boxes.size(); ++n) {
            const int i0 = cellX(boxes[n].xmin), i1 = cellX(boxes[n].xmax);
            const int j0 = cellY(boxes[n].ymin), j1 = cellY(boxes[n].ymax);
            for (int j = j0; j <= j1; ++j)
                for (int i = i0; i <= i1; ++i) cells[std::size_t(j) * mNx + i].push_back(std::uint32_t(n));
        }
        mStart.assign(cells.size() + 1, 0);
        for (std::size_t c = 0; c < cells.size(); ++c) mStart[c + 1] = mStart[c] + std::uint32_t(cells[c].size());
        mItems.reserve(mStart.back());
        for (const auto& list : cells) mItems.insert(mItems.end(), list.begin(), list.end());
    }

    /// Items whose box may contain (x, y), as a [begin, end) range of indices.
    std::pair<const std::uint32_t*, const std::uint32_t*> query(double x, double y) const
    {
        if (mItems.empty()) return {nullptr, nullptr};
        const std::size_t c = std::size_t(cellY(y)) * mNx + cellX(x);
        return {mItems.data() + mStart[c], mItems.data() + mStart[c + 1]};
    }

private:
    int cellX(double x) const { return clampCell((x - mX0) / mCell, mNx); }
    int cellY(double y) const { return clampCell((y - mY0) / mCell, mNy); }
    static int clampCell(double t, int n)
    {
        if (!(t > 0.0)) return 0;  // also NaN
        return t >= double(n - 1) ? n - 1 : int(t);
    }

    double mX0 = 0, mY0 = 0, mCell = 1;
    int mNx = 1, mNy = 1;
    std::vector<std::uint32_t> mStart, mItems;
};

/// A Gaussian-like hill a (1 - r^2 / R^2)^4 for r < R, 0 beyond: within 3 % of a Gaussian
/// of sigma = R / 3, but with compact support and without exp().
struct Hill {
    double cx, cy, radius, amplitude;
};

/// A cuneiform wedge: the pit a triangular pyramid (stylus corner) leaves in the clay. Its
/// outline is a long isosceles triangle (head edge across the stroke, apex at the end of
/// the tail); the deepest point lies on the axis near the head. The pit is the max of the
/// three planes through an outline edge and the deepest point (the convex piecewise-linear
/// pyramid), blended by smoothMax / smoothMin over `blend` (height units).
struct Wedge {
    std::array<std::array<double, 3>, 3> planes;  ///< a x + b y + c, 0 on an outline edge
    double blend;
    Box reach;  ///< outside it the pit function is >= blend, i.e. exactly no effect
};

class HeightFunction {
public:
    explicit HeightFunction(const HeightFieldOptions& options);
    double operator()(double x, double y) const;

private:
    double hills(double x, double y) const;
    double wedges(double x, double y) const;
    double valueNoise(double x, double y) const;

    HeightFieldKind mKind;
    std::uint64_t mSeed;
    double mCx = 0, mCy = 0, mCurvature = 0;
    double mNoise = 0, mNoiseFrequency = 1;
    std::vector<Hill> mHills;
    std::vector<Wedge> mWedges;
    BucketGrid mGrid;
};

void validate(const HeightFieldOptions& o)
{
    requirePositive(o.width, "width");
    requirePositive(o.height, "height");
    requirePositive(o.spacing, "spacing");
    if (o.closed) requirePositive(o.thickness, "thickness");
    requireNonNegative(o.wallStep, "wall step");
    requirePositive(o.anisotropy, "anisotropy");
    if (!(o.densityVariation >= 1) || !std::isfinite(o.densityVariation))
        throw InvalidInputError("sample mesh: density variation must be a finite number of at least 1.");
    requireNonNegative(o.roughness, "roughness");
    if (o.kind == HeightFieldKind::Terrain) {
        if (!std::isfinite(o.relief)) throw InvalidInputError("sample mesh: relief must be finite.");
        requirePositive(o.hillWidth, "hill width");
        requireNonNegative(o.noise, "noise");
    }
    if (o.kind == HeightFieldKind::Tablet) {
        if (!std::isfinite(o.sag)) throw InvalidInputError("sample mesh: sag must be finite.");
        requireNonNegative(o.wedgeDensity, "wedge density");
        requireNonNegative(o.wedgeMargin, "wedge margin");
        if (o.wedgeDensity > 0.0) requirePositive(o.wedgeSize, "wedge size");
        requireNonNegative(o.noise, "noise");
    }
}

HeightFunction::HeightFunction(const HeightFieldOptions& o) : mKind(o.kind), mSeed(o.seed)
{
    validate(o);
    if (mKind == HeightFieldKind::Plane) return;
    mNoise = o.noise;
    mNoiseFrequency = 1.0 / (kNoiseWavelength * o.spacing);

    std::vector<Box> boxes;
    if (mKind == HeightFieldKind::Terrain) {
        // Hill centres cover the rectangle grown by the largest support radius, so the
        // border looks like the inside. Amplitudes are uniform in [-relief, relief]; with
        // density 0.75 / (pi sigma^2) the standard deviation of the sum is ~relief / 2.
        SplitMix64 rng(hashKey(o.seed, kStreamHills, 0));
        const double maxRadius = 3.0 * 1.4 * o.hillWidth;
        const double area = (o.width + 2 * maxRadius) * (o.height + 2 * maxRadius);
        const double count = std::round(0.75 * area / (kPi * o.hillWidth * o.hillWidth));
        if (count > 1e6) throw InvalidInputError("sample mesh: hill width too small for the terrain size.");
        for (int n = 0; n < int(count); ++n) {
            Hill hill;
            hill.cx = rng.uniform(-maxRadius, o.width + maxRadius);
            hill.cy = rng.uniform(-maxRadius, o.height + maxRadius);
            hill.radius = 3.0 * o.hillWidth * rng.uniform(0.6, 1.4);
            hill.amplitude = o.relief * rng.uniform(-1.0, 1.0);
            mHills.push_back(hill);
            boxes.push_back({hill.cx - hill.radius, hill.cx + hill.radius, hill.cy - hill.radius,
                             hill.cy + hill.radius});
        }
        mGrid = BucketGrid({-maxRadius, o.width + maxRadius, -maxRadius, o.height + maxRadius},
                           2.0 * o.hillWidth, boxes);
        return;
    }

    // Tablet: z = -c ((x - xc)^2 + (y - yc)^2), c from the sag at the middle of the longer side.
    mCx = 0.5 * o.width;
    mCy = 0.5 * o.height;
    const double halfLong = 0.5 * std::max(o.width, o.height);
    mCurvature = o.sag / (halfLong * halfLong);

    const double m = o.wedgeMargin;
    const double innerW = o.width - 2 * m, innerH = o.height - 2 * m;
    if (o.wedgeDensity <= 0.0 || innerW <= 0.0 || innerH <= 0.0) return;
    const double count = std::round(o.wedgeDensity * innerW * innerH);
    if (count > 1e6) throw InvalidInputError("sample mesh: too many wedges requested (over a million).");

    // The layout uses only the sizes and the seed (not the spacing), so one tablet can be
    // sampled at several resolutions. Wedges that do not fit inside the margin after 100
    // attempts are dropped (small tablets).
    SplitMix64 rng(hashKey(o.seed, kStreamWedges, 0));
    for (int n = 0; n < int(count); ++n) {
        for (int attempt = 0; attempt < 100; ++attempt) {
            const double length = o.wedgeSize * rng.uniform(0.6, 1.4);
            const double headWidth = length * rng.uniform(0.35, 0.5);
            const double deepAt = length * rng.uniform(0.2, 0.3);
            const double depth = 0.2 * length;
            const auto dir = rng.direction();
            const double hx = rng.uniform(m, o.width - m), hy = rng.uniform(m, o.height - m);
            const double px = -dir[1], py = dir[0];  // across the stroke
            const std::array<std::array<double, 2>, 3> corner = {{
                {hx + 0.5 * headWidth * px, hy + 0.5 * headWidth * py},
                {hx - 0.5 * headWidth * px, hy - 0.5 * headWidth * py},
                {hx + length * dir[0], hy + length * dir[1]},
            }};
            const double qx = hx + deepAt * dir[0], qy = hy + deepAt * dir[1];
            Wedge w;
            double minSlope = std::numeric_limits<double>::infinity();
            for (int e = 0; e < 3; ++e) {
                // Plane through edge (p1, p2) at height 0 and through Q at -depth.
                const auto& p1 = corner[e];
                const auto& p2 = corner[(e + 1) % 3];
                const double ex = p2[0] - p1[0], ey = p2[1] - p1[1];
                const double s = ex * (qy - p1[1]) - ey * (qx - p1[0]);  // 2D cross, signed
                const double a = depth * ey / s, b = -depth * ex / s;
                w.planes[e] = {a, b, -(a * p1[0] + b * p1[1])};
                minSlope = std::min(minSlope, std::sqrt(a * a + b * b));
            }
            // Smallest half-angle of the outline (the tail apex): beyond a corner the pit
            // function rises at least at minSlope * sin(angle / 2) per unit of distance.
            double minSinHalf = 1.0;
            for (int v = 0; v < 3; ++v) {
                const auto& p = corner[v];
                const auto& p1 = corner[(v + 1) % 3];
                const auto& p2 = corner[(v + 2) % 3];
                const double ux = p1[0] - p[0], uy = p1[1] - p[1], vx = p2[0] - p[0], vy = p2[1] - p[1];
                const double cosAngle = (ux * vx + uy * vy) / std::sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy));
                minSinHalf = std::min(minSinHalf, std::sqrt(std::max(0.0, 0.5 * (1.0 - cosAngle))));
            }
            // The blend (creases rounded over ~1 spacing, at most kMaxBlendLength) reaches at
            // most blendLength / minSinHalf beyond the outline; keep that inside the margin
            // for the largest blend, so the layout does not depend on the spacing.
            const double maxReach = 1.01 * kMaxBlendLength / minSinHalf;
            const bool inside = std::all_of(corner.begin(), corner.end(), [&](const std::array<double, 2>& c) {
                return c[0] - maxReach >= m && c[0] + maxReach <= o.width - m && c[1] - maxReach >= m &&
                       c[1] + maxReach <= o.height - m;
            });
            if (!inside) continue;
            const double blendLength = std::min(o.spacing, kMaxBlendLength);
            w.blend = blendLength * minSlope;
            const double reach = 1.01 * blendLength / minSinHalf;
            w.reach = {std::min({corner[0][0], corner[1][0], corner[2][0]}) - reach,
                       std::max({corner[0][0], corner[1][0], corner[2][0]}) + reach,
                       std::min({corner[0][1], corner[1][1], corner[2][1]}) - reach,
                       std::max({corner[0][1], corner[1][1], corner[2][1]}) + reach};
            mWedges.push_back(w);
            boxes.push_back(w.reach);
            break;
        }
    }
    mGrid = BucketGrid({0.0, o.width, 0.0, o.height}, std::max(2.0 * o.wedgeSize, 0.25), boxes);
}

double HeightFunction::operator()(double x, double y) const
{
    switch (mKind) {
    case HeightFieldKind::Plane:
        return 0.0;
    case HeightFieldKind::Terrain:
        return hills(x, y) + mNoise * valueNoise(x, y);
    case HeightFieldKind::Tablet:
        break;
    }
    const double dx = x - mCx, dy = y - mCy;
    return -mCurvature * (dx * dx + dy * dy) + wedges(x, y) + mNoise * valueNoise(x, y);
}

double HeightFunction::hills(double x, double y) const
{
    double z = 0.0;
    const auto [begin, end] = mGrid.query(x, y);
    for (const std::uint32_t* it = begin; it != end; ++it) {
        const Hill& h = mHills[*it];
        const double dx = x - h.cx, dy = y - h.cy;
        const double t = (dx * dx + dy * dy) / (h.radius * h.radius);
        if (t < 1.0) {
            const double u = (1.0 - t) * (1.0 - t);
            z += h.amplitude * u * u;
        }
    }
    return z;
}

double HeightFunction::wedges(double x, double y) const
{
    double z = 0.0;  // the undisturbed surface; pits are negative
    const auto [begin, end] = mGrid.query(x, y);
    for (const std::uint32_t* it = begin; it != end; ++it) {
        const Wedge& w = mWedges[*it];
        if (!w.reach.contains(x, y)) continue;
        const auto plane = [&](int e) { return w.planes[e][0] * x + w.planes[e][1] * y + w.planes[e][2]; };
        const double pit = smoothMax(smoothMax(plane(0), plane(1), w.blend), plane(2), w.blend);
        z = smoothMin(z, pit, w.blend);
    }
    return z;
}

/// Value noise in [-1, 1]: seeded lattice values, quintic (C2) interpolation.
double HeightFunction::valueNoise(double x, double y) const
{
    if (mNoise == 0.0) return 0.0;
    const double fx = x * mNoiseFrequency, fy = y * mNoiseFrequency;
    const double ix = std::floor(fx), iy = std::floor(fy);
    const double tx = fx - ix, ty = fy - iy;
    const auto fade = [](double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); };
    const auto value = [&](double i, double j) {
        return signedUnit(hashKey(mSeed, kStreamNoise, std::uint64_t(std::int64_t(i)), std::uint64_t(std::int64_t(j))));
    };
    const double sx = fade(tx), sy = fade(ty);
    const double v0 = value(ix, iy) + sx * (value(ix + 1, iy) - value(ix, iy));
    const double v1 = value(ix, iy + 1) + sx * (value(ix + 1, iy + 1) - value(ix, iy + 1));
    return v0 + sy * (v1 - v0);
}

// ---------------------------------------------------------------------------------------
// Icosahedron
// ---------------------------------------------------------------------------------------

struct Icosahedron {
    std::array<Vec3, 12> vertices;
    std::vector<std::array<int, 3>> faces;  ///< counter-clockwise seen from outside
};

Icosahedron makeIcosahedron()
{
    const double phi = 0.5 * (1.0 + std::sqrt(5.0));
    Icosahedron ico;
    int n = 0;
    for (double s : {-1.0, 1.0})
        for (double t : {-1.0, 1.0}) {
            ico.vertices[n++] = {0.0, s, t * phi};
            ico.vertices[n++] = {s, t * phi, 0.0};
            ico.vertices[n++] = {t * phi, 0.0, s};
        }
    // Faces are the triples of mutually adjacent vertices (edge length 2).
    const auto adjacent = [&](int a, int b) {
        return std::abs(squaredNorm(ico.vertices[a] - ico.vertices[b]) - 4.0) < 1e-9;
    };
    for (int a = 0; a < 12; ++a)
        for (int b = a + 1; b < 12; ++b)
            for (int c = b + 1; c < 12; ++c)
                if (adjacent(a, b) && adjacent(b, c) && adjacent(a, c)) {
                    const Vec3& A = ico.vertices[a];
                    if (dot(cross(ico.vertices[b] - A, ico.vertices[c] - A), A) > 0)
                        ico.faces.push_back({a, b, c});
                    else
                        ico.faces.push_back({a, c, b});
                }
    return ico;
}

} // namespace

// ---------------------------------------------------------------------------------------
// Sphere
// ---------------------------------------------------------------------------------------

TriMesh makeSphere(const SphereOptions& options)
{
    requirePositive(options.radius, "radius");
    requirePositive(options.spacing, "spacing");
    if (!isFinite(options.center))
        throw InvalidInputError("sample mesh: the sphere centre must be finite.");
    // 10 k^2 + 2 vertices on 4 pi R^2: k = sqrt(0.4 pi) R / spacing gives ~spacing^2 per vertex.
    const double kReal = std::round(std::sqrt(0.4 * kPi) * options.radius / options.spacing);
    requireVertexCount(10.0 * kReal * kReal + 2.0);
    const int k = std::max(1, int(kReal));

    const Icosahedron ico = makeIcosahedron();
    // Edges (a < b) in first-seen order.
    std::vector<std::array<int, 2>> edges;
    std::unordered_map<int, int> edgeIds;  // key a * 12 + b
    for (const auto& f : ico.faces)
        for (int e = 0; e < 3; ++e) {
            const int a = std::min(f[e], f[(e + 1) % 3]), b = std::max(f[e], f[(e + 1) % 3]);
            if (edgeIds.emplace(a * 12 + b, int(edges.size())).second) edges.push_back({a, b});
        }

    const std::size_t perEdge = std::size_t(k - 1);
    const std::size_t perFace = std::size_t(k - 1) * std::size_t(std::max(k - 2, 0)) / 2;
    const std::size_t edgeBase = 12, faceBase = edgeBase + edges.size() * perEdge;
    const std::size_t numVertices = faceBase + ico.faces.size() * perFace;

    // Vertex id of lattice point (i, j) of face f (point A + (B - A) i / k + (C - A) j / k).
    const auto edgePoint = [&](int u, int v, int t) -> std::uint32_t {
        const int e = edgeIds.at(std::min(u, v) * 12 + std::max(u, v));
        const int tt = u < v ? t : k - t;  // measured from the lower-numbered vertex
        return std::uint32_t(edgeBase + std::size_t(e) * perEdge + std::size_t(tt - 1));
    };
    const auto pointId = [&](std::size_t f, int i, int j) -> std::uint32_t {
        const auto& F = ico.faces[f];
        if (i == 0 && j == 0) return std::uint32_t(F[0]);
        if (i == k && j == 0) return std::uint32_t(F[1]);
        if (i == 0 && j == k) return std::uint32_t(F[2]);
        if (j == 0) return edgePoint(F[0], F[1], i);
        if (i == 0) return edgePoint(F[0], F[2], j);
        if (i + j == k) return edgePoint(F[1], F[2], j);
        // Interior: row j has k - 1 - j points (i = 1 .. k - 1 - j), rows j = 1 .. k - 2.
        const std::size_t before = std::size_t(j - 1) * std::size_t(k - 1) - std::size_t(j - 1) * std::size_t(j) / 2;
        return std::uint32_t(faceBase + f * perFace + before + std::size_t(i - 1));
    };

    // Positions on the flat icosahedron (jittered in its faces / along its edges), then
    // projected centrally onto the sphere: central projection keeps every triangle's
    // orientation (det(p1, p2, p3) keeps its sign under positive scaling), so validity on
    // the flat lattice carries over.
    TriMesh mesh;
    mesh.points.resize(numVertices);
    const Vec3 c = options.center;
    const double R = options.radius;
    const auto project = [&](const Vec3& p) {
        const Vec3 u = p / norm(p);
        return Vec3{c.x + R * u.x, c.y + R * u.y, c.z + R * u.z};
    };
    const std::uint64_t seed = options.seed;
    for (int v = 0; v < 12; ++v) mesh.points[std::size_t(v)] = project(ico.vertices[std::size_t(v)]);
    tbb::parallel_for(std::size_t(0), edges.size(), [&](std::size_t e) {
        const Vec3& A = ico.vertices[std::size_t(edges[e][0])];
        const Vec3 AB = ico.vertices[std::size_t(edges[e][1])] - A;
        for (int t = 1; t < k; ++t) {
            const std::size_t id = edgeBase + e * perEdge + std::size_t(t - 1);
            const double s = (t + kJitter * signedUnit(hashKey(seed, kStreamJitter, id))) / k;
            mesh.points[id] = project(A + AB * s);
        }
    });
    tbb::parallel_for(std::size_t(0), ico.faces.size(), [&](std::size_t f) {
        const auto& F = ico.faces[f];
        const Vec3& A = ico.vertices[std::size_t(F[0])];
        const Vec3 AB = ico.vertices[std::size_t(F[1])] - A, AC = ico.vertices[std::size_t(F[2])] - A;
        const double step = norm(AB) / k;
        const Vec3 e1 = normalized(AB);
        const Vec3 e2 = normalized(AC - e1 * dot(AC, e1));
        for (int j = 1; j + 1 < k; ++j)
            for (int i = 1; i + j < k; ++i) {
                const std::uint32_t id = pointId(f, i, j);
                const auto d = unitDiscPoint(hashKey(seed, kStreamJitter, id));
                const Vec3 p = A + AB * (double(i) / k) + AC * (double(j) / k) +
                               (e1 * d[0] + e2 * d[1]) * (kJitter * step);
                mesh.points[id] = project(p);
            }
    });

    // k^2 triangles per face: "up" (i, j), (i+1, j), (i, j+1) and "down" (i+1, j),
    // (i+1, j+1), (i, j+1), both counter-clockwise like (A, B, C).
    mesh.triangles.resize(ico.faces.size() * std::size_t(k) * std::size_t(k));
    tbb::parallel_for(std::size_t(0), ico.faces.size(), [&](std::size_t f) {
        std::size_t t = f * std::size_t(k) * std::size_t(k);
        for (int j = 0; j < k; ++j)
            for (int i = 0; i + j < k; ++i) {
                mesh.triangles[t++] = {pointId(f, i, j), pointId(f, i + 1, j), pointId(f, i, j + 1)};
                if (i + j + 1 < k)
                    mesh.triangles[t++] = {pointId(f, i + 1, j), pointId(f, i + 1, j + 1), pointId(f, i, j + 1)};
            }
    });
    if (options.cavity)
        for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
    return mesh;
}

// ---------------------------------------------------------------------------------------
// Box lattices: the cube and the rounded tablet
// ---------------------------------------------------------------------------------------

namespace {

/// The surface of the integer lattice box {0..n[0]} × {0..n[1]} × {0..n[2]}: its vertices
/// face by face, row by row, shared along the box's edges, and per face the grid of vertex
/// ids that triangulateGrid takes.
struct BoxLattice {
    /// A face: the lattice points origin + i u + j v (0 <= i <= nu, 0 <= j <= nv), u × v
    /// the outward normal.
    struct Face {
        std::array<int, 3> origin, u, v;
        int nu = 0, nv = 0;
        std::vector<std::uint32_t> grid;  ///< vertex id of (i, j) at j (nu + 1) + i
    };
    std::array<int, 3> n{};
    std::vector<std::array<int, 3>> points;  ///< lattice position of each vertex
    std::array<Face, 6> faces;

    /// A number unique to each lattice position (the jitter's hash key).
    std::uint64_t key(const std::array<int, 3>& p) const
    {
        return (std::uint64_t(p[0]) * std::uint64_t(n[1] + 1) + std::uint64_t(p[1])) * std::uint64_t(n[2] + 1) +
               std::uint64_t(p[2]);
    }
    std::size_t numTriangles() const
    {
        std::size_t count = 0;
        for (const Face& f : faces) count += 2 * std::size_t(f.nu) * std::size_t(f.nv);
        return count;
    }
};

BoxLattice makeBoxLattice(const std::array<int, 3>& n)
{
    BoxLattice box;
    box.n = n;
    const auto face = [&](std::array<int, 3> origin, std::array<int, 3> u, std::array<int, 3> v) {
        BoxLattice::Face f{origin, u, v, 0, 0, {}};
        for (int a = 0; a < 3; ++a) f.nu += u[std::size_t(a)] * n[std::size_t(a)], f.nv += v[std::size_t(a)] * n[std::size_t(a)];
        return f;
    };
    box.faces = {{
        face({0, 0, 0}, {0, 1, 0}, {1, 0, 0}),     // z = 0, normal -z
        face({0, 0, n[2]}, {1, 0, 0}, {0, 1, 0}),  // z = top, +z
        face({0, 0, 0}, {0, 0, 1}, {0, 1, 0}),     // x = 0, -x
        face({n[0], 0, 0}, {0, 1, 0}, {0, 0, 1}),  // x = top, +x
        face({0, 0, 0}, {1, 0, 0}, {0, 0, 1}),     // y = 0, -y
        face({0, n[1], 0}, {0, 0, 1}, {1, 0, 0}),  // y = top, +y
    }};
    std::unordered_map<std::uint64_t, std::uint32_t> shared;
    for (BoxLattice::Face& F : box.faces) {
        F.grid.resize(std::size_t(F.nu + 1) * std::size_t(F.nv + 1));
        for (int j = 0; j <= F.nv; ++j)
            for (int i = 0; i <= F.nu; ++i) {
                const std::array<int, 3> p = {F.origin[0] + i * F.u[0] + j * F.v[0],
                                              F.origin[1] + i * F.u[1] + j * F.v[1],
                                              F.origin[2] + i * F.u[2] + j * F.v[2]};
                std::uint32_t id;
                if (i == 0 || j == 0 || i == F.nu || j == F.nv) {
                    const auto [it, inserted] = shared.emplace(box.key(p), std::uint32_t(box.points.size()));
                    if (inserted) box.points.push_back(p);
                    id = it->second;
                } else {
                    id = std::uint32_t(box.points.size());
                    box.points.push_back(p);
                }
                F.grid[std::size_t(j) * std::size_t(F.nu + 1) + std::size_t(i)] = id;
            }
    }
    return box;
}

/// The lattice's points at @p extent (mm per axis), jittered: coordinates on a face or edge
/// (0 < p < n) are free, in a disc for face vertices and along the edge for edge vertices;
/// 0 and n stay exact.
std::vector<Vec3> jitteredBoxPoints(const BoxLattice& box, const std::array<double, 3>& extent, std::uint64_t seed)
{
    std::vector<Vec3> points(box.points.size());
    tbb::parallel_for(std::size_t(0), box.points.size(), [&](std::size_t id) {
        const auto& p = box.points[id];
        const std::uint64_t h = hashKey(seed, kStreamJitter, box.key(p));
        std::array<double, 2> d = unitDiscPoint(h);
        int freeAxes = 0;
        for (std::size_t a = 0; a < 3; ++a) freeAxes += (p[a] > 0 && p[a] < box.n[a]);
        if (freeAxes == 1) d[0] = signedUnit(h);
        Vec3 q;
        int used = 0;
        for (std::size_t a = 0; a < 3; ++a) {
            const int pa = p[a], na = box.n[a];
            q[int(a)] = latticeCoord(pa, na, extent[a]);
            if (pa > 0 && pa < na) q[int(a)] += kJitter * (extent[a] / na) * d[std::size_t(used++)];
        }
        points[id] = q;
    });
    return points;
}

/// The lattice's faces triangulated (triangulateGrid), face after face.
std::vector<Triangle> boxTriangles(const BoxLattice& box, const std::vector<Vec3>& points, std::uint64_t seed)
{
    std::vector<Triangle> triangles(box.numTriangles());
    std::size_t at = 0;
    for (std::size_t f = 0; f < 6; ++f) {
        const BoxLattice::Face& F = box.faces[f];
        const std::uint32_t* g = F.grid.data();
        const int nu = F.nu;
        const auto index = [g, nu](int i, int j) { return g[std::size_t(j) * std::size_t(nu + 1) + std::size_t(i)]; };
        triangulateGrid(points, F.nu, F.nv, index, seed, kStreamCubeDiagonal + std::uint64_t(f), false,
                        triangles.data() + at);
        at += 2 * std::size_t(F.nu) * std::size_t(F.nv);
    }
    return triangles;
}

} // namespace

TriMesh makeCube(const CubeOptions& options)
{
    requirePositive(options.side, "side");
    requirePositive(options.spacing, "spacing");
    const int n = latticeCells(options.side, options.spacing);
    requireVertexCount(6.0 * double(n) * double(n) + 2.0);
    const BoxLattice box = makeBoxLattice({n, n, n});
    TriMesh mesh;
    mesh.points = jitteredBoxPoints(box, {options.side, options.side, options.side}, options.seed);
    mesh.triangles = boxTriangles(box, mesh.points, options.seed);
    return mesh;
}

namespace {

/// A side of the rounded tablet: its outward axis (x 0, y 1, z 2) and sign, and the two
/// axes of its face.
struct SideAxes {
    int axis, sign, u, v;
};
constexpr std::array<SideAxes, 6> kSideAxes = {{
    {2, +1, 0, 1},  // obverse, +z
    {2, -1, 0, 1},  // reverse, -z
    {1, +1, 0, 2},  // top, +y
    {1, -1, 0, 2},  // bottom, -y
    {0, -1, 1, 2},  // left, -x
    {0, +1, 1, 2},  // right, +x
}};

/// A mark's place before it is pressed in: the side and the face coordinates of its centre.
struct MarkPlace {
    std::size_t side;
    double u, v;
};

/// The marks' centres: per side, its count on a grid of cells over the flat part of the
/// face (the part the rounding leaves flat, less a mark's radius and a margin), each at its
/// cell's centre moved by up to 15 % of the cell.
/// @throw InvalidInputError if they do not fit.
std::vector<MarkPlace> placeMarks(const RoundedTabletOptions& o, const std::array<double, 3>& inner)
{
    std::vector<MarkPlace> places;
    const double margin = o.markRadius + 0.3 * o.markRadius;
    for (std::size_t s = 0; s < 6; ++s) {
        const int count = o.marks[s];
        if (count < 0) throw InvalidInputError("sample mesh: a side's number of marks must not be negative.");
        if (count == 0) continue;
        const SideAxes& a = kSideAxes[s];
        const double lu = 2 * (inner[std::size_t(a.u)] - margin), lv = 2 * (inner[std::size_t(a.v)] - margin);
        int cols = std::clamp(int(std::lround(std::sqrt(count * std::max(lu, 0.0) / std::max(lv, 1e-9)))), 1, count);
        const int rows = (count + cols - 1) / cols;
        const double cu = lu / cols, cv = lv / rows;
        const bool fits = lu >= 0 && lv >= 0 && (cols == 1 || cu >= 2.2 * o.markRadius) &&
                          (rows == 1 || cv >= 2.2 * o.markRadius);
        if (!fits)
            throw InvalidInputError("sample mesh: " + std::to_string(count) +
                                    " marks do not fit on a side of the tablet; make it larger, its rounding or its "
                                    "marks smaller, or use fewer marks.");
        for (int k = 0; k < count; ++k) {
            const std::uint64_t h = hashKey(o.seed, kStreamMarks, s, std::uint64_t(k));
            const double ju = 0.15 * signedUnit(h), jv = 0.15 * signedUnit(mix64(h));
            places.push_back({s, -0.5 * lu + cu * (k % cols + 0.5 + (cols > 1 ? ju : 0)),
                              -0.5 * lv + cv * (k / cols + 0.5 + (rows > 1 ? jv : 0))});
        }
    }
    return places;
}

/// The depth of the marks at face coordinates (u, v) of side @p s: a smooth round pit
/// depth (1 − d²/r²)² within the mark's radius r of its centre.
double markDepthAt(const std::vector<MarkPlace>& places, const RoundedTabletOptions& o, std::size_t s, double u,
                   double v)
{
    double depth = 0;
    for (const MarkPlace& m : places) {
        if (m.side != s) continue;
        const double d2 = ((u - m.u) * (u - m.u) + (v - m.v) * (v - m.v)) / (o.markRadius * o.markRadius);
        if (d2 < 1) depth = std::max(depth, o.markDepth * (1 - d2) * (1 - d2));
    }
    return depth;
}

void validate(const RoundedTabletOptions& o)
{
    requirePositive(o.width, "width");
    requirePositive(o.height, "height");
    requirePositive(o.thickness, "thickness");
    requirePositive(o.rounding, "rounding");
    requirePositive(o.spacing, "spacing");
    requirePositive(o.markRadius, "mark radius");
    requireNonNegative(o.markDepth, "mark depth");
    requireNonNegative(o.obverseBulge, "obverse bulge");
    requireNonNegative(o.reverseBulge, "reverse bulge");
    requireNonNegative(o.roughness, "roughness");
    if (!(2 * o.rounding < std::min({o.width, o.height, o.thickness})))
        throw InvalidInputError("sample mesh: the rounding must be less than half the tablet's smallest side.");
    if (!(o.markDepth < o.rounding)) throw InvalidInputError("sample mesh: the marks must be shallower than the rounding.");
}

} // namespace

const char* tabletSideName(TabletSide side)
{
    static const char* const names[] = {"obverse", "reverse", "top", "bottom", "left", "right"};
    return names[int(side)];
}

RoundedTablet makeRoundedTablet(const RoundedTabletOptions& o)
{
    validate(o);
    const std::array<double, 3> size = {o.width, o.height, o.thickness};
    const std::array<double, 3> half = {0.5 * o.width, 0.5 * o.height, 0.5 * o.thickness};
    const std::array<double, 3> inner = {half[0] - o.rounding, half[1] - o.rounding, half[2] - o.rounding};
    const std::vector<MarkPlace> places = placeMarks(o, inner);
    const std::array<int, 3> n = {latticeCells(size[0], o.spacing), latticeCells(size[1], o.spacing),
                                  latticeCells(size[2], o.spacing)};
    requireVertexCount(2.0 * (double(n[0]) * n[1] + double(n[1]) * n[2] + double(n[0]) * n[2]) + 2.0);
    const BoxLattice box = makeBoxLattice(n);
    const std::vector<Vec3> lattice = jitteredBoxPoints(box, size, o.seed);

    // Each point of the box's surface goes to the rounded box: the closest point of the
    // inner box plus the rounding radius in the direction from it (the normal there).
    RoundedTablet tablet;
    tablet.mesh.points.resize(lattice.size());
    const auto bulge = [&](const Vec3& p) {  // the faces' rise, 0 along the edges
        const double fx = 1 - (p.x / half[0]) * (p.x / half[0]), fy = 1 - (p.y / half[1]) * (p.y / half[1]);
        return std::max(fx, 0.0) * std::max(fy, 0.0) * (p.z >= 0 ? o.obverseBulge : o.reverseBulge) / half[2];
    };
    tbb::parallel_for(std::size_t(0), lattice.size(), [&](std::size_t id) {
        const Vec3 q(lattice[id].x - half[0], lattice[id].y - half[1], lattice[id].z - half[2]);
        const Vec3 core(std::clamp(q.x, -inner[0], inner[0]), std::clamp(q.y, -inner[1], inner[1]),
                        std::clamp(q.z, -inner[2], inner[2]));
        const Vec3 normal = normalized(q - core);
        Vec3 p = core + normal * o.rounding;
        p.z += p.z * bulge(p);
        // On a flat part of a side (the normal along its axis): the marks pressed in.
        for (std::size_t s = 0; s < 6; ++s) {
            const SideAxes& a = kSideAxes[s];
            if (normal[a.axis] != a.sign) continue;
            p[a.axis] -= a.sign * markDepthAt(places, o, s, q[a.u], q[a.v]);
        }
        if (o.roughness > 0) p += normal * (o.roughness * signedUnit(hashKey(o.seed, kStreamRoughness, box.key(box.points[id]))));
        tablet.mesh.points[id] = p;
    });
    tablet.mesh.triangles = boxTriangles(box, tablet.mesh.points, o.seed);

    for (const MarkPlace& m : places) {
        const SideAxes& a = kSideAxes[m.side];
        TabletMark mark;
        mark.side = TabletSide(m.side);
        mark.centre[a.axis] = a.sign * half[std::size_t(a.axis)];
        mark.centre[a.u] = m.u;
        mark.centre[a.v] = m.v;
        mark.centre.z += mark.centre.z * bulge(mark.centre);
        mark.normal[a.axis] = a.sign;
        mark.radius = o.markRadius;
        mark.depth = o.markDepth;
        tablet.marks.push_back(mark);
    }
    return tablet;
}

// ---------------------------------------------------------------------------------------
// Height fields
// ---------------------------------------------------------------------------------------

namespace {

bool sameOptions(const HeightFieldOptions& a, const HeightFieldOptions& b)
{
    // Adding a field to HeightFieldOptions changes the size: compare it here too.
    static_assert(sizeof(HeightFieldOptions) == 16 * sizeof(double) + 2 * sizeof(std::uint64_t),
                  "update sameOptions for the new HeightFieldOptions field");
    return a.kind == b.kind && a.width == b.width && a.height == b.height && a.spacing == b.spacing &&
           a.closed == b.closed && a.thickness == b.thickness && a.wallStep == b.wallStep && a.relief == b.relief &&
           a.hillWidth == b.hillWidth && a.sag == b.sag && a.wedgeSize == b.wedgeSize &&
           a.wedgeDensity == b.wedgeDensity && a.wedgeMargin == b.wedgeMargin && a.noise == b.noise &&
           a.seed == b.seed && a.anisotropy == b.anisotropy && a.densityVariation == b.densityVariation &&
           a.roughness == b.roughness;
}

} // namespace

double heightFieldValue(const HeightFieldOptions& options, double x, double y)
{
    // Tests evaluate the surface point by point: keep the last few layouts per thread
    // (building one costs ~10 us, evaluating ~0.1 us). The cache holds only options that
    // were validated, and the result does not depend on it.
    struct Entry {
        HeightFieldOptions options;
        HeightFunction function;
    };
    thread_local std::vector<Entry> cache;
    thread_local std::size_t nextSlot = 0;
    for (const Entry& e : cache)
        if (sameOptions(e.options, options)) return e.function(x, y);
    Entry entry{options, HeightFunction(options)};
    const double z = entry.function(x, y);
    if (cache.size() < 4) {
        cache.push_back(std::move(entry));
    } else {
        cache[nextSlot] = std::move(entry);
        nextSlot = (nextSlot + 1) % cache.size();
    }
    return z;
}

/// The jittered (nx + 1) x (ny + 1) lattice of a height field (vertex (i, j) has index
/// j * (nx + 1) + i): interior vertices jittered in a disc, border ones along the border.
struct HeightLattice {
    int nx = 1, ny = 1;
    double width = 1, height = 1, reach = 0;
    double warp = 0;       ///< amplitude α of the density warp s + α sin(2πs) / (2π)
    double roughness = 0;  ///< HeightFieldOptions::roughness
    std::uint64_t seed = 1;
    std::size_t rowLength = 2;

    explicit HeightLattice(const HeightFieldOptions& options)
        : nx(latticeCells(options.width, options.spacing * std::sqrt(options.anisotropy))),
          ny(latticeCells(options.height, options.spacing / std::sqrt(options.anisotropy))), width(options.width),
          height(options.height), roughness(options.roughness), seed(options.seed), rowLength(std::size_t(nx) + 1)
    {
        reach = kJitter * std::min(width / nx, height / ny);
        // Spacing along each axis varies by (1 + α) / (1 − α) = sqrt(densityVariation).
        const double ratio = std::sqrt(options.densityVariation);
        warp = (ratio - 1) / (ratio + 1);
    }
    std::size_t numPoints() const { return rowLength * (std::size_t(ny) + 1); }
    std::uint32_t index(int i, int j) const { return std::uint32_t(std::size_t(j) * rowLength + std::size_t(i)); }
    std::array<double, 2> xy(int i, int j, std::uint64_t stream) const
    {
        const auto p = jittered(i, j, stream);
        if (warp == 0) return p;
        return {width * warped(p[0] / width), height * warped(p[1] / height)};
    }
    /// The top's z at lattice vertex (i, j), at (x, y) = xy(i, j, kStreamJitter).
    template <class Height> double z(const Height& h, int i, int j, double x, double y) const
    {
        const double value = h(x, y);
        if (roughness == 0) return value;
        return value + roughness * signedUnit(hashKey(seed, kStreamRoughness, std::uint64_t(j) * rowLength + std::uint64_t(i)));
    }

private:
    std::array<double, 2> jittered(int i, int j, std::uint64_t stream) const
    {
        double x = latticeCoord(i, nx, width), y = latticeCoord(j, ny, height);
        const bool borderX = i == 0 || i == nx, borderY = j == 0 || j == ny;
        if (borderX && borderY) return {x, y};
        const std::uint64_t h = hashKey(seed, stream, std::uint64_t(j) * rowLength + std::uint64_t(i));
        if (borderX) return {x, y + reach * signedUnit(h)};
        if (borderY) return {x + reach * signedUnit(h), y};
        const auto d = unitDiscPoint(h);
        return {x + reach * d[0], y + reach * d[1]};
    }
    /// Monotone on [0, 1] with fixed ends (the outline stays the rectangle).
    double warped(double s) const
    {
        if (s <= 0 || s >= 1) return s;
        return s + warp * std::sin(2 * kPi * s) / (2 * kPi);
    }
};

/// Closes the open top (border vertices at lattice positions i = 0, nx and j = 0, ny) with
/// walls and a bottom of long triangles: each side's fine border polyline is zipped to
/// bottom vertices about @p step apart, by their parameter along the side, and the bottom
/// is a fan around its centre (HeightFieldOptions::wallStep).
template <class TopIndex>
void addLongWalls(TriMesh& mesh, int nx, int ny, const TopIndex& top, double bottomZ, double step)
{
    // The four sides counter-clockwise seen from above, as top border vertices.
    std::vector<std::vector<std::uint32_t>> sides(4);
    for (int i = 0; i <= nx; ++i) sides[0].push_back(top(i, 0));
    for (int j = 0; j <= ny; ++j) sides[1].push_back(top(nx, j));
    for (int i = nx; i >= 0; --i) sides[2].push_back(top(i, ny));
    for (int j = ny; j >= 0; --j) sides[3].push_back(top(0, j));
    std::array<std::uint32_t, 4> corner{};  // bottom corners below the top's corners
    for (std::size_t k = 0; k < 4; ++k) {
        const Vec3 p = mesh.points[sides[k].front()];
        mesh.points.push_back({p.x, p.y, bottomZ});
        corner[k] = std::uint32_t(mesh.points.size() - 1);
    }
    std::vector<std::uint32_t> bottomRing;
    for (std::size_t k = 0; k < 4; ++k) {
        const std::vector<std::uint32_t>& side = sides[k];
        const Vec3 a = mesh.points[side.front()], b = mesh.points[side.back()];
        const int segments = std::max(1, int(std::lround(norm(b - a) / step)));
        std::vector<std::uint32_t> bottom{corner[k]};
        for (int q = 1; q < segments; ++q) {
            const Vec3 p = a + (b - a) * (double(q) / segments);
            mesh.points.push_back({p.x, p.y, bottomZ});
            bottom.push_back(std::uint32_t(mesh.points.size() - 1));
        }
        bottom.push_back(corner[(k + 1) % 4]);
        bottomRing.insert(bottomRing.end(), bottom.begin(), bottom.end() - 1);
        const double length = norm(Vec3(b.x - a.x, b.y - a.y, 0));
        const auto param = [&](std::uint32_t v) {
            const Vec3& p = mesh.points[v];
            return norm(Vec3(p.x - a.x, p.y - a.y, 0)) / length;
        };
        std::size_t i = 0, j = 0;
        while (i + 1 < side.size() || j + 1 < bottom.size()) {
            const bool advanceTop =
                j + 1 == bottom.size() || (i + 1 < side.size() && param(side[i + 1]) <= param(bottom[j + 1]));
            if (advanceTop) {
                mesh.triangles.push_back({side[i], bottom[j], side[i + 1]});
                ++i;
            } else {
                mesh.triangles.push_back({side[i], bottom[j], bottom[j + 1]});
                ++j;
            }
        }
    }
    Vec3 centre{0, 0, bottomZ};
    for (const std::uint32_t v : bottomRing) centre = centre + Vec3(mesh.points[v].x, mesh.points[v].y, 0);
    centre = {centre.x / double(bottomRing.size()), centre.y / double(bottomRing.size()), bottomZ};
    mesh.points.push_back(centre);
    const std::uint32_t c = std::uint32_t(mesh.points.size() - 1);
    for (std::size_t k = 0; k < bottomRing.size(); ++k)
        mesh.triangles.push_back({c, bottomRing[(k + 1) % bottomRing.size()], bottomRing[k]});
}

TriMesh makeHeightField(const HeightFieldOptions& options)
{
    const HeightFunction height(options);  // validates
    const HeightLattice lattice(options);
    const int nx = lattice.nx, ny = lattice.ny;
    const std::size_t rowLength = lattice.rowLength;
    const std::size_t numTop = lattice.numPoints();
    const int nz = options.closed ? latticeCells(options.thickness, options.spacing) : 0;
    const std::size_t perimeter = 2 * (std::size_t(nx) + std::size_t(ny));
    const std::size_t numBottomInterior = std::size_t(nx - 1) * std::size_t(ny - 1);
    requireVertexCount(double(numTop) + (options.closed ? double(nz) * double(perimeter) + double(numBottomInterior) : 0.0));

    const std::uint64_t seed = options.seed;
    const auto latticeXY = [&](int i, int j, std::uint64_t stream) { return lattice.xy(i, j, stream); };

    TriMesh mesh;
    mesh.points.resize(numTop);
    tbb::parallel_for(tbb::blocked_range<int>(0, ny + 1), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i <= nx; ++i) {
                const auto xy = latticeXY(i, j, kStreamJitter);
                mesh.points[std::size_t(j) * rowLength + std::size_t(i)] = {xy[0], xy[1], lattice.z(height, i, j, xy[0], xy[1])};
            }
    });
    const std::size_t numTopTriangles = 2 * std::size_t(nx) * std::size_t(ny);
    const auto topIndex = [rowLength](int i, int j) { return std::uint32_t(std::size_t(j) * rowLength + std::size_t(i)); };
    if (!options.closed) {
        mesh.triangles.resize(numTopTriangles);
        triangulateGrid(mesh.points, nx, ny, topIndex, seed, kStreamDiagonal, false, mesh.triangles.data());
        return mesh;
    }

    // ---- Closed slab: walls below the border, then the bottom. ----
    const double bottomZ = -options.thickness;
    double lowestTop = std::numeric_limits<double>::infinity();
    for (const Vec3& p : mesh.points) lowestTop = std::min(lowestTop, p.z);
    if (!(lowestTop > bottomZ))
        throw InvalidInputError("sample mesh: slab thickness " + formatNumber(options.thickness) +
                                " does not reach below the lowest top point (z = " + formatNumber(lowestTop) + ").");

    if (options.wallStep > 0) {
        mesh.triangles.resize(numTopTriangles);
        triangulateGrid(mesh.points, nx, ny, topIndex, seed, kStreamDiagonal, false, mesh.triangles.data());
        addLongWalls(mesh, nx, ny, topIndex, bottomZ, options.wallStep);
        return mesh;
    }
    // Perimeter positions, counter-clockwise seen from above (the way the top triangles run
    // along the border): bottom side +x, right side +y, top side -x, left side -y.
    std::vector<std::array<int, 2>> border(perimeter);
    {
        std::size_t p = 0;
        for (int i = 0; i < nx; ++i) border[p++] = {i, 0};
        for (int j = 0; j < ny; ++j) border[p++] = {nx, j};
        for (int i = nx; i > 0; --i) border[p++] = {i, ny};
        for (int j = ny; j > 0; --j) border[p++] = {0, j};
    }
    // Wall vertex (column p, row r), r = 1 .. nz; row nz is the bottom outline.
    const std::size_t wallBase = numTop;
    const auto wallIndex = [&](std::size_t p, int r) -> std::uint32_t {
        p %= perimeter;
        if (r == 0) return topIndex(border[p][0], border[p][1]);
        return std::uint32_t(wallBase + std::size_t(r - 1) * perimeter + p);
    };
    const std::size_t bottomBase = wallBase + std::size_t(nz) * perimeter;
    mesh.points.resize(bottomBase + numBottomInterior);
    // Wall rows divide each column evenly (inner rows jittered vertically by a quarter of a
    // row, which keeps every wall triangle valid: its two same-column vertices stay apart).
    tbb::parallel_for(std::size_t(0), perimeter, [&](std::size_t p) {
        const Vec3 top = mesh.points[topIndex(border[p][0], border[p][1])];
        const double dz = (top.z - bottomZ) / nz;
        for (int r = 1; r <= nz; ++r) {
            double z = r == nz ? bottomZ : top.z - dz * r;
            if (r < nz) z += 0.25 * dz * signedUnit(hashKey(seed, kStreamWallJitter, p, std::uint64_t(r)));
            mesh.points[wallIndex(p, r)] = {top.x, top.y, z};
        }
    });
    // Bottom: the lattice again, border shared with the walls' last row, interior jittered
    // by its own stream.
    std::vector<std::uint32_t> borderPosition(numTop, 0);  // top border vertex -> perimeter position
    for (std::size_t p = 0; p < perimeter; ++p) borderPosition[topIndex(border[p][0], border[p][1])] = std::uint32_t(p);
    const auto bottomIndex = [&](int i, int j) -> std::uint32_t {
        if (i == 0 || j == 0 || i == nx || j == ny) return wallIndex(borderPosition[topIndex(i, j)], nz);
        return std::uint32_t(bottomBase + std::size_t(j - 1) * std::size_t(nx - 1) + std::size_t(i - 1));
    };
    tbb::parallel_for(tbb::blocked_range<int>(1, std::max(ny, 1)), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 1; i < nx; ++i) {
                const auto xy = latticeXY(i, j, kStreamBottomJitter);
                mesh.points[bottomIndex(i, j)] = {xy[0], xy[1], bottomZ};
            }
    });

    const std::size_t numWallTriangles = 2 * perimeter * std::size_t(nz);
    mesh.triangles.resize(numTopTriangles + numWallTriangles + 2 * std::size_t(nx) * std::size_t(ny));
    Triangle* out = mesh.triangles.data();
    triangulateGrid(mesh.points, nx, ny, topIndex, seed, kStreamDiagonal, false, out);
    // Walls: grid (perimeter position, row downwards); reversed so each wall quad runs
    // along the top border edge opposite to the top triangle (outward normals).
    const auto wallGrid = [&](int p, int r) { return wallIndex(std::size_t(p), r); };
    triangulateGrid(mesh.points, int(perimeter), nz, wallGrid, seed, kStreamWallDiagonal, true, out + numTopTriangles);
    triangulateGrid(mesh.points, nx, ny, bottomIndex, seed, kStreamBottomDiagonal, true,
                    out + numTopTriangles + numWallTriangles);
    return mesh;
}

StreamedMeshCounts writeHeightFieldPly(const HeightFieldOptions& options, const std::string& path,
                                       const WritePlyOptions& plyOptions)
{
    if (options.closed) throw InvalidInputError("sample mesh: only open height fields are streamed (no --closed).");
    if (!plyOptions.binary || plyOptions.listLength > 0)
        throw InvalidInputError("sample mesh: streamed files are binary PLY without list properties.");
    static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "binary_little_endian by copying memory");
    const HeightFunction height(options);  // validates
    const HeightLattice lattice(options);
    const int nx = lattice.nx, ny = lattice.ny;
    const std::size_t numPoints = lattice.numPoints();
    requireVertexCount(double(numPoints));
    const std::size_t numTriangles = 2 * std::size_t(nx) * std::size_t(ny);
    const bool doublePoints = plyOptions.forceDoublePoints;
    // writePly stores float unless that moves a coordinate by more than 1e-7 of the bounding
    // box diagonal, which is at least this (the corners (0, 0) and (w, h) are vertices).
    const double floatTolerance = 1e-7 * std::sqrt(options.width * options.width + options.height * options.height);
    const std::size_t pointBytes = doublePoints ? 3 * sizeof(double) : 3 * sizeof(float);

    checkWritable(path);
    AtomicFile file(path);
    const std::string header = plyHeader(numPoints, numTriangles, {}, plyOptions, doublePoints);
    file.write(header);
    const std::uint64_t facesAt = header.size() + std::uint64_t(numPoints) * pointBytes;

    // Bands of rows: the points of rows [j0, j1] (row j1 shared with the next band for its
    // quads), then the vertex records of rows [j0, j1) and the triangles of quad rows
    // [j0, j1), each band written in order (vertices sequentially, triangles at their place).
    const int band = 64;
    const std::size_t rowLength = lattice.rowLength;
    std::vector<Vec3> points;
    std::vector<char> vertexBytes, triangleBytes;
    std::vector<Triangle> triangles;
    for (int j0 = 0; j0 <= ny; j0 += band) {
        const int j1 = std::min(ny, j0 + band);  // last row computed
        const int rows = j1 - j0 + 1;
        points.resize(std::size_t(rows) * rowLength);
        tbb::parallel_for(tbb::blocked_range<int>(j0, j1 + 1), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j != r.end(); ++j)
                for (int i = 0; i <= nx; ++i) {
                    const auto xy = lattice.xy(i, j, kStreamJitter);
                    points[std::size_t(j - j0) * rowLength + std::size_t(i)] = {xy[0], xy[1], lattice.z(height, i, j, xy[0], xy[1])};
                }
        });
        // Vertex records of rows [j0, j1), and of the last row with the last band.
        const int lastVertexRow = j1 == ny ? j1 : j1 - 1;
        const std::size_t count = std::size_t(lastVertexRow - j0 + 1) * rowLength;
        vertexBytes.resize(count * pointBytes);
        char* out = vertexBytes.data();
        for (std::size_t k = 0; k < count; ++k) {
            const Vec3& p = points[k];
            for (int c = 0; c < 3; ++c) {
                const double v = p[c];
                if (doublePoints) {
                    std::memcpy(out, &v, sizeof(double));
                    out += sizeof(double);
                } else {
                    const float f = float(v);
                    if (!(std::abs(double(f) - v) <= floatTolerance))
                        throw InvalidInputError("sample mesh: coordinates need double precision (use --double).");
                    std::memcpy(out, &f, sizeof(float));
                    out += sizeof(float);
                }
            }
        }
        file.write(vertexBytes.data(), vertexBytes.size());
        // Triangles of quad rows [j0, j1).
        if (j1 > j0) {
            triangles.resize(2 * std::size_t(j1 - j0) * std::size_t(nx));
            tbb::parallel_for(tbb::blocked_range<int>(j0, j1), [&](const tbb::blocked_range<int>& r) {
                for (int j = r.begin(); j != r.end(); ++j)
                    for (int i = 0; i < nx; ++i) {
                        const std::size_t q = std::size_t(j) * std::size_t(nx) + std::size_t(i);
                        const auto at = [&](int di, int dj) -> const Vec3& {
                            return points[std::size_t(j + dj - j0) * rowLength + std::size_t(i + di)];
                        };
                        quadTriangles(lattice.index(i, j), lattice.index(i + 1, j), lattice.index(i + 1, j + 1),
                                      lattice.index(i, j + 1), at(0, 0), at(1, 0), at(1, 1), at(0, 1), options.seed,
                                      kStreamDiagonal, q, false,
                                      triangles.data() + 2 * (std::size_t(j - j0) * std::size_t(nx) + std::size_t(i)));
                    }
            });
            formatPlyFaces(triangles.data(), triangles.size(), triangleBytes);
            const std::uint64_t firstTriangle = 2 * std::uint64_t(j0) * std::uint64_t(nx);
            file.writeAt(facesAt + firstTriangle * kPlyFaceBytes, triangleBytes.data(), triangleBytes.size());
        }
        if (j1 == ny) break;
    }
    file.commit();
    return {numPoints, numTriangles};
}

Dem makeDem(const DemSampleOptions& options)
{
    const HeightFieldOptions& f = options.surface;
    heightFieldValue(f, 0.0, 0.0);  // validates the sizes
    const double h = f.spacing;
    const int cols = std::max(2, int(std::lround(f.width / h))), rows = std::max(2, int(std::lround(f.height / h)));
    Dem dem;
    RasterGeoreference& g = dem.georeference;
    g.width = cols;
    g.height = rows;
    g.transform = {options.west, h, 0.0, options.north, 0.0, -h};
    g.crsWkt = crsWkt(options.crs);
    dem.heights.resize(std::size_t(cols) * std::size_t(rows));
    // Cell (col, row)'s centre is at local (x, y) = ((col + ½) h, height − (row + ½) h): the
    // surface of makeHeightField, with y up as in the mesh.
    tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const auto& r) {
        for (int row = r.begin(); row < r.end(); ++row)
            for (int col = 0; col < cols; ++col)
                dem.heights[std::size_t(row) * std::size_t(cols) + std::size_t(col)] =
                    float(options.baseHeight + heightFieldValue(f, (col + 0.5) * h, f.height - (row + 0.5) * h));
    });
    // Nodata patches: seeded centres and radii (one cell up to patchRadius).
    const double largest = options.patchRadius > 0 ? options.patchRadius : 2.0 * h;
    for (std::size_t k = 0; k < options.nodataPatches; ++k) {
        const double cx = unitInterval(hashKey(f.seed, kStreamHoles, 2 * k)) * cols;
        const double cy = unitInterval(hashKey(f.seed, kStreamHoles, 2 * k + 1)) * rows;
        const double radius = (h + unitInterval(hashKey(f.seed, kStreamHoles, k, 7)) * std::max(0.0, largest - h)) / h;
        for (int row = std::max(0, int(cy - radius - 1)); row < std::min(rows, int(cy + radius + 2)); ++row)
            for (int col = std::max(0, int(cx - radius - 1)); col < std::min(cols, int(cx + radius + 2)); ++col)
                if (std::hypot(col + 0.5 - cx, row + 0.5 - cy) <= radius)
                    dem.heights[std::size_t(row) * std::size_t(cols) + std::size_t(col)] =
                        std::numeric_limits<float>::quiet_NaN();
    }
    for (float v : dem.heights) dem.numValid += std::isnan(v) ? 0 : 1;
    return dem;
}

HoleReport punchHoles(TriMesh& mesh, const HoleOptions& options)
{
    if (!(options.minSize > 0) || !(options.maxSize >= options.minSize) || !std::isfinite(options.maxSize))
        throw InvalidInputError("hole sizes must be positive with minSize <= maxSize");
    HoleReport report;
    if (options.count == 0 || mesh.empty()) return report;
    // Centres: seeded vertices, each at least 2 maxSize + minSize from the others (holes
    // stay apart), tried in a fixed order so the result depends on the seed alone.
    const double apart = 2.0 * options.maxSize + options.minSize;
    std::vector<std::uint32_t> centres;
    std::vector<double> radii;
    for (std::uint64_t k = 0; centres.size() < options.count && k < 64 * options.count + 1000; ++k) {
        const std::uint32_t v = std::uint32_t(hashKey(options.seed, kStreamHoles, k) % mesh.numVertices());
        const Vec3& p = mesh.points[v];
        bool free = true;
        for (std::uint32_t c : centres) free = free && norm(mesh.points[c] - p) > apart;
        if (!free) continue;
        centres.push_back(v);
        radii.push_back(options.minSize + (options.maxSize - options.minSize) *
                                              unitInterval(hashKey(options.seed, kStreamHoles, k, 1)));
    }
    // A face goes when one of its vertices lies within its hole's radius of the centre.
    std::vector<char> gone(mesh.numVertices(), 0);
    for (std::size_t h = 0; h < centres.size(); ++h) {
        const Vec3& c = mesh.points[centres[h]];
        for (std::size_t v = 0; v < mesh.numVertices(); ++v)
            if (norm(mesh.points[v] - c) <= radii[h]) gone[v] = 1;
        gone[centres[h]] = 1;
    }
    const std::size_t before = mesh.numTriangles();
    mesh.triangles.erase(std::remove_if(mesh.triangles.begin(), mesh.triangles.end(),
                                        [&](const Triangle& t) { return gone[t[0]] || gone[t[1]] || gone[t[2]]; }),
                         mesh.triangles.end());
    report.holes = centres.size();
    report.facesRemoved = before - mesh.numTriangles();
    return report;
}

} // namespace msii::samples
