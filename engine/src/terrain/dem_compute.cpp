#include <msii/terrain/dem_compute.h>

#include <msii/terrain/grid_continuation.h>
#include <msii/terrain/height_field.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/scales.h>
#include <msii/io/feature_properties.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/tiling/tiled_compute.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>

namespace msii {

namespace {

std::string fileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

/// The features written: by name, or quality and the first invariant computed (V) at a
/// quarter, half, three quarters of R and R (docs/terrain.md, Output size: four radii show
/// the scales to the eye, and keep the file at a fraction of all N; `--bands quality,V`
/// writes every radius). quality first: GIS open a raster on its first band (QGIS on the
/// first three as red, green and blue), and quality is the one to look at.
std::vector<std::string> bandNames(const DemComputeOptions& options)
{
    if (!options.bands.empty()) return options.bands;
    const InvariantsOptions& o = options.compute.invariants;
    const char letter = o.computeVolume ? 'V' : o.computeSphere ? 'S' : o.computePatch ? 'P' : 'L';
    std::vector<std::string> names{"quality"};
    int previous = 0;
    for (int k = 1; k <= 4; ++k) {
        const int j = std::max(1, (k * o.scales + 3) / 4);  // r_j at about k/4 of R
        if (j > previous) names.push_back(featureName(letter, std::size_t(j - 1)));
        previous = j;
    }
    return names;
}

/// @p options with only the invariants that @p bands need: those named (V_01 …), and for
/// quality and valid_radii the one they come from (the first computed, V before S, P, L).
/// The plan, and so every value written, does not depend on which are computed.
DemComputeOptions onlyWhatIsWritten(const DemComputeOptions& options, const std::vector<std::string>& bands)
{
    const InvariantsOptions& o = options.compute.invariants;
    const std::vector<Invariant> selected = o.selected();
    bool need[4] = {false, false, false, false};
    for (const std::string& name : bands) {
        if (name == "quality" || name == "valid_radii") {
            if (!selected.empty()) need[std::size_t(selected.front())] = true;
            continue;
        }
        for (const Invariant i : selected)
            if (name.size() > 2 && name[0] == invariantLetter(i) && name[1] == '_') need[std::size_t(i)] = true;
    }
    if (std::none_of(std::begin(need), std::end(need), [](bool b) { return b; }) && !selected.empty())
        need[std::size_t(selected.front())] = true;  // height or filled_share alone: the cheapest run
    DemComputeOptions run = options;
    InvariantsOptions& r = run.compute.invariants;
    r.computeVolume = o.computeVolume && need[std::size_t(Invariant::Volume)];
    r.computeSphere = o.computeSphere && need[std::size_t(Invariant::Sphere)];
    r.computePatch = o.computePatch && need[std::size_t(Invariant::Patch)];
    r.computeLine = o.computeLine && need[std::size_t(Invariant::Line)];
    return run;
}

/// Whether every one of @p bands is a fraction in [0, 1] (V̂, Ŝ, filled_share, and quality
/// when it comes from V or S), so that scaled 16-bit integers hold it to 1.5e-5.
bool allFractions(const std::vector<std::string>& bands, const InvariantsOptions& invariants)
{
    const std::vector<Invariant> selected = invariants.selected();
    const bool qualityIsFraction = !selected.empty() && (selected.front() == Invariant::Volume ||
                                                         selected.front() == Invariant::Sphere);
    return std::all_of(bands.begin(), bands.end(), [&](const std::string& name) {
        if (name == "quality") return qualityIsFraction;
        return name == "filled_share" || name.rfind("V_", 0) == 0 || name.rfind("S_", 0) == 0;
    });
}

/// Whether a window's remark @p d stands for the DEM: not that the smallest radius is below
/// the edge length when it is a cell or more (a DEM's edges are longer than its cells where
/// it slopes, but a ball of a cell's radius still holds its neighbours).
bool kept(const Diagnostic& d, const ScalePlan& plan, double cell)
{
    return !(d.kind == "smallest_radius_below_edge" && !plan.radii.empty() && plan.radii.front() >= cell * (1 - 1e-9));
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
            // Counted things (holes, vertices): the window with the most, and the sum; a
            // remark without a count (a radius below the cell size) is the same in each.
            if (mWindows.at(kind) > 1 && d.count > 0)
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

/// How the raster is cut: windows of side × side own cells with a halo, all with one plan.
struct WindowLayout {
    int width = 0, height = 0;       ///< of the raster, cells
    int side = 0;                    ///< own cells per window side
    RasterRegion region;             ///< the cells computed and written (all by default)
    int narrowHalo = 0, wideHalo = 0;  ///< cells
    double cell = 0;                 ///< the shortest step between cell centres, ground units
    bool oneWindow = true;
    /// Windows' options: with the shared plan when there are several.
    ComputeOptions options;
    /// The height-field route: its kernel's options (radii, cell, which radii), and the grid's
    /// filling and continuation.
    bool heightField = false;
    HeightFieldOptions kernel;
    GridContinuationOptions continuation;
};

/// The cells computed and written: options.region, checked, or all @p width × @p height.
RasterRegion regionOf(const DemComputeOptions& options, int width, int height)
{
    if (options.region.cols == 0) return {0, 0, width, height};
    const RasterRegion& g = options.region;
    if (g.col < 0 || g.row < 0 || g.rows < 1 || g.col + g.cols > width || g.row + g.rows > height)
        throw InvalidInputError("the region to compute lies outside the raster");
    return g;
}

/// The plan of several windows, made on the window of 1024² cells at the raster's centre:
/// its voxel size and vertex spacing, and the local frame's origin at the raster's centre.
/// With @p whole, the plan of the raster computed in one piece instead, on all of it (one
/// source tile of a mosaic that fits one window computes with it, to equal that one piece).
ScalePlan sharedPlan(const DemSource& source, const std::string& input, const ComputeOptions& options,
                     std::vector<Diagnostic>& diagnostics, bool whole = false)
{
    const RasterGeoreference& grid = source.info().georeference;
    const std::array<double, 6>& t = grid.transform;
    const int W = grid.width, H = grid.height;
    const int pc = whole ? W : std::min(W, 1024), pr = whole ? H : std::min(H, 1024);
    const DemMesh pm = demToMesh(source.read((W - pc) / 2, (H - pr) / 2, pc, pr));
    if (pm.mesh.numTriangles() == 0)
        throw InvalidInputError(fileName(input) + ": the window at its centre has no surface to plan the computation on");
    PrepareMeshOptions po;
    po.repair = options.repair;
    po.leaveOutSpikes = false;  // as the windows (below)
    po.radius = options.invariants.radius;
    po.maxHolePerimeter = options.maxHolePerimeter;
    InvariantsOptions planning = options.invariants;
    planning.memoryLimit = 0;  // the plan only: each window's surface is checked as it is computed
    const InvariantsResult planned = planInvariants(prepareMesh(pm.mesh, po).mesh, planning);
    diagnostics = planned.diagnostics;
    ScalePlan plan = planned.plan;
    if (whole) return plan;  // as compute() plans the one piece
    const double midX = t[0] + 0.5 * W * t[1] + 0.5 * H * t[2], midY = t[3] + 0.5 * W * t[4] + 0.5 * H * t[5];
    plan.origin = localOrigin({midX, midY, 0.5 * (planned.stats.bboxMin.z + planned.stats.bboxMax.z)}, plan.voxelSize);
    return plan;
}

/// The windows for @p options: one if the raster fits the budget (or --window-cells), else
/// as many as fit, with the shared plan and halos that reach past everything a window's own
/// cells depend on. With @p split, windows with halos even for a raster that fits one (its
/// surface exceeded the memory limit), with the plan of the raster in one piece.
WindowLayout layWindows(const DemSource& source, const std::string& input, const DemComputeOptions& options,
                        DemComputeResult& result, bool split = false)
{
    const InvariantsOptions& asked = options.compute.invariants;
    const RasterGeoreference& grid = source.info().georeference;
    WindowLayout w;
    w.width = grid.width, w.height = grid.height;
    w.options = options.compute;
    if (w.options.maxHolePerimeter < 0) w.options.maxHolePerimeter = defaultMaxHolePerimeter(asked.radius);
    w.options.tiling = TilingOptions();  // each window in one piece
    // A DEM's spikes are heights: every window must judge its cells alike, whatever its extent.
    w.options.leaveOutSpikes = false;
    // The shortest step between neighbouring cell centres on the ground.
    const double cell = shortestCellStep(grid);
    w.cell = cell;
    const double budget =
        options.compute.tiling.memoryBudget > 0 ? options.compute.tiling.memoryBudget : defaultDemMemoryBudget();
    w.options.invariants.memoryLimit = budget;  // a window whose surface exceeds it stops at once
    const double cellsPerWindow = budget / computationBytesPerVertex(asked);
    w.oneWindow = options.windowCells == 0 ? double(w.width) * double(w.height) <= cellsPerWindow
                                           : options.windowCells >= std::max(w.width, w.height);
    w.side = std::max(w.width, w.height);
    w.region = regionOf(options, w.width, w.height);
    const bool part = options.region.cols > 0;
    if (w.oneWindow && !part && !split) return w;  // planned on its own mesh, as the mesh path would
    // A part of a raster that fits one window (or a raster that fits one by its cells but not
    // by its surface) computes with the plan of that one piece, in windows with halos like a
    // larger raster's, so that it equals the one piece.
    w.options.invariants.plan = sharedPlan(source, input, w.options, result.diagnostics, w.oneWindow);
    w.oneWindow = false;
    const ScalePlan& plan = *w.options.invariants.plan;
    result.plan = plan;
    // The narrow halo holds everything the own cells depend on; the wide one also a hole next
    // to the window's edge that the whole raster would fill (at most half its perimeter across).
    w.narrowHalo = int(std::ceil(haloWidth(plan) / cell)) + 1;
    // Windows are sized for the wide halo of hole filling; one read wider for the
    // continuation computes only what is within the narrow halo of its own cells
    // (ComputeOptions::valuesWithin), so it costs about as much.
    const int fillHalo = int(std::ceil((haloWidth(plan) + 0.5 * w.options.maxHolePerimeter) / cell)) + 1;
    w.wideHalo = fillHalo;
    if (w.options.border == BorderHandling::Continue)
        w.wideHalo = std::max(fillHalo, int(std::ceil(continuationReach(plan) / cell)) + 1);
    w.side = options.windowCells > 0 ? options.windowCells : int(std::floor(std::sqrt(cellsPerWindow))) - 2 * fillHalo;
    if (w.side < 16)
        throw InvalidInputError("the memory budget is too small for a window of the raster at this radius (its halo is " +
                                std::to_string(w.wideHalo) + " cells wide)");
    return w;
}

/// The height-field route's windows (docs/terrain.md, Engines): no plan, halos in cells from
/// the radius alone. The narrow halo holds every ball an own cell sums over (S's reaches
/// R(1 + 1/20)); the wide one also a gap that the whole raster fills (at most half its
/// perimeter across) and, with borders continued, what the continuation of a cell in the
/// balls reads: its nearest height, within the margin, that height's mirror point as far
/// again, and the plane's fit radius about it.
WindowLayout layHeightFieldWindows(const DemSource& source, const DemComputeOptions& options,
                                   const std::vector<std::string>& bands, DemComputeResult& result)
{
    const InvariantsOptions& asked = options.compute.invariants;
    const RasterGeoreference& grid = source.info().georeference;
    WindowLayout w;
    w.heightField = true;
    w.width = grid.width, w.height = grid.height;
    w.options = options.compute;
    if (w.options.maxHolePerimeter < 0) w.options.maxHolePerimeter = defaultMaxHolePerimeter(asked.radius);
    w.cell = shortestCellStep(grid);
    HeightFieldOptions& k = w.kernel;
    k.radii = equidistantRadii(asked.radius, asked.scales);
    const auto [cellWidth, cellHeight] = cellSides(grid);
    k.cellWidth = cellWidth, k.cellHeight = cellHeight;
    k.computeVolume = asked.computeVolume, k.computeSphere = asked.computeSphere;
    // The radii the bands need: those named; R for quality; every one for valid_radii, and
    // for quality where balls are masked (the largest with a value).
    const std::size_t n = k.radii.size();
    std::vector<bool> wanted(n, false);
    for (const std::string& name : bands) {
        if (name == "valid_radii" || (name == "quality" && w.options.border == BorderHandling::Mask))
            wanted.assign(n, true);
        else if (name == "quality")
            wanted[n - 1] = true;
        else if (name.size() > 2 && name[1] == '_' && (name[0] == 'V' || name[0] == 'S'))
            wanted[std::size_t(std::stoi(name.substr(2)) - 1)] = true;
    }
    for (std::size_t j = 0; j < n; ++j)
        if (wanted[j]) k.wanted.push_back(int(j));
    if (k.wanted.empty()) k.wanted.push_back(int(n - 1));  // height or filled_share alone
    GridContinuationOptions& c = w.continuation;
    c.cellWidth = k.cellWidth, c.cellHeight = k.cellHeight;
    c.maxHolePerimeter = w.options.maxHolePerimeter;
    c.continueBorders = w.options.border == BorderHandling::Continue;
    const int reach = int(std::ceil(asked.radius * (1 + kHeightFieldSphereStep) / std::min(k.cellWidth, k.cellHeight))) + 2;
    c.margin = reach;
    c.fitRadius = std::max(0.25 * asked.radius, 3 * w.cell);
    w.region = regionOf(options, w.width, w.height);
    result.plan.radii = k.radii;
    // Within a cell the height field is the plane of its two triangles: a ball smaller than
    // a cell measures that plane's slope, not relief (the paper's smallest radius above the
    // shortest edge, §3). Said once, as the mesh route says it of the median edge.
    if (k.radii.front() < w.cell * (1 - 1e-9)) {
        std::ostringstream msg;
        msg << "the smallest radius (" << k.radii.front() << ") is below the cell size (" << w.cell
            << "): within a cell the DEM is a plane, so values at such radii show its slope, not relief; "
            << "every radius is at least a cell when R is at least N cells (" << w.cell * double(k.radii.size())
            << " for N = " << k.radii.size() << "), or with fewer radii";
        result.diagnostics.push_back(
            {"smallest_radius_below_cell", 0, {{"radius", k.radii.front()}, {"cell", w.cell}}, msg.str()});
    }
    // Own cells per window: 2048² cells take about 0.2 GB with their halos and bands.
    constexpr int kSide = 2048;
    const int side = options.windowCells > 0 ? options.windowCells : kSide;
    w.oneWindow = options.region.cols == 0 && std::max(w.width, w.height) <= side;
    w.side = std::max(w.width, w.height);
    if (w.oneWindow) return w;
    w.side = side;
    w.narrowHalo = reach;
    const int fillHalo = reach + int(std::ceil(0.5 * c.maxHolePerimeter / w.cell)) + 1;
    w.wideHalo = fillHalo;
    // A hole near the box's edge that the whole raster fills, read whole too: the
    // continuation's heights depend on it.
    if (c.continueBorders) w.wideHalo = fillHalo + 2 * reach + int(std::ceil(c.fitRadius / w.cell)) + 1;
    return w;
}

/// Cells [col, col + cols) × [row, row + rows) of the raster.
struct CellRect {
    int col = 0, row = 0, cols = 0, rows = 0;
};

/// A window's own cells and the box read around them.
struct Window : CellRect {
    std::array<int, 4> box{};  ///< x0, y0, x1, y1 of the cells read
    bool wide = false;
    Dem dem;
    /// The cell index in the box of own cell (x, y).
    std::size_t boxCell(int x, int y) const
    {
        return std::size_t(y - box[1]) * std::size_t(box[2] - box[0]) + std::size_t(x - box[0]);
    }
};

/// Whether the @p bw × @p bh cells of @p heights have a nodata gap that hole filling leaves
/// open: one whose border (its cell edges next to cells with heights, half as long again
/// for the staircase) is longer than @p maxPerimeter.
bool hasOpenGap(const std::vector<float>& heights, int bw, int bh, double cell, double maxPerimeter)
{
    std::vector<char> seen(heights.size(), 0);
    std::vector<std::size_t> stack;
    const auto index = [&](int x, int y) { return std::size_t(y) * std::size_t(bw) + std::size_t(x); };
    for (std::size_t start = 0; start < heights.size(); ++start) {
        if (seen[start] || !std::isnan(heights[start])) continue;
        std::size_t edges = 0;
        seen[start] = 1;
        stack.assign(1, start);
        while (!stack.empty()) {
            const std::size_t c = stack.back();
            stack.pop_back();
            const int x = int(c % std::size_t(bw)), y = int(c / std::size_t(bw));
            for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
                const int nx = x + dx, ny = y + dy;
                if (nx < 0 || ny < 0 || nx >= bw || ny >= bh) continue;
                const std::size_t n = index(nx, ny);
                if (!std::isnan(heights[n])) ++edges;
                else if (!seen[n]) seen[n] = 1, stack.push_back(n);
            }
        }
        if (1.5 * double(edges) * cell > maxPerimeter) return true;
    }
    return false;
}

/// Reads the window of own cells @p own with the narrow halo, or the wide one if a nodata
/// gap crosses the narrow one's edge: such a gap would be filled in the whole DEM but is a
/// border in the window. A gap that crosses has a cell on the narrow window's outermost rows
/// or columns (those on the DEM's edge excepted: there the whole DEM has the same border).
/// When borders are continued, a border in the narrow box (the DEM's edge, a gap too large
/// to fill) takes the wide one: the continuation the own cells see depends on the raster
/// that far (continuationReach).
Window readWindow(const DemSource& source, const WindowLayout& w, const CellRect& own)
{
    Window win;
    static_cast<CellRect&>(win) = own;
    const auto boxOf = [&](int halo) {
        return std::array<int, 4>{std::max(0, win.col - halo), std::max(0, win.row - halo),
                                  std::min(w.width, win.col + win.cols + halo), std::min(w.height, win.row + win.rows + halo)};
    };
    win.box = boxOf(w.narrowHalo);
    win.dem = source.read(win.box[0], win.box[1], win.box[2] - win.box[0], win.box[3] - win.box[1]);
    if (w.narrowHalo >= w.wideHalo) return win;
    const int bw = win.box[2] - win.box[0], bh = win.box[3] - win.box[1];
    const auto gap = [&](int x, int y) { return std::isnan(win.dem.heights[std::size_t(y) * std::size_t(bw) + std::size_t(x)]); };
    bool crossed = w.options.border == BorderHandling::Continue &&
                   (win.box[0] == 0 || win.box[1] == 0 || win.box[2] == w.width || win.box[3] == w.height ||
                    hasOpenGap(win.dem.heights, bw, bh, w.cell, w.options.maxHolePerimeter));
    for (int x = 0; x < bw && !crossed; ++x)
        crossed = (win.box[1] > 0 && gap(x, 0)) || (win.box[3] < w.height && gap(x, bh - 1));
    for (int y = 0; y < bh && !crossed; ++y)
        crossed = (win.box[0] > 0 && gap(0, y)) || (win.box[2] < w.width && gap(bw - 1, y));
    if (crossed) {
        win.box = boxOf(w.wideHalo);
        win.dem = source.read(win.box[0], win.box[1], win.box[2] - win.box[0], win.box[3] - win.box[1]);
        win.wide = true;
    }
    return win;
}

/// The bands of a computed window, per cell of its box. A cell with a height but in no
/// triangle (no 2 × 2 block of heights around it) has no surface to compute on: it is
/// nodata in every band but the height, `quality` included (a mesh's vertices keep a
/// plane's value there, for viewers that do not check for NaN; GIS do).
std::vector<std::vector<float>> bandsOf(const Window& win, const DemMesh& dm, const ComputeResult& r,
                                        const std::vector<std::string>& bands)
{
    std::vector<VertexProperty> props = outputProperties(r.features, r.filledShare);
    for (VertexProperty& p : props)
        for (std::size_t v = 0; v < p.values.size(); ++v)
            if (std::isnan(r.filledShare[v])) p.values[v] = std::numeric_limits<float>::quiet_NaN();  // in no face
    std::vector<std::vector<float>> cells;
    for (const std::string& name : bands) {
        if (name == "height") {  // the DEM's own heights
            cells.push_back(win.dem.heights);
            continue;
        }
        const auto p = std::find_if(props.begin(), props.end(), [&](const VertexProperty& q) { return q.name == name; });
        cells.push_back(toCells(dm, p->values));
    }
    return cells;
}

/// The vertices of the cells on the window box's sides that are not the DEM's edge: the
/// raster goes on past them, so they are no border of the surface.
std::vector<std::uint32_t> cutVerticesOf(const Window& win, const WindowLayout& w, const DemMesh& dm)
{
    std::vector<std::uint32_t> cut;
    const auto add = [&](int x, int y) {
        const std::uint32_t v = dm.vertexOfCell[win.boxCell(x, y)];
        if (v != DemMesh::kNoVertex) cut.push_back(v);
    };
    for (int x = win.box[0]; x < win.box[2]; ++x) {
        if (win.box[1] > 0) add(x, win.box[1]);
        if (win.box[3] < w.height) add(x, win.box[3] - 1);
    }
    for (int y = win.box[1]; y < win.box[3]; ++y) {
        if (win.box[0] > 0) add(win.box[0], y);
        if (win.box[2] < w.width) add(win.box[2] - 1, y);
    }
    return cut;
}

/// Computes window @p win; adds its diagnostics, masked own cells and cost to @p result;
/// returns its bands per cell of its box (NaN throughout for a window without surface).
std::vector<std::vector<float>> computeWindow(const Window& win, const WindowLayout& w, DiagnosticSum& diagnostics,
                                              DemComputeResult& result, RunContext* context)
{
    const DemMesh dm = demToMesh(win.dem);
    if (dm.mesh.numTriangles() == 0)
        return std::vector<std::vector<float>>(result.bands.size(),
                                               std::vector<float>(dm.vertexOfCell.size(), std::numeric_limits<float>::quiet_NaN()));
    ComputeOptions options = w.options;
    options.cutVertices = cutVerticesOf(win, w, dm);
    if (win.wide && options.border == BorderHandling::Continue)
        for (int y = win.row; y < win.row + win.rows; ++y)
            for (int x = win.col; x < win.col + win.cols; ++x)
                if (const std::uint32_t v = dm.vertexOfCell[win.boxCell(x, y)]; v != DemMesh::kNoVertex) {
                    const Vec3& p = dm.mesh.points[v];
                    options.valuesWithin.add({p.x, p.y, 0.0});
                }
    if (!options.valuesWithin.empty()) {  // every height
        options.valuesWithin.min.z = -std::numeric_limits<double>::infinity();
        options.valuesWithin.max.z = std::numeric_limits<double>::infinity();
    }
    const ComputeResult r = compute(dm.mesh, options, context);
    if (w.oneWindow) result.plan = r.plan;
    for (const Diagnostic& d : r.diagnostics) {
        if (d.kind == "mostly_masked") continue;  // counted below over the own cells
        if (kept(d, r.plan, w.cell)) diagnostics.add(d);
    }
    result.cost += r.cost;
    result.prepareSeconds += r.preparation.seconds;
    result.triangles += dm.mesh.numTriangles();
    // The own cells in a face (a vertex in no face has no filled share), for the masked count.
    std::vector<std::uint32_t> own;
    for (int y = win.row; y < win.row + win.rows; ++y)
        for (int x = win.col; x < win.col + win.cols; ++x) {
            const std::uint32_t v = dm.vertexOfCell[win.boxCell(x, y)];
            if (v != DemMesh::kNoVertex && !std::isnan(r.filledShare[v])) own.push_back(v);
        }
    result.masked.add(r.features, r.filledShare, own);
    return bandsOf(win, dm, r, result.bands);
}

/// The kinds of the continued grid's cells (GridCell), and of its squares of 2 × 2 cells.
struct GridKinds {
    const GridContinuationResult& g;
    /// Cell (c, r)'s kind; None outside the grid.
    GridCell at(int c, int r) const
    {
        if (c < 0 || r < 0 || c >= g.grid.cols || r >= g.grid.rows) return GridCell::None;
        return g.kind[std::size_t(r) * std::size_t(g.grid.cols) + std::size_t(c)];
    }
    /// Whether the square from cell (c, r) has four heights of the DEM's.
    bool given(int c, int r) const
    {
        return at(c, r) == GridCell::Height && at(c + 1, r) == GridCell::Height && at(c, r + 1) == GridCell::Height &&
               at(c + 1, r + 1) == GridCell::Height;
    }
    /// Whether it has a filled or continued corner.
    bool added(int c, int r) const
    {
        for (const auto& [dx, dy] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}}) {
            const GridCell k = at(c + dx, r + dy);
            if (k == GridCell::Filled || k == GridCell::Continued) return true;
        }
        return false;
    }
};

