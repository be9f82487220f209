#include "patch_line_fit.h"

#include "patch_line_gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace msii::detail {
namespace {

/// Samples whose normals lie within about 18° of a point's normal on average (mean (n·n_p)²
/// at least this) are on the same smooth side of the surface: P̂ and L̂ bend across creases,
/// where a fit over both sides would blur them.
constexpr double kSameSide = 0.9;
/// The fit needs at least 6 such samples spread around the point: det M / M₀₀³ of its
/// normal equations at least this (a full disc of samples gives about 0.2).
constexpr double kWellSpread = 0.02;

/// interpolateFromSamples's points go in groups of 2³ cells (of 4³, four fifths of the
/// samples near a group lie beyond 2h of a point; of 2³, two thirds).
constexpr int kFitGroupBits = 1;

/// The weighted RMS residual of the least-squares fit (normal equations @p m, determinant
/// @p det; samples @p index with weights @p weight and basis @p basis) of each field with a
/// residuals entry, into residuals[f][i]: Σ w (f − c·φ)² = Σ w f² − c·b with b = Σ w φ f
/// and c = m⁻¹ b.
void fitResiduals(const double m[3][3], double det, const std::vector<std::uint32_t>& index,
                  const std::vector<double>& weight, const std::vector<std::array<double, 3>>& basis,
                  const std::vector<const float*>& values, const std::vector<float*>& residuals, std::size_t i)
{
    double inverse[3][3];  // m is symmetric: its cofactors over det
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const int a1 = (a + 1) % 3, a2 = (a + 2) % 3, b1 = (b + 1) % 3, b2 = (b + 2) % 3;
            inverse[b][a] = (m[a1][b1] * m[a2][b2] - m[a1][b2] * m[a2][b1]) / det;
        }
    double total = 0;
    for (const double w : weight) total += w;
    for (std::size_t f = 0; f < residuals.size(); ++f) {
        if (!residuals[f]) continue;
        double b[3] = {0, 0, 0}, squares = 0;
        for (std::size_t k = 0; k < index.size(); ++k) {
            const double v = values[f][index[k]], wv = weight[k] * v;
            for (int a = 0; a < 3; ++a) b[a] += wv * basis[k][a];
            squares += wv * v;
        }
        double fitted = 0;
        for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c) fitted += b[a] * inverse[a][c] * b[c];
        residuals[f][i] = float(std::sqrt(std::max(0.0, squares - fitted) / total));
    }
}

/// The samples within the fit's window of the 2^kFitGroupBits-cell box of the group of
/// points whose first point lies in @p c0 (cells of @p level): @p visit(s), with the box's
/// squared distance test of the window (2h) as interpolateFromSamples makes it.
template <class Visit>
void forEachSampleNearGroup(const Level& level, const CellCoord& c0, Visit&& visit)
{
    const std::int64_t groupCells = std::int64_t(1) << kFitGroupBits;
    const double h = level.h, radius2 = 4.0 * h * h, groupSide = double(groupCells) * h;
    const std::array<double, 6> groupBox{0, 0, 0, groupSide, groupSide, groupSide};  // about (ox, oy, oz)
    const std::int64_t gx = c0.x & ~(groupCells - 1), gy = c0.y & ~(groupCells - 1), gz = c0.z & ~(groupCells - 1);
    // Samples within 2h of the group's box: at most 2 cells beyond it.
    const std::int64_t lo[3] = {gx - 2, gy - 2, gz - 2}, hi[3] = {gx + groupCells + 1, gy + groupCells + 1, gz + groupCells + 1};
    const double ox = double(gx - (kOffset >> level.index)) * h, oy = double(gy - (kOffset >> level.index)) * h,
                 oz = double(gz - (kOffset >> level.index)) * h;
    forEachSampleInCells(level, lo, hi, [&](std::uint32_t s) {
        if (squaredDistanceToBox(level.cx[s] - ox, level.cy[s] - oy, level.cz[s] - oz, groupBox) < radius2) visit(s);
    });
}

} // namespace

std::vector<char> samplesBeyondFit(const Level& level, double h0, const std::vector<Vec3>& p,
                                   const std::vector<char>& skip)
{
    const std::size_t ns = level.cx.size();
    const CellGroups groups = groupByCells(p, h0, level.index, kFitGroupBits);
    // Marked from several groups at once: atomic bytes, set to 1 only.
    const std::unique_ptr<std::atomic<std::uint8_t>[]> near(new std::atomic<std::uint8_t>[ns]());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.start.size() - 1), [&](const auto& range) {
        for (std::size_t g = range.begin(); g < range.end(); ++g) {
            bool any = false;
            for (std::size_t q = groups.start[g]; q < groups.start[g + 1] && !any; ++q) any = !skip[groups.order[q].second];
            if (!any) continue;
            forEachSampleNearGroup(level, groups.cell[groups.order[groups.start[g]].second],
                                   [&](std::uint32_t s) { near[s].store(1, std::memory_order_relaxed); });
        }
    });
    std::vector<char> beyond(ns);
    for (std::size_t s = 0; s < ns; ++s) beyond[s] = near[s].load(std::memory_order_relaxed) ? 0 : 1;
    return beyond;
}

