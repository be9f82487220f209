/// Tests of map/feature_map.h: multichannel OpenEXR feature maps written and read back. The
/// tilted plane z = 0.3 x − 0.2 y (with a hole, so that there is background) seen from +z and
/// along its best-fit plane: channel names, height, normal, mask and interpolated properties
/// at every pixel against the closed forms; the header's frame and strings; half channels;
/// lossless compressions (bit-identical); atomic writing (no file on failure, no temporary
/// files left); rejected properties, compressions and files.

#include <msii/featuremap/feature_map.h>
#include <msii/featuremap/half_floats.h>

#include <msii/core/errors.h>
#include <msii/featuremap/map_frame.h>
#include <msii/samples/generators.h>

#include "../support/temp_dir.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <Imath/half.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace msii;

namespace msii {
/// Readable MapView values in gtest messages.
void PrintTo(MapView view, std::ostream* os)
{
    static const char* const names[] = {"BestFit", "PlusX", "MinusX", "PlusY", "MinusY", "PlusZ", "MinusZ", "Direction"};
    *os << names[int(view)];
}
} // namespace msii

namespace {

constexpr double kA = 0.3, kB = -0.2;  // z = kA x + kB y

/// A measured value for the XML report (--gtest_output=xml), not printed.
void record(const std::string& key, double value)
{
    std::ostringstream s;
    s.precision(3);
    s << value;
    ::testing::Test::RecordProperty(key, s.str());
}

/// The plane z = 0.3 x − 0.2 y over [0, 10] × [0, 8] (spacing 0.1, triangles facing up), with
/// the triangles whose centroid lies in [4, 6] × [3, 5] removed: a hole of background.
TriMesh tiltedPlaneWithHole()
{
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Plane;
    o.width = 10;
    o.height = 8;
    o.spacing = 0.1;
    TriMesh mesh = samples::makeHeightField(o);
    for (Vec3& p : mesh.points) p.z = kA * p.x + kB * p.y;
    std::vector<Triangle> kept;
    for (const Triangle& t : mesh.triangles) {
        const Vec3 c = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) / 3.0;
        if (!(c.x > 4 && c.x < 6 && c.y > 3 && c.y < 5)) kept.push_back(t);
    }
    mesh.triangles = kept;
    return mesh;
}

/// "quality" = x + 2 y and "V_01" = 0.25 per vertex.
std::vector<VertexProperty> testProperties(const TriMesh& mesh)
{
    VertexProperty quality{"quality", {}}, v01{"V_01", {}};
    for (const Vec3& p : mesh.points) {
        quality.values.push_back(float(p.x + 2 * p.y));
        v01.values.push_back(0.25f);
    }
    return {quality, v01};
}

MapFrame frameOf(const TriMesh& mesh, MapView view, double pixelSize)
{
    MapFrameOptions o;
    o.view = view;
    o.pixelSize = pixelSize;
    return makeMapFrame(mesh, o);
}

FeatureMapOptions plainOptions(ExrCompression compression = ExrCompression::Piz)
{
    FeatureMapOptions o;
    o.compression = compression;
    return o;
}

/// Where the pixel centre lies relative to the hole [4, 6] × [3, 5] (in x, y of the plane):
/// +1 certainly covered (0.25 away from the hole and inside the rectangle), −1 certainly in
/// the hole (0.25 inside it), 0 undecided (triangles are below 0.2 across).
int classify(double x, double y)
{
    if (x > 4.25 && x < 5.75 && y > 3.25 && y < 4.75) return -1;
    const bool nearHole = x > 3.75 && x < 6.25 && y > 2.75 && y < 5.25;
    const bool inside = x > 0 && x < 10 && y > 0 && y < 8;
    return inside && !nearHole ? 1 : 0;
}

/// Bitwise equality of two float channels (NaN bits included).
bool sameBits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

std::vector<std::string> channelNames(const FeatureMapImage& image)
{
    std::vector<std::string> names;
    for (const auto& [name, data] : image.channels) names.push_back(name);
    return names;
}

const std::vector<std::string> kChannels{"V_01", "height", "mask", "normal.x", "normal.y", "normal.z", "quality"};

