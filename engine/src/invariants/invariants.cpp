#include <msii/invariants/invariants.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/exact.h>
#include <msii/invariants/scales.h>
#include <msii/invariants/patch_line.h>
#include <msii/invariants/volume_sphere.h>
#include <msii/levelset/levelset.h>
#include <msii/mesh/border_distance.h>

#include <algorithm>
#include <cmath>
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

namespace {

/// Parameters and mesh: the refusals of computeInvariants, the check and statistics.
InvariantsResult checkComputation(const TriMesh& mesh, const InvariantsOptions& options)
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
    if (!options.computeVolume && !options.computeSphere && !options.computePatch && !options.computeLine)
        throw InvalidInputError("no invariant selected (choose any of V, S, P, L)");
    if (mesh.numVertices() == 0) throw InvalidInputError("the mesh has no vertices");
    if (mesh.numTriangles() == 0) throw InvalidInputError("the mesh has no faces");

    InvariantsResult result;
    const Stopwatch stage;
    result.check = checkMesh(mesh);
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
    result.cost.check = stage.seconds();
    return result;
}

} // namespace

double surfaceBytesEstimate(double area, double voxelSize, const InvariantsOptions& options)
{
    const double perCell = options.computePatch || options.computeLine ? kBytesPerSurfaceSample : kBytesPerSurfaceVoxel;
    return perCell * area / (voxelSize * voxelSize);
}

namespace {

std::string gigabytes(double bytes)
{
    std::ostringstream out;
    out.precision(bytes < 1e10 ? 2 : 3);
    out << bytes / 1e9 << " GB";
    return out.str();
}

/// Refuses, before anything is allocated, a surface whose level set or samples alone would
/// not fit. A surface of more than 20 times the area of as many triangles of its median edge
/// (a scan or terrain has about 0.4 to 1) is named as spiky or noisy: that is what makes it
/// large, not its number of triangles.
void checkSurfaceMemory(const MeshStats& stats, double voxelSize, const InvariantsOptions& options)
{
    const double limit = options.exact ? 0 : options.memoryLimit;
    const double estimate = surfaceBytesEstimate(stats.area, voxelSize, options);
    if (!(limit > 0) || estimate <= limit) return;
    std::ostringstream msg;
    msg.precision(3);
    msg << "the surface would take about " << gigabytes(estimate) << " (area " << stats.area << " at the voxel size "
        << voxelSize << ": " << stats.area / (voxelSize * voxelSize) << " cells of surface), more than the "
        << gigabytes(limit) << " the computation may use";
    const double typical = double(stats.numTriangles) * stats.medianEdge * stats.medianEdge;
    if (stats.area > 20.0 * typical)
        msg << "; its " << stats.numTriangles << " triangles have " << stats.area / typical
            << " times the area their median edge (" << stats.medianEdge
            << ") gives, as spikes or noise in the coordinates or heights make them";
    throw MemoryLimitError(msg.str());
}

} // namespace

InvariantsResult planInvariants(const TriMesh& mesh, const InvariantsOptions& options)
{
    InvariantsResult result = checkComputation(mesh, options);
    if (options.plan) {  // a piece of a surface planned whole
        result.plan = *options.plan;
        checkSurfaceMemory(result.stats, result.plan.voxelSize, options);
        return result;
    }
    const std::vector<double> radii = equidistantRadii(options.radius, options.scales);
    const double diagonal = result.stats.diagonal;
    if (options.radius > 10.0 * diagonal) {
        std::ostringstream msg;
        msg << "the radius " << options.radius << " is more than 10 times the mesh's size ("
            << diagonal << "); use a radius about the size of the largest feature";
        throw InvalidInputError(msg.str());
    }
    const double h0 = options.voxelSize > 0
                          ? options.voxelSize
                          : chooseVoxelSize(result.stats.medianEdge, radii, options.minVoxelsPerRadius);
    checkSurfaceMemory(result.stats, h0, options);
    // A grid beyond ~2e9 surface voxels would not fit in memory: say so instead of trying.
    const double surfaceVoxels = result.stats.area / (h0 * h0);
    if (surfaceVoxels > 2e9) {
        std::ostringstream msg;
        msg << "the voxel size " << h0 << " is far too small for a surface of area " << result.stats.area;
        throw InvalidInputError(msg.str());
    }
    result.plan = makeScalePlan(radii, h0, options.minVoxelsPerRadius, patchLinePrecision(options), result.stats.medianEdge);
    result.plan.origin = localOrigin((result.stats.bboxMin + result.stats.bboxMax) * 0.5, h0);
    if (radii.front() < result.stats.medianEdge) {
        std::ostringstream msg;
        msg << "the smallest radius (" << radii.front() << ") is below the median edge length ("
            << result.stats.medianEdge << "): its values carry little information (paper §3)";
        result.diagnostics.push_back({"smallest_radius_below_edge",
                                      0,
                                      {{"radius", radii.front()}, {"median_edge", result.stats.medianEdge}},
                                      msg.str()});
    }
    return result;
}

