#include <msii/invariants/patch_line.h>

#include "patch_line_exact.h"
#include "patch_line_fit.h"
#include "patch_line_gather.h"
#include "patch_line_kernels.h"
#include "patch_line_samples.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/vertex_normals.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace msii {

using detail::CellCoord;
using detail::cellOf;
using detail::coarser;
using detail::evaluatePairsExactly;
using detail::evaluatePoints;
using detail::finestSamples;
using detail::interpolateFromSamples;
using detail::kCoordLimit;
using detail::kDirectCellsPerSpacing;
using detail::KernelSums;
using detail::kernelReach;
using detail::Level;
using detail::LevelKernel;
using detail::makeLevel;
using detail::makeLevelKernel;
using detail::SampleParts;
using detail::totalSize;

namespace {

/// The check flags radii of at least this many median edges, as the stated bounds hold from
/// there (docs/accuracy.md): below, a ball holds too few triangles for the values to mean
/// much, and the kernels' blur is most of their width.
constexpr double kCheckFromEdges = 3;
/// Where P̂ and L̂ are fitted from the samples, a vertex whose fit's RMS residual times this
/// exceeds the check's thresholds is evaluated where it is: the fit blurs a crease or an
/// onset within its window for the kernels of both widths alike, where the check cannot see
/// it (docs/method.md, Exact where the kernels blur).
constexpr double kFitResidualWeight = 2;

/// @throw InvalidInputError for invalid radii, sample cell size or precision.
void validateOptions(const PatchLineOptions& options)
{
    validateRadii(options.radii);
    const double h0 = options.cellSize;
    if (!(h0 > 0) || !std::isfinite(h0)) throw InvalidInputError("the sample cell size must be positive");
    if (!(options.minCellsPerRadius >= 1))
        throw InvalidInputError("the precision (cells per radius) must be at least 1");
    if (!(options.checkThresholdPatch >= 0) || !(options.checkThresholdLine >= 0))
        throw InvalidInputError("the check's thresholds must be positive or 0");
}

/// @throw InvalidInputError if the border distances do not match the vertices, or the mesh
/// reaches beyond the sample cells' coordinates.
void validateMesh(const TriMesh& mesh, const PatchLineOptions& options)
{
    if (!options.borderDistance.empty() && options.borderDistance.size() != mesh.numVertices())
        throw InvalidInputError("border distances do not match the vertex count");
    for (const Vec3& p : mesh.points) {
        const CellCoord c = cellOf(p, options.cellSize);
        if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= kCoordLimit || c.y >= kCoordLimit || c.z >= kCoordLimit)
            throw InvalidInputError("the mesh reaches more than a million sample cells from the origin; "
                                    "use a larger voxel size or move the mesh near the origin");
    }
}

/// The surface samples of levels 0 .. @p numLevels − 1, each coarser level from the one
/// below; @p numSamples: those of the finest.
std::vector<Level> sampleLevels(const TriMesh& mesh, double h0, int numLevels, std::size_t& numSamples)
{
    std::vector<Level> levels;
    SampleParts sums = finestSamples(mesh, h0, numLevels - 1);
    numSamples = totalSize(sums);
    for (int l = 0; l < numLevels; ++l) {
        if (l > 0) sums = coarser(sums);
        levels.push_back(makeLevel(sums, h0, l));
    }
    return levels;
}

/// The radii evaluated on one level, and what they share there.
struct LevelRadii {
    std::vector<int> index;         ///< into the radii; empty if the level has none
    LevelKernel kernel;
    double binVariance = 0;         ///< of the binning's tent, bin²/6
    std::vector<double> maskReach;  ///< per radius of the level: masked where the border is nearer
};

