#include <msii/invariants/exact.h>

#include <msii/core/errors.h>
#include <msii/invariants/scales.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <unordered_set>
#include <utility>

namespace msii {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

inline double sign(double x) { return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0); }

/// Integrals over one triangle ∩ B_r (TriangleBallMeasures without the distance).
struct Measures {
    double area = 0, arcLength = 0, solidAngle = 0;
};

// ---------------------------------------------------------------------------------------
// Sector integrals (docs/method.md, Exact identities and Per triangle). In the triangle's
// plane, with the foot point c of p as origin, the triangle is the signed sum of the
// sectors (c, A, B) of its directed edges, sign σ = sign((A − c) × (B − c)). Within one
// sector, polar coordinates (s, φ) about c, φ measured from the perpendicular onto the
// edge's line (distance e): the region is s <= m(φ) = min(ρ, e / cos φ), where the disc
// bounds it for |φ| > φ* = arccos(e/ρ) (everywhere if e >= ρ) and the line elsewhere. A
// point of the line at coordinate t along the edge (t = 0 at the perpendicular's foot) has
// tan φ = t/e, so the pieces are split at t = ±t*, t* = sqrt(ρ² − e²), and integrated in
// closed form:
//   area  ∫∫ s ds dφ:            disc ½ρ²Δφ,  line ½e²Δ tan φ = ½eΔt;
//   arc   d area / dρ:           disc ρΔφ,    line 0;
//   solid ∫∫ d s/(d² + s²)^{3/2} ds dφ:  disc (sgn d − d/r)Δφ,
//                                line sgn d·[Δφ − Δ asin(|d| sin φ / sqrt(d² + e²))],
// with asin(|d| sin φ / sqrt(d² + e²)) = atan2(|d| t, e·sqrt(d² + e² + t²)) (atan2 keeps
// full precision where the asin argument nears 1).

/// Adds σ × the integrals of the sector (0, a, b) ∩ disc(ρ) to @p m (2D coordinates).
void addSector(double ax, double ay, double bx, double by, double rho, double d, double r,
               bool solid, Measures& m)
{
    const double wx = bx - ax, wy = by - ay;
    const double len = std::sqrt(wx * wx + wy * wy);
    if (!(len > 0)) return;
    const double ux = wx / len, uy = wy / len;
    const double h = ax * uy - ay * ux;  // signed distance of the edge's line from c
    if (h == 0) return;                  // c on the line: the sector has no area
    const double sigma = h > 0 ? 1.0 : -1.0, e = std::abs(h);
    const double tA = ax * ux + ay * uy, tB = bx * ux + by * uy;
    const double sd = sign(d), ad = std::abs(d);

    // Angle between the rays to the line points t1 <= t2 (always in [0, π)).
    const auto dphi = [&](double t1, double t2) { return std::atan2(e * (t2 - t1), e * e + t1 * t2); };
    const auto psi = [&](double t) { return std::atan2(ad * t, e * std::sqrt(d * d + e * e + t * t)); };

    double area = 0, arc = 0, omega = 0;
    const auto disc = [&](double t1, double t2) {
        if (!(t2 > t1)) return;
        const double phi = dphi(t1, t2);
        area += 0.5 * rho * rho * phi;
        arc += rho * phi;
        if (solid) omega += (sd - d / r) * phi;
    };
    const auto line = [&](double t1, double t2) {
        if (!(t2 > t1)) return;
        area += 0.5 * e * (t2 - t1);
        if (solid && d != 0) omega += sd * (dphi(t1, t2) - (psi(t2) - psi(t1)));
    };
    if (e >= rho) {
        disc(tA, tB);
    } else {
        const double ts = std::sqrt((rho - e) * (rho + e));
        disc(tA, std::min(tB, -ts));
        line(std::max(tA, -ts), std::min(tB, ts));
        disc(std::max(tA, ts), tB);
    }
    m.area += sigma * area;
    m.arcLength += sigma * arc;
    m.solidAngle += sigma * omega;
}

/// Distance from the origin to the 2D triangle (x, y), counter-clockwise.
double originTriangleDistance2D(const double x[3], const double y[3])
{
    bool inside = true;
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
        const int k = (i + 1) % 3;
        const double wx = x[k] - x[i], wy = y[k] - y[i];
        if (wx * (-y[i]) - wy * (-x[i]) < 0) inside = false;  // origin right of the edge
        const double w2 = wx * wx + wy * wy;
        const double t = w2 > 0 ? std::clamp(-(x[i] * wx + y[i] * wy) / w2, 0.0, 1.0) : 0.0;
        const double fx = x[i] + t * wx, fy = y[i] + t * wy;
        best = std::min(best, std::sqrt(fx * fx + fy * fy));
    }
    return inside ? 0.0 : best;
}

/// Per-triangle constants, computed once for the mesh.
struct TriangleFrame {
    Vec3 n, t1, t2;  // unit normal and an orthonormal frame of the plane, t1 × t2 = n
    double area = 0;
    Vec3 centroid;   // with boundingRadius: a sphere around the triangle, to skip far ones fast
    double boundingRadius = 0;
};

