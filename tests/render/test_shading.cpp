/// Tests of render/shading.h: Lambert shading of flat and tilted planes, the light's
/// direction convention (315° lights from the top left), masks, the high-contrast mode
/// against a brute-force reference (box means clipped to the image and the mask, percentile
/// stretch), a shallow groove that only high contrast brings out, thread-count independence
/// and bad input.

#include <msii/render/shading.h>

#include <msii/core/errors.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

using namespace msii;

namespace {

constexpr double kPi = 3.14159265358979323846;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

/// A normal map of one normal everywhere, all pixels masked in.
struct NormalMap {
    int width = 0, height = 0;
    std::vector<float> nx, ny, nz, mask;

    NormalMap(int w, int h, double x = 0, double y = 0, double z = 1)
        : width(w), height(h), nx(std::size_t(w) * h), ny(nx.size()), nz(nx.size()),
          mask(nx.size(), 1.0f)
    {
        for (std::size_t i = 0; i < nx.size(); ++i) setNormal(i, x, y, z);
    }
    std::size_t index(int x, int y) const { return std::size_t(y) * width + x; }
    /// Stores (x, y, z) normalised.
    void setNormal(std::size_t i, double x, double y, double z)
    {
        const double l = std::sqrt(x * x + y * y + z * z);
        nx[i] = float(x / l);
        ny[i] = float(y / l);
        nz[i] = float(z / l);
    }
    std::vector<float> shade(const ShadingOptions& o) const
    {
        return shadeRelief(width, height, nx, ny, nz, mask, o);
    }
};

struct Vec {
    double x, y, z;
};

/// The documented light vector: towards the light, the azimuth being the direction it travels.
Vec lightVector(double azimuthDeg, double elevationDeg)
{
    const double az = azimuthDeg * kPi / 180, el = elevationDeg * kPi / 180;
    return {-std::cos(el) * std::cos(az), -std::cos(el) * std::sin(az), std::sin(el)};
}

double lambertReference(Vec n, Vec l, double ambient)
{
    const double len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    return ambient + (1 - ambient) * std::max(0.0, (n.x * l.x + n.y * l.y + n.z * l.z) / len);
}

/// The p-th percentile by sorting, linear between order statistics.
double percentileReference(std::vector<double> v, double p)
{
    std::sort(v.begin(), v.end());
    const double rank = p / 100 * double(v.size() - 1);
    const auto k = std::size_t(std::floor(rank));
    if (k + 1 >= v.size()) return v[k];
    return v[k] + (rank - double(k)) * (v[k + 1] - v[k]);
}

/// High-contrast shading written out directly: box means by double loops.
std::vector<double> highContrastReference(const NormalMap& m, const ShadingOptions& o)
{
    const Vec l = lightVector(o.azimuthDeg, o.elevationDeg);
    const int r = o.contrastRadius;
    std::vector<double> out(m.nx.size(), std::nan(""));
    std::vector<double> shaded;
    for (int y = 0; y < m.height; ++y)
        for (int x = 0; x < m.width; ++x) {
            const std::size_t i = m.index(x, y);
            if (m.mask[i] == 0) continue;
            double sx = 0, sy = 0, sz = 0, count = 0;
            for (int v = std::max(0, y - r); v <= std::min(m.height - 1, y + r); ++v)
                for (int u = std::max(0, x - r); u <= std::min(m.width - 1, x + r); ++u) {
                    const std::size_t j = m.index(u, v);
                    if (m.mask[j] == 0) continue;
                    sx += m.nx[j];
                    sy += m.ny[j];
                    sz += m.nz[j];
                    count += 1;
                }
            const Vec d{m.nx[i] - sx / count, m.ny[i] - sy / count, m.nz[i] - sz / count + 1};
            out[i] = lambertReference(d, l, o.ambient);
            shaded.push_back(out[i]);
        }
    const double p1 = percentileReference(shaded, 1), p99 = percentileReference(shaded, 99);
    for (double& v : out)
        if (!std::isnan(v)) v = std::clamp((v - p1) / (p99 - p1), 0.0, 1.0);
    return out;
}

/// A wavy normal map with a masked-out disc and some masked-out pixels here and there.
NormalMap wavyMap(int w, int h, unsigned seed)
{
    NormalMap m(w, h);
    std::mt19937 rng(seed);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = m.index(x, y);
            const double noise = double(rng()) / 4294967296.0 - 0.5;
            m.setNormal(i, 0.3 * std::sin(0.21 * x) + 0.05 * noise, 0.2 * std::cos(0.17 * y), 1);
            const double dx = x - 0.3 * w, dy = y - 0.6 * h;
            if (dx * dx + dy * dy < 0.01 * w * h || rng() % 37 == 0) m.mask[i] = 0;
        }
    return m;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

} // namespace

