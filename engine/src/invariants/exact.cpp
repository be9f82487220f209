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
// Sector integrals (MSII-REFERENCE.md §1, exact identities). In the triangle's plane, with
// the foot point c of p as origin, the triangle is the signed sum of the sectors (c, A, B)
// of its directed edges, sign σ = sign((A − c) × (B − c)). Within one sector, polar
// coordinates (s, φ) about c, φ measured from the perpendicular onto the edge's line
// (distance e): the region is s <= m(φ) = min(ρ, e / cos φ), where the disc bounds it for
// |φ| > φ* = arccos(e/ρ) (everywhere if e >= ρ) and the line elsewhere. A point of the
// line at coordinate t along the edge (t = 0 at the perpendicular's foot) has tan φ = t/e,
// so the pieces are split at t = ±t*, t* = sqrt(ρ² − e²), and integrated in closed form:
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

/// One triangle as seen from p: everything that does not depend on the radius.
class LocalTriangle {
public:
    LocalTriangle(const Vec3& p, const std::array<Vec3, 3>& corners, const TriangleFrame& frame)
        : mArea(frame.area)
    {
        std::array<Vec3, 3> q;
        int nearest = 0;
        double far2 = 0, near2 = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
            q[i] = corners[i] - p;
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
        mQ = q;
    }

    double distance() const { return mD; }
    double nearestDistance() const { return mNear; }  ///< distance from p to the triangle
    double farthestDistance() const { return mFar; }  ///< distance from p to its farthest corner

    /// The whole triangle (inside the ball): area, no arc, solid angle by Van Oosterom and
    /// Strackee's formula, tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|)
    /// (a·(b×c) = 2·area·d, so Ω has the sign of d).
    Measures whole(bool solid) const
    {
        Measures m;
        m.area = mArea;
        if (solid && mD != 0) {
            const Vec3 &a = mQ[0], &b = mQ[1], &c = mQ[2];
            const double la = norm(a), lb = norm(b), lc = norm(c);
            const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
            m.solidAngle = 2.0 * std::atan2(dot(a, cross(b, c)), den);
        }
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
    double mX[3], mY[3];
    std::array<Vec3, 3> mQ;
    double mArea, mD, mNear, mFar;
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
/// convex cube corner π/2). NaN if an edge at v has no second triangle (border).
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
    return sum - double(k - 2) * kPi;
}

// ---------------------------------------------------------------------------------------
// Uniform grid of triangles by centroid: a query box grown by the largest centroid-corner
// distance finds every triangle that meets a ball.

class TriangleGrid {
public:
    TriangleGrid(const TriMesh& mesh, double cellSize)
    {
        const std::size_t nt = mesh.numTriangles();
        std::vector<Vec3> centroid(nt);
        Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
        for (std::size_t t = 0; t < nt; ++t) {
            const auto& tri = mesh.triangles[t];
            const Vec3 &a = mesh.points[tri[0]], &b = mesh.points[tri[1]], &c = mesh.points[tri[2]];
            centroid[t] = (a + b + c) / 3.0;
            mReach = std::max({mReach, norm(a - centroid[t]), norm(b - centroid[t]),
                               norm(c - centroid[t])});
            for (int i = 0; i < 3; ++i) {
                lo[i] = std::min(lo[i], centroid[t][i]);
                hi[i] = std::max(hi[i], centroid[t][i]);
            }
        }
        mOrigin = lo;
        // At most ~1e6 cells per axis, so the packed keys cannot overflow.
        const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        mCell = std::max({cellSize, extent * 1e-6, std::numeric_limits<double>::min()});
        for (int i = 0; i < 3; ++i) mCount[i] = std::int64_t(std::floor((hi[i] - lo[i]) / mCell)) + 1;
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(nt);
        for (std::size_t t = 0; t < nt; ++t) {
            std::int64_t c[3];
            for (int i = 0; i < 3; ++i) c[i] = clampIndex(i, (centroid[t][i] - mOrigin[i]) / mCell);
            keyed[t] = {key(c[0], c[1], c[2]), std::uint32_t(t)};
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

    /// Calls @p visit(triangle) for every triangle that may meet B_radius(p), each once, in
    /// an order that depends only on p and the radius.
    template <class Visit> void forEachNear(const Vec3& p, double radius, Visit&& visit) const
    {
        const double reach = radius + mReach;
        std::int64_t lo[3], hi[3];
        for (int i = 0; i < 3; ++i) {
            lo[i] = clampIndex(i, (p[i] - reach - mOrigin[i]) / mCell);
            hi[i] = clampIndex(i, (p[i] + reach - mOrigin[i]) / mCell);
        }
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                    const std::uint64_t k = key(x, y, z);
                    const auto it = std::lower_bound(mKeys.begin(), mKeys.end(), k);
                    if (it == mKeys.end() || *it != k) continue;
                    const std::size_t cell = std::size_t(it - mKeys.begin());
                    for (std::uint32_t s = mFirst[cell]; s < mFirst[cell + 1]; ++s) visit(mTriangles[s]);
                }
    }

private:
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
// MSII-REFERENCE.md §1, per vertex from sums over the triangles near it (identities: header).
ExactResult computeExact(const TriMesh& mesh, const ExactOptions& options, Progress* progress)
{
    validate(mesh, options);
    ExactResult result;
    result.radii = options.radii;
    const auto& radii = result.radii;
    const std::size_t nr = radii.size();
    if (options.vertices.empty()) {
        result.vertices.resize(mesh.numVertices());
        for (std::size_t v = 0; v < mesh.numVertices(); ++v) result.vertices[v] = std::uint32_t(v);
    } else {
        result.vertices = options.vertices;
    }
    const std::size_t nk = result.vertices.size();
    const bool wantVS = options.computeVolumeSphere, wantPL = options.computePatchLine;
    if (wantVS) {
        result.volume.assign(nr, std::vector<double>(nk, kNaN));
        result.sphere.assign(nr, std::vector<double>(nk, kNaN));
    }
    if (wantPL) {
        result.patch.assign(nr, std::vector<double>(nk, kNaN));
        result.line.assign(nr, std::vector<double>(nk, kNaN));
    }
    if (nk == 0 || mesh.numTriangles() == 0 || !(wantVS || wantPL)) return result;

    std::vector<TriangleFrame> frames(mesh.numTriangles());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frames.size()), [&](const auto& range) {
        for (std::size_t t = range.begin(); t < range.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            frames[t] = makeFrame(mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]);
        }
    });
    const VertexFaces vf = wantVS ? vertexFaces(mesh) : VertexFaces{};
    const TriangleGrid grid(mesh, 0.5 * radii.back());