/// The squares with a filled or continued corner counted over rectangles (a summed-area
/// table, in 32-bit integers whose differences wrap exactly), so that a cell whose ball's
/// bounding square has none gets 0 without its disc's squares: most cells are far from
/// the fills and the continuation.
class AddedSquares {
public:
    AddedSquares(const GridKinds& kinds, const DiscSquares& disc) : gc(kinds.g.grid.cols), gr(kinds.g.grid.rows)
    {
        if (disc.area.empty()) return;
        dcLow = *std::min_element(disc.column.begin(), disc.column.end());
        dcHigh = *std::max_element(disc.column.begin(), disc.column.end());
        drLow = *std::min_element(disc.row.begin(), disc.row.end());
        drHigh = *std::max_element(disc.row.begin(), disc.row.end());
        addedBelow.assign(std::size_t(gc + 1) * std::size_t(gr + 1), 0);
        tbb::parallel_for(0, gr, [&](int r) {
            std::uint32_t running = 0;
            std::uint32_t* out = &addedBelow[std::size_t(r + 1) * std::size_t(gc + 1)];
            for (int c = 0; c < gc; ++c) out[c + 1] = running += kinds.added(c, r) ? 1u : 0u;
        });
        for (int r = 1; r <= gr; ++r) {
            std::uint32_t* out = &addedBelow[std::size_t(r) * std::size_t(gc + 1)];
            const std::uint32_t* above = out - (gc + 1);
            for (int c = 0; c <= gc; ++c) out[c] += above[c];
        }
    }
    /// Whether any square of the disc's bounding square around cell (c, r) has one.
    bool any(int c, int r) const
    {
        const int c0 = std::max(0, c + dcLow), c1 = std::min(gc, c + dcHigh + 1), r0 = std::max(0, r + drLow),
                  r1 = std::min(gr, r + drHigh + 1);
        if (c0 >= c1 || r0 >= r1) return false;
        const auto at = [&](int x, int y) { return addedBelow[std::size_t(y) * std::size_t(gc + 1) + std::size_t(x)]; };
        return at(c1, r1) - at(c0, r1) - at(c1, r0) + at(c0, r0) != 0;
    }

private:
    int gc, gr;
    std::vector<std::uint32_t> addedBelow;  // (gc + 1) × (gr + 1): squares (< c, < r) added
    int dcLow = 0, dcHigh = -1, drLow = 0, drHigh = -1;
};

