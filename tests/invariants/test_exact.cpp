// The exact reference mode: the per-triangle closed forms against brute-force quadrature,
// then V̂, Ŝ, P̂ and L̂ against the closed forms of docs/method.md, Closed forms (cube
// corners and edges, planes, a sphere and a spherical cavity), the identity S = dV/dr,
// rigid-motion invariance, border masking, bad input and thread-count independence.
#include <msii/invariants/exact.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/border_distance.h>
#include <msii/mesh/mesh_check.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <iterator>
#include <limits>
#include <queue>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../support/rotation.h"

using namespace msii;
using msii::test::Rotation;

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------
// Brute force: globally adaptive Gauss–Kronrod (7/15) quadrature, QUADPACK-style (always
// split the piece with the largest error estimate), which also converges on jumps.

double integrate(const std::function<double(double)>& f, double a, double b, double absTol,
                 int maxPieces = 20000)
{
    static const double xk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                 0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                 0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                 0.207784955007898467600689403773245, 0.0};
    static const double wk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                 0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                 0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                 0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
    static const double wg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                 0.381830050505118944950369775488975, 0.417959183673469387755102040816327};
    struct Piece {
        double a, b, value, error;
        bool operator<(const Piece& o) const { return error < o.error; }
    };
    const auto rule = [&](double lo, double hi) {
        const double c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
        const double fc = f(c);
        double k = wk[7] * fc, g = wg[3] * fc;
        for (int i = 0; i < 7; ++i) {
            const double s = f(c - h * xk[i]) + f(c + h * xk[i]);
            k += wk[i] * s;
            if (i % 2 == 1) g += wg[i / 2] * s;
        }
        return Piece{lo, hi, k * h, std::abs((k - g) * h)};
    };
    std::priority_queue<Piece> pieces;
    pieces.push(rule(a, b));
    double error = pieces.top().error;
    while (error > absTol && int(pieces.size()) < maxPieces) {
        const Piece worst = pieces.top();
        pieces.pop();
        const double mid = 0.5 * (worst.a + worst.b);
        const Piece left = rule(worst.a, mid), right = rule(mid, worst.b);
        error += left.error + right.error - worst.error;
        pieces.push(left);
        pieces.push(right);
    }
    double sum = 0;
    for (; !pieces.empty(); pieces.pop()) sum += pieces.top().value;
    return sum;
}

/// triangle ∩ B_r(p) integrated in polar coordinates (s, φ) about the foot point c, with the
/// ray from c at angle φ clipped against the three edges' half-planes and the disc; solid
/// angle radially by quadrature too, arc length as ∫ ρ·[circle point inside] dφ.
TriangleBallMeasures bruteForce(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double r)
{
    TriangleBallMeasures m;
    const Vec3 n = normalized(cross(b - a, c - a));
    const double d = dot(a - p, n);
    m.distance = d;
    if (std::abs(d) >= r) return m;
    const double rho = std::sqrt(r * r - d * d);
    const Vec3 foot = p + n * d;
    const Vec3 e1 = normalized(b - a), e2 = cross(n, e1);
    double x[3], y[3];
    const Vec3 corners[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
        x[i] = dot(corners[i] - foot, e1);
        y[i] = dot(corners[i] - foot, e2);
    }
    // [s0, s1]: the part of the ray at angle φ inside the triangle and the disc.
    const auto ray = [&](double phi, double& s0, double& s1) {
        const double vx = std::cos(phi), vy = std::sin(phi);
        s0 = 0;
        s1 = rho;
        for (int i = 0; i < 3; ++i) {
            const int k = (i + 1) % 3;
            const double nx = -(y[k] - y[i]), ny = x[k] - x[i];  // inward normal (CCW)
            const double along = nx * vx + ny * vy, offset = nx * x[i] + ny * y[i];
            if (along > 0) s0 = std::max(s0, offset / along);
            else if (along < 0) s1 = std::min(s1, offset / along);
            else if (offset > 0) s1 = -1;
        }
        return s1 > s0;
    };
    // Break points: the corners' directions (where the ray's entry or exit switches edges)
    // and the points where the circle crosses an edge (where the disc starts or stops
    // bounding the ray); in between, the integrands are smooth and the arc's indicator is
    // constant. Plus a uniform split, for good measure.
    std::vector<double> cuts;
    const auto addCut = [&](double phi) { cuts.push_back(phi < 0 ? phi + 2 * kPi : phi); };
    for (int i = 0; i <= 64; ++i) cuts.push_back(2 * kPi * i / 64);
    for (int i = 0; i < 3; ++i) {
        addCut(std::atan2(y[i], x[i]));
        const int k = (i + 1) % 3;
        // |corner_i + t (corner_k − corner_i)|² = ρ², t in [0, 1]
        const double wx = x[k] - x[i], wy = y[k] - y[i];
        const double qa = wx * wx + wy * wy, qb = 2 * (x[i] * wx + y[i] * wy),
                     qc = x[i] * x[i] + y[i] * y[i] - rho * rho;
        const double disc = qb * qb - 4 * qa * qc;
        if (disc < 0) continue;
        for (const double t : {(-qb - std::sqrt(disc)) / (2 * qa), (-qb + std::sqrt(disc)) / (2 * qa)})
            if (t >= 0 && t <= 1) addCut(std::atan2(y[i] + t * wy, x[i] + t * wx));
    }
    std::sort(cuts.begin(), cuts.end());
    const auto overPhi = [&](const std::function<double(double)>& f, double tol) {
        double sum = 0;
        for (std::size_t i = 0; i + 1 < cuts.size(); ++i)
            if (cuts[i + 1] > cuts[i]) sum += integrate(f, cuts[i], cuts[i + 1], tol / cuts.size());
        return sum;
    };
    m.area = overPhi(
        [&](double phi) {
            double s0, s1;
            if (!ray(phi, s0, s1)) return 0.0;
            return integrate([](double s) { return s; }, s0, s1, 1e-15 * rho * rho);
        },
        1e-13 * rho * rho);
    if (d != 0)
        m.solidAngle = overPhi(
            [&](double phi) {
                double s0, s1;
                if (!ray(phi, s0, s1)) return 0.0;
                return integrate([&](double s) { return d * s / std::pow(d * d + s * s, 1.5); }, s0, s1,
                                 1e-15, 400);
            },
            1e-13);
    m.arcLength = overPhi(
        [&](double phi) {
            const double px = rho * std::cos(phi), py = rho * std::sin(phi);
            for (int i = 0; i < 3; ++i) {
                const int k = (i + 1) % 3;
                if ((x[k] - x[i]) * (py - y[i]) - (y[k] - y[i]) * (px - x[i]) < 0) return 0.0;
            }
            return rho;
        },
        1e-13 * rho);
    return m;
}

