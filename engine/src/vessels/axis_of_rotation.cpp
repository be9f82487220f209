#include <msii/vessels/axis_of_rotation.h>

#include <msii/core/errors.h>
#include <msii/mesh/principal_axes.h>
#include <msii/mesh/vertex_normals.h>

#include "../mesh/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

namespace msii {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Matrix6 = std::array<std::array<double, 6>, 6>;

/// A point of the surface relative to its centroid, its unit normal and the area it stands for.
struct Sample {
    Vec3 p, n;
    double area = 0;
    bool mainSheet = false;  ///< a vertex of the largest smooth sheet (smoothSheets)
};

std::string number(double v)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", v);
    return text;
}

/// The surface's smooth sheets: its triangles joined across edges where their normals differ
/// by less than 30°. The walls of a sherd are its two largest (one, with the lip, for a rim
/// sherd); its break faces meet them at sharp edges and fall apart into small pieces.
struct Sheets {
    std::vector<std::uint32_t> of;  ///< per triangle, its sheet (the smallest triangle in it)
    std::vector<double> area;  ///< per sheet (at its index)
    std::uint32_t largest = 0;
    double total = 0;
};

Sheets smoothSheets(const TriMesh& mesh)
{
    const std::size_t nt = mesh.numTriangles();
    std::vector<Vec3> normal(nt);
    Sheets s;
    s.area.assign(nt, 0.0);
    for (std::size_t t = 0; t < nt; ++t) {
        const Triangle& tri = mesh.triangles[t];
        normal[t] =
            normalized(cross(mesh.points[tri[1]] - mesh.points[tri[0]], mesh.points[tri[2]] - mesh.points[tri[0]]));
    }
    const detail::VertexTriangles around = detail::vertexTriangles(mesh);
    s.of.resize(nt);
    std::iota(s.of.begin(), s.of.end(), 0u);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {  // the triangles across edge (a, b) share both corners
            const std::uint32_t a = mesh.triangles[t][std::size_t(k)], b = mesh.triangles[t][std::size_t((k + 1) % 3)];
            for (std::uint32_t i = around.offsets[a]; i < around.offsets[a + 1]; ++i) {
                const std::uint32_t o = around.triangles[i];
                if (o <= t) continue;
                const Triangle& other = mesh.triangles[o];
                if ((other[0] == b || other[1] == b || other[2] == b) && std::abs(dot(normal[t], normal[o])) > 0.866)
                    detail::unite(s.of, std::uint32_t(t), o);
            }
        }
    for (std::size_t t = 0; t < nt; ++t) {
        const Triangle& tri = mesh.triangles[t];
        const double area =
            0.5 * norm(cross(mesh.points[tri[1]] - mesh.points[tri[0]], mesh.points[tri[2]] - mesh.points[tri[0]]));
        s.of[t] = detail::findRoot(s.of, std::uint32_t(t));
        s.area[s.of[t]] += area, s.total += area;
        if (s.area[s.of[t]] > s.area[s.largest]) s.largest = s.of[t];
    }
    return s;
}

/// Triangles as samples (centroid, normal, area) and vertices as samples (point, vertex
/// normal, a third of the incident area), each marked if on the largest smooth sheet.
void samplesOf(const TriMesh& mesh, const Vec3& centre, const Sheets& sheets, std::vector<Sample>& triangles,
               std::vector<Sample>& vertices)
{
    triangles.resize(mesh.numTriangles());
    std::vector<double> vertexArea(mesh.numVertices(), 0.0);
    std::vector<char> main(mesh.numVertices(), 0);
    for (std::size_t t = 0; t < mesh.numTriangles(); ++t) {
        const Triangle& tri = mesh.triangles[t];
        const Vec3 &a = mesh.points[tri[0]], &b = mesh.points[tri[1]], &c = mesh.points[tri[2]];
        const Vec3 n = cross(b - a, c - a);
        const double area = 0.5 * norm(n);
        const bool onMain = sheets.of[t] == sheets.largest;
        triangles[t] = {(a + b + c) / 3.0 - centre, area > 0 ? normalized(n) : Vec3{}, area, onMain};
        for (std::uint32_t i : tri) vertexArea[i] += area / 3.0, main[i] |= char(onMain);
    }
    const std::vector<Vec3> normals = vertexNormals(mesh);
    vertices.clear();
    vertices.reserve(mesh.numVertices());
    for (std::size_t i = 0; i < mesh.numVertices(); ++i)
        if (vertexArea[i] > 0 && isFinite(mesh.points[i]))
            vertices.push_back({mesh.points[i] - centre, normals[i], vertexArea[i], main[i] != 0});
}

/// Σ f(i) over [0, n) in fixed chunks added in order, so that sums do not depend on threads.
template <class T, class F>
T chunkedSum(std::size_t n, const T& zero, const F& f)
{
    constexpr std::size_t kChunk = 1 << 14;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<T> parts(chunks, zero);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks), [&](const auto& r) {
        for (std::size_t c = r.begin(); c < r.end(); ++c)
            for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) f(i, parts[c]);
    });
    T total = zero;
    for (const T& p : parts) total = total + p;
    return total;
}

/// A 6 × 6 sum (its upper triangle used).
struct Sum6 {
    Matrix6 m{};
    Sum6 operator+(const Sum6& o) const
    {
        Sum6 s;
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) s.m[i][j] = m[i][j] + o.m[i][j];
        return s;
    }
};