/// Per square of 2 × 2 cells from the own cells' row and column before them on, whether it
/// has four heights of the DEM's ((cols + 1) × (rows + 1), row by row).
std::vector<char> givenSquares(const GridKinds& kinds, const GridRect& own, const Window& win)
{
    const GridContinuationResult& g = kinds.g;
    const int gc = g.grid.cols, gr = g.grid.rows;
    const std::size_t sc = std::size_t(win.cols) + 1;
    std::vector<char> givenSquare(sc * (std::size_t(win.rows) + 1));
    tbb::parallel_for(0, win.rows + 1, [&](int y) {
        char* out = &givenSquare[std::size_t(y) * sc];
        const int r = own.row - 1 + y, c0 = own.col - 1;
        if (r < 0 || r + 1 >= gr || c0 < 0 || c0 + int(sc) >= gc) {  // at the grid's edge
            for (std::size_t x = 0; x < sc; ++x) out[x] = kinds.given(c0 + int(x), r);
            return;
        }
        const GridCell* k0 = &g.kind[std::size_t(r) * std::size_t(gc) + std::size_t(c0)];
        const GridCell* k1 = k0 + gc;
        for (std::size_t x = 0; x < sc; ++x)
            out[x] = (k0[x] == GridCell::Height) & (k0[x + 1] == GridCell::Height) & (k1[x] == GridCell::Height) &
                     (k1[x + 1] == GridCell::Height);
    });
    return givenSquare;
}

