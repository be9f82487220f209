/// @file maps_case.cpp
/// @brief After compute, on the tablet's results: the EXR feature map (`msii map`: every
/// feature and quality; default PIZ float, and the variants) and a PNG picture (`msii
/// render`: shaded colour, isolines, bars).
#include "benchmark.h"

#include <msii/core/stopwatch.h>
#include <msii/featuremap/rasterize.h>
#include <msii/render/annotate.h>
#include <msii/render/picture.h>
#include <msii/render/typeface.h>

#include <array>

namespace msii::benchmark {

namespace {
/// One run of a PNG picture as msii render makes it: rasterise, colour, shade, isolines,
/// bars, write; returns its seconds.
double timePicture(const TriMesh& mesh, const MapFrame& frame, const std::vector<float>& quality,
                   const std::string& png)
{
    const Stopwatch t;
    const PixelHits hits = rasterize(mesh, frame);
    const std::vector<float> value = interpolateToPixels(mesh, hits, quality), mask = coverageMask(hits);
    const std::array<std::vector<float>, 3> normals = vertexNormalsInFrame(mesh, frame);
    std::vector<float> n3[3];
    for (std::size_t a = 0; a < 3; ++a) n3[a] = interpolateToPixels(mesh, hits, normals[a]);
    PictureChannels pc;
    pc.width = hits.width, pc.height = hits.height;
    pc.value = &value, pc.mask = &mask, pc.nx = &n3[0], pc.ny = &n3[1], pc.nz = &n3[2];
    PictureOptions po;
    po.shade = true;
    po.isolineCount = 5;
    const PictureResult pic = renderPicture(pc, po);
    FigureOptions fig;
    static const FontResult font = findFont();  // as msii render: DejaVu Sans if installed
    if (!font.typeface.isBuiltIn()) fig.typeface = &font.typeface;
    fig.lineHeight = labelLineHeight(pic.image.height);
    fig.range = pic.range;
    fig.isolines = pic.isolineLevels;
    fig.pixelSize = frame.pixelSize;
    writePng(png, composeFigure(pic.image, fig));
    return t.seconds();
}
} // namespace

MapRuns timeMapsAndPictures(const Bench& bench, const TriMesh& mesh, const std::vector<VertexProperty>& props,
                            const std::vector<float>& quality)
{
    const Settings& s = bench.settings;
    MapRuns m;
    m.mapRows.resize(3);
    m.mapRows[0].name = "float, piz (default)";
    m.mapRows[1].name = "float, none";
    m.mapRows[1].options.compression = ExrCompression::None;
    m.mapRows[2].name = "half, piz";
    m.mapRows[2].options.half = true;
    if (!(s.mapPixels > 0 && s.picturePixels > 0)) return m;
    fs::create_directories(bench.dir);
    MapFrameOptions fo;
    fo.longerSidePixels = s.mapPixels;
    m.mapFrame = makeMapFrame(mesh, fo);
    fo.longerSidePixels = s.picturePixels;
    m.pictureFrame = makeMapFrame(mesh, fo);
    const std::string exr = (bench.dir / "map.exr").string(), png = (bench.dir / "picture.png").string();
    for (int run = 0; run < s.runs; ++run) {
        for (MapRow& row : m.mapRows) {
            const Stopwatch t;
            writeFeatureMap(exr, mesh, m.mapFrame, props, row.options);
            row.seconds.push_back(t.seconds());
            row.megabytes = double(fs::file_size(exr)) / 1e6;
            fs::remove(exr);
        }
        m.pictureSeconds.push_back(timePicture(mesh, m.pictureFrame, quality, png));
    }
    fs::remove_all(bench.dir);
    return m;
}

void printMapRows(Report& report, const MapRuns& maps, std::size_t numProperties)
{
    for (const MapRow& m : maps.mapRows)
        if (!m.seconds.empty())
            row(report,
                ("EXR map " + std::to_string(maps.mapFrame.width) + " x " + std::to_string(maps.mapFrame.height) + ", " +
                 std::to_string(numProperties + 5) + " ch, " + m.name + ", " + std::to_string(int(m.megabytes)) + " MB")
                    .c_str(),
                median(m.seconds), "%8.2f");
    if (!maps.pictureSeconds.empty())
        row(report,
            ("PNG picture " + std::to_string(maps.pictureFrame.width) + " x " + std::to_string(maps.pictureFrame.height) +
             " (shaded colour, isolines, bars)")
                .c_str(),
            median(maps.pictureSeconds), "%8.2f");
}

} // namespace msii::benchmark