/// The median of |values| where the weight is positive, over at most about 20,000 of them
/// (every k-th): a robust scale, not a statistic to report.
double medianAbs(const std::vector<double>& values, const std::vector<double>& weights)
{
    const std::size_t k = std::max<std::size_t>(1, values.size() / 20000);
    std::vector<double> v;
    v.reserve(values.size() / k + 1);
    for (std::size_t i = 0; i < values.size(); i += k)
        if (weights[i] > 0) v.push_back(std::abs(values[i]));
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

/// Tukey's biweight for residual @p e at scale @p s (0 beyond 4.685 s).
double tukey(double e, double s)
{
    if (!(s > 0)) return 1;
    const double u = e / (4.685 * s);
    return std::abs(u) < 1 ? (1 - u * u) * (1 - u * u) : 0.0;
}

/// The line the normal lines meet best: x = (a, ā) minimising Σ w (n·ā + (p × n)·a)² with
/// |a| = 1 (two lines meet where one's direction dotted with the other's moment, plus the
/// reverse, is zero). ā is eliminated through the pseudo-inverse of Σ w n nᵀ (singular for a
/// cylinder, whose normals are all across its axis), leaving a 3 × 3 eigenproblem for a.
struct LineFit {
    Vec3 direction, moment;
    std::array<double, 3> eigen{};  ///< of the reduced problem, ascending
};

LineFit fitLine(const std::vector<Sample>& lines, const std::vector<double>& weights)
{
    const Matrix6 M = chunkedSum(lines.size(), Sum6{}, [&](std::size_t i, Sum6& sum) {
                          Matrix6& m = sum.m;
                          const double w = weights[i] * lines[i].area;
                          if (!(w > 0)) return;
                          const Vec3 mo = cross(lines[i].p, lines[i].n), n = lines[i].n;
                          const double l[6] = {mo.x, mo.y, mo.z, n.x, n.y, n.z};
                          for (int r = 0; r < 6; ++r)
                              for (int c = r; c < 6; ++c) m[r][c] += w * l[r] * l[c];
                      }).m;
    Matrix3 mm{}, mn{}, nn{};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            const auto at = [&](int i, int j) { return i <= j ? M[i][j] : M[j][i]; };
            mm[r][c] = at(r, c), mn[r][c] = at(r, c + 3), nn[r][c] = at(r + 3, c + 3);
        }
    const PrincipalAxes e = principalAxes(nn);
    Matrix3 pinv{};
    for (int k = 0; k < 3; ++k) {
        if (!(e.variances[std::size_t(k)] > 1e-10 * e.variances[2])) continue;
        const Vec3& v = e.axes[std::size_t(k)];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) pinv[r][c] += v[r] * v[c] / e.variances[std::size_t(k)];
    }
    Matrix3 G{}, S{};  // G = Nn⁺ Mnᵀ; S = Mm − Mn G
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) G[r][c] += pinv[r][k] * mn[c][k];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            S[r][c] = mm[r][c];
            for (int k = 0; k < 3; ++k) S[r][c] -= mn[r][k] * G[k][c];
        }
    for (int r = 0; r < 3; ++r)  // symmetric to rounding
        for (int c = r + 1; c < 3; ++c) S[r][c] = S[c][r] = 0.5 * (S[r][c] + S[c][r]);
    const PrincipalAxes s = principalAxes(S);
    LineFit fit;
    fit.direction = normalized(s.axes[0]);
    for (int r = 0; r < 3; ++r)
        fit.moment[r] = -(G[r][0] * fit.direction.x + G[r][1] * fit.direction.y + G[r][2] * fit.direction.z);
    fit.eigen = s.variances;
    return fit;
}

/// The fitted line as a point (nearest the centroid, the origin here) and a direction; the
/// moment's part along the direction (a screw's pitch) dropped.
void lineOf(const LineFit& fit, Vec3& point, Vec3& direction)
{
    direction = fit.direction;
    const Vec3 moment = fit.moment - direction * dot(fit.moment, direction);
    point = cross(direction, moment);
}

/// The axis the normal lines meet, reweighted so that lines far off it (decoration, handles,
/// break faces) lose weight.
void fitNormalLines(const std::vector<Sample>& triangles, int iterations, Vec3& point, Vec3& direction,
                    std::array<double, 3>& eigen)
{
    std::vector<double> weights(triangles.size(), 1.0), residual(triangles.size());
    for (int it = 0; it < iterations; ++it) {
        const LineFit fit = fitLine(triangles, weights);
        lineOf(fit, point, direction);
        eigen = fit.eigen;
        const Vec3 moment = cross(point, direction);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size()), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Sample& s = triangles[i];
                residual[i] = dot(s.n, moment) + dot(cross(s.p, s.n), direction);
            }
        });
        std::vector<double> all(triangles.size(), 1.0);
        const double scale = 1.4826 * medianAbs(residual, all);
        for (std::size_t i = 0; i < triangles.size(); ++i) weights[i] = tukey(residual[i], scale);
    }
}

/// A profile r(h) per side of the wall (0: facing away from the axis, 1: towards it), the
/// weighted mean radius in bins of height, linear between bin centres.
struct Profile {
    double h0 = 0, step = 1;
    std::array<std::vector<double>, 2> r;

    double at(int side, double h, double& slope) const
    {
        const std::vector<double>& v = r[std::size_t(side)];
        const double x = (h - h0) / step - 0.5;
        const int n = int(v.size());
        const int i = std::clamp(int(std::floor(x)), 0, std::max(0, n - 2));
        if (n < 2) return slope = 0, n ? v[0] : 0;
        slope = (v[std::size_t(i) + 1] - v[std::size_t(i)]) / step;
        return v[std::size_t(i)] + (x - i) * (v[std::size_t(i) + 1] - v[std::size_t(i)]);
    }
};

/// The wall: samples whose normal is mostly radial (within 45°), where r is a function of h.
/// side 0 is the side whose normals point away from the axis (the outer wall of a mesh that
/// faces outward; `outerSide` below tells which is outer if it faces inward).
bool onWall(const AxisFrame& f, const Sample& s, int& side, double& h, double& r, Vec3& u)
{
    h = dot(s.p - f.point, f.direction);
    const Vec3 rho = s.p - f.point - f.direction * h;
    r = norm(rho);
    if (!(r > 0)) return false;
    u = rho / r;
    const double radial = dot(s.n, u);
    if (std::abs(radial) < 0.7071) return false;
    side = radial > 0 ? 0 : 1;
    return true;
}