/// The own cells on the surface, their filled_share, and the squares of the DEM's
/// heights (two triangles each on the mesh route).
struct OwnSurface {
    std::vector<char> onSurface;
    std::vector<float> filledShare;
    std::size_t squares = 0;
};

/// An own cell with a height is on the surface where one of its four squares has four
/// heights of the DEM's, as a vertex of the DEM's mesh is in a face (a filled hole adds
/// faces only between the heights on its rim). filled_share: the area of the squares
/// inside the ball at R with a filled or continued corner, over πR², as the mesh's fill
/// and skirt (docs/method.md, Filled share); computed only where @p wantsShare.
OwnSurface ownSurface(const GridContinuationResult& g, const GridRect& own, const Window& win, const WindowLayout& w,
                      bool wantsShare)
{
    const std::size_t nOwn = std::size_t(win.cols) * std::size_t(win.rows);
    const GridKinds kinds{g};
    OwnSurface s;
    s.filledShare.assign(nOwn, std::numeric_limits<float>::quiet_NaN());
    const DiscSquares disc =
        wantsShare ? discSquares(w.kernel.radii.back(), w.kernel.cellWidth, w.kernel.cellHeight) : DiscSquares();
    const double discArea = 3.14159265358979323846 * w.kernel.radii.back() * w.kernel.radii.back();
    const AddedSquares addedNear(kinds, disc);
    // Row by row in parallel: the squares with four heights (from the own cells' row and
    // column before them on), then the cells in a face.
    const std::size_t sc = std::size_t(win.cols) + 1;
    const std::vector<char> givenSquare = givenSquares(kinds, own, win);
    std::vector<std::size_t> squaresOfRow(std::size_t(win.rows), 0);
    s.onSurface.assign(nOwn, 0);
    tbb::parallel_for(0, win.rows, [&](int y) {
        const char* above = &givenSquare[std::size_t(y) * sc];
        const char* here = above + sc;
        // (inside the grid)
        const GridCell* cellKinds = &g.kind[std::size_t(own.row + y) * std::size_t(g.grid.cols) + std::size_t(own.col)];
        for (int x = 0; x < win.cols; ++x) {
            const int c = own.col + x, r = own.row + y;
            if (cellKinds[x] != GridCell::Height) continue;
            squaresOfRow[std::size_t(y)] += here[x + 1];
            if (!here[x + 1] && !here[x] && !above[x + 1] && !above[x]) continue;
            const std::size_t k = std::size_t(y) * std::size_t(win.cols) + std::size_t(x);
            s.onSurface[k] = 1;
            double share = 0;
            if (!disc.area.empty() && addedNear.any(c, r))
                for (std::size_t i = 0; i < disc.area.size(); ++i)
                    if (kinds.added(c + disc.column[i], r + disc.row[i])) share += disc.area[i];
            s.filledShare[k] = float(std::min(1.0, share / discArea));
        }
    });
    for (const std::size_t n : squaresOfRow) s.squares += n;
    return s;
}

