#include <msii/invariants/scales.h>

#include <msii/core/errors.h>

namespace msii {

std::vector<double> equidistantRadii(double largestRadius, int scales)
{
    if (!(largestRadius > 0)) throw InvalidInputError("the radius must be positive");
    if (scales < 1) throw InvalidInputError("the number of scales must be at least 1");
    std::vector<double> radii(scales);
    for (int j = 1; j <= scales; ++j) radii[j - 1] = largestRadius * j / scales;  // Eq. 5
    return radii;
}

} // namespace msii