TriangleFrame makeFrame(const Vec3& a, const Vec3& b, const Vec3& c)
{
    TriangleFrame f;
    const Vec3 nn = cross(b - a, c - a);
    f.area = 0.5 * norm(nn);
    f.n = normalized(nn);
    f.t1 = normalized(b - a);
    f.t2 = cross(f.n, f.t1);
    f.centroid = (a + b + c) / 3.0;
    f.boundingRadius = std::sqrt(std::max({squaredNorm(a - f.centroid), squaredNorm(b - f.centroid),
                                           squaredNorm(c - f.centroid)}));
    return f;
}

/// A complex number, for sums of angles as arguments of products (one atan2 for many).
struct Complex {
    double re = 1, im = 0;
    void multiply(double r, double i)
    {
        const double t = re * r - im * i;
        im = re * i + im * r;
        re = t;
    }
    double arg() const { return std::atan2(im, re); }
};

/// Van Oosterom and Strackee's formula for the solid angle Ω of the triangle q (corners
/// relative to p, at distances la, lb, lc): Ω/2 = arg(|a||b||c| + (a·b)|c| + (a·c)|b| +
/// (b·c)|a| + i a·(b×c)) (a·(b×c) = 2·area·d, so Ω has the sign of d).
Complex vanOosterom(const std::array<Vec3, 3>& q, double la, double lb, double lc)
{
    const Vec3 &a = q[0], &b = q[1], &c = q[2];
    return {la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la, dot(a, cross(b, c))};
}

/// One triangle as seen from p: everything that does not depend on the radius.
class LocalTriangle {
public:
    LocalTriangle(const Vec3& p, const std::array<Vec3, 3>& corners, const TriangleFrame& frame)
        : LocalTriangle({corners[0] - p, corners[1] - p, corners[2] - p}, frame)
    {
    }

    /// @p q: the corners relative to p.
    LocalTriangle(const std::array<Vec3, 3>& q, const TriangleFrame& frame) : mQ(q), mArea(frame.area)
    {
        int nearest = 0;
        double far2 = 0, near2 = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
            const double q2 = squaredNorm(q[i]);
            if (q2 < near2) near2 = q2, nearest = i;
            far2 = std::max(far2, q2);
            // c − p is along n, so coordinates relative to p are those relative to c.
            mX[i] = dot(q[i], frame.t1);
            mY[i] = dot(q[i], frame.t2);
        }
        // From the nearest corner: least rounding, and exactly 0 when p is a corner
        // (the triangles at p must not contribute to Σ Ω_t; their part is Ω_p).
        mD = dot(q[nearest], frame.n);
        mFar = std::sqrt(far2);
        const double inPlane = originTriangleDistance2D(mX, mY);
        mNear = std::sqrt(mD * mD + inPlane * inPlane);
    }

    double distance() const { return mD; }
    double nearestDistance() const { return mNear; }  ///< distance from p to the triangle
    double farthestDistance() const { return mFar; }  ///< distance from p to its farthest corner

    /// The whole triangle (inside the ball): area, no arc, solid angle (vanOosterom()).
    Measures whole(bool solid) const
    {
        Measures m;
        m.area = mArea;
        if (solid && mD != 0) m.solidAngle = 2.0 * vanOosterom(mQ, norm(mQ[0]), norm(mQ[1]), norm(mQ[2])).arg();
        return m;
    }

    /// The triangle ∩ B_r for any r, by the sector decomposition.
    Measures sectors(double r, bool solid) const
    {
        Measures m;
        const double ad = std::abs(mD);
        if (!(r > ad)) return m;
        const double rho = std::sqrt((r - ad) * (r + ad));
        for (int i = 0; i < 3; ++i) {
            const int k = (i + 1) % 3;
            addSector(mX[i], mY[i], mX[k], mY[k], rho, mD, r, solid, m);
        }
        return m;
    }

    /// The triangle ∩ B_r: nothing, the whole triangle, or the sectors.
    Measures measure(double r, bool solid) const
    {
        if (r <= mNear) return {};
        if (r >= mFar) return whole(solid);
        return sectors(r, solid);
    }

private:
    std::array<Vec3, 3> mQ;
    double mArea;
    double mX[3], mY[3];
    double mD, mNear, mFar;
};

// ---------------------------------------------------------------------------------------
// The cone at a vertex (S/r² = Ω_p − Σ Ω_t needs Ω_p, the limit of S(ε)/ε²).

/// Triangles incident to each vertex (CSR), with the corner at which the vertex sits.
struct VertexFaces {
    std::vector<std::uint32_t> first;                       // numVertices + 1
    std::vector<std::pair<std::uint32_t, std::uint8_t>> faces;  // (triangle, corner)
};

VertexFaces vertexFaces(const TriMesh& mesh)
{
    VertexFaces vf;
    vf.first.assign(mesh.numVertices() + 1, 0);
    for (const Triangle& t : mesh.triangles)
        for (int i = 0; i < 3; ++i) ++vf.first[t[i] + 1];
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) vf.first[v + 1] += vf.first[v];
    vf.faces.resize(vf.first.back());
    std::vector<std::uint32_t> fill(vf.first.begin(), vf.first.end() - 1);
    for (std::size_t t = 0; t < mesh.numTriangles(); ++t)
        for (int i = 0; i < 3; ++i)
            vf.faces[fill[mesh.triangles[t][i]]++] = {std::uint32_t(t), std::uint8_t(i)};
    return vf;
}