/// The radii of level @p l (@p levelOfRadius), its kernel and where the values are masked.
/// @p planLevel: the level of each radius in the V/S plan.
LevelRadii radiiOfLevel(const std::vector<double>& radii, const std::vector<int>& levelOfRadius,
                        const std::vector<int>& planLevel, const Level& level, int l, double h0, double checkSpacing)
{
    LevelRadii out;
    for (std::size_t j = 0; j < radii.size(); ++j)
        if (levelOfRadius[j] == l) out.index.push_back(int(j));
    if (out.index.empty()) return out;
    std::vector<double> levelR;
    for (int j : out.index) levelR.push_back(radii[std::size_t(j)]);
    out.kernel = makeLevelKernel(levelR, level.h, l, checkSpacing);
    out.binVariance = out.kernel.bin * out.kernel.bin / 6.0;
    // A value is masked when the kernel's reach, plus the spread of a sample, gets to a
    // border: max(kernelReach, r + 4h) + 2 h0, with h the cell of the radius's level in
    // the V/S plan, so at least where V and S are (r + 4h + 2 h0), also for a merged level.
    out.maskReach.resize(levelR.size());
    for (std::size_t k = 0; k < levelR.size(); ++k) {
        const double r = levelR[k];
        const double vs = r + 4.0 * h0 * std::ldexp(1.0, planLevel[std::size_t(out.index[k])]);
        out.maskReach[k] = std::max(kernelReach(r, level.h, l), vs) + 2.0 * h0;
    }
    return out;
}

/// Stores the sums of a level's radii at the vertices into the result, normalised, where
/// they are not masked, and flags the pairs where the check's narrow kernels disagree.
struct LevelStore {
    const PatchLineOptions& options;
    const LevelRadii& level;
    PatchLineResult& result;
    std::vector<std::vector<std::uint8_t>>& flagged;  ///< [j][i]; empty without the check
    double checkFrom;  ///< radii below are not flagged (kCheckFromEdges)

    /// Whether the value of the level's radius @p k at vertex @p i is masked.
    bool masked(std::size_t i, std::size_t k) const
    {
        return !options.borderDistance.empty() && level.maskReach[k] > options.borderDistance[i];
    }

    /// The level's radius @p k at vertex @p i from the sums at @p at of @p sums.
    void operator()(std::size_t i, std::size_t k, const KernelSums& sums, std::size_t at) const
    {
        const std::size_t j = std::size_t(level.index[k]);
        if (masked(i, k)) return;
        const float p = patch(j, sums.patch[at]), l = line(j, sums.line[at]);
        if (options.computePatch) result.patch[j][i] = p;
        if (options.computeLine) result.line[j][i] = l;
        if (flagged.empty()) return;
        // The check (docs/method.md, Exact where the kernels blur): the kernels of two widths.
        const float dp = sums.checkPatch[at], dl = sums.checkLine[at];
        if (options.keepCheck) {
            if (options.computePatch) result.patchDifference[j][i] = dp;
            if (options.computeLine) result.lineDifference[j][i] = dl;
        }
        if (options.radii[j] < checkFrom) return;
        const bool patchOff = options.computePatch && !(dp <= options.checkThresholdPatch);
        const bool lineOff = options.computeLine && !(dl <= options.checkThresholdLine);
        if (patchOff || lineOff) flagged[j][i] = 1;
    }

    /// Whether the fit of the level's radius @p k to vertex @p i bends more than the check
    /// allows: its residual (in @p sums at @p at) times kFitResidualWeight beyond a threshold.
    bool fitBends(std::size_t i, std::size_t k, const KernelSums& sums, std::size_t at) const
    {
        const std::size_t j = std::size_t(level.index[k]);
        if (masked(i, k) || options.radii[j] < checkFrom) return false;
        return (options.computePatch && kFitResidualWeight * patch(j, sums.patchResidual[at]) > options.checkThresholdPatch) ||
               (options.computeLine && kFitResidualWeight * line(j, sums.lineResidual[at]) > options.checkThresholdLine);
    }

private:
    /// P̂ from the sum at radius j. K has no second moment, but the binning adds a tent of
    /// variance bin²/6 to the blur across r: P = π r² gives π (r² + bin²/6), divided out.
    float patch(std::size_t j, float sum) const
    {
        const double r = options.radii[j];
        return float(sum / (M_PI * (r * r + level.binVariance)));
    }
    float line(std::size_t j, float sum) const { return float(sum / (2.0 * M_PI * options.radii[j])); }
};