TEST(FeatureMap, PlusZViewChannelsMatchTheClosedForms)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::PlusZ, 0.05);  // 200 x 160: three 64-row chunks
    ASSERT_EQ(frame.width, 200);
    ASSERT_EQ(frame.height, 160);
    test::TempDir dir;
    const std::string path = dir.file("plane.exr");
    const FeatureMapInfo info = writeFeatureMap(path, mesh, frame, testProperties(mesh), plainOptions());
    EXPECT_EQ(info.channels, kChannels);

    const FeatureMapImage image = readFeatureMap(path);
    EXPECT_EQ(image.width, frame.width);
    EXPECT_EQ(image.height, frame.height);
    ASSERT_EQ(channelNames(image), kChannels);
    for (const auto& [name, data] : image.channels)
        ASSERT_EQ(data.size(), std::size_t(frame.width) * std::size_t(frame.height)) << name;

    const Vec3 n = normalized(Vec3(-kA, -kB, 1));
    const auto& height = image.channels.at("height");
    const auto& mask = image.channels.at("mask");
    const auto& nx = image.channels.at("normal.x");
    const auto& ny = image.channels.at("normal.y");
    const auto& nz = image.channels.at("normal.z");
    const auto& quality = image.channels.at("quality");
    const auto& v01 = image.channels.at("V_01");
    double heightError = 0, qualityError = 0, normalError = 0, v01Error = 0;
    std::size_t covered = 0, checkedCovered = 0, checkedHole = 0;
    int wrongMask = 0, coveredNotCovered = 0, holeNotBackground = 0, backgroundNotNaN = 0;
    for (int y = 0; y < frame.height; ++y)
        for (int x = 0; x < frame.width; ++x) {
            const std::size_t k = std::size_t(y) * std::size_t(frame.width) + std::size_t(x);
            // +z view: u = x − origin.x, v = y − origin.y, height = z − origin.z (the
            // origin is the surface's centroid).
            const double u = frame.minU + (x + 0.5) * frame.pixelSize + frame.origin.x;
            const double v = frame.maxV - (y + 0.5) * frame.pixelSize + frame.origin.y;
            if (mask[k] != 0 && mask[k] != 1) ++wrongMask;
            const int where = classify(u, v);
            if (where == 1 && mask[k] != 1) ++coveredNotCovered;
            if (where == -1 && mask[k] != 0) ++holeNotBackground;
            if (where == 1) ++checkedCovered;
            if (where == -1) ++checkedHole;
            if (mask[k] == 0) {
                for (const auto* c : {&height, &nx, &ny, &nz, &quality, &v01})
                    backgroundNotNaN += !std::isnan((*c)[k]);
                continue;
            }
            ++covered;
            heightError = std::max(heightError, std::abs(height[k] - (kA * u + kB * v - frame.origin.z)));
            qualityError = std::max(qualityError, std::abs(quality[k] - (u + 2 * v)));
            normalError = std::max({normalError, std::abs(nx[k] - n.x), std::abs(ny[k] - n.y), std::abs(nz[k] - n.z)});
            v01Error = std::max(v01Error, std::abs(v01[k] - 0.25));
        }
    EXPECT_EQ(wrongMask, 0);
    EXPECT_EQ(coveredNotCovered, 0);
    EXPECT_EQ(holeNotBackground, 0);
    EXPECT_EQ(backgroundNotNaN, 0);
    EXPECT_GT(checkedCovered, 25000u);
    EXPECT_GT(checkedHole, 800u);  // 30 x 30 pixels in the hole's core
    EXPECT_EQ(covered, info.coveredPixels);
    EXPECT_LE(heightError, 1e-5);
    EXPECT_LE(qualityError, 1e-4);
    EXPECT_LE(normalError, 1e-5);
    EXPECT_LE(v01Error, 1e-6);
    record("heightError", heightError);
    record("qualityError", qualityError);
    record("normalError", normalError);
    record("v01Error", v01Error);
    record("covered", double(covered));
}

