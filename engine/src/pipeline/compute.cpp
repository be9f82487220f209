#include <msii/pipeline/compute.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/mesh/prepare_mesh.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

namespace msii {
namespace {

/// Stage 1: the prepared mesh, and what preparation did into @p result.
PrepareMeshResult prepare(const TriMesh& input, const ComputeOptions& options, ComputeResult& result)
{
    const Stopwatch watch;
    PrepareMeshOptions po;
    po.repair = options.repair;
    po.leaveOutSpikes = options.leaveOutSpikes;
    po.radius = options.invariants.radius;
    po.maxHolePerimeter =
        options.maxHolePerimeter >= 0 ? options.maxHolePerimeter : defaultMaxHolePerimeter(options.invariants.radius);
    PrepareMeshResult prepared = prepareMesh(input, po);
    PreparationSummary& s = result.preparation;
    s.changes = prepared.changes;
    s.holes = prepared.holes;
    s.maxHolePerimeter = po.maxHolePerimeter;
    s.isolatedVertices = prepared.numIsolatedVertices;
    s.vertices = prepared.mesh.numVertices();
    s.faces = prepared.mesh.numTriangles();
    s.seconds = watch.seconds();
    result.diagnostics = s.changes;
    return prepared;
}

/// Drops the triangles of @p prepared that lie wholly farther than @p halo from @p box (the
/// values in the box depend on none of them: haloWidth, so they are as in the whole), and the
/// vertices left in no face, renumbering the rest in order. Returns the new number of vertex
/// @p firstNew (the first of the skirt's).
std::size_t keepNear(PrepareMeshResult& prepared, const BoundingBox& box, double halo, std::size_t firstNew)
{
    BoundingBox grown = box;
    grown.min = grown.min - Vec3{halo, halo, halo};
    grown.max = grown.max + Vec3{halo, halo, halo};
    std::vector<Triangle> kept;
    std::size_t fill = prepared.firstFillTriangle;
    for (std::size_t f = 0; f < prepared.mesh.numTriangles(); ++f) {
        const Triangle& t = prepared.mesh.triangles[f];
        BoundingBox tb;
        for (std::uint32_t v : t) tb.add(prepared.mesh.points[v]);
        const bool keep = tb.max.x >= grown.min.x && tb.min.x <= grown.max.x && tb.max.y >= grown.min.y &&
                          tb.min.y <= grown.max.y && tb.max.z >= grown.min.z && tb.min.z <= grown.max.z;
        if (keep) kept.push_back(t);
        else if (f < prepared.firstFillTriangle) --fill;
    }
    prepared.mesh.triangles.swap(kept);
    prepared.firstFillTriangle = fill;
    // Vertices in no face: dropped (their values would be NaN, and searching for the surface
    // from far off is slow).
    constexpr std::uint32_t kNone = PrepareMeshResult::kNoVertex;
    std::vector<std::uint32_t> renumbered(prepared.mesh.numVertices(), kNone);
    for (const Triangle& t : prepared.mesh.triangles)
        for (std::uint32_t v : t) renumbered[v] = 0;
    std::vector<Vec3> points;
    std::size_t newFirst = 0;
    for (std::size_t v = 0; v < renumbered.size(); ++v) {
        if (renumbered[v] == kNone) continue;
        renumbered[v] = std::uint32_t(points.size());
        points.push_back(prepared.mesh.points[v]);
        if (v < firstNew) newFirst = points.size();
    }
    for (Triangle& t : prepared.mesh.triangles)
        for (std::uint32_t& v : t) v = renumbered[v];
    prepared.mesh.points.swap(points);
    for (std::uint32_t& p : prepared.preparedOf)
        if (p != kNone) p = renumbered[p];
    return newFirst;
}

/// Stage 1b (BorderHandling::Continue): the prepared mesh continued past the borders left open,
/// planned on the surface as prepared (the continuation changes neither the plan nor the
/// statistics), with the filled share over fill and continuation together. Returns the
/// planning, whose statistics and check stand for the surface; none if nothing is open.
std::optional<InvariantsResult> continueBorders(PrepareMeshResult& prepared, const ComputeOptions& options,
                                                InvariantsOptions& invariants, ComputeResult& result)
{
    if (options.border != BorderHandling::Continue || !prepared.open) return std::nullopt;
    const Stopwatch watch;
    InvariantsResult planned = planInvariants(prepared.mesh, invariants);
    ExtendBordersOptions eo;
    eo.width = haloWidth(planned.plan);
    eo.fitRadius = continuationFitRadius(planned.plan);
    eo.step = planned.plan.vertexSpacing > 0 ? planned.plan.vertexSpacing : planned.stats.medianEdge;
    if (!options.cutVertices.empty()) {
        eo.onCut.assign(prepared.mesh.numVertices(), 0);
        for (std::uint32_t v : options.cutVertices)
            if (v < prepared.preparedOf.size() && prepared.preparedOf[v] != PrepareMeshResult::kNoVertex)
                eo.onCut[prepared.preparedOf[v]] = 1;
    }
    const ExtendBordersResult e = extendBorders(prepared.mesh, eo);
    result.preparation.borders = e;
    std::size_t firstNew = e.firstNewVertex;
    if (!options.valuesWithin.empty()) firstNew = keepNear(prepared, options.valuesWithin, haloWidth(planned.plan), firstNew);
    invariants.plan = planned.plan;
    invariants.maskBorders = false;
    invariants.evaluatedVertices = firstNew;  // the surface's vertices, not the skirt's
    result.diagnostics.insert(result.diagnostics.end(), planned.diagnostics.begin(), planned.diagnostics.end());
    if (e.numChains > 0 || !options.valuesWithin.empty())
        prepared.filledShare = fillShare(prepared.mesh, prepared.firstFillTriangle, invariants.radius, firstNew);
    if (e.numChains > 0) {
        std::ostringstream msg;
        msg.precision(3);
        msg << "continued the surface past " << e.numChains << (e.numChains == 1 ? " border" : " borders")
            << " (outer edges, gaps too large to fill) for the computation, " << eo.width
            << " wide; values within R of them rest partly on the continuation (filled_share)";
        result.diagnostics.push_back(
            {"borders_continued", e.numChains, {{"width", eo.width}, {"area_added", e.areaAdded}}, msg.str()});
    }
    result.preparation.seconds += watch.seconds();
    return planned;
}

/// The invariants' options on the prepared mesh: the exact mode's vertices renumbered.
InvariantsOptions onPrepared(const ComputeOptions& options, const PrepareMeshResult& prepared)
{
    InvariantsOptions o = options.invariants;
    for (std::uint32_t& v : o.exactVertices) {
        if (v >= prepared.preparedOf.size())
            throw InvalidInputError("vertex " + std::to_string(v) + " chosen for the exact mode does not exist (the mesh has " +
                                    std::to_string(prepared.preparedOf.size()) + " vertices)");
        if (prepared.preparedOf[v] == PrepareMeshResult::kNoVertex)
            throw InvalidInputError("vertex " + std::to_string(v) + " chosen for the exact mode belongs to no face");
        v = prepared.preparedOf[v];
    }
    return o;
}

/// Rows @p rows of every column of @p values, in that order.
FeatureSet rowsOf(const FeatureSet& values, const std::vector<std::uint32_t>& rows)
{
    FeatureSet out;
    out.radii = values.radii;
    for (Invariant i : values.invariants())
        for (const std::vector<float>& column : values[i]) {
            std::vector<float> picked(rows.size());
            for (std::size_t k = 0; k < rows.size(); ++k) picked[k] = column[rows[k]];
            out[i].push_back(std::move(picked));
        }
    return out;
}

/// The input vertices of prepared vertices @p prepared (rows of their values): each input
/// vertex once, with the row of its prepared vertex.
void inputsOf(const InputVertexLists& lists, const std::vector<std::uint32_t>& prepared, ComputedPiece& piece,
              std::vector<std::uint32_t>& rows)
{
    for (std::size_t l = 0; l < prepared.size(); ++l)
        for (std::size_t k = lists.offsets[prepared[l]]; k < lists.offsets[prepared[l] + 1]; ++k) {
            piece.vertices.push_back(lists.inputs[k]);
            rows.push_back(std::uint32_t(l));
        }
}

/// Columns of the input's vertices, NaN until a piece fills them.
void scatter(const ComputedPiece& piece, std::size_t numInputVertices, ComputeResult& result)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (Invariant i : piece.features.invariants()) {
        FeatureColumns& to = result.features[i];
        const FeatureColumns& from = piece.features[i];
        if (to.empty()) to.assign(from.size(), std::vector<float>(numInputVertices, nan));
        for (std::size_t j = 0; j < from.size(); ++j)
            for (std::size_t k = 0; k < piece.vertices.size(); ++k) to[j][piece.vertices[k]] = from[j][k];
    }
    if (result.filledShare.empty()) result.filledShare.assign(numInputVertices, nan);
    for (std::size_t k = 0; k < piece.vertices.size(); ++k) result.filledShare[piece.vertices[k]] = piece.filledShare[k];
}

/// The computation's plan, mesh statistics, cost and remarks into @p result.
void takeSummary(const InvariantsResult& r, ComputeResult& result)
{
    result.plan = r.plan, result.stats = r.stats, result.check = r.check, result.cost = r.cost;
    result.diagnostics.insert(result.diagnostics.end(), r.diagnostics.begin(), r.diagnostics.end());
    result.features.radii = r.plan.radii;
}

/// Stages 2 to 4 in one piece: the prepared mesh's values, mapped to the input's vertices.
void computeWhole(const PrepareMeshResult& prepared, const InvariantsOptions& options, const PieceSink* sink,
                  ComputeResult& result, RunContext* context)
{
    InvariantsResult r = computeInvariants(prepared.mesh, options, context);
    takeSummary(r, result);
    std::vector<std::uint32_t> inFace;  // the input vertices in a face
    for (std::uint32_t v = 0; v < prepared.preparedOf.size(); ++v)
        if (prepared.preparedOf[v] != PrepareMeshResult::kNoVertex) inFace.push_back(v);
    if (sink) {
        ComputedPiece piece;
        piece.features = rowsOf(r.features, [&] {
            std::vector<std::uint32_t> rows;
            for (std::uint32_t v : inFace) rows.push_back(prepared.preparedOf[v]);
            return rows;
        }());
        piece.vertices = std::move(inFace);
        piece.plan = r.plan;
        for (std::uint32_t v : piece.vertices) piece.filledShare.push_back(prepared.filledShare[prepared.preparedOf[v]]);
        if (!options.exact) result.masked.add(piece.features, piece.filledShare);
        (*sink)(piece);
        return;
    }
    for (Invariant i : r.features.invariants())
        for (std::vector<float>& column : r.features[i]) {
            result.features[i].push_back(toInputVertices(prepared, column));
            std::vector<float>().swap(column);
        }
    result.filledShare = toInputVertices(prepared, prepared.filledShare);
    if (!options.exact) result.masked.add(result.features, result.filledShare, inFace);
}

/// Stages 2 to 4 in tiles: each tile's values mapped to the input's vertices as it comes.
void computeTiled(const PrepareMeshResult& prepared, const InvariantsOptions& options, const TilingOptions& tiling,
                  std::size_t numInputVertices, const PieceSink* sink, ComputeResult& result, RunContext* context)
{
    TilingOptions t = tiling;
    if (!sink)  // the whole result's columns stay while the tiles are computed
        t.reservedBytes += 4.0 * double(numInputVertices) * double(options.selected().size() * options.scales + 1);
    const InputVertexLists lists = inputVerticesOf(prepared);
    const auto handOn = [&](const TileResult& part) {
        ComputedPiece piece;
        std::vector<std::uint32_t> rows;  // of part.vertices, for each input vertex
        inputsOf(lists, part.vertices, piece, rows);
        piece.plan = part.values.plan;
        piece.features = rowsOf(part.values.features, rows);
        for (std::uint32_t row : rows) piece.filledShare.push_back(prepared.filledShare[part.vertices[row]]);
        result.masked.add(piece.features, piece.filledShare);
        if (sink) (*sink)(piece);
        else scatter(piece, numInputVertices, result);
    };
    takeSummary(computeTiles(prepared.mesh, options, t, handOn, &result.tiling, context), result);
    result.tiled = true;
}

ComputeResult run(const TriMesh& input, const ComputeOptions& options, const PieceSink* sink, RunContext* context)
{
    if (options.tiling.tiled() && options.invariants.exact)
        throw InvalidInputError("the exact mode is not tiled (restrict it to chosen vertices instead)");
    ComputeResult result;
    PrepareMeshResult prepared = prepare(input, options, result);
    InvariantsOptions invariants = onPrepared(options, prepared);
    const std::optional<InvariantsResult> planned = continueBorders(prepared, options, invariants, result);
    // The memory the level set may take, checked before it is built: the machine's, or the
    // budget a DEM window sets. Tiles are sized to their budget by the tiling itself.
    if (invariants.memoryLimit == 0 && !options.tiling.tiled()) invariants.memoryLimit = defaultMemoryLimit();
    if (options.tiling.tiled())
        computeTiled(prepared, invariants, options.tiling, input.numVertices(), sink, result, context);
    else
        computeWhole(prepared, invariants, sink, result, context);
    if (planned) {  // the surface's, not the continued mesh's
        result.stats = planned->stats;
        result.check = planned->check;
    }
    if (!invariants.exact && !result.check.closed && options.tiling.onlyTile < 0)
        if (std::optional<Diagnostic> d = result.masked.mostlyMasked(result.plan.radii))
            result.diagnostics.push_back(std::move(*d));
    return result;
}

} // namespace

BorderHandling parseBorderHandling(const std::string& name)
{
    if (name == "continue") return BorderHandling::Continue;
    if (name == "mask") return BorderHandling::Mask;
    throw InvalidInputError("unknown border handling '" + name +
                            "' (continue: the surface is continued past its borders; mask: NaN where a ball reaches one)");
}

const char* borderHandlingName(BorderHandling border) { return border == BorderHandling::Mask ? "mask" : "continue"; }

double continuationFitRadius(const ScalePlan& plan)
{
    return std::max(0.25 * plan.radii.back(), 3.0 * plan.vertexSpacing);
}

double continuationReach(const ScalePlan& plan) { return 3.0 * haloWidth(plan) + continuationFitRadius(plan); }

ComputeResult compute(const TriMesh& input, const ComputeOptions& options, RunContext* context)
{
    return run(input, options, nullptr, context);
}

ComputeResult computeStreamed(const TriMesh& input, const ComputeOptions& options, const PieceSink& sink,
                              RunContext* context)
{
    return run(input, options, &sink, context);
}

} // namespace msii