/// Solid angle of the solid's cone at vertex v. On the unit sphere about v the cone is a
/// spherical polygon with a geodesic side per incident triangle and a corner per incident
/// edge e, where its interior angle is the solid's interior dihedral angle δ_e at e (π flat,
/// < π convex, > π concave). Girard: Ω = Σ_e δ_e − (k − 2)π over the k edges (flat 2π,
/// convex cube corner π/2). NaN if an edge at v has no second triangle (border), or if the
/// triangles at v fold over one another.
double coneSolidAngle(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                      const VertexFaces& vf, std::uint32_t v)
{
    const std::uint32_t begin = vf.first[v], end = vf.first[v + 1];
    const std::size_t k = end - begin;
    if (k < 3) return kNaN;
    double sum = 0;
    for (std::uint32_t f = begin; f < end; ++f) {
        const auto [t, i] = vf.faces[f];
        // Edge v → q of triangle t; its twin q → v lies in the triangle where q precedes v.
        const std::uint32_t q = mesh.triangles[t][(i + 1) % 3];
        std::uint32_t twin = UINT32_MAX;
        for (std::uint32_t g = begin; g < end; ++g) {
            const auto [u, j] = vf.faces[g];
            if (mesh.triangles[u][(j + 2) % 3] == q) {
                twin = u;
                break;
            }
        }
        if (twin == UINT32_MAX) return kNaN;
        const Vec3& n1 = frames[t].n;
        const Vec3& n2 = frames[twin].n;
        const Vec3 e = normalized(mesh.points[q] - mesh.points[v]);
        // The normals turn by θ about e (positive: convex fold); δ = π − θ.
        sum += kPi - std::atan2(dot(cross(n1, n2), e), dot(n1, n2));
    }
    // A cone is a simple closed curve on the unit sphere, enclosing 0 < Ω < 4π. Outside
    // that range the triangles at v fold over one another (a crumpled patch of a scan), the
    // curve crosses itself and the solid is not defined at v: NaN.
    const double omega = sum - double(k - 2) * kPi;
    return omega > 0 && omega < 4 * kPi ? omega : kNaN;
}

// ---------------------------------------------------------------------------------------
// Uniform grid of triangles by centroid: a query box grown by the largest centroid-corner
// distance finds every triangle that meets a ball. computeExact() keeps the triangles much
// larger than a cell in a second grid, so that a few long triangles (a scan's walls and
// bottom, a hole's fill) do not widen every query.

class TriangleGrid {
public:
    /// A grid of @p triangles (indices into @p frames), sorted by cell.
    TriangleGrid(const std::vector<TriangleFrame>& frames, const std::vector<std::uint32_t>& triangles,
                 double cellSize)
    {
        const std::size_t nt = triangles.size();
        Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
        for (const std::uint32_t t : triangles) {
            mReach = std::max(mReach, frames[t].boundingRadius);
            for (int i = 0; i < 3; ++i) {
                lo[i] = std::min(lo[i], frames[t].centroid[i]);
                hi[i] = std::max(hi[i], frames[t].centroid[i]);
            }
        }
        if (nt == 0) lo = hi = Vec3(0, 0, 0);
        mOrigin = lo;
        // At most ~1e6 cells per axis, so the packed keys cannot overflow.
        const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        mCell = std::max({cellSize, extent * 1e-6, std::numeric_limits<double>::min()});
        for (int i = 0; i < 3; ++i) mCount[i] = std::int64_t(std::floor((hi[i] - lo[i]) / mCell)) + 1;
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(nt);
        for (std::size_t s = 0; s < nt; ++s) {
            const Vec3& centroid = frames[triangles[s]].centroid;
            std::int64_t c[3];
            for (int i = 0; i < 3; ++i) c[i] = clampIndex(i, (centroid[i] - mOrigin[i]) / mCell);
            keyed[s] = {key(c[0], c[1], c[2]), triangles[s]};
        }
        std::sort(keyed.begin(), keyed.end());
        mTriangles.resize(nt);
        for (std::size_t s = 0; s < nt; ++s) {
            mTriangles[s] = keyed[s].second;
            if (s == 0 || keyed[s].first != keyed[s - 1].first) {
                mKeys.push_back(keyed[s].first);
                mFirst.push_back(std::uint32_t(s));
            }
        }
        mFirst.push_back(std::uint32_t(nt));
    }

    std::size_t size() const { return mTriangles.size(); }
    /// The triangle in slot @p s: slots run cell by cell, so a cell's triangles lie together.
    std::uint32_t triangleAt(std::size_t s) const { return mTriangles[s]; }

    /// Calls @p visit(slot) for the slots of every cell that may hold a triangle meeting
    /// B_radius(p), each once, in an order that depends only on p and the radius.
    template <class Visit> void forEachNear(const Vec3& p, double radius, Visit&& visit) const
    {
        const double reach = radius + mReach;
        // Cells are culled by their distance to p (with a margin for rounding in the binning).
        const double cellReach = reach + 1e-6 * mCell, cellReach2 = cellReach * cellReach;
        std::int64_t lo[3], hi[3];
        for (int i = 0; i < 3; ++i) {
            lo[i] = clampIndex(i, (p[i] - reach - mOrigin[i]) / mCell);
            hi[i] = clampIndex(i, (p[i] + reach - mOrigin[i]) / mCell);
        }
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
            const double gx = gap(0, x, p.x);
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                const double gy = gap(1, y, p.y), gxy = gx * gx + gy * gy;
                if (gxy > cellReach2) continue;
                // A column's cells are consecutive keys: one search, then a walk.
                const std::uint64_t column = key(x, y, 0), last = column + std::uint64_t(hi[2]);
                auto it = std::lower_bound(mKeys.begin(), mKeys.end(), column + std::uint64_t(lo[2]));
                for (; it != mKeys.end() && *it <= last; ++it) {
                    const double gz = gap(2, std::int64_t(*it - column), p.z);
                    if (gxy + gz * gz > cellReach2) continue;
                    const std::size_t cell = std::size_t(it - mKeys.begin());
                    for (std::uint32_t s = mFirst[cell]; s < mFirst[cell + 1]; ++s) visit(s);
                }
            }
        }
    }

