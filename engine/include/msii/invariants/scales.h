#pragma once
/// @file scales.h
/// @brief The nested radii of MSII (paper §3, Eq. 3 and 5): r_j = j·R/N, j = 1..N.

#include <vector>

namespace msii {

/// Radii r_j = j·R/N for j = 1..N, ascending. @pre R > 0, N >= 1.
std::vector<double> equidistantRadii(double largestRadius, int scales);

} // namespace msii