double uniform(std::mt19937_64& rng, double lo, double hi)
{
    return lo + (hi - lo) * double(rng() >> 11) * 0x1.0p-53;  // the generator's bits, no std distribution
}

// ---------------------------------------------------------------------------------------
// Mesh helpers.

std::vector<double> equidistant(double largest, int scales) { return equidistantRadii(largest, scales); }

/// Max |value − expected| over the given vertices, per radius; printed.
std::vector<double> maxErrors(const std::vector<std::vector<double>>& values,
                              const std::vector<double>& radii,
                              const std::function<double(double, std::size_t)>& expected)
{
    std::vector<double> out(radii.size(), 0.0);
    for (std::size_t j = 0; j < radii.size(); ++j)
        for (std::size_t k = 0; k < values[j].size(); ++k) {
            const double err = std::abs(values[j][k] - expected(radii[j], k));
            out[j] = std::isnan(err) ? INFINITY : std::max(out[j], err);
        }
    return out;
}

void printErrors(const char* title, const std::vector<double>& radii,
                 const std::vector<std::vector<double>>& columns, const char* names)
{
    std::printf("%s\n     r    %s\n", title, names);
    for (std::size_t j = 0; j < radii.size(); ++j) {
        std::printf("  %6.3f", radii[j]);
        for (const auto& c : columns) std::printf("   %.2e", c[j]);
        std::printf("\n");
    }
}

bool sameOrBothNaN(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

} // namespace

// ---------------------------------------------------------------------------------------
// Per-triangle closed forms.