private:
    /// Distance along @p axis from @p coordinate to the cells of index @p index.
    double gap(int axis, std::int64_t index, double coordinate) const
    {
        const double lo = mOrigin[axis] + double(index) * mCell, hi = lo + mCell;
        return coordinate < lo ? lo - coordinate : (coordinate > hi ? coordinate - hi : 0.0);
    }
    std::int64_t clampIndex(int axis, double coordinate) const
    {
        if (!(coordinate > 0)) return 0;  // also NaN
        if (coordinate >= double(mCount[axis] - 1)) return mCount[axis] - 1;
        return std::int64_t(std::floor(coordinate));
    }
    std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) const
    {
        return (std::uint64_t(x) * std::uint64_t(mCount[1]) + std::uint64_t(y)) * std::uint64_t(mCount[2]) +
               std::uint64_t(z);
    }

    Vec3 mOrigin;
    double mCell = 1, mReach = 0;
    std::int64_t mCount[3] = {1, 1, 1};
    std::vector<std::uint64_t> mKeys;
    std::vector<std::uint32_t> mFirst, mTriangles;
};

// ---------------------------------------------------------------------------------------
// The per-vertex sums. Every triangle near p adds to the radii whose sphere it straddles
// (sectors) and, once, to the first radius whose ball holds it whole: a difference array
// over the radii, summed at the end. The formulas are LocalTriangle's, arranged so that
// most triangles cost no transcendental call:
// - whole triangles: the solid angles Ω_t of one radius are summed as arguments of a
//   product of Van Oosterom's complex numbers (vanOosterom()), one atan2 for many
//   triangles. A triangle inside a sphere of radius ρ_t at distance D from p subtends at
//   most 2π(1 − sqrt(1 − ρ_t²/D²)) <= 2πρ_t²/D², and the product is resolved before these
//   bounds of its half-angles reach π/2, so its argument is never wrapped;
// - straddled triangles: the signed sector angles of the three edges add up to Φ = 2π if
//   the foot point c lies inside the triangle and 0 if outside, so the disc pieces
//   together span Φ − Σ σΔφ over the line pieces (edge inside the disc), and only those
//   are evaluated. Over the line pieces, Σ σΔφ/2 is the argument of a product of
//   half-angle numbers |X1||X2| + X1·X2 + i X1×X2, and their solid angle Σ σ sgn(d)(Δφ −
//   Δψ) is twice the argument of a product of Van Oosterom's numbers for the triangles
//   (c, X1, X2). Both sums lie in [0, 2π) (c inside) or (−π, π) (c outside: the pieces
//   lie within the triangle's angle at c, less than π), so the halved arguments are
//   recovered exactly, with one unwrap near π when c is inside. At a piece's end the
//   distance to p is r (cut by the sphere) or the corner's distance. When c is close to
//   an edge's line these products lose precision (X1 and X2 nearly opposite), and
//   LocalTriangle's sectors are used instead.

/// A triangle with what the per-vertex loop needs, stored in grid-slot order; its bounding
/// sphere, which every visited triangle is tested against, is kept apart (SlotBound).
struct SlotTriangle {
    Vec3 corner[3];
    Vec3 n;
    double area;
    Vec3 t1, t2;
    // Edge i → i + 1 in the frame (t1, t2) with corner 0 as origin: unit direction u, the
    // start's coordinates across (corner_i × u) and along (corner_i · u), and the length.
    double ux[3], uy[3], across[3], along[3], length[3];
};
struct SlotBound {
    Vec3 centroid;
    double radius;
};

SlotTriangle makeSlot(const TriMesh& mesh, const TriangleFrame& f, std::uint32_t t)
{
    SlotTriangle s;
    for (int i = 0; i < 3; ++i) s.corner[i] = mesh.points[mesh.triangles[t][i]];
    s.n = f.n;
    s.area = f.area;
    s.t1 = f.t1;
    s.t2 = f.t2;
    double x[3], y[3];
    for (int i = 0; i < 3; ++i) {
        x[i] = dot(s.corner[i] - s.corner[0], f.t1);
        y[i] = dot(s.corner[i] - s.corner[0], f.t2);
    }
    for (int i = 0; i < 3; ++i) {
        const int k = (i + 1) % 3;
        const double wx = x[k] - x[i], wy = y[k] - y[i];
        s.length[i] = std::sqrt(wx * wx + wy * wy);
        s.ux[i] = wx / s.length[i];
        s.uy[i] = wy / s.length[i];
        s.across[i] = x[i] * s.uy[i] - y[i] * s.ux[i];
        s.along[i] = x[i] * s.ux[i] + y[i] * s.uy[i];
    }
    return s;
}