Profile estimateProfile(const AxisFrame& f, const std::vector<Sample>& v, const std::vector<double>& w, double step)
{
    double lo = 1e300, hi = -1e300;
    for (const Sample& s : v) lo = std::min(lo, f.height(s.p)), hi = std::max(hi, f.height(s.p));
    Profile pr;
    pr.h0 = lo, pr.step = step;
    const std::size_t bins = std::size_t(std::max(1.0, std::ceil((hi - lo) / step)));
    std::array<std::vector<double>, 2> sum, weight;
    for (int k = 0; k < 2; ++k) sum[std::size_t(k)].assign(bins, 0), weight[std::size_t(k)].assign(bins, 0);
    for (std::size_t i = 0; i < v.size(); ++i) {
        int side;
        double h, r;
        Vec3 u;
        if (!(w[i] > 0) || !onWall(f, v[i], side, h, r, u)) continue;
        const std::size_t b = std::min(bins - 1, std::size_t(std::max(0.0, (h - lo) / step)));
        sum[std::size_t(side)][b] += w[i] * v[i].area * r, weight[std::size_t(side)][b] += w[i] * v[i].area;
    }
    for (int k = 0; k < 2; ++k) {  // empty bins take their nearest filled neighbour's value
        std::vector<double>& out = pr.r[std::size_t(k)];
        out.assign(bins, std::nan(""));
        for (std::size_t b = 0; b < bins; ++b)
            if (weight[std::size_t(k)][b] > 0) out[b] = sum[std::size_t(k)][b] / weight[std::size_t(k)][b];
        double last = std::nan("");
        for (double& x : out) std::isnan(x) ? (void)(x = last) : (void)(last = x);
        last = std::nan("");
        for (auto it = out.rbegin(); it != out.rend(); ++it) std::isnan(*it) ? (void)(*it = last) : (void)(last = *it);
        for (double& x : out)
            if (std::isnan(x)) x = 0;
    }
    return pr;
}

/// The robust residuals of the wall samples from the profile: r − f(h) (0 off the wall).
struct ProfileFit {
    std::vector<double> residual, weight;  ///< per vertex sample; weight 0 off the wall or an outlier
    double rms = 0, wallArea = 0, inlierArea = 0;
};

ProfileFit profileResiduals(const AxisFrame& f, const std::vector<Sample>& v, const Profile& pr)
{
    ProfileFit fit;
    fit.residual.assign(v.size(), 0);
    fit.weight.assign(v.size(), 0);
    std::vector<double> onIt(v.size(), 0);
    for (std::size_t i = 0; i < v.size(); ++i) {
        int side;
        double h, r, slope;
        Vec3 u;
        if (!onWall(f, v[i], side, h, r, u)) continue;
        fit.residual[i] = r - pr.at(side, h, slope);
        onIt[i] = 1;
    }
    const double scale = 1.4826 * medianAbs(fit.residual, onIt);
    double sum = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (!onIt[i]) continue;
        fit.weight[i] = tukey(fit.residual[i], scale);
        fit.wallArea += v[i].area;
        if (fit.weight[i] > 0) {
            fit.inlierArea += v[i].area;
            sum += v[i].area * fit.residual[i] * fit.residual[i];
        }
    }
    fit.rms = fit.inlierArea > 0 ? std::sqrt(sum / fit.inlierArea) : 0;
    return fit;
}

/// Solves the 4 × 4 symmetric system A x = b (Gaussian elimination with partial pivoting);
/// false if it is singular.
bool solve4(std::array<std::array<double, 4>, 4> A, std::array<double, 4> b, std::array<double, 4>& x)
{
    for (int c = 0; c < 4; ++c) {
        int p = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(A[r][c]) > std::abs(A[p][c])) p = r;
        if (!(std::abs(A[p][c]) > 1e-300)) return false;
        std::swap(A[p], A[c]), std::swap(b[p], b[c]);
        for (int r = c + 1; r < 4; ++r) {
            const double f = A[r][c] / A[c][c];
            for (int k = c; k < 4; ++k) A[r][k] -= f * A[c][k];
            b[r] -= f * b[c];
        }
    }
    for (int r = 3; r >= 0; --r) {
        double s = b[r];
        for (int k = r + 1; k < 4; ++k) s -= A[r][k] * x[k];
        x[r] = s / A[r][r];
    }
    return true;
}

/// One Gauss–Newton step on the axis (shift along e1, e2; tilt towards e1, e2), the profile
/// held: ∂e/∂shift_k = −u·e_k, ∂e/∂tilt_k = −(h + f′(h) r) u·e_k for e = r − f(h).
/// Returns the normal matrix (for the uncertainty) and moves the frame.
std::array<std::array<double, 4>, 4> profileStep(AxisFrame& f, const std::vector<Sample>& v, const Profile& pr,
                                                 const ProfileFit& fit, double& change)
{
    struct Normal {
        std::array<std::array<double, 4>, 4> A{};
        std::array<double, 4> b{};
        Normal operator+(const Normal& o) const
        {
            Normal s = *this;
            for (int i = 0; i < 4; ++i) {
                s.b[i] += o.b[i];
                for (int j = 0; j < 4; ++j) s.A[i][j] += o.A[i][j];
            }
            return s;
        }
    };
    // The profile is fitted again after the step, so what a step changes alike across a bin
    // of one side, it absorbs: each sample's derivatives less their bin's mean (the profile's
    // part projected out) make the steps converge where the profile and the axis trade off,
    // as on a sherd, where moving the axis towards the piece changes every radius about alike.
    const std::size_t bins = pr.r[0].size();
    std::vector<std::array<double, 5>> mean(2 * bins, std::array<double, 5>{});  // Σ w J, Σ w
    const auto derivatives = [&](std::size_t i, int& side, std::size_t& bin, double& e, std::array<double, 4>& J) {
        double h, r, slope;
        Vec3 u;
        if (!(fit.weight[i] > 0) || !onWall(f, v[i], side, h, r, u)) return false;
        e = r - pr.at(side, h, slope);
        const double u1 = dot(u, f.e1), u2 = dot(u, f.e2);
        J = {-u1, -u2, -(h + slope * r) * u1, -(h + slope * r) * u2};
        bin = std::min(bins - 1, std::size_t(std::max(0.0, (h - pr.h0) / pr.step)));
        return true;
    };
    for (std::size_t i = 0; i < v.size(); ++i) {
        int side;
        std::size_t bin;
        double e;
        std::array<double, 4> J;
        if (!derivatives(i, side, bin, e, J)) continue;
        std::array<double, 5>& m = mean[std::size_t(side) * bins + bin];
        const double w = fit.weight[i] * v[i].area;
        for (int a = 0; a < 4; ++a) m[std::size_t(a)] += w * J[std::size_t(a)];
        m[4] += w;
    }
    const Normal n = chunkedSum(v.size(), Normal{}, [&](std::size_t i, Normal& acc) {
        int side;
        std::size_t bin;
        double e;
        std::array<double, 4> J;
        if (!derivatives(i, side, bin, e, J)) return;
        const std::array<double, 5>& m = mean[std::size_t(side) * bins + bin];
        const double w = fit.weight[i] * v[i].area;
        for (int a = 0; a < 4; ++a) J[std::size_t(a)] -= m[std::size_t(a)] / m[4];
        for (int a = 0; a < 4; ++a) {
            acc.b[a] -= w * J[std::size_t(a)] * e;
            for (int c = 0; c < 4; ++c) acc.A[a][c] += w * J[std::size_t(a)] * J[std::size_t(c)];
        }
    });
    std::array<double, 4> x{};
    change = 0;
    if (!solve4(n.A, n.b, x)) return n.A;
    const Vec3 point = f.point + f.e1 * x[0] + f.e2 * x[1];
    const Vec3 direction = normalized(f.direction + f.e1 * x[2] + f.e2 * x[3]);
    change = std::hypot(x[2], x[3]);
    f = AxisFrame(point - direction * dot(point, direction), direction);  // nearest the centroid
    return n.A;
}