TEST(Exact, TrianglePiecesMatchQuadrature)
{
    // A fixed triangle, moved to a general position; foot points c and disc radii ρ chosen
    // so that the disc cuts 0, 1, 2 or 3 edges, holds the whole triangle or misses it, with
    // c inside, outside, on an edge and at a corner; each at d = 0, d > 0 and d < 0.
    const Rotation rotate(normalized(Vec3(0.3, -0.8, 0.5)), 1.1);
    const Vec3 shift(2.5, -1.25, 0.75);
    const auto place = [&](double x, double y, double z) { return rotate(Vec3(x, y, z)) + shift; };
    const Vec3 a = place(0, 0, 0), b = place(4, 0, 0), c = place(1, 3, 0);
    struct Config {
        double cx, cy, rho;
        const char* what;
    };
    const Config configs[] = {
        {1.5, 1.0, 0.5, "c inside, disc inside"},      {1.5, 1.0, 1.03, "c inside, cuts 1 edge"},
        {1.5, 1.0, 1.08, "c inside, cuts 2 edges"},    {1.5, 1.0, 1.5, "c inside, cuts 3 edges"},
        {1.5, 1.0, 2.5, "c inside, corners B, C out"}, {1.5, 1.0, 3.0, "c inside, triangle inside"},
        {5.0, 2.0, 2.5, "c outside, cuts 1 edge"},     {5.0, 2.0, 3.5, "c outside, cuts 2 edges"},
        {-1.0, -1.0, 1.5, "c outside, around A"},      {-1.0, -1.0, 1.0, "c outside, misses"},
        {-1.0, -1.0, 7.0, "c outside, triangle inside"}, {2.0, 0.0, 1.0, "c on edge AB"},
        {0.0, 0.0, 1.0, "c at corner A"},              {0.0, 0.0, 2.0, "c at A, cuts 2 edges"},
        {0.0, 0.0, 5.0, "c at A, triangle inside"},
    };
    double worst[3] = {0, 0, 0};
    int checked = 0;
    const auto check = [&](const Vec3& p, double r, const Vec3& ta, const Vec3& tb, const Vec3& tc,
                           const std::string& what) {
        const TriangleBallMeasures exact = triangleBallMeasures(p, ta, tb, tc, r);
        const TriangleBallMeasures brute = bruteForce(p, ta, tb, tc, r);
        // Relative, with a floor for values that vanish (1e-6 of the whole disc's measure).
        const auto relative = [](double value, double reference, double floor) {
            return std::abs(value - reference) / std::max(std::abs(reference), floor);
        };
        const double errArea = relative(exact.area, brute.area, 1e-6 * kPi * r * r);
        const double errArc = relative(exact.arcLength, brute.arcLength, 1e-6 * 2 * kPi * r);
        const double errSolid = relative(exact.solidAngle, brute.solidAngle, 1e-6 * 2 * kPi);
        EXPECT_LE(errArea, 1e-9) << what << ": area " << exact.area << " vs " << brute.area;
        EXPECT_LE(errArc, 1e-9) << what << ": arc " << exact.arcLength << " vs " << brute.arcLength;
        EXPECT_LE(errSolid, 1e-9) << what << ": solid angle " << exact.solidAngle << " vs "
                                  << brute.solidAngle;
        EXPECT_NEAR(exact.distance, brute.distance, 1e-12) << what;
        worst[0] = std::max(worst[0], errArea);
        worst[1] = std::max(worst[1], errArc);
        worst[2] = std::max(worst[2], errSolid);
        ++checked;
    };
    for (const Config& cfg : configs) {
        for (const double d : {0.7, -0.4, 1e-3}) {
            // p sits at distance d behind the plane along −n: d = (a − p)·n.
            const Vec3 p = place(cfg.cx, cfg.cy, -d);
            const double r = std::sqrt(cfg.rho * cfg.rho + d * d);
            const std::string what = std::string(cfg.what) + ", d = " + std::to_string(d);
            check(p, r, a, b, c, what);
            check(p, r, b, c, a, what + " (relabelled: another edge first)");
        }
        // d = 0 (the solid angle jumps there, from −2π to 2π with c inside): exactly in the
        // plane z = 0, unrotated, so that d is exactly 0 for either labelling.
        const Vec3 p(cfg.cx, cfg.cy, 0);
        const Vec3 a0(0, 0, 0), b0(4, 0, 0), c0(1, 3, 0);
        check(p, cfg.rho, a0, b0, c0, std::string(cfg.what) + ", d = 0");
        check(p, cfg.rho, b0, c0, a0, std::string(cfg.what) + ", d = 0 (relabelled)");
    }
    // Random triangles, points and radii.
    std::mt19937_64 rng(20240611);
    for (int i = 0; i < 60; ++i) {
        Vec3 q[3];
        for (auto& v : q) v = Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
        if (norm(cross(q[1] - q[0], q[2] - q[0])) < 0.1) continue;
        const Vec3 p(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
        const double r = uniform(rng, 0.1, 2.0);
        check(p, r, q[0], q[1], q[2], "random " + std::to_string(i));
    }
    std::printf("per-triangle pieces: %d configurations, max relative error: area %.2e, arc %.2e, "
                "solid angle %.2e\n",
                checked, worst[0], worst[1], worst[2]);
    EXPECT_GT(checked, 160);
}

TEST(Exact, TrianglePiecesKnownValues)
{
    // c inside, disc inside the triangle: the whole disc; the triangle inside the ball: the
    // whole triangle; a plane through p: no solid angle; and the solid angle of a triangle
    // seen from far behind a small disc: Ω = 2π(1 − d/r) (a spherical cap).
    const Vec3 a(0, 0, 0), b(4, 0, 0), c(1, 3, 0);
    const TriangleBallMeasures inside = triangleBallMeasures(Vec3(1.5, 1, 0), a, b, c, 0.5);
    EXPECT_NEAR(inside.area, kPi * 0.25, 1e-14);
    EXPECT_NEAR(inside.arcLength, kPi, 1e-14);
    EXPECT_EQ(inside.solidAngle, 0.0);
    const TriangleBallMeasures cap = triangleBallMeasures(Vec3(1.5, 1, -0.3), a, b, c, 0.5);
    EXPECT_NEAR(cap.distance, 0.3, 1e-15);
    EXPECT_NEAR(cap.area, kPi * 0.16, 1e-14);
    EXPECT_NEAR(cap.arcLength, 2 * kPi * 0.4, 1e-14);
    EXPECT_NEAR(cap.solidAngle, 2 * kPi * (1 - 0.3 / 0.5), 1e-14);
    const TriangleBallMeasures whole = triangleBallMeasures(Vec3(1.5, 1, 0), a, b, c, 10);
    EXPECT_NEAR(whole.area, 6.0, 1e-14);
    EXPECT_EQ(whole.arcLength, 0.0);
    const TriangleBallMeasures none = triangleBallMeasures(Vec3(10, 10, 0), a, b, c, 1);
    EXPECT_EQ(none.area, 0.0);
    EXPECT_EQ(none.arcLength, 0.0);
    EXPECT_EQ(none.solidAngle, 0.0);
}

// ---------------------------------------------------------------------------------------
// Closed forms on meshes (docs/method.md, Closed forms).

TEST(Exact, CubeCornersAndEdges)
{
    samples::CubeOptions co;
    co.side = 10;
    co.spacing = 0.25;
    const TriMesh mesh = samples::makeCube(co);
    // The 8 corners are vertices; on each of the 12 edges, the vertex nearest its middle
    // (edge vertices lie exactly on the edges).
    std::vector<std::uint32_t> corners, edges;
    for (int cx = 0; cx < 2; ++cx)
        for (int cy = 0; cy < 2; ++cy)
            for (int cz = 0; cz < 2; ++cz) {
                const Vec3 corner(10.0 * cx, 10.0 * cy, 10.0 * cz);
                for (std::size_t i = 0; i < mesh.numVertices(); ++i)
                    if (mesh.points[i] == corner) corners.push_back(std::uint32_t(i));
            }
    for (int axis = 0; axis < 3; ++axis)
        for (int s = 0; s < 2; ++s)
            for (int t = 0; t < 2; ++t) {
                const int u = (axis + 1) % 3, w = (axis + 2) % 3;
                std::uint32_t best = UINT32_MAX;
                double bestOffset = INFINITY;
                for (std::size_t i = 0; i < mesh.numVertices(); ++i) {
                    const Vec3& q = mesh.points[i];
                    if (q[u] != 10.0 * s || q[w] != 10.0 * t) continue;
                    if (std::abs(q[axis] - 5) < bestOffset) {
                        bestOffset = std::abs(q[axis] - 5);
                        best = std::uint32_t(i);
                    }
                }
                ASSERT_NE(best, UINT32_MAX);
                edges.push_back(best);
            }
    ASSERT_EQ(corners.size(), 8u);
    ASSERT_EQ(edges.size(), 12u);

    ExactOptions o;
    o.radii = equidistant(2.0, 16);
    o.vertices = corners;
    const ExactResult rc = computeExact(mesh, o);
    o.vertices = edges;
    const ExactResult re = computeExact(mesh, o);
    const auto eV = maxErrors(rc.volume, o.radii, [](double, std::size_t) { return 0.125; });
    const auto eS = maxErrors(rc.sphere, o.radii, [](double, std::size_t) { return 0.125; });
    const auto eP = maxErrors(rc.patch, o.radii, [](double, std::size_t) { return 0.75; });
    const auto eL = maxErrors(rc.line, o.radii, [](double, std::size_t) { return 0.75; });
    const auto fV = maxErrors(re.volume, o.radii, [](double, std::size_t) { return 0.25; });
    const auto fS = maxErrors(re.sphere, o.radii, [](double, std::size_t) { return 0.25; });
    const auto fP = maxErrors(re.patch, o.radii, [](double, std::size_t) { return 1.0; });
    const auto fL = maxErrors(re.line, o.radii, [](double, std::size_t) { return 1.0; });
    printErrors("cube side 10: 8 corners (V S P L = 1/8 1/8 3/4 3/4), 12 edges (1/4 1/4 1 1)", o.radii,
                {eV, eS, eP, eL, fV, fS, fP, fL},
                "corner dV  dS         dP         dL         edge dV    dS         dP         dL");
    for (std::size_t j = 0; j < o.radii.size(); ++j)
        for (const auto* e : {&eV, &eS, &eP, &eL, &fV, &fS, &fP, &fL})
            EXPECT_LE((*e)[j], 1e-9) << "radius " << j;
}

namespace {
samples::HeightFieldOptions flatPatch(bool closed)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Plane;
    ho.width = 12;
    ho.height = 12;
    ho.spacing = 0.2;
    ho.noise = 0;
    ho.closed = closed;
    ho.thickness = 5;
    return ho;
}
} // namespace

