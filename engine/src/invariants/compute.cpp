#include <msii/invariants/compute.h>
#include <msii/tiling/tiled_compute.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/exact.h>
#include <msii/invariants/scales.h>
#include <msii/levelset/levelset.h>
#include <msii/mesh/border_distance.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace msii {

double chooseVoxelSize(double medianEdge, const std::vector<double>& radii,
                       double minVoxelsPerRadius)
{
    double first = radii.back();
    for (double r : radii)
        if (r >= 3.0 * medianEdge) {
            first = r;
            break;
        }
    return std::max(0.5 * medianEdge, first / minVoxelsPerRadius);
}

ComputeResult prepareComputation(const TriMesh& mesh, const ComputeOptions& options)
{
    if (!(options.radius > 0) || !std::isfinite(options.radius))
        throw InvalidInputError("the radius must be a positive number");
    if (options.scales < 1) throw InvalidInputError("the number of scales must be at least 1");
    if (options.scales > 256)
        throw InvalidInputError("at most 256 scales are supported (16 is usual)");
    if (options.voxelSize < 0 || !std::isfinite(options.voxelSize))
        throw InvalidInputError("the voxel size must be positive (or 0 for automatic)");
    if (!(options.minVoxelsPerRadius >= 1) || options.minVoxelsPerRadius > 64)
        throw InvalidInputError("the precision must be between 1 and 64 voxels per radius");
    if (options.patchLinePrecision != 0 && !(options.patchLinePrecision >= 1 && options.patchLinePrecision <= 64))
        throw InvalidInputError("the P and L precision must be between 1 and 64 cells per radius (or 0: 4/3 of the V and S precision)");
    if (mesh.numVertices() == 0) throw InvalidInputError("the mesh has no vertices");
    if (mesh.numTriangles() == 0) throw InvalidInputError("the mesh has no faces");

    ComputeResult result;
    const Stopwatch stage;
    result.check = checkMesh(mesh);
    if (result.check.numNonFinitePoints > 0) throw InvalidInputError(result.check.firstProblem());
    if (const std::string problem = result.check.firstProblem(); !problem.empty())
        throw InvalidInputError(problem);
    if (result.check.numInconsistentEdges > 0) {
        std::ostringstream msg;
        msg << "the mesh is not consistently oriented (" << result.check.numInconsistentEdges
            << " edges are traversed the same way by both their faces), so its inside is "
               "undefined; prepare it first (mesh/prepare_mesh.h)";
        throw InvalidInputError(msg.str());
    }
    result.stats = computeMeshStats(mesh);
    result.timings.check = stage.seconds();

    const std::vector<double> radii = equidistantRadii(options.radius, options.scales);
    const double diagonal = result.stats.diagonal;
    if (options.radius > 10.0 * diagonal) {
        std::ostringstream msg;
        msg << "the radius " << options.radius << " is more than 10 times the mesh's size ("
            << diagonal << "); use a radius about the size of the largest feature";
        throw InvalidInputError(msg.str());
    }
    result.voxelSize = options.voxelSize > 0
                           ? options.voxelSize
                           : chooseVoxelSize(result.stats.medianEdge, radii,
                                             options.minVoxelsPerRadius);
    // A grid beyond ~2e9 surface voxels would not fit in memory: say so instead of trying.
    const double surfaceVoxels = result.stats.area / (result.voxelSize * result.voxelSize);
    if (surfaceVoxels > 2e9) {
        std::ostringstream msg;
        msg << "the voxel size " << result.voxelSize << " is far too small for a surface of area "
            << result.stats.area;
        throw InvalidInputError(msg.str());
    }
    if (radii.front() < result.stats.medianEdge) {
        std::ostringstream msg;
        msg << "the smallest radius (" << radii.front() << ") is below the median edge length ("
            << result.stats.medianEdge << "): its values carry little information (paper §3)";
        result.warnings.push_back(msg.str());
    }
    return result;
}

double patchLinePrecision(const ComputeOptions& options)
{
    return options.patchLinePrecision > 0 ? options.patchLinePrecision : 4.0 / 3.0 * options.minVoxelsPerRadius;
}

double coarsestPrecision(const ComputeOptions& options)
{
    return std::min(options.minVoxelsPerRadius, patchLinePrecision(options));
}

void countMaskedVertices(const ComputeResult& result, std::vector<std::size_t>& counts)
{
    for (const auto* columns : {&result.invariants.volume, &result.invariants.sphere, &result.patchLine.patch,
                                &result.patchLine.line}) {
        if (columns->empty()) continue;
        counts.resize(columns->size(), 0);
        for (std::size_t j = 0; j < columns->size(); ++j)
            for (float v : (*columns)[j]) counts[j] += std::isnan(v);
        return;
    }
}

std::string mostlyMaskedWarning(const std::vector<double>& radii, const std::vector<std::size_t>& maskedPerRadius,
                                std::size_t numVertices)
{
    if (numVertices == 0 || radii.empty() || maskedPerRadius.size() != radii.size()) return {};
    const auto share = [&](std::size_t j) { return double(maskedPerRadius[j]) / double(numVertices); };
    const std::size_t last = radii.size() - 1;
    if (share(last) <= 0.5) return {};
    std::ostringstream msg;
    msg << std::setprecision(3) << int(std::lround(100.0 * share(last)))
        << " % of the vertices are masked (NaN) at the largest radius " << radii[last]
        << ", as their ball reaches a border of the open mesh (its edge or holes); ";
    std::size_t kept = radii.size();  // the largest radius with at least half unmasked
    for (std::size_t j = 0; j < radii.size(); ++j)
        if (share(j) <= 0.5) kept = j;
    if (kept == radii.size())
        msg << "more than half are even at the smallest radius: fill the holes or use a much smaller largest radius";
    else
        msg << "at r = " << radii[kept] << " at least half have values: a smaller largest radius keeps more";
    return msg.str();
}