/// An algebraic sphere through the points: |p|² + D·p + E = 0 by least squares; returns the
/// RMS of the distance from it relative to its radius (∞ if none).
double sphereMisfit(const std::vector<Sample>& v)
{
    std::array<std::array<double, 4>, 4> A{};
    std::array<double, 4> b{};
    for (const Sample& s : v) {
        const double row[4] = {s.p.x, s.p.y, s.p.z, 1.0}, y = -dot(s.p, s.p);
        for (int i = 0; i < 4; ++i) {
            b[i] += s.area * row[i] * y;
            for (int j = 0; j < 4; ++j) A[i][j] += s.area * row[i] * row[j];
        }
    }
    std::array<double, 4> x{};
    if (!solve4(A, b, x)) return 1e300;
    const Vec3 c(-0.5 * x[0], -0.5 * x[1], -0.5 * x[2]);
    const double rho2 = dot(c, c) - x[3];
    if (!(rho2 > 0)) return 1e300;
    const double rho = std::sqrt(rho2);
    double sum = 0, area = 0;
    for (const Sample& s : v) {
        const double d = norm(s.p - c) - rho;
        sum += s.area * d * d, area += s.area;
    }
    return std::sqrt(sum / area) / rho;
}

/// The refusals that need no axis: a plane (all normals parallel), a sphere.
void refuseDegenerate(const std::vector<Sample>& triangles, const std::vector<Sample>& vertices, double area)
{
    Matrix3 nn{};
    for (const Sample& s : triangles)
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) nn[r][c] += s.area * s.n[r] * s.n[c] / area;
    const PrincipalAxes e = principalAxes(nn);
    if (e.variances[1] < 1e-4)
        throw InvalidInputError("not a surface of revolution: the surface is flat (a plane), and every line across it "
                                "is an axis of rotation of a plane");
    if (sphereMisfit(vertices) < 0.005)
        throw InvalidInputError("not a surface of revolution with one axis: the surface is a sphere, and every line "
                                "through its centre is an axis of rotation of a sphere");
}

/// Every k-th of the @p samples that @p keep, at most about @p most of them, their areas
/// scaled up by k.
template <class Keep>
std::vector<Sample> thinned(const std::vector<Sample>& samples, std::size_t most, const Keep& keep)
{
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < samples.size(); ++i)
        if (keep(i)) kept.push_back(i);
    const std::size_t k = std::max<std::size_t>(1, (kept.size() + most - 1) / most);
    std::vector<Sample> out;
    out.reserve(kept.size() / k + 1);
    for (std::size_t i = 0; i < kept.size(); i += k) {
        out.push_back(samples[kept[i]]);
        out.back().area *= double(k);
    }
    return out;
}

std::vector<Sample> thinned(const std::vector<Sample>& samples, std::size_t most)
{
    return thinned(samples, most, [](std::size_t) { return true; });
}

/// How well the normal lines meet one line along @p a: in the plane across a, the point c
/// that the projected normal lines pass nearest (least squares of their distances, weighted
/// by the normals' part across a), fitted again on the 70 % nearest; returns the RMS of those
/// distances and c in @p centre.
double normalLinesMisfit(const std::vector<Sample>& v, const Vec3& a, Vec3& centre)
{
    const AxisFrame f(Vec3{}, a);
    double cx = 0, cy = 0;
    std::vector<double> distance(v.size());
    double keep = 1e300;  // the first round takes all
    for (int round = 0; round < 2; ++round) {
        double A00 = 0, A01 = 0, A11 = 0, b0 = 0, b1 = 0;
        for (std::size_t i = 0; i < v.size(); ++i) {
            if (distance[i] > keep) continue;
            const double nx = dot(v[i].n, f.e1), ny = dot(v[i].n, f.e2), x = dot(v[i].p, f.e1), y = dot(v[i].p, f.e2);
            const double m = nx * y - ny * x;  // e = m + ny cx − nx cy
            A00 += ny * ny, A01 -= ny * nx, A11 += nx * nx, b0 -= ny * m, b1 += nx * m;
        }
        const double det = A00 * A11 - A01 * A01;
        if (!(det > 0)) return 1e300;
        cx = (A11 * b0 - A01 * b1) / det, cy = (A00 * b1 - A01 * b0) / det;
        for (std::size_t i = 0; i < v.size(); ++i) {
            const double nx = dot(v[i].n, f.e1), ny = dot(v[i].n, f.e2), x = dot(v[i].p, f.e1), y = dot(v[i].p, f.e2);
            const double across = std::sqrt(nx * nx + ny * ny);
            distance[i] = across > 0.3 ? std::abs(nx * (y - cy) - ny * (x - cx)) / across : 1e299;
        }
        std::vector<double> sorted(distance);
        const std::size_t k = std::size_t(0.7 * double(sorted.size()));
        std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(k), sorted.end());
        keep = sorted[k];
    }
    double sum = 0, n = 0;
    for (double d : distance)
        if (d <= keep) sum += d * d, n += 1;
    centre = f.e1 * cx + f.e2 * cy;
    return n > 0 ? std::sqrt(sum / n) : 1e300;
}