TEST(Exact, FlatSlabIsOneHalf)
{
    const TriMesh mesh = samples::makeHeightField(flatPatch(true));
    ExactOptions o;
    o.radii = equidistant(2.0, 16);
    for (std::size_t i = 0; i < mesh.numVertices(); ++i) {
        const Vec3& q = mesh.points[i];
        if (q.z == 0 && q.x >= 4 && q.x <= 8 && q.y >= 4 && q.y <= 8) o.vertices.push_back(std::uint32_t(i));
    }
    ASSERT_GT(o.vertices.size(), 300u);
    const ExactResult res = computeExact(mesh, o);
    const auto half = [](double, std::size_t) { return 0.5; };
    const auto one = [](double, std::size_t) { return 1.0; };
    const auto eV = maxErrors(res.volume, o.radii, half), eS = maxErrors(res.sphere, o.radii, half);
    const auto eP = maxErrors(res.patch, o.radii, one), eL = maxErrors(res.line, o.radii, one);
    printErrors("closed flat slab, top middle", o.radii, {eV, eS, eP, eL},
                "max|dV|    max|dS|    max|dP|    max|dL|");
    for (std::size_t j = 0; j < o.radii.size(); ++j)
        for (const auto* e : {&eV, &eS, &eP, &eL}) EXPECT_LE((*e)[j], 1e-9) << "radius " << j;
}

TEST(Exact, OpenPatchMasksTheBorder)
{
    const TriMesh mesh = samples::makeHeightField(flatPatch(false));
    const MeshCheckResult check = checkMesh(mesh);
    ASSERT_FALSE(check.closed);
    ExactOptions o;
    o.radii = equidistant(2.0, 8);
    o.borderDistance = borderDistance(mesh, check.borderEdges, 2 * o.radii.back());
    const ExactResult res = computeExact(mesh, o);
    ASSERT_EQ(res.vertices.size(), mesh.numVertices());
    std::size_t masked = 0, valued = 0;
    double maxErr = 0;
    for (std::size_t k = 0; k < res.vertices.size(); ++k) {
        const Vec3& q = mesh.points[res.vertices[k]];
        const double toBorder = std::min({q.x, 12 - q.x, q.y, 12 - q.y});
        for (std::size_t j = 0; j < o.radii.size(); ++j) {
            const double r = o.radii[j];
            if (std::abs(r - toBorder) < 1e-9) continue;  // on the fence: either is right
            const double values[4] = {res.volume[j][k], res.sphere[j][k], res.patch[j][k], res.line[j][k]};
            if (r >= toBorder) {
                for (double v : values) EXPECT_TRUE(std::isnan(v)) << "vertex " << k << " radius " << j;
                ++masked;
                continue;
            }
            const double expected[4] = {0.5, 0.5, 1, 1};
            for (int i = 0; i < 4; ++i) {
                ASSERT_FALSE(std::isnan(values[i])) << "vertex " << k << " radius " << j;
                maxErr = std::max(maxErr, std::abs(values[i] - expected[i]));
            }
            ++valued;
        }
    }
    std::printf("open flat patch: %zu values masked, %zu computed, max error %.2e\n", masked, valued, maxErr);
    EXPECT_GT(masked, 1000u);
    EXPECT_GT(valued, 10000u);
    EXPECT_LE(maxErr, 1e-9);
}