TEST(FeatureMap, BestFitViewIsFlat)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::BestFit, 0.06);
    ASSERT_LE(std::max(frame.width, frame.height), 512);
    test::TempDir dir;
    const std::string path = dir.file("best.exr");
    const FeatureMapInfo info = writeFeatureMap(path, mesh, frame, testProperties(mesh), plainOptions());
    const FeatureMapImage image = readFeatureMap(path);
    ASSERT_EQ(channelNames(image), kChannels);
    ASSERT_TRUE(image.hasFrame);
    const auto& height = image.channels.at("height");
    const auto& mask = image.channels.at("mask");
    const auto& nx = image.channels.at("normal.x");
    const auto& ny = image.channels.at("normal.y");
    const auto& nz = image.channels.at("normal.z");
    const auto& quality = image.channels.at("quality");
    double heightError = 0, normalError = 0, qualityError = 0;
    std::size_t covered = 0, background = 0;
    for (std::size_t k = 0; k < mask.size(); ++k) {
        if (mask[k] == 0) {
            ++background;
            continue;
        }
        ++covered;
        heightError = std::max(heightError, double(std::abs(height[k])));
        normalError = std::max({normalError, double(std::abs(nx[k])), double(std::abs(ny[k])), std::abs(nz[k] - 1.0)});
        // The pixel centre's point in space gives the expected quality x + 2 y.
        const int x = int(k % std::size_t(frame.width)), y = int(k / std::size_t(frame.width));
        const Vec3 p = frame.origin + frame.axisU * (frame.minU + (x + 0.5) * frame.pixelSize) +
                       frame.axisV * (frame.maxV - (y + 0.5) * frame.pixelSize) + frame.normal * double(height[k]);
        qualityError = std::max(qualityError, std::abs(quality[k] - (p.x + 2 * p.y)));
    }
    EXPECT_EQ(covered, info.coveredPixels);
    // Area of the tilted 10 x 8 rectangle minus the ~2 x 2 hole, over the pixel area.
    const double area = norm(cross(Vec3(10, 0, 10 * kA), Vec3(0, 8, 8 * kB))) -
                        norm(cross(Vec3(2, 0, 2 * kA), Vec3(0, 2, 2 * kB)));
    EXPECT_NEAR(double(covered) * frame.pixelSize * frame.pixelSize, area, 0.02 * area);
    EXPECT_GT(background, 0u);  // the corners of the parallelogram and the hole
    EXPECT_LE(heightError, 1e-5);
    EXPECT_LE(normalError, 1e-5);
    EXPECT_LE(qualityError, 1e-4);
    record("heightError", heightError);
    record("normalError", normalError);
    record("qualityError", qualityError);
    record("coveredArea", double(covered) * frame.pixelSize * frame.pixelSize);
    record("expectedArea", area);
}

TEST(FeatureMap, HeaderAttributesReadBack)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::BestFit, 0.1);
    FeatureMapOptions o;
    o.units = "um";
    o.source = "/data/scans/tablet 42.ply";
    o.parameters = "msii features --radii 0.25,0.5,1.5 --scales 3\nsecond line";
    o.radii = {0.1, 0.25, 0.5, 1.5, 3.0};
    test::TempDir dir;
    const std::string path = dir.file("header.exr");
    writeFeatureMap(path, mesh, frame, testProperties(mesh), o);
    const FeatureMapImage image = readFeatureMap(path);
    ASSERT_TRUE(image.hasFrame);
    EXPECT_NEAR(image.frame.pixelSize, frame.pixelSize, 1e-12);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(image.frame.origin[i], frame.origin[i], 1e-12) << i;
        EXPECT_NEAR(image.frame.axisU[i], frame.axisU[i], 1e-12) << i;
        EXPECT_NEAR(image.frame.axisV[i], frame.axisV[i], 1e-12) << i;
        EXPECT_NEAR(image.frame.normal[i], frame.normal[i], 1e-12) << i;
    }
    EXPECT_NEAR(image.frame.minU, frame.minU, 1e-12);
    EXPECT_NEAR(image.frame.maxV, frame.maxV, 1e-12);
    EXPECT_EQ(image.frame.width, frame.width);
    EXPECT_EQ(image.frame.height, frame.height);
    EXPECT_EQ(image.units, "um");
    EXPECT_EQ(image.source, o.source);
    EXPECT_EQ(image.parameters, o.parameters);
    ASSERT_EQ(image.radii.size(), o.radii.size());
    for (std::size_t i = 0; i < o.radii.size(); ++i)
        EXPECT_EQ(image.radii[i], double(float(o.radii[i]))) << i;  // stored as floats

    // Defaults: units "mm", empty strings and no radii.
    const std::string path2 = dir.file("defaults.exr");
    writeFeatureMap(path2, mesh, frame, {}, FeatureMapOptions{});
    const FeatureMapImage image2 = readFeatureMap(path2);
    EXPECT_TRUE(image2.hasFrame);
    EXPECT_EQ(image2.units, "mm");
    EXPECT_EQ(image2.source, "");
    EXPECT_EQ(image2.parameters, "");
    EXPECT_TRUE(image2.radii.empty());
    EXPECT_EQ(channelNames(image2), (std::vector<std::string>{"height", "mask", "normal.x", "normal.y", "normal.z"}));
}