/// Starts for the axis that break faces cannot pull away (a sherd's may hold a fifth of its
/// area): the @p count directions, on a grid over the half sphere, whose normal lines meet
/// one line best (normalLinesMisfit, on a few thousand samples), each refined twice around it.
std::vector<AxisFrame> searchDirections(const std::vector<Sample>& all, std::size_t count)
{
    std::vector<Sample> v;
    const std::size_t k = std::max<std::size_t>(1, all.size() / 3000);
    for (std::size_t i = 0; i < all.size(); i += k) v.push_back(all[i]);
    struct Found {
        double misfit;
        Vec3 direction, point;
    };
    constexpr int kDirections = 1500;  // a Fibonacci lattice on the half sphere: about 3° apart
    std::vector<Found> grid(kDirections);
    tbb::parallel_for(0, kDirections, [&](int i) {
        const double z = (i + 0.5) / kDirections, r = std::sqrt(1 - z * z), phi = i * 2.39996322972865332;
        Found& g = grid[std::size_t(i)];
        g.direction = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        g.misfit = normalLinesMisfit(v, g.direction, g.point);
    });
    // The best directions at least 10° apart (the valleys of an ambiguous piece), each refined
    // on two finer grids around it.
    std::sort(grid.begin(), grid.end(), [](const Found& a, const Found& b) { return a.misfit < b.misfit; });
    std::vector<AxisFrame> starts;
    std::vector<Vec3> taken;
    for (const Found& g : grid) {
        if (starts.size() >= count) break;
        if (std::any_of(taken.begin(), taken.end(),
                        [&](const Vec3& t) { return std::abs(dot(t, g.direction)) > 0.985; }))
            continue;
        taken.push_back(g.direction);
        Found best = g;
        for (const double spread : {0.06, 0.008}) {  // radians
            const AxisFrame f(Vec3{}, best.direction);
            const Vec3 centre = best.direction;
            std::vector<Found> around(13 * 13);
            tbb::parallel_for(0, 13 * 13, [&](int k) {
                const int i = k / 13 - 6, j = k % 13 - 6;
                Found& t = around[std::size_t(k)];
                t.direction = normalized(centre + f.e1 * (spread * i / 6) + f.e2 * (spread * j / 6));
                t.misfit = normalLinesMisfit(v, t.direction, t.point);
            });
            for (const Found& t : around)  // the first of the best, in the grid's order
                if (t.misfit < best.misfit) best = t;
        }
        starts.emplace_back(best.point - best.direction * dot(best.point, best.direction), best.direction);
    }
    return starts;
}

/// The median |profile residual| over the wall's samples: how well an axis fits, robustly.
double medianMisfit(const ProfileFit& fit)
{
    std::vector<double> wall(fit.weight.size(), 0.0);
    for (std::size_t i = 0; i < wall.size(); ++i) wall[i] = fit.residual[i] != 0 ? 1.0 : 0.0;
    return medianAbs(fit.residual, wall);
}

/// The median length of the mesh's edges (of every triangle's first edge).
double medianEdge(const TriMesh& mesh)
{
    std::vector<double> lengths;
    lengths.reserve(mesh.numTriangles());
    for (const Triangle& t : mesh.triangles) lengths.push_back(norm(mesh.points[t[1]] - mesh.points[t[0]]));
    if (lengths.empty()) return 0;
    std::nth_element(lengths.begin(), lengths.begin() + std::ptrdiff_t(lengths.size() / 2), lengths.end());
    return lengths[lengths.size() / 2];
}

/// The axis refined on the profile (the normal lines' axis to start with); returns the
/// direction's uncertainty in degrees.
double refineOnProfile(AxisFrame& f, const std::vector<Sample>& v, double step, int iterations, ProfileFit& fit,
                       Profile& profile)
{
    std::vector<double> all(v.size(), 1.0);
    profile = estimateProfile(f, v, all, step);
    fit = profileResiduals(f, v, profile);
    std::array<std::array<double, 4>, 4> A{};
    for (int it = 0; it < iterations; ++it) {
        double change = 0;
        A = profileStep(f, v, profile, fit, change);
        profile = estimateProfile(f, v, fit.weight, step);
        fit = profileResiduals(f, v, profile);

        if (change < 1e-9) break;
    }
    // The tilt's covariance, σ² (JᵀWJ)⁻¹, from its 2 × 2 block of the inverse.
    std::array<std::array<double, 4>, 4> inv{};
    for (int c = 0; c < 4; ++c) {
        std::array<double, 4> unit{}, column{};
        unit[std::size_t(c)] = 1;
        if (!solve4(A, unit, column)) return 180.0;
        for (int r = 0; r < 4; ++r) inv[r][c] = column[std::size_t(r)];
    }
    const double a = inv[2][2], b = 0.5 * (inv[2][3] + inv[3][2]), d = inv[3][3];
    const double largest = 0.5 * (a + d) + std::sqrt(0.25 * (a - d) * (a - d) + b * b);
    // The weights are areas: the residuals' variance per unit weight is rms² · area / n.
    std::size_t n = 0;
    for (double w : fit.weight) n += w > 0;
    const double sigma2 = fit.rms * fit.rms * fit.inlierArea / double(std::max<std::size_t>(n, 5) - 4);
    return std::atan(std::sqrt(std::max(0.0, sigma2 * largest))) * 180.0 / kPi;
}