/// How many of the first n radii lie below a distance, from a table over the squared
/// distance (a start that is never too high, and within a step or two) and a short walk.
class RadiusCounter {
public:
    explicit RadiusCounter(const std::vector<double>& radii) : mRadii2(radii.size())
    {
        double gap = std::numeric_limits<double>::infinity(), previous = 0;
        for (std::size_t j = 0; j < radii.size(); ++j) {
            mRadii2[j] = radii[j] * radii[j];
            gap = std::min(gap, mRadii2[j] - previous);
            previous = mRadii2[j];
        }
        // Bins of half the smallest gap between squared radii, at most 2^16 of them.
        const double bins = std::clamp(std::ceil(2 * mRadii2.back() / gap), 1.0, 65536.0);
        mScale = bins / mRadii2.back();
        mStart.resize(std::size_t(bins) + 2);
        for (std::size_t b = 0; b < mStart.size(); ++b) {
            const double x2 = double(b) / mScale * (1 - 1e-12);
            mStart[b] = std::uint32_t(std::lower_bound(mRadii2.begin(), mRadii2.end(), x2) - mRadii2.begin());
        }
    }
    double squared(std::size_t j) const { return mRadii2[j]; }  ///< r_j²
    /// count(r_j² < x2) over j < n.
    std::size_t below(double x2, std::size_t n) const
    {
        std::size_t j = std::min<std::size_t>(start(x2), n);
        while (j < n && mRadii2[j] < x2) ++j;
        return j;
    }
    /// count(r_j² <= x2) over j < n.
    std::size_t atMost(double x2, std::size_t n) const
    {
        std::size_t j = std::min<std::size_t>(start(x2), n);
        while (j < n && mRadii2[j] <= x2) ++j;
        return j;
    }

private:
    std::uint32_t start(double x2) const
    {
        const double b = x2 * mScale;
        return b < double(mStart.size() - 1) ? mStart[std::size_t(b)] : mStart.back();
    }
    std::vector<double> mRadii2;
    std::vector<std::uint32_t> mStart;
    double mScale = 1;
};

/// A triangle whose spheres about p it may straddle: its edges in its plane, origin c.
struct Straddler {
    double d = 0, near2 = 0;
    double e[3], sigma[3], tA[3], tB[3], distance2[3];
    bool inside = false, precise = true;  ///< c inside; fastMeasures() is accurate

    Straddler(const SlotTriangle& s, const std::array<Vec3, 3>& q, const double q2[3], int nearest)
        : distance2{q2[0], q2[1], q2[2]}
    {
        // c relative to corner 0; LocalTriangle computes the corners' coordinates from p
        // instead, so that they are exactly 0 at p, which matters only when c is near an
        // edge's line, where this falls back to it anyway (precise).
        const double x0 = dot(q[0], s.t1), y0 = dot(q[0], s.t2);
        d = dot(q[nearest], s.n);
        const double far2 = std::max({q2[0], q2[1], q2[2]});
        int positive = 0;
        double inPlane2 = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
            const double h = x0 * s.uy[i] - y0 * s.ux[i] + s.across[i];
            sigma[i] = h > 0 ? 1.0 : -1.0;
            positive += h > 0;
            e[i] = std::abs(h);
            tA[i] = x0 * s.ux[i] + y0 * s.uy[i] + s.along[i];
            tB[i] = tA[i] + s.length[i];
            // The angles at c lose ~ 1e-16 far / e: keep e above 1e-4 of the corners' reach.
            if (!(e[i] * e[i] > 1e-8 * far2)) precise = false;
            const double along = tA[i] > 0 ? tA[i] : (tB[i] < 0 ? tB[i] : 0.0);
            inPlane2 = std::min(inPlane2, e[i] * e[i] + along * along);
        }
        inside = positive == 3;  // counter-clockwise: c inside iff left of every edge
        near2 = d * d + (inside ? 0.0 : inPlane2);
    }

    /// triangle ∩ B_r (module comment above); requires precise.
    Measures fastMeasures(double r, bool solid) const
    {
        Measures m;
        const double ad = std::abs(d);
        if (!(r > ad)) return m;
        const double rho2 = (r - ad) * (r + ad), rho = std::sqrt(rho2);
        const double sd = sign(d);
        double lineArea = 0;
        Complex angle, omega;
        for (int i = 0; i < 3; ++i) {
            if (e[i] >= rho) continue;
            const double ts = std::sqrt((rho - e[i]) * (rho + e[i]));
            const bool cutA = tA[i] < -ts, cutB = tB[i] > ts;
            const double t1 = cutA ? -ts : tA[i], t2 = cutB ? ts : tB[i];
            if (!(t2 > t1)) continue;
            const double e2 = e[i] * e[i];
            const double crossX = sigma[i] * e[i] * (t2 - t1), dotX = e2 + t1 * t2;  // X1 × X2, X1 · X2
            lineArea += 0.5 * crossX;
            angle.multiply(std::sqrt((e2 + t1 * t1) * (e2 + t2 * t2)) + dotX, crossX);
            if (solid && d != 0) {
                const double l1 = cutA ? r : std::sqrt(distance2[i]), l2 = cutB ? r : std::sqrt(distance2[(i + 1) % 3]);
                // Van Oosterom for (c, X1, X2) seen from p, divided by |d|.
                omega.multiply(l1 * l2 + ad * (l1 + l2) + dotX + d * d, sd * crossX);
            }
        }
        double half = angle.arg();  // Σ σΔφ / 2
        if (inside && half < -0.5 * kPi) half += 2 * kPi;
        const double disc = (inside ? 2 * kPi : 0.0) - 2 * half;
        m.area = 0.5 * rho2 * disc + lineArea;
        m.arcLength = rho * disc;
        if (solid && d != 0) {
            double halfOmega = omega.arg();
            if (inside && sd * halfOmega < -0.5 * kPi) halfOmega += sd * 2 * kPi;
            m.solidAngle = (sd - d / r) * disc + 2 * halfOmega;
        }
        return m;
    }
};