namespace {

TriMesh testSphere(bool cavity)
{
    samples::SphereOptions so;
    so.radius = 10.0;
    so.spacing = 0.15;
    so.cavity = cavity;
    so.seed = 7;
    return samples::makeSphere(so);
}

/// The inscribed mesh lies inside the sphere: on a triangle with edges l_i (corners on the
/// sphere), R² − |x|² = Σ_{i<j} λ_i λ_j |A_i − A_j|² in barycentric coordinates λ, whose
/// mean over the triangle is Σ l² / 12; so the area-mean gap is g = Σ area·Σl²/(24R) / Σ area.
double meanChordGap(const TriMesh& mesh, double radius)
{
    double sum = 0, area = 0;
    for (const auto& t : mesh.triangles) {
        const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const double at = 0.5 * norm(cross(b - a, c - a));
        sum += at * (squaredNorm(b - a) + squaredNorm(c - b) + squaredNorm(a - c)) / (24 * radius);
        area += at;
    }
    return sum / area;
}

/// V̂, Ŝ, P̂, L̂ on the sphere (or cavity) of radius 10 against the closed forms.
/// Discretisation error: the faces are chords, so the mesh is (on average) the sphere moved
/// inwards by the mean gap g, with each vertex g above (convex) or below (cavity) it. A
/// ball whose centre is x·r off the surface has V̂ = V̂(0) ∓ ¾x + O(x²) and
/// Ŝ = Ŝ(0) ∓ (2 − r²/R²)x/4 + O(x²) (docs/method.md, Back to the vertices), x = g/r; P̂
/// and L̂ move only at second order (1 − g²/r², and g/R). The test asserts both the raw
/// error against that bound and the residual after removing the first-order offset.
void checkSphere(bool cavity)
{
    const TriMesh mesh = testSphere(cavity);
    ASSERT_GE(mesh.numVertices(), 40000u);
    const double R = 10.0, g = meanChordGap(mesh, R), sg = cavity ? 1.0 : -1.0;
    ExactOptions o;
    o.radii = equidistant(4.0, 16);
    for (std::size_t i = 0; i < 100; ++i) o.vertices.push_back(std::uint32_t(i * (mesh.numVertices() / 100)));
    Stopwatch watch;
    const ExactResult res = computeExact(mesh, o);
    const double seconds = watch.seconds();
    std::printf("%s R=10: %zu vertices, mean chord gap g = %.3e, 100 vertices x 16 radii in %.2f s\n",
                cavity ? "spherical cavity" : "convex sphere", mesh.numVertices(), g, seconds);

    const auto closedV = [&](double r) { return 0.5 + sg * 3 * r / (16 * R); };
    const auto closedS = [&](double r) { return 0.5 + sg * r / (4 * R); };
    const auto closedL = [&](double r) { return std::sqrt(1 - r * r / (4 * R * R)); };
    const auto eV = maxErrors(res.volume, o.radii, [&](double r, std::size_t) { return closedV(r); });
    const auto eS = maxErrors(res.sphere, o.radii, [&](double r, std::size_t) { return closedS(r); });
    const auto eP = maxErrors(res.patch, o.radii, [&](double, std::size_t) { return 1.0; });
    const auto eL = maxErrors(res.line, o.radii, [&](double r, std::size_t) { return closedL(r); });
    const auto offV = [&](double r) { return sg * 0.75 * g / r; };
    const auto offS = [&](double r) { return sg * (2 - r * r / (R * R)) / 4 * g / r; };
    const auto cV =
        maxErrors(res.volume, o.radii, [&](double r, std::size_t) { return closedV(r) + offV(r); });
    const auto cS =
        maxErrors(res.sphere, o.radii, [&](double r, std::size_t) { return closedS(r) + offS(r); });
    std::vector<double> boundV, boundS;
    for (double r : o.radii) boundV.push_back(std::abs(offV(r))), boundS.push_back(std::abs(offS(r)));
    printErrors("  max |value - closed form|, the first-order chord offset, and the residual after it",
                o.radii,
                {eV, eS, eP, eL, boundV, boundS, cV, cS},
                "dV         dS         dP         dL         offset V   offset S   resid V    resid S");

    const double medianEdge = 1.09 * 0.15;  // generators.h: mean edge ~1.09 x spacing
    std::size_t asserted = 0;
    for (std::size_t j = 0; j < o.radii.size(); ++j) {
        const double r = o.radii[j];
        if (r < 3 * medianEdge) continue;
        ++asserted;
        EXPECT_LE(eV[j], 1.5 * boundV[j] + 5e-5) << "radius " << r;
        EXPECT_LE(eS[j], 1.5 * boundS[j] + 5e-5) << "radius " << r;
        EXPECT_LE(cV[j], 0.5 * boundV[j] + 2e-5) << "radius " << r;
        EXPECT_LE(cS[j], 0.5 * boundS[j] + 2e-5) << "radius " << r;
        EXPECT_LE(eV[j], 1e-3) << "radius " << r;
        EXPECT_LE(eS[j], 1e-3) << "radius " << r;
        // Measured 3e-5 (P̂: about g/R, the chords shrink the patch) and 2e-5 (L̂).
        EXPECT_LE(eP[j], 1e-4) << "radius " << r;
        EXPECT_LE(eL[j], 1e-4) << "radius " << r;
    }
    EXPECT_GE(asserted, 13u);
}

} // namespace