TEST(FeatureMap, ViewReadBack)
{
    // FeatureMapImage::frame is documented as "view, pixel size, axes and corner from the
    // header"; the view is written as msii:view (mapViewName) and must come back too.
    const TriMesh mesh = tiltedPlaneWithHole();
    test::TempDir dir;
    for (const char* view : {"+z", "-x", "best", "1,-1,2"}) {
        MapFrameOptions o;
        parseMapView(view, o);
        o.pixelSize = 0.2;
        const MapFrame frame = makeMapFrame(mesh, o);
        const std::string path = dir.file("view.exr");
        writeFeatureMap(path, mesh, frame, {}, plainOptions());
        const FeatureMapImage image = readFeatureMap(path);
        ASSERT_TRUE(image.hasFrame) << view;
        EXPECT_EQ(image.frame.view, frame.view) << view;
        EXPECT_EQ(mapViewName(image.frame), mapViewName(frame)) << view;
    }
}

TEST(FeatureMap, PlainExrWithoutFrameReads)
{
    // Any scanline EXR reads, without the msii attributes: hasFrame = false.
    test::TempDir dir;
    const std::string path = dir.file("plain.exr");
    const int w = 5, h = 3;
    std::vector<float> y(w * h);
    for (int i = 0; i < w * h; ++i) y[std::size_t(i)] = 0.5f * float(i);
    {
        Imf::Header header(w, h);
        header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
        Imf::OutputFile file(path.c_str(), header);
        Imf::FrameBuffer fb;
        fb.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(y.data()), sizeof(float), sizeof(float) * w));
        file.setFrameBuffer(fb);
        file.writePixels(h);
    }
    const FeatureMapImage image = readFeatureMap(path);
    EXPECT_FALSE(image.hasFrame);
    EXPECT_EQ(image.width, w);
    EXPECT_EQ(image.height, h);
    ASSERT_EQ(channelNames(image), std::vector<std::string>{"Y"});
    EXPECT_EQ(image.channels.at("Y"), y);
    EXPECT_TRUE(image.radii.empty());
}

TEST(FeatureMap, HalfChannelsWithinHalfPrecision)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::PlusZ, 0.08);
    test::TempDir dir;
    writeFeatureMap(dir.file("float.exr"), mesh, frame, testProperties(mesh), plainOptions());
    FeatureMapOptions o = plainOptions();
    o.half = true;
    writeFeatureMap(dir.file("half.exr"), mesh, frame, testProperties(mesh), o);
    const FeatureMapImage full = readFeatureMap(dir.file("float.exr"));
    const FeatureMapImage half = readFeatureMap(dir.file("half.exr"));
    ASSERT_EQ(channelNames(half), kChannels);
    EXPECT_EQ(half.width, full.width);
    EXPECT_EQ(half.height, full.height);
    double worstRelative = 0;
    int nanMismatch = 0, beyond = 0, differ = 0;
    for (const auto& [name, f] : full.channels) {
        const std::vector<float>& h = half.channels.at(name);
        ASSERT_EQ(h.size(), f.size()) << name;
        for (std::size_t k = 0; k < f.size(); ++k) {
            if (std::isnan(f[k]) || std::isnan(h[k])) {
                nanMismatch += std::isnan(f[k]) != std::isnan(h[k]);
                continue;
            }
            const double d = std::abs(double(h[k]) - double(f[k]));
            differ += d > 0;
            // Relative 1e-3 (half: 2^-11 = 4.9e-4), or the subnormal step near 0 (2^-24).
            if (d > 1e-3 * std::abs(f[k]) + 6e-8) ++beyond;
            if (std::abs(f[k]) > 1e-4) worstRelative = std::max(worstRelative, d / std::abs(f[k]));
        }
    }
    EXPECT_EQ(nanMismatch, 0);
    EXPECT_EQ(beyond, 0);
    EXPECT_GT(differ, 0);  // it really is half precision
    EXPECT_LE(worstRelative, 1e-3);
    record("worstRelative", worstRelative);
}