/// The outer wall's best cylinder and cone, and the shape class: the simplest whose misfit is
/// within 1.3 times the profile's (plus a thousandth of the radius).
void classify(const AxisFrame& f, const std::vector<Sample>& v, const ProfileFit& fit, int outer, AxisOfRotation& out)
{
    double W = 0, Sh = 0, Sr = 0, Shh = 0, Shr = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        int side;
        double h, r;
        Vec3 u;
        if (!(fit.weight[i] > 0) || !onWall(f, v[i], side, h, r, u) || side != outer) continue;
        const double w = fit.weight[i] * v[i].area;
        W += w, Sh += w * h, Sr += w * r, Shh += w * h * h, Shr += w * h * r;
    }
    if (!(W > 0)) return;
    out.meanRadius = out.cylinderRadius = Sr / W;
    const double denominator = W * Shh - Sh * Sh;
    out.coneSlope = denominator > 0 ? (W * Shr - Sh * Sr) / denominator : 0;
    out.coneRadius0 = (Sr - out.coneSlope * Sh) / W;
    double cylinder = 0, cone = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        int side;
        double h, r;
        Vec3 u;
        if (!(fit.weight[i] > 0) || !onWall(f, v[i], side, h, r, u) || side != outer) continue;
        const double w = fit.weight[i] * v[i].area, c = r - out.cylinderRadius,
                     k = r - out.coneRadius0 - out.coneSlope * h;
        cylinder += w * c * c, cone += w * k * k;
    }
    out.cylinderMisfit = std::sqrt(cylinder / W), out.coneMisfit = std::sqrt(cone / W);
    const double tolerance = 1.3 * fit.rms + 1e-3 * out.meanRadius;
    out.shape = out.cylinderMisfit <= tolerance ? RevolutionShape::Cylinder
                : out.coneMisfit <= tolerance   ? RevolutionShape::Cone
                                                : RevolutionShape::General;
}

/// Which side of the wall is the outer one: 0 (normals pointing away from the axis) unless,
/// where the profile has both sides, the other lies further out (a mesh facing inward).
int outerSide(const Profile& pr)
{
    double sum = 0;
    for (std::size_t b = 0; b < pr.r[0].size(); ++b)
        if (pr.r[0][b] > 0 && pr.r[1][b] > 0) sum += pr.r[1][b] - pr.r[0][b];
    return sum > 0 ? 1 : 0;
}

/// Whether the surface reaches the axis within a tenth of the height of the end at @p end
/// (a base, or a closed end).
bool closedAt(const AxisFrame& f, const std::vector<Sample>& v, double end, double height, double radius)
{
    for (const Sample& s : v)
        if (std::abs(f.height(s.p) - end) < 0.1 * height && f.radius(s.p) < 0.25 * radius) return true;
    return false;
}

/// Least squares r = c0 + c1 h over the samples @p take accepts; false with fewer than 3.
template <class Take>
bool fitLineOfRadius(const AxisFrame& f, const std::vector<Sample>& v, const Take& take, double& c0, double& c1)
{
    double W = 0, Sh = 0, Sr = 0, Shh = 0, Shr = 0;
    for (const Sample& s : v) {
        const double h = f.height(s.p), r = f.radius(s.p);
        if (!take(s, h)) continue;
        W += 1, Sh += h, Sr += r, Shh += h * h, Shr += h * r;
    }
    const double d = W * Shh - Sh * Sh;
    if (W < 3 || !(d > 0)) return false;
    c1 = (W * Shr - Sh * Sr) / d, c0 = (Sr - c1 * Sh) / W;
    return true;
}

/// Least squares r = c0 + c1 (h − at) + c2 (h − at)² over the samples @p take accepts: the
/// radius c0 and slope c1 at @p at; false with fewer than 4.
template <class Take>
bool fitRadiusAt(const AxisFrame& f, const std::vector<Sample>& v, double at, const Take& take, double& c0, double& c1)
{
    std::array<std::array<double, 4>, 4> A{};
    std::array<double, 4> b{};
    int n = 0;
    for (const Sample& s : v) {
        const double h = f.height(s.p);
        if (!take(s, h)) continue;
        const double x = h - at, row[3] = {1, x, x * x}, r = f.radius(s.p);
        for (int i = 0; i < 3; ++i) {
            b[i] += row[i] * r;
            for (int j = 0; j < 3; ++j) A[i][j] += row[i] * row[j];
        }
        ++n;
    }
    A[3][3] = 1;  // the fourth unknown is 0
    std::array<double, 4> c{};
    if (n < 4 || !solve4(A, b, c)) return false;
    c0 = c[0], c1 = c[1];
    return true;
}

/// The outer diameter at the top of the rim, where the outer wall meets the lip: the lip is
/// taken to round the wall's end across its thickness w (along the wall's normal), so it
/// starts w/2 + (w/2)·sin(tilt) below the top (the wall leaning out by the tilt); the outer
/// wall's radius there, from a line through its points just below.
std::optional<double> rimDiameterAt(const AxisFrame& f, const std::vector<Sample>& v, double top, double edge,
                                    int outer)
{
    const double sign = outer == 0 ? 1.0 : -1.0;
    const auto facing = [&](const Sample& s) {  // +1 outer wall, −1 inner wall, 0 neither (radial within 45°)
        const Vec3 d = s.p - f.point, rho = d - f.direction * dot(d, f.direction);
        const double r = norm(rho), radial = r > 0 ? sign * dot(s.n, rho) / r : 0;
        return radial > 0.7071 ? 1 : radial < -0.7071 ? -1 : 0;
    };
    // The wall's horizontal thickness near the top: per bin of height in the top quarter,
    // the outer side's mean radius less the inner side's; their median.
    constexpr int kBins = 50;  // of at least 1.5 edges, over at least the top quarter
    const double band = std::min(top, std::max(0.25 * top, 75 * edge)), step = band / kBins;
    std::array<double, kBins> sum[2] = {}, count[2] = {};
    for (const Sample& s : v) {
        const double h = f.height(s.p);
        const int side = facing(s);
        if (side == 0 || h < top - band || h >= top) continue;
        const std::size_t b = std::min<std::size_t>(kBins - 1, std::size_t((h - (top - band)) / step));
        sum[side > 0 ? 0 : 1][b] += f.radius(s.p), count[side > 0 ? 0 : 1][b] += 1;
    }
    // The thickness along the wall's normal: the horizontal gap times the cosine of the
    // outer wall's local tilt (from the neighbouring bins).
    std::vector<double> thickness;
    for (std::size_t b = 1; b + 1 < kBins; ++b) {
        if (!(count[0][b] > 0 && count[1][b] > 0 && count[0][b - 1] > 0 && count[0][b + 1] > 0)) continue;
        const double slope = (sum[0][b + 1] / count[0][b + 1] - sum[0][b - 1] / count[0][b - 1]) / (2 * step);
        thickness.push_back((sum[0][b] / count[0][b] - sum[1][b] / count[1][b]) / std::sqrt(1 + slope * slope));
    }
    if (thickness.empty()) return std::nullopt;
    std::nth_element(thickness.begin(), thickness.begin() + std::ptrdiff_t(thickness.size() / 2), thickness.end());
    const double w = thickness[thickness.size() / 2];
    double c0, k;
    if (!(w > 0) ||
        !fitLineOfRadius(
            f, v, [&](const Sample& s, double h) { return facing(s) > 0 && h > top - 3 * w && h < top - 1.5 * w; }, c0,
            k))
        return std::nullopt;
    // Where the lip starts depends on the wall's tilt there, and the tilt (the slope of the
    // outer wall just below, from a quadratic through its points) on where that is: a few
    // rounds.
    double start = top - w;
    for (int round = 0; round < 4; ++round) {
        const double cosT = 1 / std::sqrt(1 + k * k);
        start = top - 0.5 * w - 0.5 * w * k * cosT;
        if (!fitRadiusAt(
                f, v, start,
                [&](const Sample& s, double h) {
                    return facing(s) > 0 && h > start - std::max(1.5 * w, 6 * edge) && h <= start;
                },
                c0, k))
            return std::nullopt;
    }
    return 2 * c0;
}