TEST(Exact, ConvexSphereMatchesClosedForm) { checkSphere(false); }

TEST(Exact, SphericalCavityMatchesClosedForm) { checkSphere(true); }

namespace {
samples::HeightFieldOptions terrainSlab()
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Terrain;
    ho.width = 10;
    ho.height = 8;
    ho.spacing = 0.1;
    ho.closed = true;
    ho.thickness = 4;
    ho.seed = 5;
    return ho;
}

std::vector<std::uint32_t> middleTopVertices(const TriMesh& mesh, std::size_t count)
{
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < mesh.numVertices() && out.size() < count; i += 13) {
        const Vec3& q = mesh.points[i];
        if (q.x > 3 && q.x < 7 && q.y > 3 && q.y < 5 && q.z > -1) out.push_back(std::uint32_t(i));
    }
    return out;
}
} // namespace

// S is the radial derivative of V (docs/method.md, Exact identities): central differences
// of the exact V over ±1e-4 match the exact S, on a curved, irregular surface.
TEST(Exact, SphereAreaIsVolumeDerivative)
{
    const TriMesh mesh = samples::makeHeightField(terrainSlab());
    ExactOptions o;
    o.vertices = middleTopVertices(mesh, 40);
    ASSERT_GE(o.vertices.size(), 20u);
    const double delta = 1e-4;
    const double centres[] = {0.3, 0.75, 1.2, 1.9};
    for (double r : centres) o.radii.insert(o.radii.end(), {r - delta, r, r + delta});
    const ExactResult res = computeExact(mesh, o);
    double worst = 0;
    for (std::size_t c = 0; c < std::size(centres); ++c) {
        const double r = centres[c];
        double maxRel = 0;
        for (std::size_t k = 0; k < o.vertices.size(); ++k) {
            const auto volume = [&](std::size_t j) {
                return res.volume[j][k] * 4.0 / 3.0 * kPi * std::pow(o.radii[j], 3);
            };
            const double dVdr = (volume(3 * c + 2) - volume(3 * c)) / (2 * delta);
            const double s = res.sphere[3 * c + 1][k] * 4 * kPi * r * r;
            // The central difference of V ≈ a r³ is 3a r² + a δ²: remove that δ²/(3r²) part.
            maxRel = std::max(maxRel, std::abs(dVdr - s * (1 + delta * delta / (3 * r * r))) / s);
        }
        std::printf("S = dV/dr at r = %.2f: max relative difference %.2e over %zu vertices\n", r, maxRel,
                    o.vertices.size());
        worst = std::max(worst, maxRel);
    }
    EXPECT_LE(worst, 1e-7);
}

// A closed solid entirely inside the ball: S = 0, so Ω_p = Σ Ω_t (Gauss), and V is the
// solid's volume, at every vertex (corners, saddles, the slab's edges); for a cavity the
// ball holds everything but the hole: Ŝ = 1. This checks the cone angle Ω_p independently
// (S = dV/dr holds whatever Ω_p is: an error ε in Ω_p adds εr² to S and εr³/3 to V).
TEST(Exact, WholeSolidInsideTheBall)
{
    const auto signedVolume = [](const TriMesh& m) {
        double v = 0;
        for (const auto& t : m.triangles) v += dot(m.points[t[0]], cross(m.points[t[1]], m.points[t[2]])) / 6;
        return v;
    };
    samples::HeightFieldOptions ho = terrainSlab();
    ho.spacing = 0.2;
    samples::SphereOptions so;
    so.radius = 3;
    so.spacing = 0.3;
    so.cavity = true;
    const TriMesh meshes[2] = {samples::makeHeightField(ho), samples::makeSphere(so)};
    for (int which = 0; which < 2; ++which) {
        const TriMesh& mesh = meshes[which];
        const double volume = signedVolume(mesh);  // < 0 for the cavity: the hole's volume
        ExactOptions o;
        o.radii = {20.0, 30.0};
        for (std::size_t i = 0; i < mesh.numVertices(); i += 37) o.vertices.push_back(std::uint32_t(i));
        const ExactResult res = computeExact(mesh, o);
        double maxS = 0, maxV = 0;
        for (std::size_t j = 0; j < o.radii.size(); ++j) {
            const double r = o.radii[j], ball = 4.0 / 3.0 * kPi * r * r * r;
            const double expectV = which == 0 ? volume / ball : 1 + volume / ball;
            const double expectS = which == 0 ? 0.0 : 1.0;
            for (std::size_t k = 0; k < o.vertices.size(); ++k) {
                maxS = std::max(maxS, std::abs(res.sphere[j][k] - expectS));
                maxV = std::max(maxV, std::abs(res.volume[j][k] - expectV) / std::abs(volume / ball));
            }
        }
        std::printf("%s inside the ball: %zu vertices, max |dS| %.2e, max relative volume error %.2e\n",
                    which == 0 ? "terrain slab" : "spherical cavity", o.vertices.size(), maxS, maxV);
        EXPECT_LE(maxS, 1e-12);
        EXPECT_LE(maxV, 1e-10);
    }
}