// The bulk conversion of --half maps (F16C where the processor has it) gives Imath's
// half(float) bit for bit: every 997th float bit pattern (4.3M of them: normal, denormal,
// overflowing, infinite, NaN) and the rounding ties around 1.
TEST(FeatureMap, HalfConversionIsImaths)
{
    std::vector<float> in;
    for (std::uint64_t bits = 0; bits < (std::uint64_t(1) << 32); bits += 997) {
        const std::uint32_t b = std::uint32_t(bits);
        float f;
        std::memcpy(&f, &b, sizeof f);
        in.push_back(f);
    }
    for (int k = 0; k < 64; ++k) in.push_back(1.0f + float(k) * 0x1p-11f + 0x1p-12f);  // ties
    in.push_back(65519.0f), in.push_back(65520.0f), in.push_back(-0.0f), in.push_back(0x1p-25f);
    std::vector<std::uint16_t> out(in.size() + 3);  // odd lengths: the tail after 8-wide steps
    for (const std::size_t n : {in.size(), in.size() - 5}) {
        std::fill(out.begin(), out.end(), std::uint16_t(0xabcd));
        floatsToHalf(in.data(), out.data(), n);
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const half expected(in[i]);
            half got;
            got.setBits(out[i]);
            const bool same = std::isnan(in[i]) ? got.isNan() : out[i] == expected.bits();
            if (!same && ++wrong < 5) ADD_FAILURE() << "float " << in[i] << ": " << out[i] << " != " << expected.bits();
        }
        EXPECT_EQ(wrong, 0u);
        EXPECT_EQ(out[n], 0xabcd);  // nothing written beyond n
    }
    std::printf("half conversion with F16C: %s\n", halfConversionUsesF16c() ? "yes" : "no");
}

TEST(FeatureMap, CompressionsAreLossless)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::BestFit, 0.08);  // over 64 rows
    ASSERT_GT(frame.height, 64);
    test::TempDir dir;
    const std::vector<VertexProperty> props = testProperties(mesh);
    const std::pair<const char*, ExrCompression> kinds[] = {{"none", ExrCompression::None},
                                                            {"rle", ExrCompression::Rle},
                                                            {"zips", ExrCompression::Zips},
                                                            {"zip", ExrCompression::Zip},
                                                            {"piz", ExrCompression::Piz}};
    std::vector<FeatureMapImage> images;
    std::vector<std::uintmax_t> sizes;
    for (const auto& [name, kind] : kinds) {
        EXPECT_EQ(parseExrCompression(name), kind) << name;
        FeatureMapOptions o = plainOptions(kind);
        if (kind == ExrCompression::Zip) o.zipLevel = 9;
        const std::string path = dir.file(std::string(name) + ".exr");
        writeFeatureMap(path, mesh, frame, props, o);
        images.push_back(readFeatureMap(path));
        sizes.push_back(std::filesystem::file_size(path));
    }
    const FeatureMapImage& reference = images[0];
    ASSERT_EQ(channelNames(reference), kChannels);
    for (std::size_t i = 1; i < images.size(); ++i) {
        ASSERT_EQ(channelNames(images[i]), kChannels) << kinds[i].first;
        for (const auto& [name, data] : reference.channels)
            EXPECT_TRUE(sameBits(images[i].channels.at(name), data)) << kinds[i].first << " " << name;
    }
    // The compressed files are smaller than the uncompressed one.
    for (std::size_t i = 1; i < sizes.size(); ++i) EXPECT_LT(sizes[i], sizes[0]) << kinds[i].first;
    for (std::size_t i = 0; i < sizes.size(); ++i) record(std::string("bytes-") + kinds[i].first, double(sizes[i]));
}

TEST(FeatureMap, SameMapWithTheSameInput)
{
    // Deterministic: writing twice gives the same channels, bit for bit.
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::PlusZ, 0.1);
    test::TempDir dir;
    writeFeatureMap(dir.file("a.exr"), mesh, frame, testProperties(mesh), plainOptions());
    writeFeatureMap(dir.file("b.exr"), mesh, frame, testProperties(mesh), plainOptions());
    const FeatureMapImage a = readFeatureMap(dir.file("a.exr")), b = readFeatureMap(dir.file("b.exr"));
    ASSERT_EQ(channelNames(a), channelNames(b));
    for (const auto& [name, data] : a.channels) EXPECT_TRUE(sameBits(data, b.channels.at(name))) << name;
}

