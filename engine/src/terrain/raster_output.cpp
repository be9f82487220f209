#include <msii/terrain/raster_output.h>

#include "raster_backend.h"

#include <msii/core/errors.h>

#ifndef MSII_RASTER_BUILTIN
#include "../core/engine_library.h"
#endif

namespace msii {

namespace detail {

const RasterBackend& rasterBackend()
{
#ifdef MSII_RASTER_BUILTIN
    return *msii_raster_backend();
#else
    static const RasterBackend* const backend =
        static_cast<const RasterBackend*>(loadEngineLibrary(MSII_RASTER_LIBRARY, "msii_raster_backend", "raster"));
    return *backend;
#endif
}

} // namespace detail

struct RasterPieceWriter::Impl {
    detail::PieceDataset* dataset = nullptr;  // the raster library's
    ~Impl()
    {
        if (dataset != nullptr) detail::rasterBackend().closePieces(dataset);
    }
};

RasterPieceWriter::RasterPieceWriter(const std::string& path, const RasterGeoreference& grid,
                                     const std::vector<std::string>& bandNames, const RasterOutputOptions& options)
    : mImpl(std::make_unique<Impl>())
{
    mImpl->dataset = detail::rasterBackend().openPieces(path, grid, bandNames, options);
}

RasterPieceWriter::~RasterPieceWriter() = default;

void RasterPieceWriter::write(int band, int col0, int row0, int cols, int rows, const float* values)
{
    detail::rasterBackend().writePiece(*mImpl->dataset, band, col0, row0, cols, rows, values);
}

void RasterPieceWriter::commit() { detail::rasterBackend().commitPieces(*mImpl->dataset); }

void writeRaster(const std::string& path, const RasterGeoreference& grid, const std::vector<RasterBand>& bands,
                 const RasterOutputOptions& options)
{
    if (bands.empty()) throw InvalidInputError("no band to write");
    const std::size_t cells = std::size_t(grid.width) * std::size_t(grid.height);
    std::vector<std::string> names;
    for (const RasterBand& b : bands) {
        if (b.values.size() != cells)
            throw InvalidInputError("band '" + b.name + "' has " + std::to_string(b.values.size()) +
                                    " values for a grid of " + std::to_string(cells) + " cells");
        names.push_back(b.name);
    }
    RasterPieceWriter writer(path, grid, names, options);
    for (std::size_t k = 0; k < bands.size(); ++k)
        writer.write(int(k), 0, 0, grid.width, grid.height, bands[k].values.data());
    writer.commit();
}

void joinRasterParts(const std::vector<std::string>& parts, const std::string& output)
{
    detail::rasterBackend().joinRasterParts(parts, output);
}

RasterImage readRaster(const std::string& path) { return detail::rasterBackend().readRaster(path); }

} // namespace msii