TEST(Exact, RigidMotionInvariance)
{
    const TriMesh mesh = samples::makeHeightField(terrainSlab());
    TriMesh moved = mesh;
    const Rotation rotate(normalized(Vec3(1, 2, 3)), 0.7);
    for (auto& q : moved.points) q = rotate(q) + Vec3(12.34, -5.6, 7.89);
    ExactOptions o;
    o.radii = equidistant(1.5, 8);
    o.vertices = middleTopVertices(mesh, 40);
    ASSERT_EQ(o.vertices.size(), 40u);
    const ExactResult r1 = computeExact(mesh, o), r2 = computeExact(moved, o);
    double worst = 0;
    std::size_t compared = 0;
    for (std::size_t j = 0; j < o.radii.size(); ++j)
        for (std::size_t k = 0; k < o.vertices.size(); ++k)
            for (const double d : {r1.volume[j][k] - r2.volume[j][k], r1.sphere[j][k] - r2.sphere[j][k],
                                   r1.patch[j][k] - r2.patch[j][k], r1.line[j][k] - r2.line[j][k]}) {
                worst = std::isnan(d) ? INFINITY : std::max(worst, std::abs(d));  // NaN fails
                ++compared;
            }
    std::printf("rigid motion: %zu values compared, max difference %.2e\n", compared, worst);
    EXPECT_EQ(compared, 4 * o.radii.size() * o.vertices.size());
    EXPECT_LE(worst, 1e-11);
}

// Reversing every triangle swaps solid and complement: V̂ and Ŝ become 1 − V̂ and 1 − Ŝ
// (Ω_p and every Ω_t change sign), P̂ and L̂ stay.
TEST(Exact, ReversedOrientationGivesTheComplement)
{
    const TriMesh mesh = samples::makeHeightField(terrainSlab());
    TriMesh reversed = mesh;
    for (auto& t : reversed.triangles) std::swap(t[1], t[2]);
    ExactOptions o;
    o.radii = equidistant(1.5, 8);
    o.vertices = middleTopVertices(mesh, 40);
    ASSERT_EQ(o.vertices.size(), 40u);
    const ExactResult r1 = computeExact(mesh, o), r2 = computeExact(reversed, o);
    double worst = 0;
    std::size_t compared = 0;
    for (std::size_t j = 0; j < o.radii.size(); ++j)
        for (std::size_t k = 0; k < o.vertices.size(); ++k)
            for (const double d : {r1.volume[j][k] + r2.volume[j][k] - 1, r1.sphere[j][k] + r2.sphere[j][k] - 1,
                                   r1.patch[j][k] - r2.patch[j][k], r1.line[j][k] - r2.line[j][k]}) {
                worst = std::isnan(d) ? INFINITY : std::max(worst, std::abs(d));  // NaN fails
                ++compared;
            }
    std::printf("reversed orientation: %zu values compared, max deviation from the complement %.2e\n", compared,
                worst);
    EXPECT_EQ(compared, 4 * o.radii.size() * o.vertices.size());
    EXPECT_LE(worst, 1e-12);
}

TEST(Exact, OnlyWhatIsAsked)
{
    const TriMesh mesh = samples::makeHeightField(terrainSlab());
    ExactOptions o;
    o.radii = {0.5, 1.0};
    o.vertices = middleTopVertices(mesh, 5);
    o.computePatchLine = false;
    const ExactResult vs = computeExact(mesh, o);
    EXPECT_EQ(vs.volume.size(), 2u);
    EXPECT_TRUE(vs.patch.empty() && vs.line.empty());
    o.computePatchLine = true;
    o.computeVolumeSphere = false;
    const ExactResult pl = computeExact(mesh, o);
    EXPECT_TRUE(pl.volume.empty() && pl.sphere.empty());
    ASSERT_EQ(pl.patch.size(), 2u);
    o.computeVolumeSphere = true;
    const ExactResult all = computeExact(mesh, o);
    for (std::size_t j = 0; j < 2; ++j)
        for (std::size_t k = 0; k < o.vertices.size(); ++k) {
            EXPECT_EQ(vs.volume[j][k], all.volume[j][k]);
            EXPECT_EQ(vs.sphere[j][k], all.sphere[j][k]);
            EXPECT_EQ(pl.patch[j][k], all.patch[j][k]);
            EXPECT_EQ(pl.line[j][k], all.line[j][k]);
        }
}

TEST(Exact, RejectsBadInput)
{
    const TriMesh mesh = samples::makeHeightField(flatPatch(true));
    const auto run = [&](std::vector<double> radii, std::vector<std::uint32_t> vertices = {}) {
        ExactOptions o;
        o.radii = std::move(radii);
        o.vertices = std::move(vertices);
        computeExact(mesh, o);
    };
    EXPECT_THROW(run({}), InvalidInputError);
    EXPECT_THROW(run({0.0, 1.0}), InvalidInputError);
    EXPECT_THROW(run({-1.0}), InvalidInputError);
    EXPECT_THROW(run({std::nan("")}), InvalidInputError);
    EXPECT_THROW(run({1.0, 1.0}), InvalidInputError);
    EXPECT_THROW(run({2.0, 1.0}), InvalidInputError);
    const std::uint32_t n = std::uint32_t(mesh.numVertices());
    try {
        run({1.0}, {0, n});
        FAIL() << "no error for an out-of-range vertex";
    } catch (const InvalidInputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(std::to_string(n)), std::string::npos) << what;
        EXPECT_NE(what.find("vertex"), std::string::npos) << what;
    }
    ExactOptions o;
    o.radii = {1.0};
    o.borderDistance = {1.0, 2.0};
    EXPECT_THROW(computeExact(mesh, o), InvalidInputError);
}