TEST(ShadeRelief, FlatSurfaceGetsTheElevationsSine)
{
    const NormalMap flat(17, 9);
    for (double elevation : {45.0, 30.0, 90.0, 5.0})
        for (double ambient : {0.15, 0.0, 0.5})
            for (double azimuth : {315.0, 0.0, 123.0}) {
                ShadingOptions o;
                o.elevationDeg = elevation;
                o.ambient = ambient;
                o.azimuthDeg = azimuth;
                const std::vector<float> b = flat.shade(o);
                ASSERT_EQ(b.size(), 17u * 9u);
                const double expected = ambient + (1 - ambient) * std::sin(elevation * kPi / 180);
                for (float v : b) ASSERT_NEAR(v, expected, 1e-6) << elevation << " " << ambient;
            }
}

TEST(ShadeRelief, PlaneFacingTheLightIsFullyLit)
{
    for (auto [azimuth, elevation] : {std::pair{315.0, 45.0}, {10.0, 20.0}, {200.0, 70.0}}) {
        const Vec l = lightVector(azimuth, elevation);
        const NormalMap facing(8, 6, l.x, l.y, l.z);
        ShadingOptions o;
        o.azimuthDeg = azimuth;
        o.elevationDeg = elevation;
        for (float v : facing.shade(o)) EXPECT_NEAR(v, 1.0, 1e-6) << azimuth;
        // Facing straight away from the light horizontally: only the ambient term.
        const NormalMap away(8, 6, -l.x, -l.y, 0);
        for (float v : away.shade(o)) EXPECT_NEAR(v, o.ambient, 1e-6) << azimuth;
    }
}

TEST(ShadeRelief, DefaultLightComesFromTheTopLeft)
{
    // y is up on the picture: a slope facing up-left is (−1, +1, ·).
    const NormalMap upLeft(4, 4, -0.3, 0.3, 1), downRight(4, 4, 0.3, -0.3, 1);
    const NormalMap upRight(4, 4, 0.3, 0.3, 1), downLeft(4, 4, -0.3, -0.3, 1);
    const ShadingOptions o;
    const float a = upLeft.shade(o)[0], b = downRight.shade(o)[0];
    const float c = upRight.shade(o)[0], d = downLeft.shade(o)[0];
    EXPECT_GT(a, c + 0.1);
    EXPECT_GT(c, b + 0.1);
    EXPECT_NEAR(c, d, 1e-6);  // both perpendicular to the light's direction in the plane
    EXPECT_NEAR(a, lambertReference({-0.3, 0.3, 1}, lightVector(315, 45), 0.15), 1e-6);
    // Azimuth 90: the light travels up the picture, so it comes from the bottom.
    ShadingOptions up;
    up.azimuthDeg = 90;
    const NormalMap facingDown(4, 4, 0, -0.5, 1), facingUp(4, 4, 0, 0.5, 1);
    EXPECT_GT(facingDown.shade(up)[0], facingUp.shade(up)[0] + 0.1);
}

TEST(ShadeRelief, MaskedPixelsAreNaN)
{
    NormalMap m(10, 7);
    m.mask[m.index(3, 2)] = 0;
    m.mask[m.index(9, 6)] = 0;
    m.nx[m.index(5, 5)] = kNaN;  // a broken normal in a masked-in pixel
    for (bool highContrast : {false, true}) {
        ShadingOptions o;
        o.highContrast = highContrast;
        o.contrastRadius = 2;
        const std::vector<float> b = m.shade(o);
        int nan = 0;
        for (std::size_t i = 0; i < b.size(); ++i) {
            if (std::isnan(b[i])) {
                ++nan;
                continue;
            }
            EXPECT_GE(b[i], 0.0f);
            EXPECT_LE(b[i], 1.0f);
        }
        EXPECT_TRUE(std::isnan(b[m.index(3, 2)]));
        EXPECT_TRUE(std::isnan(b[m.index(9, 6)]));
        EXPECT_TRUE(std::isnan(b[m.index(5, 5)]));
        EXPECT_EQ(nan, 3) << highContrast;
    }
    NormalMap none(5, 5);
    std::fill(none.mask.begin(), none.mask.end(), 0.0f);
    ShadingOptions o;
    o.highContrast = true;
    for (float v : none.shade(o)) EXPECT_TRUE(std::isnan(v));
}

TEST(ShadeRelief, HighContrastMatchesBruteForce)
{
    // The last two span more than one block of rows.
    for (auto [w, h, radius] : {std::tuple{41, 29, 3}, {23, 57, 8}, {64, 40, 1}, {30, 20, 40},
                                {50, 300, 6}, {20, 200, 40}}) {
        const NormalMap m = wavyMap(w, h, unsigned(w * h));
        ShadingOptions o;
        o.highContrast = true;
        o.contrastRadius = radius;
        o.azimuthDeg = 250;
        o.elevationDeg = 35;
        o.ambient = 0.1;
        const std::vector<float> got = m.shade(o);
        const std::vector<double> expected = highContrastReference(m, o);
        ASSERT_EQ(got.size(), expected.size());
        int zeros = 0, ones = 0, count = 0;
        for (std::size_t i = 0; i < got.size(); ++i) {
            ASSERT_EQ(std::isnan(got[i]), std::isnan(expected[i])) << i;
            if (std::isnan(got[i])) continue;
            ASSERT_NEAR(got[i], expected[i], 2e-4)
                << w << "x" << h << " r " << radius << " at " << i;
            ++count;
            zeros += got[i] == 0.0f;
            ones += got[i] == 1.0f;
        }
        // The stretch clips about 1 % at each end.
        EXPECT_LE(zeros, count / 100 + 2);
        EXPECT_LE(ones, count / 100 + 2);
    }
}