/// The bands of the own cells (row by row) from @p props: a property's values become its
/// band (moved where no later band names it again), nodata where not on the surface;
/// `height` is the DEM's own heights.
void ownBands(std::vector<VertexProperty>& props, const Window& win, const std::vector<char>& onSurface,
              const std::vector<std::string>& bands, std::vector<std::vector<float>>& cells)
{
    const std::size_t nOwn = std::size_t(win.cols) * std::size_t(win.rows);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t b = 0; b < bands.size(); ++b) {
        const std::string& name = bands[b];
        const bool height = name == "height";  // found once per band, not per cell
        const auto p = std::find_if(props.begin(), props.end(), [&](const VertexProperty& q) { return q.name == name; });
        if (!height && p == props.end())
            throw InvalidInputError("the band '" + name + "' is none of the features computed (names as msii writes them, e.g. V_04)");
        const bool again = std::find(bands.begin() + std::ptrdiff_t(b) + 1, bands.end(), name) != bands.end();
        if (!height && !again) cells[b] = std::move(p->values);
        else if (!height) cells[b] = p->values;
        else cells[b].resize(nOwn);
        tbb::parallel_for(0, win.rows, [&](int y) {
            for (int x = 0; x < win.cols; ++x) {
                const std::size_t k = std::size_t(y) * std::size_t(win.cols) + std::size_t(x);
                // Not on the surface: nodata in every band but the height.
                if (height) cells[b][k] = win.dem.heights[win.boxCell(win.col + x, win.row + y)];
                else if (!onSurface[k]) cells[b][k] = nan;
            }
        });
    }
}