ComputeResult computeInvariants(const TriMesh& mesh, const ComputeOptions& options, Progress* progress)
{
    if (options.memoryBudget != 0 || options.tilesPerAxis != 0) {
        TilingOptions tiling;
        tiling.memoryBudget = options.memoryBudget;
        tiling.tilesPerAxis = options.tilesPerAxis;
        return computeTiled(mesh, options, tiling, nullptr, progress);  // tiles run untiled
    }
    const Stopwatch total;
    ComputeResult result = prepareComputation(mesh, options);
    Stopwatch stage;
    const std::vector<double> radii = equidistantRadii(options.radius, options.scales);

    if (!options.computeVolume && !options.computeSphere && !options.computePatch &&
        !options.computeLine)
        throw InvalidInputError("no invariant selected (choose any of V, S, P, L)");
    std::vector<double> border;
    if (!result.check.closed)
        border = borderDistance(mesh, result.check.borderEdges,
                                dependenceReach(radii, result.voxelSize, coarsestPrecision(options)) +
                                    2.0 * result.voxelSize);
    const float nan = std::numeric_limits<float>::quiet_NaN();

    if (options.exact) {
        // Exact reference mode: the chosen vertices from the triangles, the rest NaN.
        stage.restart();
        ExactOptions eo;
        eo.radii = radii;
        eo.vertices = options.exactVertices;
        eo.borderDistance = border;
        eo.computeVolumeSphere = options.computeVolume || options.computeSphere;
        eo.computePatchLine = options.computePatch || options.computeLine;
        const ExactResult exact = computeExact(mesh, eo, progress);
        const std::size_t nv = mesh.numVertices();
        const auto scatter = [&](const std::vector<std::vector<double>>& from, bool wanted) {
            std::vector<std::vector<float>> to;
            if (!wanted) return to;
            to.assign(radii.size(), std::vector<float>(nv, nan));
            for (std::size_t j = 0; j < radii.size(); ++j)
                for (std::size_t k = 0; k < exact.vertices.size(); ++k)
                    to[j][exact.vertices[k]] = float(from[j][k]);
            return to;
        };
        result.invariants.radii = radii;
        result.invariants.volume = scatter(exact.volume, options.computeVolume);
        result.invariants.sphere = scatter(exact.sphere, options.computeSphere);
        result.patchLine.radii = radii;
        result.patchLine.patch = scatter(exact.patch, options.computePatch);
        result.patchLine.line = scatter(exact.line, options.computeLine);
        result.timings.exact = stage.seconds();
        result.timings.total = total.seconds();
        return result;
    }

    if (options.computeVolume || options.computeSphere) {
        stage.restart();
        LevelSetOptions lsOptions;
        lsOptions.voxelSize = result.voxelSize;
        lsOptions.halfWidth = 2;  // occupancy reads φ within 1 voxel and its neighbours'
        const LevelSet levelSet = buildLevelSet(mesh, lsOptions, progress);
        result.bandHalfWidth = lsOptions.halfWidth;
        result.levelSetVoxels = levelSet.info().activeVoxels;
        result.levelSetBytes = levelSet.info().memoryBytes;
        result.timings.levelSet = stage.seconds();

        VolumeSphereOptions vsOptions;
        vsOptions.radii = radii;
        vsOptions.minVoxelsPerRadius = options.minVoxelsPerRadius;
        vsOptions.computeSphere = options.computeSphere;
        vsOptions.borderDistance = border;
        result.invariants = computeVolumeSphere(mesh, levelSet, vsOptions, progress);
        if (!options.computeVolume) result.invariants.volume.clear();
        result.timings.occupancy = result.invariants.occupancySeconds;
        result.timings.stencils = result.invariants.stencilSeconds;
        result.timings.interpolation = result.invariants.interpolationSeconds;
    } else {
        result.invariants.radii = radii;
        result.invariants.levelOfRadius =
            volumeSphereLevels(radii, result.voxelSize, options.minVoxelsPerRadius);
        result.invariants.numLevels =
            *std::max_element(result.invariants.levelOfRadius.begin(),
                              result.invariants.levelOfRadius.end()) + 1;
    }

    if (options.computePatch || options.computeLine) {
        PatchLineOptions plOptions;
        plOptions.radii = radii;
        plOptions.cellSize = result.voxelSize;
        plOptions.minCellsPerRadius = patchLinePrecision(options);
        plOptions.computePatch = options.computePatch;
        plOptions.computeLine = options.computeLine;
        plOptions.borderDistance = border;
        plOptions.vertexSpacing = options.vertexSpacing > 0 ? options.vertexSpacing : result.stats.medianEdge;
        result.patchLine = computePatchLine(mesh, plOptions, progress);
        result.timings.samples = result.patchLine.samplingSeconds;
        result.timings.patchLine = result.patchLine.gatherSeconds;
    }
    if (!result.check.closed) {
        std::vector<std::size_t> masked;
        countMaskedVertices(result, masked);
        if (std::string w = mostlyMaskedWarning(radii, masked, mesh.numVertices()); !w.empty())
            result.warnings.push_back(std::move(w));
    }
    result.timings.total = total.seconds();
    return result;
}

} // namespace msii
