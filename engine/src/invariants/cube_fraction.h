#pragma once
// Private to the engine: volume fractions of a unit voxel cut by a plane, the building block
// of sub-voxel accuracy for occupancy (voxel ∩ solid) and for anti-aliased ball stencils
// (voxel ∩ ball); docs/method.md, Occupancy and Stencils.
#include <algorithm>
#include <cmath>

namespace msii::detail {

/// Fraction of the unit cube [-1/2, 1/2]^3 on the side {x : n·x <= d} of a plane with unit
/// normal n, given as (|n_x|, |n_y|, |n_z|). This is the distribution function of n·U for U
/// uniform in the cube, i.e. of a sum of three uniforms of widths |n_i|: a piecewise cubic,
/// written as the alternating sum over the cube's corners. Widths are floored at 1e-2, which
/// changes the result by less than 1e-5 but keeps the formula well conditioned.
inline double cubeFraction(double d, double ax, double ay, double az)
{
    const double a = std::max(ax, 1e-2), b = std::max(ay, 1e-2), c = std::max(az, 1e-2);
    const double half = 0.5 * (a + b + c);
    if (d <= -half) return 0.0;
    if (d >= half) return 1.0;
    double sum = 0;
    for (int s = 0; s < 8; ++s) {
        const double sa = (s & 1) ? -a : a, sb = (s & 2) ? -b : b, sc = (s & 4) ? -c : c;
        const double x = d + 0.5 * (sa + sb + sc);
        if (x > 0) {
            const int sign = ((s & 1) ? -1 : 1) * ((s & 2) ? -1 : 1) * ((s & 4) ? -1 : 1);
            sum += sign * x * x * x;
        }
    }
    return std::clamp(sum / (6.0 * a * b * c), 0.0, 1.0);
}

/// Fraction of the unit voxel centred at offset (x, y, z) (voxel units) inside the ball of
/// radius rho centred at the origin. The sphere is replaced by its tangent plane at the
/// voxel, moved inwards by the mean sagitta over a voxel cross-section, 1/(12 rho), which
/// removes the leading curvature error.
inline double ballFraction(double x, double y, double z, double rho)
{
    if (rho <= 0) return 0.0;
    const double dist = std::sqrt(x * x + y * y + z * z);
    if (dist < 1e-12) return std::min(1.0, 4.0 / 3.0 * M_PI * rho * rho * rho);
    const double s = rho - dist - 1.0 / (12.0 * rho);
    return cubeFraction(s, std::abs(x) / dist, std::abs(y) / dist, std::abs(z) / dist);
}

} // namespace msii::detail