/// What the grid's filling and continuation did, as diagnostics: the holes filled, and the
/// cells continued @p margin cells wide.
void addContinuationDiagnostics(const GridContinuationResult& g, int margin, double cell, DiagnosticSum& diagnostics)
{
    if (g.gapsFilled > 0) {
        std::ostringstream msg;
        msg.precision(3);
        msg << "filled " << g.gapsFilled << (g.gapsFilled == 1 ? " hole" : " holes") << " (nodata gaps)"
            << " for the computation (the longest " << g.largestFilledPerimeter << " around, " << g.cellsFilled
            << " cells); values near them rest partly on the filled surface (filled_share)";
        diagnostics.add({"holes_filled", g.gapsFilled, {{"largest_perimeter", g.largestFilledPerimeter}}, msg.str()});
    }
    if (g.cellsContinued > 0) {
        std::ostringstream msg;
        msg << "continued the surface past the DEM's edge and the gaps too large to fill for the computation, "
            << margin << " cells wide; values within R of them rest partly on the continuation (filled_share)";
        diagnostics.add({"borders_continued", g.cellsContinued, {{"width", margin * cell}}, msg.str()});
    }
}

/// Computes window @p win on the height-field route: the box's gaps filled and its borders
/// continued on the grid, V and S of its own cells from the heights, filled_share from the
/// same hat weights at R. Adds its diagnostics, masked own cells and time to @p result;
/// returns its bands per own cell (row by row).
std::vector<std::vector<float>> computeHeightWindow(const Window& win, const WindowLayout& w, DiagnosticSum& diagnostics,
                                                    DemComputeResult& result, RunContext* context)
{
    const int bw = win.box[2] - win.box[0], bh = win.box[3] - win.box[1];
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<std::vector<float>> cells(result.bands.size());
    if (win.dem.numValid == 0) {
        for (std::vector<float>& band : cells) band.assign(std::size_t(win.cols) * std::size_t(win.rows), nan);
        return cells;
    }
    Stopwatch clock;
    HeightGrid heights;
    heights.cols = bw, heights.rows = bh, heights.z = win.dem.heights;
    const GridContinuationResult g = continueGrid(heights, w.continuation);
    const int m = w.continuation.margin;
    const GridRect own{win.col - win.box[0] + m, win.row - win.box[1] + m, win.cols, win.rows};
    result.prepareSeconds += clock.seconds();
    HeightFieldResult hf = computeHeightField(g.grid, own, w.kernel, context);
    result.heightFieldSeconds += hf.seconds;
    clock.restart();
    const bool wantsShare = std::find(result.bands.begin(), result.bands.end(), "filled_share") != result.bands.end();
    OwnSurface surface = ownSurface(g, own, win, w, wantsShare);
    result.triangles += 2 * surface.squares;
    // The bands, from the columns computed (those of the radii the bands need; the others
    // are empty and give no property, io/feature_properties.h).
    FeatureSet features;
    features.radii = w.kernel.radii;
    // (moved, not copied: a window's columns are tens of MB each)
    if (!hf.volume.empty()) features[Invariant::Volume] = std::move(hf.volume);
    if (!hf.sphere.empty()) features[Invariant::Sphere] = std::move(hf.sphere);
    result.masked.addWhere(features, surface.filledShare, surface.onSurface);
    std::vector<VertexProperty> props = outputProperties(std::move(features), std::move(surface.filledShare));
    ownBands(props, win, surface.onSurface, result.bands, cells);
    addContinuationDiagnostics(g, m, w.cell, diagnostics);
    result.prepareSeconds += clock.seconds();
    return cells;
}

