#include <msii/invariants/scales.h>

#include <msii/core/errors.h>
#include <msii/invariants/patch_line.h>

#include <algorithm>
#include <cmath>

namespace msii {

std::vector<double> equidistantRadii(double largestRadius, int scales)
{
    if (!(largestRadius > 0)) throw InvalidInputError("the radius must be positive");
    if (scales < 1) throw InvalidInputError("the number of scales must be at least 1");
    std::vector<double> radii(scales);
    for (int j = 1; j <= scales; ++j) radii[j - 1] = largestRadius * j / scales;  // Eq. 5
    return radii;
}

void validateRadii(const std::vector<double>& radii)
{
    if (radii.empty()) throw InvalidInputError("no radii given");
    for (std::size_t j = 0; j < radii.size(); ++j) {
        if (!(radii[j] > 0) || !std::isfinite(radii[j]))
            throw InvalidInputError("radii must be positive and finite");
        if (j > 0 && !(radii[j] > radii[j - 1]))
            throw InvalidInputError("radii must be strictly ascending");
    }
}

std::vector<int> gridLevelOfRadius(const std::vector<double>& radii, double h0,
                                   double minCellsPerRadius)
{
    std::vector<int> levels;
    levels.reserve(radii.size());
    for (double r : radii)
        levels.push_back(
            std::max(0, int(std::floor(std::log2(r / (minCellsPerRadius * h0)) + 1e-9))));
    return levels;
}

std::vector<int> volumeSphereLevels(const std::vector<double>& radii, double h0,
                                    double minVoxelsPerRadius)
{
    std::vector<int> levels = gridLevelOfRadius(radii, h0, minVoxelsPerRadius);
    if (levels.empty() || levels.back() < 2) return levels;
    const double finer = h0 * double(1 << (levels.back() - 1));
    if (radii.back() / finer <= 8.0 / 3.0 * minVoxelsPerRadius + 1e-9) --levels.back();
    return levels;
}

double dependenceReach(const std::vector<double>& radii, double h0, double minCellsPerRadius)
{
    const std::vector<int> levels = gridLevelOfRadius(radii, h0, minCellsPerRadius);
    double reach = 0;
    for (std::size_t j = 0; j < radii.size(); ++j) {
        const double h = h0 * double(1 << levels[j]);
        // V and S: stencils and interpolation, r + 4h + 2h0. P and L: a vertex takes its
        // values from samples within 2h, each sums the samples within its kernels' reach
        // (P r + 3w, w <= r/3 and 1 cell; L r + 4w, w <= r/4 and 1.5 cells: at most
        // r + min(r, 6h)), and a sample holds surface within √3·h of its centroid plus a
        // piece h0.
        const double patchLine = std::min(radii[j], 6.0 * h) + (2.0 + std::sqrt(3.0)) * h + h0;
        reach = std::max(reach, radii[j] + std::max(4.0 * h + 2.0 * h0, patchLine));
    }
    return reach;
}

int ScalePlan::numVolumeSphereLevels() const
{
    return volumeSphereLevels.empty() ? 0 : *std::max_element(volumeSphereLevels.begin(), volumeSphereLevels.end()) + 1;
}

Vec3 localOrigin(const Vec3& centre, double h0)
{
    const double step = 1024.0 * h0;
    return {std::round(centre.x / step) * step, std::round(centre.y / step) * step, std::round(centre.z / step) * step};
}

ScalePlan makeScalePlan(const std::vector<double>& radii, double h0, double volumeSpherePrecision,
                        double patchLinePrecision, double vertexSpacing)
{
    validateRadii(radii);
    if (!(h0 > 0) || !std::isfinite(h0)) throw InvalidInputError("the voxel size must be positive");
    ScalePlan plan;
    plan.radii = radii;
    plan.voxelSize = h0;
    plan.volumeSpherePrecision = volumeSpherePrecision;
    plan.patchLinePrecision = patchLinePrecision;
    plan.volumeSphereLevels = volumeSphereLevels(radii, h0, volumeSpherePrecision);
    plan.vertexSpacing = vertexSpacing;
    plan.patchLineLevels = patchLineLevelsNearVertices(patchLineLevelOfRadius(radii, h0, patchLinePrecision), radii,
                                                       h0, vertexSpacing, patchLinePrecision);
    plan.reach = dependenceReach(radii, h0, std::min(volumeSpherePrecision, patchLinePrecision));
    return plan;
}

} // namespace msii