double patchLinePrecision(const InvariantsOptions& options)
{
    return options.patchLinePrecision > 0 ? options.patchLinePrecision : 4.0 / 3.0 * options.minVoxelsPerRadius;
}

namespace {

/// The exact reference mode: the chosen vertices from the triangles, the rest NaN.
void computeExactValues(const TriMesh& mesh, const InvariantsOptions& options, const std::vector<double>& border,
                        InvariantsResult& result, RunContext* context)
{
    const Stopwatch stage;
    const std::vector<double>& radii = result.plan.radii;
    ExactOptions eo;
    eo.radii = radii;
    eo.vertices = options.exactVertices;
    eo.borderDistance = border;
    eo.computeVolumeSphere = options.computeVolume || options.computeSphere;
    eo.computePatchLine = options.computePatch || options.computeLine;
    const ExactResult exact = computeExact(mesh, eo, context);
    const std::size_t nv = mesh.numVertices();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const auto scatter = [&](const std::vector<std::vector<double>>& from, bool wanted) {
        FeatureColumns to;
        if (!wanted) return to;
        to.assign(radii.size(), std::vector<float>(nv, nan));
        for (std::size_t j = 0; j < radii.size(); ++j)
            for (std::size_t k = 0; k < exact.vertices.size(); ++k) to[j][exact.vertices[k]] = float(from[j][k]);
        return to;
    };
    result.features[Invariant::Volume] = scatter(exact.volume, options.computeVolume);
    result.features[Invariant::Sphere] = scatter(exact.sphere, options.computeSphere);
    result.features[Invariant::Patch] = scatter(exact.patch, options.computePatch);
    result.features[Invariant::Line] = scatter(exact.line, options.computeLine);
    result.cost.exact = stage.seconds();
}

/// The fast mode on one piece, with result.plan made.
void computeFastValues(const TriMesh& mesh, const InvariantsOptions& options, const std::vector<double>& border,
                       InvariantsResult& result, RunContext* context)
{
    const ScalePlan& plan = result.plan;
    Stopwatch stage;
    if (options.computeVolume || options.computeSphere) {
        LevelSetOptions lsOptions;
        lsOptions.voxelSize = plan.voxelSize;
        lsOptions.halfWidth = 2;  // occupancy reads φ within 1 voxel and its neighbours'
        const LevelSet levelSet = buildLevelSet(mesh, lsOptions, context);
        result.cost.bandHalfWidth = lsOptions.halfWidth;
        result.cost.levelSetVoxels = levelSet.info().activeVoxels;
        result.cost.levelSetBytes = levelSet.info().memoryBytes;
        result.cost.levelSet = stage.seconds();

        VolumeSphereOptions vsOptions;
        vsOptions.radii = plan.radii;
        vsOptions.minVoxelsPerRadius = plan.volumeSpherePrecision;
        vsOptions.levelOfRadius = plan.volumeSphereLevels;
        vsOptions.computeSphere = options.computeSphere;
        vsOptions.borderDistance = border;
        VolumeSphereResult vs = computeVolumeSphere(mesh, levelSet, vsOptions, context);
        if (options.computeVolume) result.features[Invariant::Volume] = std::move(vs.volume);
        result.features[Invariant::Sphere] = std::move(vs.sphere);
        result.cost.stencilNodes = vs.numNodes;
        result.cost.occupancy = vs.occupancySeconds;
        result.cost.stencils = vs.stencilSeconds;
        result.cost.interpolation = vs.interpolationSeconds;
    }
    if (options.computePatch || options.computeLine) {
        PatchLineOptions plOptions;
        plOptions.radii = plan.radii;
        plOptions.cellSize = plan.voxelSize;
        plOptions.minCellsPerRadius = plan.patchLinePrecision;
        plOptions.levelOfRadius = plan.patchLineLevels;
        plOptions.computePatch = options.computePatch;
        plOptions.computeLine = options.computeLine;
        plOptions.borderDistance = border;
        plOptions.vertexSpacing = plan.vertexSpacing > 0 ? plan.vertexSpacing : result.stats.medianEdge;
        plOptions.exactWhereBlurred = options.patchLineExactWhereBlurred;
        PatchLineResult pl = computePatchLine(mesh, plOptions, context);
        result.features[Invariant::Patch] = std::move(pl.patch);
        result.features[Invariant::Line] = std::move(pl.line);
        result.cost.numSamples = pl.numSamples;
        result.cost.directEvaluations = pl.directEvaluations;
        result.cost.samples = pl.samplingSeconds;
        result.cost.patchLine = pl.gatherSeconds;
        result.cost.patchLineCheck = pl.checkSeconds;
        result.cost.patchLineExact = pl.exactSeconds;
        result.cost.patchLinePairs = pl.pairs;
        result.cost.patchLinePairsExact = pl.pairsExact;
        result.cost.patchLineVerticesExact = pl.verticesExact;
    }
}

/// The values of @p result on the mesh in the local frame: the border distances, then the
/// exact or the fast mode.
void computeLocalValues(const TriMesh& mesh, const InvariantsOptions& options, InvariantsResult& result,
                        RunContext* context)
{
    // Values are masked where their reach meets a border; distances are searched a little
    // beyond it (docs/method.md, Borders).
    std::vector<double> border;
    if (!result.check.closed && options.maskBorders)
        border = borderDistance(mesh, result.check.borderEdges, result.plan.reach + 2.0 * result.plan.voxelSize);
    if (options.evaluatedVertices > 0 && options.evaluatedVertices < mesh.numVertices()) {
        // The vertices past the count are masked as if on a border: no values, no work.
        if (border.empty()) border.assign(mesh.numVertices(), std::numeric_limits<double>::infinity());
        std::fill(border.begin() + std::ptrdiff_t(options.evaluatedVertices), border.end(), 0.0);
    }
    if (options.exact)
        computeExactValues(mesh, options, border, result, context);
    else
        computeFastValues(mesh, options, border, result, context);
}

/// The values of @p result (checked, with its plan) on one piece of mesh.
void computeValues(const TriMesh& mesh, const InvariantsOptions& options, InvariantsResult& result,
                   RunContext* context)
{
    const Stopwatch total;
    result.features.radii = result.plan.radii;
    // The local frame (ScalePlan::origin): a moved copy where the origin is not zero.
    TriMesh moved;
    if (const Vec3 o = result.plan.origin; o.x != 0 || o.y != 0 || o.z != 0) {
        moved.triangles = mesh.triangles;
        moved.points.resize(mesh.numVertices());
        for (std::size_t i = 0; i < moved.points.size(); ++i) moved.points[i] = mesh.points[i] - o;
        computeLocalValues(moved, options, result, context);
    } else {
        computeLocalValues(mesh, options, result, context);
    }
    result.cost.total = result.cost.check + total.seconds();
}

} // namespace