/// Copies the own cells of @p cells (per cell of the window's box) into the output.
void writeOwnCells(const Window& win, const RasterRegion& region, const std::vector<std::vector<float>>& cells,
                   RasterPieceWriter& writer)
{
    std::vector<float> own(std::size_t(win.cols) * std::size_t(win.rows));
    for (std::size_t b = 0; b < cells.size(); ++b) {
        for (int y = 0; y < win.rows; ++y)
            std::copy_n(cells[b].begin() + std::ptrdiff_t(win.boxCell(win.col, win.row + y)), win.cols,
                        own.begin() + std::ptrdiff_t(std::size_t(y) * std::size_t(win.cols)));
        writer.write(int(b), win.col - region.col, win.row - region.row, win.cols, win.rows, own.data());
    }
}

/// The own cells of @p own in two halves along each side longer than a cell.
std::vector<CellRect> quarters(const CellRect& own)
{
    std::vector<CellRect> parts;
    const int c1 = (own.cols + 1) / 2, r1 = (own.rows + 1) / 2;
    for (const auto& [row, rows] : {std::pair{own.row, r1}, std::pair{own.row + r1, own.rows - r1}})
        for (const auto& [col, cols] : {std::pair{own.col, c1}, std::pair{own.col + c1, own.cols - c1}})
            if (rows > 0 && cols > 0) parts.push_back({col, row, cols, rows});
    return parts;
}

/// What is counted over the own cells of all windows.
struct WindowTotals {
    DiagnosticSum diagnostics;
    std::size_t ownCellsWithHeight = 0;
    std::map<float, std::size_t> undeclared;  ///< implausible heights taken as nodata
};

/// Computes windows and writes their own cells, and counts over them. A window whose surface
/// would take more than the memory limit (spikes or noise in the heights make a surface far
/// larger than its cells) is computed in quarters instead, down to windows no wider than
/// their halo, where quartering would hardly shrink what is read (docs/limits.md, Memory
/// rule). Every window has the shared plan and halos that hold what its own cells depend
/// on, so the values do not depend on the windows' sizes.
class WindowRun {
public:
    WindowRun(const DemSource& source, const std::string& input, const WindowLayout& w, DemComputeResult& result,
              RasterPieceWriter& writer, RunContext* context)
        : mSource(source), mInput(input), mW(w), mResult(result), mWriter(writer), mContext(context)
    {
    }

    /// Computes and writes the own cells @p own; @p label names the window in progress.
    void run(const CellRect& own, const std::string& label)
    {
        Stopwatch stage;
        const Window win = readWindow(mSource, mW, own);
        mResult.readSeconds += stage.seconds();
        if (mContext && !label.empty()) mContext->setPrefix(label + ": ");
        if (mW.oneWindow && win.dem.numValid == 0)
            throw InvalidInputError(fileName(mInput) + " has no cell with a height (all nodata)");
        std::vector<std::vector<float>> cells;  // per cell of the box (the mesh route) or own cell (heights)
        try {
            cells = mW.heightField ? computeHeightWindow(win, mW, totals.diagnostics, mResult, mContext)
                                   : computeWindow(win, mW, totals.diagnostics, mResult, mContext);
        } catch (const MemoryLimitError& e) {
            if (mW.oneWindow) throw;  // computeDem lays the raster out in windows and retries
            if (std::max(own.cols, own.rows) <= std::max(1, mW.narrowHalo)) {
                std::ostringstream msg;
                msg << e.what() << "; this is in the window of " << own.cols << " x " << own.rows
                    << " cells at column " << own.col << ", row " << own.row << " with its halo of " << mW.narrowHalo
                    << " cells, the smallest the raster is split into";
                throw MemoryLimitError(msg.str());
            }
            ++mResult.splitWindows;
            const std::vector<CellRect> parts = quarters(own);
            for (std::size_t k = 0; k < parts.size(); ++k)
                run(parts[k], (label.empty() ? "" : label + ", ") + "part " + std::to_string(k + 1) + " of " +
                                  std::to_string(parts.size()));
            return;
        }
        if (mW.oneWindow && mResult.triangles == 0)
            throw InvalidInputError(fileName(mInput) +
                                    ": no 2 x 2 block of cells has heights, so there is no surface to compute on");
        mResult.wideHaloWindows += win.wide;
        stage.restart();
        totals.ownCellsWithHeight += tbb::parallel_reduce(
            tbb::blocked_range<int>(win.row, win.row + win.rows), std::size_t(0),
            [&](const tbb::blocked_range<int>& rows, std::size_t n) {
                for (int y = rows.begin(); y < rows.end(); ++y)
                    for (int x = win.col; x < win.col + win.cols; ++x) n += !std::isnan(win.dem.heights[win.boxCell(x, y)]);
                return n;
            },
            std::plus<std::size_t>());
        if (!win.dem.undeclared.empty())
            for (int y = win.row; y < win.row + win.rows; ++y)
                for (int x = win.col; x < win.col + win.cols; ++x) win.dem.undeclared.count(win.boxCell(x, y), totals.undeclared);
        if (mW.heightField)
            for (std::size_t b = 0; b < cells.size(); ++b)
                mWriter.write(int(b), win.col - mW.region.col, win.row - mW.region.row, win.cols, win.rows, cells[b].data());
        else
            writeOwnCells(win, mW.region, cells, mWriter);
        mResult.writeSeconds += stage.seconds();
    }

    WindowTotals totals;

private:
    const DemSource& mSource;
    const std::string& mInput;
    const WindowLayout& mW;
    DemComputeResult& mResult;
    RasterPieceWriter& mWriter;
    RunContext* mContext;
};