/// The level's sums evaluated at the vertices themselves (but those to @p skip).
void evaluateAtVertices(const Level& level, const LevelRadii& radii, double h0, const TriMesh& mesh,
                        const std::vector<char>& skip, const LevelStore& store, double& checkCpuSeconds,
                        RunContext* progress)
{
    const std::size_t nv = mesh.numVertices();
    KernelSums sums;
    evaluatePoints(level, radii.kernel, h0, mesh.points, skip, sums, progress);
    checkCpuSeconds += sums.checkCpuSeconds;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i)
            for (std::size_t k = 0; k < radii.index.size(); ++k) store(i, k, sums, k * nv + i);
    });
}

/// The level's sums evaluated at its samples and fitted to the vertices (but those to
/// @p skip); vertices the fit leaves unresolved are evaluated where they are. Returns
/// how many were. @p vertexNormal: the mesh's, computed here on first use.
std::size_t evaluateAtSamples(const Level& level, const LevelRadii& radii, double h0, const TriMesh& mesh,
                              std::vector<Vec3>& vertexNormal, const std::vector<char>& skip,
                              const LevelStore& store, double& checkCpuSeconds, RunContext* progress)
{
    const std::size_t nv = mesh.numVertices();
    const std::size_t numSamples = level.cx.size();
    KernelSums sums;
    std::vector<Vec3> at(numSamples);
    for (std::size_t s = 0; s < numSamples; ++s) at[s] = Vec3(level.cx[s], level.cy[s], level.cz[s]);
    // Only the samples some vertex's fit reads (not those of a continuation beyond them).
    evaluatePoints(level, radii.kernel, h0, at, samplesBeyondFit(level, h0, mesh.points, skip), sums, progress);
    checkCpuSeconds += sums.checkCpuSeconds;
    if (vertexNormal.empty()) vertexNormal = vertexNormals(mesh, Vec3(0, 0, 1));
    // Every field of the sums (P, L, and the check's) is fitted to the vertices alike.
    const std::size_t nr = radii.index.size();
    std::vector<std::vector<float>*> fields{&sums.patch, &sums.line};
    if (!sums.checkPatch.empty()) fields.insert(fields.end(), {&sums.checkPatch, &sums.checkLine});
    KernelSums fitted;
    std::vector<std::vector<float>*> fittedFields{&fitted.patch, &fitted.line, &fitted.checkPatch, &fitted.checkLine};
    std::vector<const float*> from;
    std::vector<float*> to;
    for (std::size_t f = 0; f < fields.size(); ++f) {
        fittedFields[f]->resize(nr * nv);
        for (std::size_t k = 0; k < nr; ++k) {
            from.push_back(fields[f]->data() + k * numSamples);
            to.push_back(fittedFields[f]->data() + k * nv);
        }
    }
    // With the check, the fit's residuals of P and L (the first 2·nr fields) too.
    std::vector<float*> residuals;
    if (!sums.checkPatch.empty()) {
        fitted.patchResidual.resize(nr * nv), fitted.lineResidual.resize(nr * nv);
        for (auto* r : {&fitted.patchResidual, &fitted.lineResidual})
            for (std::size_t k = 0; k < nr; ++k) residuals.push_back(r->data() + k * nv);
    }
    std::vector<char> unresolved;
    interpolateFromSamples(level, h0, mesh.points, vertexNormal, skip, int(from.size()), from, to, unresolved,
                           residuals);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            if (skip[i] || unresolved[i]) continue;
            // Where the fit bends (its residual), it blurs for both of the check's kernels
            // alike: such vertices are evaluated where they are, as those on creases.
            bool bends = false;
            for (std::size_t k = 0; k < nr && !residuals.empty(); ++k) bends = bends || store.fitBends(i, k, fitted, k * nv + i);
            if (bends) {
                unresolved[i] = 1;
                continue;
            }
            for (std::size_t k = 0; k < nr; ++k) store(i, k, fitted, k * nv + i);
        }
    });
    // Vertices on creases and corners, and where the fit bends: evaluated where they are.
    std::vector<std::uint32_t> direct;
    for (std::size_t i = 0; i < nv; ++i)
        if (unresolved[i] && !skip[i]) direct.push_back(std::uint32_t(i));
    if (!direct.empty()) {
        std::vector<Vec3> points(direct.size());
        for (std::size_t q = 0; q < direct.size(); ++q) points[q] = mesh.points[direct[q]];
        evaluatePoints(level, radii.kernel, h0, points, std::vector<char>(direct.size(), 0), sums, nullptr);
        checkCpuSeconds += sums.checkCpuSeconds;
        const std::size_t nd = direct.size();
        for (std::size_t q = 0; q < nd; ++q)
            for (std::size_t k = 0; k < nr; ++k) store(direct[q], k, sums, k * nd + q);
    }
    return direct.size();
}