void interpolateFromSamples(const Level& level, double h0, const std::vector<Vec3>& p,
                            const std::vector<Vec3>& n, const std::vector<char>& skip,
                            int numFields, const std::vector<const float*>& values,
                            const std::vector<float*>& out, std::vector<char>& unresolved,
                            const std::vector<float*>& residuals)
{
    unresolved.assign(p.size(), 0);
    const double h = level.h, radius2 = 4.0 * h * h;
    const CellGroups groups = groupByCells(p, h0, level.index, kFitGroupBits);
    const auto& order = groups.order;
    const auto& groupStart = groups.start;

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupStart.size() - 1), [&](const auto& range) {
        // The group's nearby samples, copied together (index, centroid, normal tensor), so
        // that each point's loop over them reads memory in order.
        std::vector<std::uint32_t> near, index;
        std::vector<double> nearX, nearY, nearZ;
        std::array<std::vector<float>, 6> nearT;
        std::vector<double> weight;
        std::vector<std::array<double, 3>> basis;
        for (std::size_t g = range.begin(); g < range.end(); ++g) {
            near.clear();
            forEachSampleNearGroup(level, groups.cell[order[groupStart[g]].second], [&](std::uint32_t s) { near.push_back(s); });
            nearX.resize(near.size()), nearY.resize(near.size()), nearZ.resize(near.size());
            for (auto& t : nearT) t.resize(near.size());
            for (std::size_t k = 0; k < near.size(); ++k) {
                const std::uint32_t s = near[k];
                nearX[k] = level.cx[s], nearY[k] = level.cy[s], nearZ[k] = level.cz[s];
                for (std::size_t c = 0; c < 6; ++c) nearT[c][k] = level.tensor[c][s];
            }
            for (std::size_t q = groupStart[g]; q < groupStart[g + 1]; ++q) {
                const std::uint32_t i = order[q].second;
                if (skip[i]) continue;
                const Vec3& nrm = n[i];
                const Vec3 u = normalized(std::abs(nrm.x) < 0.9 ? cross(nrm, Vec3(1, 0, 0)) : cross(nrm, Vec3(0, 1, 0)));
                const Vec3 v = cross(nrm, u);
                double m[3][3] = {};
                index.clear(), weight.clear(), basis.clear();
                for (std::size_t k = 0; k < near.size(); ++k) {
                    const Vec3 d(nearX[k] - p[i].x, nearY[k] - p[i].y, nearZ[k] - p[i].z);
                    const double d2 = squaredNorm(d);
                    if (d2 >= radius2) continue;  // (no division for the many beyond)
                    const double q2 = d2 / radius2;
                    const auto& t = nearT;
                    const double agree = nrm.x * nrm.x * t[0][k] + nrm.y * nrm.y * t[1][k] + nrm.z * nrm.z * t[2][k] +
                                         2.0 * (nrm.x * nrm.y * t[3][k] + nrm.x * nrm.z * t[4][k] + nrm.y * nrm.z * t[5][k]);
                    if (agree < kSameSide) continue;
                    // (1 − q²)⁸ ≈ exp(−2 |d|²/h²): the fit leans on the samples within about
                    // h/2, as P̂ and L̂ bend on a scale of h near creases (docs/method.md,
                    // Where P and L are evaluated).
                    const double s2 = (1.0 - q2) * (1.0 - q2), s4 = s2 * s2;
                    const double wt = s4 * s4;
                    const std::array<double, 3> phi{1.0, dot(d, u) / h, dot(d, v) / h};
                    for (int a = 0; a < 3; ++a)
                        for (int b = 0; b < 3; ++b) m[a][b] += wt * phi[a] * phi[b];
                    index.push_back(near[k]);
                    weight.push_back(wt);
                    basis.push_back(phi);
                }
                if (index.size() < 6) {
                    unresolved[i] = 1;
                    continue;
                }
                // First row of m⁻¹ (cofactors): the fitted value is Σ wt·(row·φ)·f.
                const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
                const double c01 = -(m[1][0] * m[2][2] - m[1][2] * m[2][0]);
                const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
                const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
                if (!(det > kWellSpread * m[0][0] * m[0][0] * m[0][0])) {
                    unresolved[i] = 1;
                    continue;
                }
                if (!residuals.empty()) fitResiduals(m, det, index, weight, basis, values, residuals, i);
                for (std::size_t k = 0; k < index.size(); ++k)
                    weight[k] *= (c00 * basis[k][0] + c01 * basis[k][1] + c02 * basis[k][2]) / det;
                for (int f = 0; f < numFields; ++f) {
                    double sum = 0;
                    for (std::size_t k = 0; k < index.size(); ++k)
                        sum += weight[k] * values[std::size_t(f)][index[k]];
                    out[std::size_t(f)][i] = float(sum);
                }
            }
        }
    });
}

} // namespace msii::detail
