/// @file exact_case.cpp
/// @brief The exact mode (--exact: V, S, P, L from the triangles): on a block of the
/// tablet's vertices, setting up the whole mesh included, and on every vertex of a closed
/// slab whose walls and bottom are a few long triangles.
#include "benchmark.h"

#include <msii/core/stopwatch.h>
#include <msii/invariants/exact.h>
#include <msii/invariants/scales.h>
#include <msii/samples/generators.h>

#include <cstdint>

namespace msii::benchmark {

namespace {
/// The exact mode's options for the vertices [first, first + count).
ExactOptions exactOptions(const Settings& s, std::size_t first, std::size_t count)
{
    ExactOptions eo;
    eo.radii = equidistantRadii(s.radius, s.scales);
    eo.computeVolumeSphere = s.has('V') || s.has('S');
    eo.computePatchLine = s.has('P') || s.has('L');
    for (std::size_t i = first; i < first + count; ++i) eo.vertices.push_back(std::uint32_t(i));
    return eo;
}
} // namespace

TriMesh makeSlab(const Settings& s)
{
    samples::HeightFieldOptions so;
    so.kind = samples::HeightFieldKind::Tablet;
    so.width = 7;
    so.height = 5;
    so.spacing = s.spacing;
    so.closed = true;
    so.thickness = 3;
    so.wallStep = 1.5;
    return samples::makeHeightField(so);
}

double timeExactOnVertices(const Settings& s, const TriMesh& tablet)
{
    const std::size_t count = std::min<std::size_t>(std::size_t(s.exactVertices), tablet.numVertices());
    const ExactOptions eo = exactOptions(s, (tablet.numVertices() - count) / 2, count);
    const Stopwatch t;
    computeExact(tablet, eo);
    return t.seconds();
}

double timeExactOnSlab(const Settings& s, const TriMesh& slab)
{
    const Stopwatch t;
    computeExact(slab, exactOptions(s, 0, slab.numVertices()));
    return t.seconds();
}

void printExactRows(Report& report, const Settings& s, const ExactRuns& exact, std::size_t tabletVertices,
                    std::size_t slabVertices)
{
    if (!exact.vertexSeconds.empty()) {
        const std::size_t count = std::min<std::size_t>(std::size_t(s.exactVertices), tabletVertices);
        row(report, ("exact mode (--exact), " + std::to_string(count) + " vertices of the tablet, set-up included").c_str(),
            median(exact.vertexSeconds), "%8.2f");
    }
    if (!exact.slabSeconds.empty()) {
        row(report, ("exact mode, 7 x 5 x 3 mm slab, long walls, all " + std::to_string(slabVertices) + " vertices").c_str(),
            median(exact.slabSeconds), "%8.2f");
        row(report, "the same, milliseconds per vertex", 1e3 * median(exact.slabSeconds) / double(slabVertices), "%8.3f");
    }
}

} // namespace msii::benchmark
