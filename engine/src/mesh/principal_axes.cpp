#include <msii/mesh/principal_axes.h>

#include <algorithm>
#include <cmath>

namespace msii {

SurfaceMoments surfaceMoments(const TriMesh& mesh, bool covariance)
{
    SurfaceMoments m;
    if (mesh.triangles.empty()) return m;
    // About a point of the surface, so that coordinates far from the origin (UTM,
    // 10⁶ m) do not cancel: E[x xᵀ] − c cᵀ loses the digits the covariance needs.
    const Vec3 ref = mesh.points[mesh.triangles.front()[0]];
    double area = 0;
    Vec3 first, vectorArea;
    Matrix3 second{};
    for (const Triangle& t : mesh.triangles) {
        const Vec3 a = mesh.points[t[0]] - ref, b = mesh.points[t[1]] - ref, c = mesh.points[t[2]] - ref;
        const Vec3 va = cross(b - a, c - a) * 0.5;
        const double A = norm(va);
        area += A;
        vectorArea += va;
        const Vec3 s = a + b + c;
        first += s * (A / 3.0);
        if (!covariance) continue;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                second[i][j] += A / 12.0 * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]);
    }
    if (!(area > 0) || !std::isfinite(area)) return m;
    m.area = area;
    m.vectorArea = vectorArea;
    const Vec3 mean = first / area;
    m.centroid = ref + mean;
    if (!covariance) return m;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m.covariance[i][j] = second[i][j] / area - mean[i] * mean[j];
    return m;
}

PrincipalAxes principalAxes(const Matrix3& symmetric)
{
    Matrix3 a = symmetric, v{};
    for (int i = 0; i < 3; ++i) v[i][i] = 1;
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-30 * diag || off == 0) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
                const double c = 1 / std::sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; ++k) {  // a ← Jᵀ a J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    std::array<int, 3> order{0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int i, int j) { return a[i][i] < a[j][j]; });
    PrincipalAxes result;
    for (std::size_t k = 0; k < 3; ++k) {
        const int o = order[k];
        result.variances[k] = a[o][o];
        result.axes[k] = Vec3(v[0][o], v[1][o], v[2][o]);
    }
    return result;
}

Vec3 canonicalSign(const Vec3& a)
{
    const double ax = std::abs(a.x), ay = std::abs(a.y), az = std::abs(a.z);
    const double big = ax >= ay && ax >= az ? a.x : (ay >= az ? a.y : a.z);
    return big < 0 ? -a : a;
}

}  // namespace msii