/// Per-radius sums of one vertex.
class BallSums {
public:
    explicit BallSums(std::size_t numRadii)
        : mArea(numRadii), mArc(numRadii), mOmega(numRadii), mDArea(numRadii), mWholeArea(numRadii),
          mWholeOmega(numRadii), mWholeDArea(numRadii), mWhole(numRadii)
    {
    }

    void clear()
    {
        for (auto* v : {&mArea, &mArc, &mOmega, &mDArea, &mWholeArea, &mWholeOmega, &mWholeDArea})
            std::fill(v->begin(), v->end(), 0.0);
        std::fill(mWhole.begin(), mWhole.end(), AngleProduct{});
        mSumArea = mSumOmega = mSumDArea = 0;
    }

    void addStraddled(std::size_t j, const Measures& m, double d)
    {
        mArea[j] += m.area;
        mArc[j] += m.arcLength;
        mOmega[j] += m.solidAngle;
        mDArea[j] += d * m.area;
    }

    /// A triangle whole in B_r for radius j and beyond. @p halfBound bounds |Ω_t|/2.
    void addWhole(std::size_t j, double area, double d, const Complex* solid, double halfBound)
    {
        mWholeArea[j] += area;
        mWholeDArea[j] += d * area;
        if (!solid) return;
        if (halfBound >= 0.25 * kPi) {
            mWholeOmega[j] += 2 * solid->arg();
            return;
        }
        mWhole[j].add(*solid, halfBound, mWholeOmega[j]);
    }

    /// Totals at radius j (call with j = 0, 1, ... in order): area, arc, Σ Ω_t, Σ d_t area_t.
    Measures total(std::size_t j, double& dArea)
    {
        mWhole[j].resolve(mWholeOmega[j]);
        mSumArea += mWholeArea[j];
        mSumOmega += mWholeOmega[j];
        mSumDArea += mWholeDArea[j];
        dArea = mDArea[j] + mSumDArea;
        Measures m;
        m.area = mArea[j] + mSumArea;
        m.arcLength = mArc[j];
        m.solidAngle = mOmega[j] + mSumOmega;
        return m;
    }

private:
    /// A sum of angles kept as the product of complex numbers whose arguments are their
    /// halves, resolved (one atan2) before the bounds of the halves reach π/2.
    struct AngleProduct {
        Complex product;
        double budget = 0;
        int factors = 0;
        void add(const Complex& half, double halfBound, double& sum)
        {
            if (budget + halfBound >= 0.5 * kPi || factors == kMaxFactors) resolve(sum);
            product.multiply(half.re, half.im);
            budget += halfBound;
            ++factors;
        }
        void resolve(double& sum)
        {
            if (factors > 0) sum += 2 * product.arg();
            *this = AngleProduct{};
        }
    };
    // Factors lie within ~[1, 4] in magnitude (vanOosterom() over la·lb·lc, for a triangle
    // that subtends little): 4^64 stays finite.
    static constexpr int kMaxFactors = 64;

    std::vector<double> mArea, mArc, mOmega, mDArea;          // straddled, per radius
    std::vector<double> mWholeArea, mWholeOmega, mWholeDArea;  // whole, at their first radius
    std::vector<AngleProduct> mWhole;
    double mSumArea = 0, mSumOmega = 0, mSumDArea = 0;
};

void validate(const TriMesh& mesh, const ExactOptions& options)
{
    const auto& radii = options.radii;
    validateRadii(radii);
    for (const std::uint32_t v : options.vertices)
        if (v >= mesh.numVertices()) {
            std::ostringstream msg;
            msg << "vertex index " << v << " is out of range (the mesh has " << mesh.numVertices()
                << " vertices)";
            throw InvalidInputError(msg.str());
        }
    if (!options.borderDistance.empty() && options.borderDistance.size() != mesh.numVertices()) {
        std::ostringstream msg;
        msg << "the border distances hold " << options.borderDistance.size()
            << " values, but the mesh has " << mesh.numVertices() << " vertices";
        throw InvalidInputError(msg.str());
    }
}

/// The result before any value: the radii, the vertices to compute (all if none are
/// chosen), and NaN for every value asked for.
ExactResult unsetResult(const TriMesh& mesh, const ExactOptions& options)
{
    ExactResult result;
    result.radii = options.radii;
    const std::size_t nr = result.radii.size();
    if (options.vertices.empty()) {
        result.vertices.resize(mesh.numVertices());
        for (std::size_t v = 0; v < mesh.numVertices(); ++v) result.vertices[v] = std::uint32_t(v);
    } else {
        result.vertices = options.vertices;
    }
    const std::size_t nk = result.vertices.size();
    if (options.computeVolumeSphere) {
        result.volume.assign(nr, std::vector<double>(nk, kNaN));
        result.sphere.assign(nr, std::vector<double>(nk, kNaN));
    }
    if (options.computePatchLine) {
        result.patch.assign(nr, std::vector<double>(nk, kNaN));
        result.line.assign(nr, std::vector<double>(nk, kNaN));
    }
    return result;
}

