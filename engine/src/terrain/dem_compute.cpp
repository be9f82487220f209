#include <msii/terrain/dem_compute.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/io/feature_properties.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/tiling/tiled_compute.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

namespace msii {

namespace {

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

/// The features written: by name, or V at every radius (the first invariant computed) and quality.
std::vector<std::string> bandNames(const DemComputeOptions& options)
{
    if (!options.bands.empty()) return options.bands;
    const InvariantsOptions& o = options.invariants;
    const char letter = o.computeVolume ? 'V' : o.computeSphere ? 'S' : o.computePatch ? 'P' : 'L';
    std::vector<std::string> names;
    for (int j = 0; j < o.scales; ++j) names.push_back(featureName(letter, std::size_t(j)));
    names.push_back("quality");
    return names;
}

/// Diagnostics of several windows as one list: counts summed, figures summed (areas) or the
/// largest (perimeters, shares), the sentence of the window with the most.
class DiagnosticSum {
public:
    void add(const Diagnostic& d)
    {
        auto [it, fresh] = mByKind.try_emplace(d.kind, d);
        ++mWindows[d.kind];
        if (fresh) {
            mOrder.push_back(d.kind);
            return;
        }
        Diagnostic& sum = it->second;
        if (d.count > sum.count) sum.message = d.message;
        sum.count += d.count;
        for (const auto& [name, value] : d.figures) {
            bool found = false;
            for (auto& [n, v] : sum.figures)
                if (n == name) {
                    v = name.find("area") != std::string::npos ? v + value : std::max(v, value);
                    found = true;
                }
            if (!found) sum.figures.emplace_back(name, value);
        }
    }
    std::vector<Diagnostic> list() const
    {
        std::vector<Diagnostic> out;
        for (const std::string& kind : mOrder) {
            Diagnostic d = mByKind.at(kind);
            if (mWindows.at(kind) > 1)
                d.message += " [the window with the most; " + std::to_string(d.count) + " in all " +
                             std::to_string(mWindows.at(kind)) + " windows that had any, overlaps counted in each]";
            out.push_back(std::move(d));
        }
        return out;
    }

private:
    std::map<std::string, Diagnostic> mByKind;
    std::map<std::string, int> mWindows;
    std::vector<std::string> mOrder;
};

} // namespace

DemComputeResult computeDem(const std::string& input, const std::string& output, const DemComputeOptions& options,
                            RunContext* context)
{
    const InvariantsOptions& asked = options.invariants;
    if (asked.exact) throw InvalidInputError("the exact mode is for meshes, not rasters");
    if (asked.memoryBudget != 0 || asked.tilesPerAxis != 0)
        throw InvalidInputError("rasters are computed in windows; give their memory budget or size instead of tiles");
    if (!(options.memoryBudget > 0)) throw InvalidInputError("the memory budget must be positive");
    if (options.windowCells < 0) throw InvalidInputError("the window size must be positive (or 0: from the memory budget)");
    const double radius = asked.radius;
    const double maxHole = options.maxHolePerimeter >= 0 ? options.maxHolePerimeter : defaultMaxHolePerimeter(radius);

    Stopwatch stage;
    DemComputeResult result;
    DemReadOptions ro;
    ro.band = options.band;
    const DemSource source(input, ro);
    result.input = source.info();
    const RasterGeoreference& grid = result.input.georeference;
    const std::array<double, 6>& t = grid.transform;
    const int W = grid.width, H = grid.height;
    // The shortest step between neighbouring cell centres on the ground.
    const double cell = std::min(std::hypot(t[1], t[4]), std::hypot(t[2], t[5]));
    // Peak bytes per cell of a window's computation at N = 16: about kBytesPerTileVertex with
    // all four invariants, 1,150 with V and S alone (measured on 1M-cell DEMs, docs/terrain.md).
    const double bytesPerCell = (asked.computePatch || asked.computeLine ? kBytesPerTileVertex : 1200.0) *
                                std::max(1.0, asked.scales / 16.0);
    const double cellsPerWindow = options.memoryBudget / bytesPerCell;
    const bool oneWindow = options.windowCells == 0 ? double(W) * double(H) <= cellsPerWindow
                                                    : options.windowCells >= std::max(W, H);

    // Several windows share one plan, made on a window of 1024² cells at the centre. One
    // window makes its own, as the mesh path would (then its values are exactly those of
    // its mesh computed by the mesh path).
    InvariantsOptions shared = asked;
    PrepareMeshOptions po;
    po.maxHolePerimeter = maxHole;
    po.radius = radius;
    if (!oneWindow) {
        const int pc = std::min(W, 1024), pr = std::min(H, 1024);
        const DemMesh pm = demToMesh(source.read((W - pc) / 2, (H - pr) / 2, pc, pr));
        if (pm.mesh.numTriangles() == 0)
            throw InvalidInputError(fileName(input) + ": the window at its centre has no surface to plan the "
                                                      "computation on");
        const InvariantsResult plan = prepareComputation(prepareMesh(pm.mesh, po).mesh, shared);
        result.plan = plan.plan;
        shared.voxelSize = plan.plan.voxelSize;
        shared.vertexSpacing = shared.vertexSpacing > 0 ? shared.vertexSpacing : plan.stats.medianEdge;
        const double midX = t[0] + 0.5 * W * t[1] + 0.5 * H * t[2], midY = t[3] + 0.5 * W * t[4] + 0.5 * H * t[5];
        shared.localOrigin = Vec3{midX, midY, 0.5 * (plan.stats.bboxMin.z + plan.stats.bboxMax.z)};
    }
    // A window's own cells take their values from its mesh: the halo holds everything they
    // depend on (the reach), a hole next to the window's edge that the whole raster would
    // fill (at most half its perimeter across), and 4 voxels to spare.
    result.haloCells = oneWindow ? 0 : int(std::ceil((result.plan.reach + 0.5 * maxHole + 4.0 * result.plan.voxelSize) / cell)) + 1;
    const int narrowHalo = oneWindow ? 0 : int(std::ceil((result.plan.reach + 4.0 * result.plan.voxelSize) / cell)) + 1;
    result.narrowHaloCells = narrowHalo;
    int side = options.windowCells;
    if (oneWindow) side = std::max(W, H);
    else if (side == 0) side = int(std::floor(std::sqrt(cellsPerWindow))) - 2 * result.haloCells;
    if (side < 16)
        throw InvalidInputError("the memory budget is too small for a window of the raster at this radius (its halo is " +
                                std::to_string(result.haloCells) + " cells wide)");
    result.windowCells = side;
    result.windowsPerRow = (W + side - 1) / side;
    result.windowsPerColumn = (H + side - 1) / side;
    result.bands = bandNames(options);
    result.readSeconds += stage.seconds();

    RasterPieceWriter writer(output, grid, result.bands, options.output);
    DiagnosticSum diagnostics;
    std::vector<std::size_t> maskedPerRadius(std::size_t(asked.scales), 0);
    std::size_t ownCellsWithHeight = 0;
    const int windows = result.windowsPerRow * result.windowsPerColumn;
    for (int wy = 0; wy < result.windowsPerColumn; ++wy)
        for (int wx = 0; wx < result.windowsPerRow; ++wx) {
            const int ownCol = wx * side, ownRow = wy * side;
            const int ownCols = std::min(side, W - ownCol), ownRows = std::min(side, H - ownRow);
            // The narrow halo (the reach) suffices unless a nodata gap crosses its edge: such a
            // gap would be filled in the whole DEM but is a border in the window. A gap that
            // crosses has a cell on the narrow window's outermost rows or columns (those on
            // the DEM's edge excepted: there the whole DEM has the same border).
            stage.restart();
            const auto windowOf = [&](int halo) {
                return std::array<int, 4>{std::max(0, ownCol - halo), std::max(0, ownRow - halo),
                                          std::min(W, ownCol + ownCols + halo), std::min(H, ownRow + ownRows + halo)};
            };
            std::array<int, 4> box = windowOf(narrowHalo);
            Dem dem = source.read(box[0], box[1], box[2] - box[0], box[3] - box[1]);
            if (narrowHalo < result.haloCells) {
                const int w = box[2] - box[0], h = box[3] - box[1];
                bool crossed = false;
                const auto gap = [&](int x, int y) { return std::isnan(dem.heights[std::size_t(y) * std::size_t(w) + std::size_t(x)]); };
                for (int x = 0; x < w && !crossed; ++x)
                    crossed = (box[1] > 0 && gap(x, 0)) || (box[3] < H && gap(x, h - 1));
                for (int y = 0; y < h && !crossed; ++y)
                    crossed = (box[0] > 0 && gap(0, y)) || (box[2] < W && gap(w - 1, y));
                if (crossed) {
                    box = windowOf(result.haloCells);
                    dem = source.read(box[0], box[1], box[2] - box[0], box[3] - box[1]);
                    ++result.wideHaloWindows;
                }
            }
            const int col0 = box[0], row0 = box[1], col1 = box[2];
            const DemMesh dm = demToMesh(dem);
            result.readSeconds += stage.seconds();
            const int window = wy * result.windowsPerRow + wx;
            if (context && windows > 1)
                context->setPrefix("window " + std::to_string(window + 1) + " of " + std::to_string(windows) + ": ");

            std::vector<std::vector<float>> cells;  // per band, the window's cells
            if (dm.mesh.numTriangles() > 0) {
                stage.restart();
                const PrepareMeshResult prepared = prepareMesh(dm.mesh, po);
                result.prepareSeconds += stage.seconds();
                for (const Diagnostic& d : prepared.changes) diagnostics.add(d);
                const InvariantsResult r = computeInvariants(prepared.mesh, shared, context);
                if (oneWindow) result.plan = r.plan;
                for (const Diagnostic& d : r.diagnostics)
                    if (d.kind != "mostly_masked") diagnostics.add(d);  // counted below over own cells
                const InvariantsCost& c = r.cost;
                InvariantsCost& sum = result.cost;
                sum.check += c.check, sum.levelSet += c.levelSet, sum.occupancy += c.occupancy;
                sum.stencils += c.stencils, sum.interpolation += c.interpolation, sum.samples += c.samples;
                sum.patchLine += c.patchLine, sum.total += c.total;
                sum.levelSetVoxels += c.levelSetVoxels, sum.stencilNodes += c.stencilNodes, sum.numSamples += c.numSamples;
                stage.restart();
                std::vector<VertexProperty> props = featureProperties(r.features);
                props.push_back({"filled_share", prepared.filledShare});
                for (const std::string& name : result.bands) {
                    if (name == "height") {  // the DEM's own heights
                        cells.push_back(dem.heights);
                        continue;
                    }
                    const auto p = std::find_if(props.begin(), props.end(), [&](const VertexProperty& q) { return q.name == name; });
                    if (p == props.end()) {
                        std::string names;
                        for (const VertexProperty& q : props) names += (names.empty() ? "" : ", ") + q.name;
                        throw InvalidInputError("no feature '" + name + "' to write (there are " + names + ", height)");
                    }
                    cells.push_back(toCells(dm, toInputVertices(prepared, p->values)));
                }
                // Masked values of the own cells, per radius, for the mostly-masked remark.
                const std::vector<Invariant> present = r.features.invariants();
                const FeatureColumns& first = r.features[present.front()];
                const std::vector<std::uint32_t>& cellVertex = dm.vertexOfCell;
                for (std::size_t j = 0; j < first.size(); ++j) {
                    const std::vector<float> col = toInputVertices(prepared, first[j]);
                    for (int y = ownRow; y < ownRow + ownRows; ++y)
                        for (int x = ownCol; x < ownCol + ownCols; ++x) {
                            const std::uint32_t v = cellVertex[std::size_t(y - row0) * std::size_t(col1 - col0) + std::size_t(x - col0)];
                            if (v != DemMesh::kNoVertex && j < maskedPerRadius.size()) maskedPerRadius[j] += std::isnan(col[v]);
                        }
                }
                result.triangles += dm.mesh.numTriangles();
            } else if (oneWindow) {
                throw InvalidInputError(fileName(input) + (dem.numValid == 0 ? " has no cell with a height (all nodata)"
                                                                             : ": no 2 x 2 block of cells has heights, "
                                                                               "so there is no surface to compute on"));
            } else {
                stage.restart();
                cells.assign(result.bands.size(), std::vector<float>(dm.vertexOfCell.size(), std::numeric_limits<float>::quiet_NaN()));
            }
            for (int y = ownRow; y < ownRow + ownRows; ++y)
                for (int x = ownCol; x < ownCol + ownCols; ++x)
                    ownCellsWithHeight += dm.vertexOfCell[std::size_t(y - row0) * std::size_t(col1 - col0) + std::size_t(x - col0)] != DemMesh::kNoVertex;
            // The own cells into their place.
            std::vector<float> own(std::size_t(ownCols) * std::size_t(ownRows));
            for (std::size_t b = 0; b < cells.size(); ++b) {
                for (int y = 0; y < ownRows; ++y)
                    std::copy_n(cells[b].begin() + std::ptrdiff_t(std::size_t(ownRow - row0 + y) * std::size_t(col1 - col0) +
                                                                  std::size_t(ownCol - col0)),
                                ownCols, own.begin() + std::ptrdiff_t(std::size_t(y) * std::size_t(ownCols)));
                writer.write(int(b), ownCol, ownRow, ownCols, ownRows, own.data());
            }
            result.writeSeconds += stage.seconds();
        }
    if (context) context->setPrefix("");
    if (ownCellsWithHeight == 0) throw InvalidInputError(fileName(input) + " has no cell with a height (all nodata)");
    result.input.numValid = ownCellsWithHeight;
    for (std::size_t m : maskedPerRadius) result.maskedValues += m;
    result.diagnostics = diagnostics.list();
    if (std::optional<Diagnostic> d = mostlyMasked(result.plan.radii, maskedPerRadius, ownCellsWithHeight))
        result.diagnostics.push_back(std::move(*d));
    stage.restart();
    writer.commit();
    result.writeSeconds += stage.seconds();
    return result;
}

} // namespace msii