TEST(ShadeRelief, HighContrastBringsOutAShallowGroove)
{
    // A flat image with a strip of normals tilted by 2° (a shallow groove's side).
    NormalMap m(200, 120);
    const double tilt = 2 * kPi / 180;
    for (int y = 0; y < m.height; ++y)
        for (int x = 90; x < 110; ++x)
            m.setNormal(m.index(x, y), std::sin(tilt), 0, std::cos(tilt));
    ShadingOptions normal;
    normal.azimuthDeg = 180;  // light travelling left: from the right
    ShadingOptions contrast = normal;
    contrast.highContrast = true;
    const std::vector<float> a = m.shade(normal), b = m.shade(contrast);
    const std::size_t groove = m.index(100, 60), background = m.index(20, 60);
    const double plain = std::fabs(a[groove] - a[background]);
    const double strong = std::fabs(b[groove] - b[background]);
    EXPECT_GT(plain, 0.0);
    EXPECT_LT(plain, 0.05);
    EXPECT_GT(strong, 10 * plain) << "plain " << plain << ", high contrast " << strong;
    EXPECT_GT(strong, 0.2);
}

TEST(ShadeRelief, HugeRadiusMeansTheWholeImage)
{
    const NormalMap m = wavyMap(40, 30, 9);
    ShadingOptions o;
    o.highContrast = true;
    o.contrastRadius = 40;
    const std::vector<float> whole = m.shade(o);
    o.contrastRadius = 1 << 30;
    EXPECT_TRUE(sameBits(m.shade(o), whole));
}

TEST(ShadeRelief, FlatImageInHighContrastIsLeftUnstretched)
{
    const NormalMap flat(30, 30);
    ShadingOptions o;
    o.highContrast = true;
    const double expected = o.ambient + (1 - o.ambient) * std::sin(o.elevationDeg * kPi / 180);
    for (float v : flat.shade(o)) EXPECT_NEAR(v, expected, 1e-6);
}

TEST(ShadeRelief, ResultDoesNotDependOnThreadCount)
{
    const NormalMap m = wavyMap(333, 301, 5);  // more than one block of rows
    for (bool highContrast : {false, true}) {
        ShadingOptions o;
        o.highContrast = highContrast;
        o.contrastRadius = 5;
        std::vector<float> one, many;
        {
            tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
            one = m.shade(o);
        }
        many = m.shade(o);
        EXPECT_TRUE(sameBits(one, many)) << highContrast;
    }
}

TEST(ShadeRelief, EmptyImage)
{
    const std::vector<float> none;
    ShadingOptions o;
    EXPECT_TRUE(shadeRelief(0, 0, none, none, none, none, o).empty());
    o.highContrast = true;
    EXPECT_TRUE(shadeRelief(0, 5, none, none, none, none, o).empty());
}

TEST(ShadeRelief, RejectsBadInput)
{
    const NormalMap m(4, 3);
    const auto shade = [&](const ShadingOptions& o) { return m.shade(o); };
    ShadingOptions o;
    EXPECT_NO_THROW(shade(o));
    for (double elevation : {0.0, -10.0, 90.5, std::nan("")}) {
        ShadingOptions bad;
        bad.elevationDeg = elevation;
        EXPECT_THROW(shade(bad), InvalidInputError) << elevation;
    }
    for (double ambient : {-0.01, 1.0, 2.0, std::nan("")}) {
        ShadingOptions bad;
        bad.ambient = ambient;
        EXPECT_THROW(shade(bad), InvalidInputError) << ambient;
    }
    ShadingOptions bad;
    bad.azimuthDeg = std::numeric_limits<double>::infinity();
    EXPECT_THROW(shade(bad), InvalidInputError);
    bad = ShadingOptions();
    bad.highContrast = true;
    bad.contrastRadius = 0;
    EXPECT_THROW(shade(bad), InvalidInputError);

    const std::vector<float> twelve(12, 0.0f), eleven(11, 0.0f);
    EXPECT_THROW(shadeRelief(4, 3, twelve, twelve, eleven, twelve, o), InvalidInputError);
    EXPECT_THROW(shadeRelief(4, 3, twelve, twelve, twelve, eleven, o), InvalidInputError);
    EXPECT_THROW(shadeRelief(3, 3, twelve, twelve, twelve, twelve, o), InvalidInputError);
    EXPECT_THROW(shadeRelief(-4, -3, twelve, twelve, twelve, twelve, o), InvalidInputError);
}