/// The rim at the top end (h largest) if it is one: the top edge is level (its highest point
/// per 5° of angle within a few edges of the top, wherever the surface is) and goes all
/// round (a whole vessel) or is rounded into a lip (a rim sherd: the top lies on the wall's
/// own smooth sheet); its diameter where the outer wall meets the lip.
std::optional<double> rimAtTop(const AxisFrame& f, const std::vector<Sample>& v, double top, double edge, int outer)
{
    std::array<double, 72> highest;
    highest.fill(-1e300);
    for (const Sample& s : v) {
        const std::size_t bin = std::min<std::size_t>(71, std::size_t((f.angle(s.p) + kPi) / (2 * kPi) * 72));
        highest[bin] = std::max(highest[bin], f.height(s.p));
    }
    const double level = 3 * edge;
    int covered = 0, atTop = 0;
    for (double h : highest) covered += h > -1e299, atTop += h > top - level;
    if (covered == 0 || atTop < 0.9 * covered) return std::nullopt;
    // All round and level, it is a rim. A piece's level top is one if a lip rounds the wall's
    // end: the top lies on the wall's own smooth sheet; a break meets the walls at sharp
    // edges, its top on sheets of its own.
    double topArea = 0, lipArea = 0;
    for (const Sample& s : v)
        if (f.height(s.p) > top - level) topArea += s.area, lipArea += s.mainSheet ? s.area : 0;
    if (covered < 66 && !(lipArea >= 0.8 * topArea)) return std::nullopt;
    return rimDiameterAt(f, v, top, edge, outer);
}

}  // namespace