void InvariantsOptions::select(const std::vector<Invariant>& list)
{
    const auto has = [&](Invariant i) { return std::find(list.begin(), list.end(), i) != list.end(); };
    computeVolume = has(Invariant::Volume);
    computeSphere = has(Invariant::Sphere);
    computePatch = has(Invariant::Patch);
    computeLine = has(Invariant::Line);
}

std::vector<Invariant> InvariantsOptions::selected() const
{
    std::vector<Invariant> list;
    for (const auto& [on, i] : {std::pair{computeVolume, Invariant::Volume}, std::pair{computeSphere, Invariant::Sphere},
                                std::pair{computePatch, Invariant::Patch}, std::pair{computeLine, Invariant::Line}})
        if (on) list.push_back(i);
    return list;
}

InvariantsCost& InvariantsCost::operator+=(const InvariantsCost& piece)
{
    bandHalfWidth = std::max(bandHalfWidth, piece.bandHalfWidth);
    levelSetVoxels += piece.levelSetVoxels;
    levelSetBytes = std::max(levelSetBytes, piece.levelSetBytes);
    stencilNodes += piece.stencilNodes;
    numSamples += piece.numSamples;
    directEvaluations += piece.directEvaluations;
    patchLinePairs += piece.patchLinePairs, patchLinePairsExact += piece.patchLinePairsExact;
    patchLineVerticesExact += piece.patchLineVerticesExact;
    check += piece.check, levelSet += piece.levelSet, occupancy += piece.occupancy, stencils += piece.stencils;
    interpolation += piece.interpolation, samples += piece.samples, patchLine += piece.patchLine;
    patchLineCheck += piece.patchLineCheck, patchLineExact += piece.patchLineExact;
    exact += piece.exact, total += piece.total;
    return *this;
}

InvariantsResult computeInvariants(const TriMesh& mesh, const InvariantsOptions& options, RunContext* context)
{
    InvariantsResult result = planInvariants(mesh, options);
    computeValues(mesh, options, result, context);
    return result;
}

} // namespace msii