std::vector<TriangleFrame> triangleFrames(const TriMesh& mesh)
{
    std::vector<TriangleFrame> frames(mesh.numTriangles());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frames.size()), [&](const auto& range) {
        for (std::size_t t = range.begin(); t < range.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            frames[t] = makeFrame(mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]);
        }
    });
    return frames;
}

/// The triangles of one grid, with what the per-vertex loop reads of them in slot order.
struct TriangleSet {
    TriangleGrid grid;
    std::vector<SlotTriangle> slots;
    std::vector<SlotBound> bounds;
};

/// The triangles that may meet the balls of radius up to @p R about @p vertices, in cell
/// order, in two grids: those within a cell (R/4) of their centroid, and the larger ones
/// (module comment of TriangleGrid). Grids without triangles are left out.
std::vector<TriangleSet> triangleSets(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                                      const std::vector<std::uint32_t>& vertices, double R)
{
    const double cell = 0.25 * R;
    // With a few chosen vertices of a large mesh, only the triangles that may meet their
    // balls: a triangle no larger than R whose centroid lies within 2 R of a vertex, found
    // through cells of size R around the vertices (a hash of the cell; a collision only
    // keeps a triangle more).
    std::unordered_set<std::uint64_t> near;
    const auto cellKey = [R](const Vec3& x, int dx, int dy, int dz) {
        const auto index = [R](double c, int d) { return std::uint64_t(std::int64_t(std::floor(c / R)) + d); };
        return index(x.x, dx) * 0x9E3779B97F4A7C15ULL ^ index(x.y, dy) * 0xC2B2AE3D27D4EB4FULL ^
               index(x.z, dz) * 0x165667B19E3779F9ULL;
    };
    const bool someVertices = 4 * vertices.size() < mesh.numVertices();
    if (someVertices)
        for (const std::uint32_t v : vertices)
            for (int dx = -2; dx <= 2; ++dx)
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dz = -2; dz <= 2; ++dz) near.insert(cellKey(mesh.points[v], dx, dy, dz));
    std::vector<std::uint32_t> small, large;
    for (std::uint32_t t = 0; t < frames.size(); ++t) {
        if (someVertices && frames[t].boundingRadius <= R && near.count(cellKey(frames[t].centroid, 0, 0, 0)) == 0)
            continue;
        (frames[t].boundingRadius <= cell ? small : large).push_back(t);
    }
    std::vector<TriangleSet> sets;
    for (const auto* subset : {&small, &large}) {
        if (subset->empty()) continue;
        double largest = 0;
        for (const std::uint32_t t : *subset) largest = std::max(largest, frames[t].boundingRadius);
        TriangleSet set{TriangleGrid(frames, *subset, std::max(cell, largest)), {}, {}};
        set.slots.resize(subset->size());
        set.bounds.resize(subset->size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, subset->size()), [&](const auto& range) {
            for (std::size_t s = range.begin(); s < range.end(); ++s) {
                const std::uint32_t t = set.grid.triangleAt(s);
                set.slots[s] = makeSlot(mesh, frames[t], t);
                set.bounds[s] = {frames[t].centroid, frames[t].boundingRadius};
            }
        });
        sets.push_back(std::move(set));
    }
    return sets;
}

/// The ball about one vertex p: what each triangle near it adds to its sums, for the
/// unmasked radii [0, jEnd).
struct VertexBall {
    const Vec3& p;
    double reach;  ///< the largest unmasked radius
    std::size_t jEnd;
    const std::vector<double>& radii;
    const RadiusCounter& counter;
    bool wantVS;
    BallSums& sums;

    /// Adds the triangle in @p slot of @p set (nothing if it lies beyond reach).
    void add(const TriangleSet& set, std::uint32_t slot) const
    {
        const SlotBound& bound = set.bounds[slot];
        const double slack = reach + bound.radius;
        const double centroid2 = squaredNorm(bound.centroid - p);
        if (centroid2 >= slack * slack) return;
        const SlotTriangle& tri = set.slots[slot];
        const std::array<Vec3, 3> q{tri.corner[0] - p, tri.corner[1] - p, tri.corner[2] - p};
        const double q2[3] = {squaredNorm(q[0]), squaredNorm(q[1]), squaredNorm(q[2])};
        // The first radius whose ball holds the whole triangle.
        const std::size_t jWhole = counter.below(std::max({q2[0], q2[1], q2[2]}), jEnd);
        double d;
        // Straddled radii lie between the distances to the triangle and to its
        // farthest corner. Most triangles straddle none, which shows without the
        // distance to the triangle: for x = Σ λ_i corner_i in it, |x − p|² = Σ λ_i
        // |corner_i − p|² − Σ λ_i |corner_i − x|² >= (nearest corner)² − ρ_t², as the
        // weighted mean x minimises the last sum (<= its value about the centroid).
        const double nearest2 = std::min({q2[0], q2[1], q2[2]});
        if (jWhole > 0 && nearest2 - bound.radius * bound.radius < counter.squared(jWhole - 1)) {
            // Corner nearest to p (the first of equals), as in LocalTriangle.
            const int nearest = q2[0] <= q2[1] ? (q2[0] <= q2[2] ? 0 : 2) : (q2[1] <= q2[2] ? 1 : 2);
            const Straddler straddler(tri, q, q2, nearest);
            d = straddler.d;
            std::size_t j = counter.atMost(straddler.near2, jEnd);
            if (j < jWhole && !straddler.precise) {
                TriangleFrame frame;
                frame.n = tri.n;
                frame.t1 = tri.t1;
                frame.t2 = tri.t2;
                frame.area = tri.area;
                const LocalTriangle local(q, frame);
                for (; j < jWhole; ++j) sums.addStraddled(j, local.sectors(radii[j], wantVS), d);
            }
            for (; j < jWhole; ++j) sums.addStraddled(j, straddler.fastMeasures(radii[j], wantVS), d);
        } else {
            // A triangle at p has d = 0 exactly, and no solid angle (its part is Ω_p);
            // otherwise any corner gives d up to rounding.
            d = nearest2 == 0 ? 0.0 : dot(q[0], tri.n);
        }
        if (jWhole >= jEnd) return;
        if (!wantVS || d == 0) {
            sums.addWhole(jWhole, tri.area, d, nullptr, 0);
            return;
        }
        const double la = std::sqrt(q2[0]), lb = std::sqrt(q2[1]), lc = std::sqrt(q2[2]);
        Complex solid = vanOosterom(q, la, lb, lc);
        const double lengths = la * lb * lc, inverse = 1.0 / (lengths * centroid2);
        const double scale = inverse * centroid2;
        solid.re *= scale;
        solid.im *= scale;
        const double x = bound.radius * bound.radius * lengths * inverse;  // ρ_t² / D²
        sums.addWhole(jWhole, tri.area, d, &solid, x < 1 ? kPi * x : kPi);
    }
};