/// Steps 1 to 7: the samples of every level and their kernel sums at the vertices, into
/// @p result, and the pairs the check flags ([j][i]; empty without the check). The samples
/// live only here, so that the exact sums after do not hold them.
std::vector<std::vector<std::uint8_t>> sumKernels(const TriMesh& mesh, const PatchLineOptions& options,
                                                  const std::vector<int>& planLevel, double spacing, int numLevels,
                                                  PatchLineResult& result, RunContext* progress)
{
    const auto& radii = options.radii;
    const double h0 = options.cellSize;
    const std::size_t nv = mesh.numVertices();
    Stopwatch stage;
    const std::vector<Level> levels = sampleLevels(mesh, h0, numLevels, result.numSamples);
    result.samplingSeconds = stage.seconds();
    stage.restart();

    std::vector<Vec3> vertexNormal;                // for interpolation, when needed
    const bool check = options.exactWhereBlurred || options.keepCheck;
    // The check compares the kernels halfway between radii too: Δ, their spacing.
    const double checkSpacing = check ? (radii.size() > 1 ? radii[1] - radii[0] : radii[0]) : 0.0;
    std::vector<std::vector<std::uint8_t>> flagged;
    if (check) flagged.assign(radii.size(), std::vector<std::uint8_t>(nv, 0));
    double checkCpuSeconds = 0;
    for (int l = 0; l < numLevels; ++l) {
        const Level& level = levels[std::size_t(l)];
        const LevelRadii levelRadii = radiiOfLevel(radii, result.levelOfRadius, planLevel, level, l, h0, checkSpacing);
        if (levelRadii.index.empty()) continue;
        const LevelStore store{options, levelRadii, result, flagged, kCheckFromEdges * spacing};
        std::vector<char> skip(nv);  // every radius of the level is masked
        for (std::size_t i = 0; i < nv; ++i) skip[i] = store.masked(i, 0);
        if (level.h <= kDirectCellsPerSpacing * spacing) {
            // Cells about the vertex spacing or finer, so about as many samples as vertices
            // or more: evaluate at the vertices themselves. Decided from the whole mesh's
            // spacing, not from this mesh's counts, so that a tile with more or less of the
            // surface per vertex than the whole takes the same route (bit-identical tiles).
            evaluateAtVertices(level, levelRadii, h0, mesh, skip, store, checkCpuSeconds, progress);
        } else {
            // Far fewer samples than vertices (coarse levels of dense meshes): evaluate at the
            // samples (one per cell, on the surface) and interpolate to the vertices. P̂ and L̂
            // vary on the scale of r >= minCellsPerRadius·h, so a linear fit over 2h loses
            // about (h/r)²/8 of their variation.
            result.directEvaluations +=
                evaluateAtSamples(level, levelRadii, h0, mesh, vertexNormal, skip, store, checkCpuSeconds, progress);
        }
    }
    result.gatherSeconds = stage.seconds();
    // The check's share of the wall time, as its time over the threads.
    result.checkSeconds = checkCpuSeconds / double(std::max(1, tbb::this_task_arena::max_concurrency()));
    return flagged;
}

/// The pairs of @p result given a value, and of them those @p flagged (if not empty).
void countPairs(PatchLineResult& result, const std::vector<std::vector<std::uint8_t>>& flagged)
{
    const auto& values = result.patch.empty() ? result.line : result.patch;
    for (std::size_t j = 0; j < values.size(); ++j)
        for (std::size_t i = 0; i < values[j].size(); ++i) {
            result.pairs += !std::isnan(values[j][i]);
            if (!flagged.empty()) result.pairsExact += flagged[j][i];
        }
}

} // namespace