TEST(FeatureMap, AtomicWriting)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::PlusZ, 0.1);
    const std::vector<VertexProperty> props = testProperties(mesh);
    test::TempDir dir;

    // A missing folder: IOError, nothing written.
    EXPECT_THROW(writeFeatureMap(dir.file("missing/map.exr"), mesh, frame, props, plainOptions()), IOError);
    EXPECT_TRUE(dir.entries().empty());

    // A success leaves exactly the target; overwriting it too.
    const std::string path = dir.file("map.exr");
    writeFeatureMap(path, mesh, frame, props, plainOptions());
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"map.exr"});
    writeFeatureMap(path, mesh, frame, props, plainOptions(ExrCompression::Zip));
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"map.exr"});
    EXPECT_EQ(readFeatureMap(path).width, frame.width);

    // The target is a folder (the rename fails): IOError, and the temporary file is gone.
    test::TempDir dir2;
    std::filesystem::create_directory(dir2.file("map.exr"));
    std::ofstream(dir2.file("map.exr") + "/keep.txt") << "x";
    EXPECT_THROW(writeFeatureMap(dir2.file("map.exr"), mesh, frame, props, plainOptions()), IOError);
    EXPECT_EQ(dir2.entries(), std::vector<std::string>{"map.exr"});
    EXPECT_TRUE(std::filesystem::is_directory(dir2.file("map.exr")));

    // A bad property is rejected before anything is written.
    std::vector<VertexProperty> bad = props;
    bad[0].values.pop_back();
    EXPECT_THROW(writeFeatureMap(dir2.file("bad.exr"), mesh, frame, bad, plainOptions()), InvalidInputError);
    EXPECT_EQ(dir2.entries(), std::vector<std::string>{"map.exr"});
}

TEST(FeatureMap, RejectsBadInput)
{
    const TriMesh mesh = tiltedPlaneWithHole();
    const MapFrame frame = frameOf(mesh, MapView::PlusZ, 0.2);
    const std::vector<VertexProperty> good = testProperties(mesh);
    test::TempDir dir;
    const std::string path = dir.file("bad.exr");
    const auto rejects = [&](std::vector<VertexProperty> props, const char* what) {
        EXPECT_THROW(writeFeatureMap(path, mesh, frame, props, plainOptions()), InvalidInputError) << what;
    };
    {
        auto p = good;
        p[1].values.push_back(0);
        rejects(p, "one value too many");
        p = good;
        p[0].values.clear();
        rejects(p, "no values");
    }
    for (const char* reserved : {"height", "mask", "normal.x", "normal.y", "normal.z", ""}) {
        auto p = good;
        p[1].name = reserved;
        rejects(p, reserved);
    }
    {
        auto p = good;
        p[1].name = "quality";
        rejects(p, "duplicate");
    }
    {
        FeatureMapOptions o = plainOptions(ExrCompression::Zip);
        o.zipLevel = 0;
        EXPECT_THROW(writeFeatureMap(path, mesh, frame, good, o), InvalidInputError);
        o.zipLevel = 10;
        EXPECT_THROW(writeFeatureMap(path, mesh, frame, good, o), InvalidInputError);
    }
    EXPECT_TRUE(dir.entries().empty());

    for (const char* name : {"lzma", "", "ZIP", "dwaa", "b44"})
        EXPECT_THROW(parseExrCompression(name), InvalidInputError) << name;

    EXPECT_THROW(readFeatureMap(dir.file("missing.exr")), IOError);
    EXPECT_THROW(readFeatureMap(dir.path().string()), IOError);  // a folder
    const std::string text = dir.file("text.exr");
    std::ofstream(text) << "this is not an OpenEXR file\n";
    EXPECT_THROW(readFeatureMap(text), IOError);
    const std::string empty = dir.file("empty.exr");
    { std::ofstream touch(empty); }
    EXPECT_THROW(readFeatureMap(empty), IOError);

    // A truncated map: the header survives, the pixels do not.
    const std::string whole = dir.file("whole.exr");
    writeFeatureMap(whole, mesh, frame, good, plainOptions(ExrCompression::None));
    const auto size = std::filesystem::file_size(whole);
    std::filesystem::resize_file(whole, size / 2);
    EXPECT_THROW(readFeatureMap(whole), IOError);
}

} // namespace