/// The values of the @p k-th vertex of @p result for the radii [0, jEnd) from its ball sums
/// and the solid angle @p omegaP of the solid's cone at it.
void storeVertex(BallSums& sums, double omegaP, std::size_t jEnd, std::size_t k, bool wantVS, bool wantPL,
                 ExactResult& result)
{
    for (std::size_t j = 0; j < jEnd; ++j) {
        double dArea = 0;
        const Measures m = sums.total(j, dArea);
        const double r = result.radii[j];
        if (wantPL) {
            result.patch[j][k] = m.area / (kPi * r * r);
            result.line[j][k] = m.arcLength / (2 * kPi * r);
        }
        if (wantVS) {
            // S/r² = Ω_p − Σ Ω_t;  3V = Σ d_t area_t + r S  (module comment).
            const double s = (omegaP - m.solidAngle) * r * r;
            const double vol = (dArea + r * s) / 3.0;
            result.sphere[j][k] = s / (4 * kPi * r * r);
            result.volume[j][k] = vol / (4.0 / 3.0 * kPi * r * r * r);
        }
    }
}

} // namespace

TriangleBallMeasures triangleBallMeasures(const Vec3& p, const Vec3& a, const Vec3& b,
                                          const Vec3& c, double r)
{
    const LocalTriangle local(p, {a, b, c}, makeFrame(a, b, c));
    const Measures m = local.measure(r, true);
    TriangleBallMeasures out;
    out.area = m.area;
    out.arcLength = m.arcLength;
    out.solidAngle = m.solidAngle;
    out.distance = local.distance();
    return out;
}

// V of paper Eq. 1 and the four domains V, S, P, L of Eq. 2, normalised as in
// docs/method.md, Definitions and normalisations; per vertex from sums over the triangles
// near it (identities: header).
ExactResult computeExact(const TriMesh& mesh, const ExactOptions& options, RunContext* progress)
{
    validate(mesh, options);
    ExactResult result = unsetResult(mesh, options);
    const auto& radii = result.radii;
    const std::size_t nr = radii.size();
    const std::size_t nk = result.vertices.size();
    const bool wantVS = options.computeVolumeSphere, wantPL = options.computePatchLine;
    if (nk == 0 || mesh.numTriangles() == 0 || !(wantVS || wantPL)) return result;

    const std::vector<TriangleFrame> frames = triangleFrames(mesh);
    const VertexFaces vf = wantVS ? vertexFaces(mesh) : VertexFaces{};
    const std::vector<TriangleSet> sets = triangleSets(mesh, frames, result.vertices, radii.back());
    const RadiusCounter counter(radii);

    if (progress) progress->start("exact invariants", nk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nk, 1), [&](const auto& range) {
        BallSums sums(nr);
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
            const std::uint32_t v = result.vertices[k];
            const Vec3& p = mesh.points[v];
            // Radii [0, jEnd) are unmasked (ascending radii, r >= borderDistance is masked).
            std::size_t jEnd = nr;
            if (!options.borderDistance.empty())
                jEnd = std::size_t(std::lower_bound(radii.begin(), radii.end(), options.borderDistance[v]) -
                                   radii.begin());
            if (jEnd == 0) continue;
            sums.clear();
            const VertexBall ball{p, radii[jEnd - 1], jEnd, radii, counter, wantVS, sums};
            for (const TriangleSet& set : sets)
                set.grid.forEachNear(p, ball.reach, [&](std::uint32_t slot) { ball.add(set, slot); });
            const double omegaP = wantVS ? coneSolidAngle(mesh, frames, vf, v) : 0.0;
            storeVertex(sums, omegaP, jEnd, k, wantVS, wantPL, result);
        }
        if (progress) progress->advance(range.size());
    });
    if (progress) progress->end();
    return result;
}

} // namespace msii