std::vector<int> patchLineLevelsNearVertices(std::vector<int> levels, const std::vector<double>& radii, double h0,
                                             double vertexSpacing, double minCellsPerRadius)
{
    if (!(vertexSpacing > 0)) return levels;
    for (std::size_t j = 0; j < levels.size() && j < radii.size(); ++j)
        while (levels[j] > 0) {
            const double h = h0 * std::ldexp(1.0, levels[j]);
            if (h <= kFittedCellsPerSpacing * vertexSpacing) break;  // fits without blurring
            if (radii[j] / (0.5 * h) > kMaxCellsPerRadiusFactor * minCellsPerRadius) break;  // too many cells
            --levels[j];
        }
    return levels;
}

std::vector<int> patchLineLevelOfRadius(const std::vector<double>& radii, double h0, double minCellsPerRadius)
{
    std::vector<int> level = gridLevelOfRadius(radii, h0, minCellsPerRadius);
    const std::size_t n = radii.size();
    if (n < 2 || level[n - 1] == 0 || level[n - 2] != level[n - 1] - 1) return level;
    // Samples binned on a level of cell h and reach ρ, per unit area: (points ∝ 1/h², its
    // samples or the vertices if fewer) × (samples within reach ∝ (ρ/h)²). With c = 2h the
    // coarsest cell, extending the level below from the radius before to r costs
    // 16 (ρ_h(r)² − ρ_h(r_prev)²) / c⁴, and the coarsest level's own pass ρ_c(r)² / c⁴.
    const double r = radii[n - 1], below = h0 * std::ldexp(1.0, level[n - 1] - 1);
    const int lb = level[n - 1] - 1;
    const double extend = 16.0 * (std::pow(kernelReach(r, below, lb), 2) - std::pow(kernelReach(radii[n - 2], below, lb), 2));
    if (extend <= std::pow(kernelReach(r, 2.0 * below, lb + 1), 2)) --level[n - 1];
    return level;
}

PatchLineResult computePatchLine(const TriMesh& mesh, const PatchLineOptions& options,
                                 RunContext* progress)
{
    validateOptions(options);
    const auto& radii = options.radii;
    const double h0 = options.cellSize;
    const std::size_t nv = mesh.numVertices();
    const double spacing = options.vertexSpacing > 0 ? options.vertexSpacing : computeMeshStats(mesh).medianEdge;
    validateMesh(mesh, options);

    PatchLineResult result;
    result.radii = radii;
    result.levelOfRadius = options.levelOfRadius.empty() ? patchLineLevelOfRadius(radii, h0, options.minCellsPerRadius)
                                                         : options.levelOfRadius;
    if (result.levelOfRadius.size() != radii.size())
        throw InvalidInputError("the sample levels do not match the radii");
    const int numLevels = *std::max_element(result.levelOfRadius.begin(), result.levelOfRadius.end()) + 1;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    if (options.computePatch) result.patch.assign(radii.size(), std::vector<float>(nv, nan));
    if (options.computeLine) result.line.assign(radii.size(), std::vector<float>(nv, nan));
    if (options.keepCheck && options.computePatch) result.patchDifference = result.patch;
    if (options.keepCheck && options.computeLine) result.lineDifference = result.line;
    if (!options.computePatch && !options.computeLine) return result;

    const std::vector<int> planLevel = gridLevelOfRadius(radii, h0, options.minCellsPerRadius);
    std::vector<std::vector<std::uint8_t>> flagged = sumKernels(mesh, options, planLevel, spacing, numLevels, result, progress);
    countPairs(result, flagged);
    if (options.exactWhereBlurred && result.pairsExact > 0) {
        const Stopwatch stage;
        // Cells of two vertex spacings: the walk tests the cells within the largest flagged
        // radius and the triangles of those a flagged sphere cuts (docs/method.md).
        const double cell = std::clamp(2.0 * spacing, radii.back() / 64, radii.back() / 4);
        result.verticesExact = evaluatePairsExactly(mesh, radii, cell, flagged, result.patch, result.line, progress).vertices;
        result.exactSeconds = stage.seconds();
    }
    if (options.keepCheck) result.flagged = std::move(flagged);
    return result;
}

} // namespace msii