    if (progress) progress->start("exact invariants", nk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nk, 1), [&](const auto& range) {
        std::vector<double> area(nr), arc(nr), omega(nr), dArea(nr);
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
            const std::uint32_t v = result.vertices[k];
            const Vec3& p = mesh.points[v];
            // Radii [0, jEnd) are unmasked (ascending radii, r >= borderDistance is masked).
            std::size_t jEnd = nr;
            if (!options.borderDistance.empty())
                jEnd = std::size_t(std::lower_bound(radii.begin(), radii.end(), options.borderDistance[v]) -
                                   radii.begin());
            if (jEnd == 0) continue;
            const double reach = radii[jEnd - 1];
            std::fill(area.begin(), area.end(), 0.0);
            std::fill(arc.begin(), arc.end(), 0.0);
            std::fill(omega.begin(), omega.end(), 0.0);
            std::fill(dArea.begin(), dArea.end(), 0.0);

            grid.forEachNear(p, reach, [&](std::uint32_t t) {
                const double slack = reach + frames[t].boundingRadius;
                if (squaredNorm(frames[t].centroid - p) >= slack * slack) return;
                const auto& tri = mesh.triangles[t];
                const LocalTriangle local(p, {mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]},
                                          frames[t]);
                const double near = local.nearestDistance();
                if (!(near < reach)) return;
                const double d = local.distance();
                std::size_t j = std::size_t(std::upper_bound(radii.begin(), radii.begin() + jEnd, near) -
                                            radii.begin());
                for (; j < jEnd && radii[j] < local.farthestDistance(); ++j) {
                    const Measures m = local.sectors(radii[j], wantVS);
                    area[j] += m.area;
                    arc[j] += m.arcLength;
                    omega[j] += m.solidAngle;
                    dArea[j] += d * m.area;
                }
                if (j < jEnd) {
                    const Measures m = local.whole(wantVS);
                    for (; j < jEnd; ++j) {
                        area[j] += m.area;
                        omega[j] += m.solidAngle;
                        dArea[j] += d * m.area;
                    }
                }
            });

            const double omegaP = wantVS ? coneSolidAngle(mesh, frames, vf, v) : 0.0;
            for (std::size_t j = 0; j < jEnd; ++j) {
                const double r = radii[j];
                if (wantPL) {
                    result.patch[j][k] = area[j] / (kPi * r * r);
                    result.line[j][k] = arc[j] / (2 * kPi * r);
                }
                if (wantVS) {
                    // S/r² = Ω_p − Σ Ω_t;  3V = Σ d_t area_t + r S  (module comment).
                    const double s = (omegaP - omega[j]) * r * r;
                    const double vol = (dArea[j] + r * s) / 3.0;
                    result.sphere[j][k] = s / (4 * kPi * r * r);
                    result.volume[j][k] = vol / (4.0 / 3.0 * kPi * r * r * r);
                }
            }
        }
        if (progress) progress->advance(range.size());
    });
    if (progress) progress->end();
    return result;
}

} // namespace msii