namespace {

/// The bins of height a profile takes: two edges, and at least 30 samples each on average.
double binWidth(const AxisFrame& f, const std::vector<Sample>& v, double edge)
{
    double lo = 1e300, hi = -1e300;
    for (const Sample& s : v) lo = std::min(lo, f.height(s.p)), hi = std::max(hi, f.height(s.p));
    return std::max({2 * edge, (hi - lo) * 30.0 / double(std::max<std::size_t>(v.size(), 1)), (hi - lo) / 2000.0});
}

/// The places to start the refinement from: the normal lines' axis (best where the surface is
/// mostly of revolution: whole vessels), the same over the large smooth sheets alone (a
/// sherd's walls, not its breaks), and the directions' search (which break faces cannot pull
/// away, and which follows each valley of a piece whose axis is less plain).
std::vector<AxisFrame> startsOf(const std::vector<Sample>& allTriangles, const std::vector<Sample>& vertices,
                                const Sheets& sheets, const AxisFitOptions& options)
{
    Vec3 point, direction;
    std::array<double, 3> eigen{};
    fitNormalLines(thinned(allTriangles, 100000), options.lineIterations, point, direction, eigen);
    std::vector<AxisFrame> starts{AxisFrame(point, direction)};
    std::size_t onSheets = 0;
    const auto onLargeSheet = [&](std::size_t t) { return sheets.area[sheets.of[t]] >= 0.1 * sheets.total; };
    for (std::size_t t = 0; t < allTriangles.size(); ++t) onSheets += onLargeSheet(t) ? 1 : 0;
    if (onSheets > 100 && onSheets < allTriangles.size()) {
        const std::vector<Sample> sheetLines = thinned(allTriangles, 100000, onLargeSheet);
        fitNormalLines(sheetLines, options.lineIterations, point, direction, eigen);
        starts.emplace_back(point, direction);
    }
    const std::vector<AxisFrame> searched = searchDirections(vertices, 4);
    starts.insert(starts.end(), searched.begin(), searched.end());
    return starts;
}

/// The best of @p starts, each refined on a few tens of thousands of samples (@p few). A piece
/// that is nearly a sphere (a vessel's belly) leaves a long, shallow valley, along which the
/// steps crawl: the best is then tilted by 8°, 4°, 2° and 1° each way, refined again, and
/// what fits better kept, until nothing does.
AxisFrame bestStart(const std::vector<AxisFrame>& starts, const std::vector<Sample>& few, double edge,
                    const AxisFitOptions& options)
{
    AxisFrame f = starts[0];
    double bestMisfit = 1e300;
    // Each start refined on its own (in parallel), then taken in order: the first that fits
    // better than the best so far by the factor @p better.
    const auto tryStarts = [&](std::vector<AxisFrame> tried, int iterations, double better) {
        std::vector<double> misfit(tried.size());
        tbb::parallel_for(std::size_t(0), tried.size(), [&](std::size_t k) {
            ProfileFit fit;
            Profile profile;
            refineOnProfile(tried[k], few, binWidth(tried[k], few, edge), iterations, fit, profile);
            misfit[k] = medianMisfit(fit);
        });
        bool improved = false;
        for (std::size_t k = 0; k < tried.size(); ++k)
            if (misfit[k] < better * bestMisfit) bestMisfit = misfit[k], f = tried[k], improved = true;
        return improved;
    };
    tryStarts(starts, options.profileIterations, 1.0);
    for (const double tilt : {0.14, 0.07, 0.035, 0.0175})
        for (bool better = true; better;) {
            const AxisFrame around = f;
            std::vector<AxisFrame> tilted;
            for (int k = 0; k < 8; ++k) {
                const Vec3 side = around.e1 * std::cos(k * kPi / 4) + around.e2 * std::sin(k * kPi / 4);
                tilted.emplace_back(around.point, around.direction + side * tilt);
            }
            better = tryStarts(tilted, 4, 0.98);
        }
    return f;
}

/// The refusals of a fit that does not describe a surface of revolution.
void refuseMisfit(const ProfileFit& fit, const AxisOfRotation& out, double area, const AxisFitOptions& options)
{
    if (!(fit.wallArea > 0.2 * area))
        throw InvalidInputError("too little wall to fit an axis to: " + number(100 * fit.wallArea / area) +
                                " % of the surface faces away from (or towards) the best axis, at least 20 % is "
                                "needed (flat forms such as plates, dishes and lids are not handled)");
    if (!(out.meanRadius > 0) || fit.inlierArea < 0.5 * fit.wallArea ||
        fit.rms > options.notRevolution * out.meanRadius)
        throw InvalidInputError("not a surface of revolution: its wall lies " + number(fit.rms) +
                                " (RMS, in the mesh's units) from the best one, " +
                                number(100 * fit.rms / std::max(out.meanRadius, 1e-300)) + " % of its radius");
    if (out.directionUncertainty > options.uncertainDegrees)
        throw InvalidInputError(
            "too little of a surface of revolution to tell its axis: the direction is uncertain by " +
            number(out.directionUncertainty) + " degrees");
}

/// The axis turned from the base (the end where the surface reaches the axis) towards the
/// open end, or where neither is a base towards a rim, its point moved to the lowest point;
/// the rim diameter, where there is a rim.
void orientAndMeasure(AxisFrame& f, const std::vector<Sample>& v, const ProfileFit& fit, int outer, double edge,
                      AxisOfRotation& out)
{
    double lo = 1e300, hi = -1e300;
    for (const Sample& s : v) lo = std::min(lo, f.height(s.p)), hi = std::max(hi, f.height(s.p));
    out.height = hi - lo;
    const bool baseLow = closedAt(f, v, lo, out.height, out.meanRadius);
    const bool baseHigh = closedAt(f, v, hi, out.height, out.meanRadius);
    const auto turn = [&] { f = AxisFrame(f.point, -f.direction), std::swap(lo, hi), lo = -lo, hi = -hi; };
    if (baseHigh && !baseLow) turn();
    if (!baseLow && !baseHigh && !rimAtTop(f, v, hi, edge, outer) &&
        rimAtTop(AxisFrame(f.point, -f.direction), v, -lo, edge, outer))
        turn();
    f = AxisFrame(f.point + f.direction * lo, f.direction);
    classify(f, v, fit, outer, out);  // the cone's radius at the new origin
    if (!(baseLow && baseHigh)) out.rimDiameter = rimAtTop(f, v, hi - lo, edge, outer);
}

}  // namespace

AxisOfRotation fitAxisOfRotation(const TriMesh& mesh, const AxisFitOptions& options)
{
    const SurfaceMoments m = surfaceMoments(mesh, false);
    if (!(m.area > 0)) throw InvalidInputError("the mesh has no area: no axis to find");
    const Sheets sheets = smoothSheets(mesh);
    std::vector<Sample> allTriangles, vertices;
    samplesOf(mesh, m.centroid, sheets, allTriangles, vertices);
    // Every k-th sample, at most about 100,000 of each: plenty for five parameters, and the
    // fit's time stays bounded on meshes of millions of vertices.
    const std::vector<Sample> triangles = thinned(allTriangles, 100000);
    vertices = thinned(vertices, 100000);
    refuseDegenerate(triangles, vertices, m.area);
    const double edge = medianEdge(mesh);

    std::vector<Sample> few;
    for (std::size_t i = 0, k = std::max<std::size_t>(1, vertices.size() / 20000); i < vertices.size(); i += k)
        few.push_back(vertices[i]);
    AxisFrame f = bestStart(startsOf(allTriangles, vertices, sheets, options), few, edge, options);
    ProfileFit fit;
    Profile profile;
    AxisOfRotation out;
    out.directionUncertainty =
        refineOnProfile(f, vertices, binWidth(f, vertices, edge), options.profileIterations, fit, profile);
    const int outer = outerSide(profile);
    classify(f, vertices, fit, outer, out);
    out.residual = fit.rms;
    out.inlierShare = fit.inlierArea / m.area;
    refuseMisfit(fit, out, m.area, options);
    orientAndMeasure(f, vertices, fit, outer, edge, out);
    out.point = f.point + m.centroid;
    out.direction = f.direction;
    return out;
}

const char* revolutionShapeName(RevolutionShape shape)
{
    switch (shape) {
    case RevolutionShape::Cylinder:
        return "cylinder";
    case RevolutionShape::Cone:
        return "cone";
    case RevolutionShape::General:
        break;
    }
    return "surface of revolution";
}

AxisFrame::AxisFrame(const Vec3& p, const Vec3& d) : point(p), direction(normalized(d))
{
    const Vec3 helper = std::abs(direction.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    e1 = normalized(helper - direction * dot(helper, direction));
    e2 = cross(direction, e1);
}

double AxisFrame::radius(const Vec3& p) const
{
    const Vec3 d = p - point;
    return norm(d - direction * dot(d, direction));
}

double AxisFrame::angle(const Vec3& p) const
{
    const Vec3 d = p - point;
    return std::atan2(dot(d, e2), dot(d, e1));
}

}  // namespace msii