TEST(Exact, SameResultsForOneAndTwoThreads)
{
    const TriMesh mesh = samples::makeHeightField(terrainSlab());
    ExactOptions o;
    o.radii = equidistant(1.0, 8);
    o.vertices = middleTopVertices(mesh, 60);
    ExactResult r1, r2;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        r1 = computeExact(mesh, o);
    }
    {
        tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
        r2 = computeExact(mesh, o);
    }
    for (std::size_t j = 0; j < o.radii.size(); ++j)
        for (std::size_t k = 0; k < o.vertices.size(); ++k) {
            ASSERT_TRUE(sameOrBothNaN(r1.volume[j][k], r2.volume[j][k])) << j << " " << k;
            ASSERT_TRUE(sameOrBothNaN(r1.sphere[j][k], r2.sphere[j][k])) << j << " " << k;
            ASSERT_TRUE(sameOrBothNaN(r1.patch[j][k], r2.patch[j][k])) << j << " " << k;
            ASSERT_TRUE(sameOrBothNaN(r1.line[j][k], r2.line[j][k])) << j << " " << k;
        }
}

// computeExact() arranges the per-triangle closed forms for speed (whole triangles summed
// once as a difference array over the radii, solid angles as arguments of products, only
// the line pieces of straddled triangles evaluated). It must agree with the plain sums of
// triangleBallMeasures() over every triangle to 1e-9, on meshes with the awkward cases:
// coplanar neighbours and vertices in other triangles' planes (cube), sharp edges, long
// triangles next to short ones (the slab's walls), an irregular noisy surface, radii that
// fall on corner distances. P̂ and L̂ are compared directly; Ŝ through its differences
// across radii (Ω_p cancels) and V̂ through 3V = Σ d_t area_t + r S.
TEST(Exact, AgreesWithPerTriangleSums)
{
    samples::CubeOptions co;
    co.side = 2;
    co.spacing = 0.2;
    samples::HeightFieldOptions thin;
    thin.kind = samples::HeightFieldKind::Tablet;
    thin.width = 3;
    thin.height = 2;
    thin.spacing = 0.05;
    thin.closed = true;
    thin.thickness = 0.5;
    thin.wedgeSize = 0.8;
    thin.wedgeDensity = 1.0;
    thin.wedgeMargin = 0.3;
    thin.noise = 0.005;
    thin.seed = 3;
    samples::HeightFieldOptions longWalls = thin;  // a fine top over long wall and bottom triangles
    longWalls.thickness = 0.6;
    longWalls.wallStep = 1.0;
    samples::HeightFieldOptions terrain = terrainSlab();
    terrain.spacing = 0.25;
    // Radii reach the far side of the slabs: the bottom's large triangles lie under the top.
    const std::tuple<const char*, TriMesh, double> meshes[] = {
        {"cube", samples::makeCube(co), 0.6},
        {"thin tablet slab", samples::makeHeightField(thin), 0.8},
        {"slab with long walls", samples::makeHeightField(longWalls), 1.2},
        {"terrain slab", samples::makeHeightField(terrain), 4.5}};
    std::size_t compared = 0;
    double worst = 0;
    for (const auto& [name, mesh, R] : meshes) {
        const MeshCheckResult check = checkMesh(mesh);
        ASSERT_TRUE(check.firstProblem().empty() && check.closed && check.numInconsistentEdges == 0) << name;
        ExactOptions o;
        o.radii = equidistant(R, 12);
        std::mt19937_64 rng(11);
        for (int i = 0; i < 25; ++i) o.vertices.push_back(std::uint32_t(rng() % mesh.numVertices()));
        // A radius equal to a corner distance, at the first vertex.
        double onCorner = 0;
        for (std::size_t i = 0; i < mesh.numVertices() && !(onCorner > 0.55 * R && onCorner < 0.6 * R); ++i)
            onCorner = norm(mesh.points[i] - mesh.points[o.vertices[0]]);
        ASSERT_TRUE(onCorner > 0.55 * R && onCorner < 0.6 * R) << name;
        o.radii.push_back(onCorner);
        std::sort(o.radii.begin(), o.radii.end());
        const ExactResult res = computeExact(mesh, o);
        double nameWorst = 0;
        for (std::size_t k = 0; k < o.vertices.size(); ++k) {
            const Vec3& p = mesh.points[o.vertices[k]];
            std::vector<double> omega(o.radii.size()), dArea(o.radii.size());
            for (std::size_t j = 0; j < o.radii.size(); ++j) {
                const double r = o.radii[j];
                double area = 0, arc = 0;
                for (const Triangle& t : mesh.triangles) {
                    const TriangleBallMeasures m =
                        triangleBallMeasures(p, mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], r);
                    area += m.area;
                    arc += m.arcLength;
                    omega[j] += m.solidAngle;
                    dArea[j] += m.distance * m.area;
                }
                const double s = res.sphere[j][k], v = res.volume[j][k];
                const double sExpected = res.sphere[0][k] + (omega[0] - omega[j]) / (4 * kPi);
                const double vExpected = (dArea[j] + r * 4 * kPi * r * r * s) / (4 * kPi * r * r * r);
                for (const double diff : {res.patch[j][k] - area / (kPi * r * r), res.line[j][k] - arc / (2 * kPi * r),
                                          s - sExpected, v - vExpected}) {
                    nameWorst = std::isnan(diff) ? INFINITY : std::max(nameWorst, std::abs(diff));  // NaN fails
                    ++compared;
                }
            }
        }
        std::printf("%s: %zu vertices x %zu radii, max difference from the per-triangle sums %.2e\n", name,
                    o.vertices.size(), o.radii.size(), nameWorst);
        worst = std::max(worst, nameWorst);
    }
    EXPECT_EQ(compared, 4u * 4 * 25 * 13);
    EXPECT_LE(worst, 1e-9);
}
