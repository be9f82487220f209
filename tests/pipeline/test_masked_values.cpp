// The masked values (pipeline/masked_values.h): counted per radius in the first invariant
// computed, over the rows given; the "mostly_masked" warning when more than half are masked
// at the largest radius, naming the largest radius at which at least half have values; and
// the same warning from the pipeline on a patch whose border band covers most of it.
#include <msii/pipeline/compute.h>
#include <msii/pipeline/masked_values.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>

using namespace msii;

namespace {

/// Masked values of @p perRadius over @p vertices vertices, as MaskedValues would count them.
MaskedValues counted(std::vector<std::size_t> perRadius, std::size_t vertices)
{
    MaskedValues m;
    m.perRadius = std::move(perRadius);
    m.vertices = vertices;
    return m;
}

} // namespace

TEST(MaskedValues, CountsTheFirstInvariantOverTheRowsGiven)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    FeatureSet f;
    f.radii = {1, 2};
    f[Invariant::Sphere] = {{0.5f, nan, 0.5f, nan}, {nan, nan, 0.5f, nan}};
    f[Invariant::Line] = {{nan, nan, nan, nan}, {nan, nan, nan, nan}};  // not the first: not counted
    const std::vector<float> share{0.0f, 0.25f, 0.0f, 1.0f};
    MaskedValues all;
    all.add(f, share);
    EXPECT_EQ(all.withFilledShare, 2u);
    EXPECT_EQ(all.vertices, 4u);
    EXPECT_EQ(all.perRadius, (std::vector<std::size_t>{2, 3}));
    EXPECT_EQ(all.total(), 5u);
    MaskedValues some;
    some.add(f, share, {0, 2});
    some.add(f, share, {3});
    some.add(f, share, {});  // no rows (a DEM window with no own cell in a face): nothing counted
    EXPECT_EQ(some.vertices, 3u);
    EXPECT_EQ(some.withFilledShare, 1u);
    EXPECT_EQ(some.perRadius, (std::vector<std::size_t>{1, 2}));
    MaskedValues where;  // the same rows by a mask
    where.addWhere(f, share, {1, 0, 1, 1});
    where.addWhere(f, share, {0, 0, 0, 0});
    EXPECT_EQ(where.vertices, 3u);
    EXPECT_EQ(where.withFilledShare, 1u);
    EXPECT_EQ(where.perRadius, (std::vector<std::size_t>{1, 2}));
    f[Invariant::Volume] = {{0.5f, 0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f, nan}};  // V whenever computed
    MaskedValues withV;
    withV.add(f, share);
    EXPECT_EQ(withV.perRadius, (std::vector<std::size_t>{0, 1}));
}

TEST(MaskedValues, MostlyMaskedRule)
{
    EXPECT_FALSE(counted({5, 5, 5}, 10).mostlyMasked({1, 2, 3}).has_value());
    const std::optional<Diagnostic> some = counted({0, 3, 6}, 10).mostlyMasked({1, 2, 3});
    ASSERT_TRUE(some.has_value());
    EXPECT_EQ(some->kind, "mostly_masked");
    EXPECT_EQ(some->count, 6u);
    EXPECT_DOUBLE_EQ(some->figure("masked_share"), 0.6);
    EXPECT_DOUBLE_EQ(some->figure("largest_radius"), 3.0);
    EXPECT_DOUBLE_EQ(some->figure("radius_with_half"), 2.0);
    EXPECT_NE(some->message.find("60 % of the vertices are masked"), std::string::npos) << some->message;
    EXPECT_NE(some->message.find("at r = 2 at least half"), std::string::npos) << some->message;
    EXPECT_EQ(some->message.find("--"), std::string::npos) << "the engine names no flag: " << some->message;
    const std::optional<Diagnostic> all = counted({6, 7, 8}, 10).mostlyMasked({1, 2, 3});
    ASSERT_TRUE(all.has_value());
    EXPECT_DOUBLE_EQ(all->figure("radius_with_half", -1), 0.0);
    EXPECT_NE(all->message.find("even at the smallest radius"), std::string::npos) << all->message;
}

// A 12 mm plane: with R = 0.8 most vertices keep their values, with R = 3 the border band
// covers most of it, and the radius named keeps at least half.
TEST(MaskedValues, PipelineWarnsOnAMostlyMaskedPatch)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Plane;
    ho.width = 12;
    ho.height = 12;
    ho.spacing = 0.1;
    ho.noise = 0;
    const TriMesh mesh = samples::makeHeightField(ho);
    for (const double radius : {0.8, 3.0}) {
        ComputeOptions o;
        o.invariants.radius = radius;
        o.invariants.computePatch = o.invariants.computeLine = false;
        o.border = BorderHandling::Mask;  // the masking this warning is about
        const ComputeResult res = compute(mesh, o);
        const auto share = [&](std::size_t j) {
            const auto& column = res.features[Invariant::Volume][j];
            return double(std::count_if(column.begin(), column.end(), [](float v) { return std::isnan(v); })) /
                   double(column.size());
        };
        const std::size_t last = res.plan.radii.size() - 1;
        std::string warning;
        for (const Diagnostic& d : res.diagnostics)
            if (d.kind == "mostly_masked") warning = d.message;
        SCOPED_TRACE("R = " + std::to_string(radius));
        EXPECT_EQ(res.masked.vertices, mesh.numVertices());
        EXPECT_DOUBLE_EQ(double(res.masked.perRadius[last]) / double(mesh.numVertices()), share(last));
        if (radius < 1) {
            EXPECT_LT(share(last), 0.5);
            EXPECT_EQ(warning, "");
            continue;
        }
        EXPECT_GT(share(last), 0.8);
        ASSERT_NE(warning, "");
        std::size_t named = last;
        while (named > 0 && share(named) > 0.5) --named;
        ASSERT_LE(share(named), 0.5);
        std::ostringstream r;
        r << "at r = " << std::setprecision(3) << res.plan.radii[named] << " at least half";
        EXPECT_NE(warning.find(r.str()), std::string::npos) << warning;
    }
}