/// Computes every window of @p w into @p writer.
/// @throw MemoryLimitError if @p w is one window whose surface exceeds the memory limit.
WindowTotals runWindows(const DemSource& source, const std::string& input, const WindowLayout& w,
                     DemComputeResult& result, RasterPieceWriter& writer, RunContext* context)
{
    WindowRun run(source, input, w, result, writer, context);
    for (const Diagnostic& d : result.diagnostics)  // the shared plan's
        if (kept(d, result.plan, w.cell)) run.totals.diagnostics.add(d);
    result.haloCells = w.wideHalo, result.narrowHaloCells = w.narrowHalo, result.windowCells = w.side;
    result.windowsPerRow = (w.region.cols + w.side - 1) / w.side;
    result.windowsPerColumn = (w.region.rows + w.side - 1) / w.side;
    const int windows = result.windowsPerRow * result.windowsPerColumn;
    for (int wy = 0; wy < result.windowsPerColumn; ++wy)
        for (int wx = 0; wx < result.windowsPerRow; ++wx) {
            const CellRect own{w.region.col + wx * w.side, w.region.row + wy * w.side,
                               std::min(w.side, w.region.cols - wx * w.side), std::min(w.side, w.region.rows - wy * w.side)};
            run.run(own, windows > 1 ? "window " + std::to_string(wy * result.windowsPerRow + wx + 1) + " of " +
                                           std::to_string(windows)
                                     : std::string());
        }
    if (context) context->setPrefix("");
    return std::move(run.totals);
}

/// The options' refusals, before anything is read.
void checkOptions(const DemComputeOptions& options)
{
    const ComputeOptions& c = options.compute;
    if (c.invariants.exact) throw InvalidInputError("the exact mode is for meshes, not rasters");
    if (c.tiling.tilesPerAxis != 0 || c.tiling.onlyTile >= 0)
        throw InvalidInputError("rasters are computed in windows; give their memory budget or size instead of tiles");
    if (c.tiling.memoryBudget < 0 || !std::isfinite(c.tiling.memoryBudget))
        throw InvalidInputError("the memory budget must be positive (or 0: the default)");
    if (options.windowCells < 0) throw InvalidInputError("the window size must be positive (or 0: from the memory budget)");
    const std::vector<std::string> available = demBandNames(c);
    for (const std::string& name : options.bands)
        if (std::find(available.begin(), available.end(), name) == available.end())
            parseFeatureNames(name, available);  // throws, naming it and those that can be given
}

} // namespace

std::vector<std::string> demBandNames(const ComputeOptions& options)
{
    std::vector<std::string> names = outputPropertyNames(options.invariants.selected(), options.invariants.scales);
    names.push_back("height");
    return names;
}

DemComputeResult computeDem(const std::string& input, const std::string& output, const DemComputeOptions& asked,
                            RunContext* context)
{
    checkOptions(asked);
    const std::vector<std::string> bands = bandNames(asked);
    DemComputeOptions options = onlyWhatIsWritten(asked, bands);
    options.output.scaled16 = !asked.float32 && allFractions(bands, asked.compute.invariants);
    Stopwatch stage;
    DemComputeResult result;
    DemReadOptions ro;
    ro.band = options.band;
    const DemSource source(input, ro);
    result.input = source.info();
    const InvariantsOptions& computed = options.compute.invariants;
    // A ball wider than the whole raster holds all of it and mostly its continuation past
    // the edges, at a cost that grows with R²: most likely R in other units than the DEM's.
    {
        const RasterGeoreference& g = result.input.georeference;
        const auto [cellWidth, cellHeight] = cellSides(g);
        const double across = std::max(double(g.width) * cellWidth, double(g.height) * cellHeight);
        if (computed.radius > across) {
            std::ostringstream msg;
            msg << "the radius R = " << computed.radius << " is larger than the whole DEM (" << across
                << " across" << (g.units.empty() ? "" : "; unit: " + g.units)
                << "): every ball would hold all of it and mostly its continuation past the edges; "
                << "R is in the DEM's ground units, about the size of the largest feature to detect";
            throw InvalidInputError(msg.str());
        }
    }
    result.engine = asked.engine;
    if (asked.engine == DemEngine::HeightField && (computed.computePatch || computed.computeLine)) {
        result.engine = DemEngine::Mesh;
        result.engineNote = "P and L are computed on the DEM's mesh (the height-field kernel gives V and S)";
    }
    const WindowLayout w = result.engine == DemEngine::HeightField ? layHeightFieldWindows(source, options, bands, result)
                                                                   : layWindows(source, input, options, result);
    result.bands = bands;
    result.computed = options.compute.invariants.selected();
    result.scaled16 = options.output.scaled16;
    result.readSeconds += stage.seconds();

    // The output's grid: the region's cells of the input's.
    RasterGeoreference& grid = result.input.georeference;
    const std::array<double, 6> t = grid.transform;
    grid.transform[0] = t[0] + w.region.col * t[1] + w.region.row * t[2];
    grid.transform[3] = t[3] + w.region.col * t[4] + w.region.row * t[5];
    grid.width = w.region.cols, grid.height = w.region.rows;
    RasterPieceWriter writer(output, grid, result.bands, options.output);
    WindowTotals totals;
    try {
        totals = runWindows(source, input, w, result, writer, context);
    } catch (const MemoryLimitError&) {
        if (!w.oneWindow) throw;
        // A raster that fits one window by its cells but not by its surface: in windows, with
        // the plan of the one piece, as a larger raster (nothing was written yet).
        stage.restart();
        const WindowLayout split = layWindows(source, input, options, result, true);
        result.readSeconds += stage.seconds();
        totals = runWindows(source, input, split, result, writer, context);
    }
    // A part of a mosaic may be all nodata (sea, a tile outside the survey): written as such.
    if (totals.ownCellsWithHeight == 0 && options.region.cols == 0)
        throw InvalidInputError(fileName(input) + " has no cell with a height (all nodata)");
    result.input.numValid = totals.ownCellsWithHeight;
    result.diagnostics = totals.diagnostics.list();
    if (!totals.undeclared.empty()) {
        Diagnostic d{"undeclared_nodata", 0, {}, describeUndeclaredNodata(totals.undeclared)};
        for (const auto& [value, cells] : mostCellsFirst(totals.undeclared)) {
            d.count += cells;
            if (d.figures.size() < 4) d.figures.emplace_back("value_" + std::to_string(d.figures.size() + 1), value);
        }
        result.diagnostics.insert(result.diagnostics.begin(), std::move(d));
    }
    if (std::optional<Diagnostic> d = result.masked.mostlyMasked(result.plan.radii))
        result.diagnostics.push_back(std::move(*d));
    stage.restart();
    writer.commit();
    result.writeSeconds += stage.seconds();
    return result;
}

} // namespace msii
