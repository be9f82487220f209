#include <msii/terrain/grid_continuation.h>

#include <msii/core/errors.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <unordered_map>
#include <vector>

namespace msii {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Grid {
    int cols, rows;
    std::vector<float>& z;
    std::vector<GridCell>& kind;
    std::size_t at(int c, int r) const { return std::size_t(r) * std::size_t(cols) + std::size_t(c); }
    bool inside(int c, int r) const { return c >= 0 && r >= 0 && c < cols && r < rows; }
};

/// The gaps that mesh preparation fills in the DEM's mesh (terrain/dem.h: a square of four
/// cell centres is two triangles where all four have heights), filled on the grid: the holes
/// of the mesh are the 4-connected groups of squares left out, those that reach the grid's
/// edge are borders, and a hole is filled where its border, the edges between its squares
/// and the squares kept, is at most @p maxPerimeter long. Its NaN cells take the discrete
/// biharmonic surface through the heights around them (Gauss–Seidel sweeps in row-major order
/// from the mean of the heights next to them: the result depends only on the hole and its
/// rim). A cell whose 12 neighbours of the biharmonic stencil are not all heights or the
/// hole's takes the mean of its four (harmonic) instead.
void fillGaps(Grid& g, double cw, double ch, double maxPerimeter, GridContinuationResult& result)
{
    const int sc = g.cols - 1, sr = g.rows - 1;  // squares
    if (sc < 1 || sr < 1) return;
    const auto square = [&](int c, int r) { return std::size_t(r) * std::size_t(sc) + std::size_t(c); };
    std::vector<char> missing(std::size_t(sc) * std::size_t(sr), 0), seen(missing.size(), 0);
    tbb::parallel_for(0, sr, [&](int r) {
        for (int c = 0; c < sc; ++c)
            missing[square(c, r)] = std::isnan(g.z[g.at(c, r)]) || std::isnan(g.z[g.at(c + 1, r)]) ||
                                    std::isnan(g.z[g.at(c, r + 1)]) || std::isnan(g.z[g.at(c + 1, r + 1)]);
    });
    std::vector<std::size_t> squares, stack, gap;
    for (std::size_t start = 0; start < missing.size(); ++start) {
        if (!missing[start] || seen[start]) continue;
        squares.clear();
        double perimeter = 0;
        bool open = false;
        seen[start] = 1;
        stack.assign(1, start);
        while (!stack.empty()) {
            const std::size_t q = stack.back();
            stack.pop_back();
            squares.push_back(q);
            const int c = int(q % std::size_t(sc)), r = int(q / std::size_t(sc));
            for (const auto& [dc, dr] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
                const int nc = c + dc, nr = r + dr;
                if (nc < 0 || nr < 0 || nc >= sc || nr >= sr) {
                    open = true;
                    continue;
                }
                const std::size_t n = square(nc, nr);
                if (!missing[n]) perimeter += dc != 0 ? ch : cw;  // the edge between them
                else if (!seen[n]) seen[n] = 1, stack.push_back(n);
            }
        }
        if (open || perimeter > maxPerimeter) continue;
        gap.clear();
        for (const std::size_t q : squares) {
            const int c = int(q % std::size_t(sc)), r = int(q / std::size_t(sc));
            for (const auto& [dc, dr] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}})
                if (std::isnan(g.z[g.at(c + dc, r + dr)])) gap.push_back(g.at(c + dc, r + dr));
        }
        gap.erase(std::unique((std::sort(gap.begin(), gap.end()), gap.begin()), gap.end()), gap.end());
        if (gap.empty()) continue;
        std::sort(gap.begin(), gap.end());
        const std::size_t none = std::numeric_limits<std::size_t>::max();
        const auto indexInGap = [&](std::size_t c) {
            const auto it = std::lower_bound(gap.begin(), gap.end(), c);
            return it != gap.end() && *it == c ? std::size_t(it - gap.begin()) : none;
        };
        // Per gap cell: its stencil's gap neighbours with their coefficients, the known
        // heights' share as a constant, and the divisor: biharmonic (20 u = 8 Σ axis −
        // 2 Σ diagonal − Σ two apart) or harmonic (4 u = Σ axis).
        struct Stencil {
            std::vector<std::pair<std::size_t, double>> terms;
            double constant = 0, divisor = 1;
        };
        std::vector<Stencil> stencils(gap.size());
        double rim = 0;
        std::size_t rimCount = 0;
        const int ax[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}}, dg[4][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
        for (std::size_t i = 0; i < gap.size(); ++i) {
            const int x = int(gap[i] % std::size_t(g.cols)), y = int(gap[i] / std::size_t(g.cols));
            const auto known = [&](int c, int r) {
                return g.inside(c, r) && (!std::isnan(g.z[g.at(c, r)]) || indexInGap(g.at(c, r)) != none);
            };
            bool biharmonic = true;
            for (int k = 0; k < 4; ++k) {
                biharmonic = biharmonic && known(x + dg[k][0], y + dg[k][1]) && known(x + 2 * ax[k][0], y + 2 * ax[k][1]);
                const std::size_t n = g.at(x + ax[k][0], y + ax[k][1]);  // inside: the gap is closed
                if (!std::isnan(g.z[n])) rim += g.z[n], ++rimCount;
            }
            Stencil& s = stencils[i];
            const auto add = [&](int c, int r, double coefficient) {
                const std::size_t n = g.at(c, r), j = indexInGap(n);
                if (j != none) s.terms.emplace_back(j, coefficient);
                else s.constant += coefficient * double(g.z[n]);
            };
            s.divisor = biharmonic ? 20 : 4;
            for (int k = 0; k < 4; ++k) {
                add(x + ax[k][0], y + ax[k][1], biharmonic ? 8 : 1);
                if (!biharmonic) continue;
                add(x + dg[k][0], y + dg[k][1], -2);
                add(x + 2 * ax[k][0], y + 2 * ax[k][1], -1);
            }
        }
        std::vector<double> u(gap.size(), rim / double(std::max<std::size_t>(1, rimCount)));
        const double scale = std::max(1.0, std::abs(u.front()));
        for (int sweep = 0; sweep < 20000; ++sweep) {
            double change = 0;
            for (std::size_t i = 0; i < gap.size(); ++i) {
                const Stencil& s = stencils[i];
                double next = s.constant;
                for (const auto& [j, coefficient] : s.terms) next += coefficient * u[j];
                next /= s.divisor;
                change = std::max(change, std::abs(next - u[i]));
                u[i] = next;
            }
            if (change <= 1e-7 * scale) break;
        }
        for (std::size_t i = 0; i < gap.size(); ++i) {
            g.z[gap[i]] = float(u[i]);
            g.kind[gap[i]] = GridCell::Filled;
        }
        ++result.gapsFilled;
        result.cellsFilled += gap.size();
        result.largestFilledPerimeter = std::max(result.largestFilledPerimeter, perimeter);
    }
}

/// z = c0 + c1 x + c2 y fitted by least squares to the heights @p z (NaN: none) within @p fit
/// of cell (@p bc, @p br) of @p g (x, y from it in ground units); the constant where they span
/// no plane.
std::array<double, 3> fitPlane(const std::vector<float>& z, const Grid& g, int bc, int br, double cw, double ch, double fit)
{
    const int rx = std::max(1, int(std::floor(fit / cw))), ry = std::max(1, int(std::floor(fit / ch)));
    const double fit2 = std::max(fit * fit, cw * cw + ch * ch);
    double m[3][3] = {}, v[3] = {};
    const double z0 = z[g.at(bc, br)];
    for (int dy = -ry; dy <= ry; ++dy)
        for (int dx = -rx; dx <= rx; ++dx) {
            const double x = dx * cw, y = dy * ch;
            if (x * x + y * y > fit2 || !g.inside(bc + dx, br + dy)) continue;
            const std::size_t c = g.at(bc + dx, br + dy);
            if (std::isnan(z[c])) continue;  // (a continued cell is NaN in z)
            const double p[3] = {1, x, y}, dz = z[c] - z0;
            for (int i = 0; i < 3; ++i) {
                v[i] += p[i] * dz;
                for (int j = 0; j < 3; ++j) m[i][j] += p[i] * p[j];
            }
        }
    // Cramer's rule on the 3 × 3 normal equations.
    const auto det3 = [](const double a[3][3]) {
        return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
               a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    };
    const double d = det3(m);
    if (!(std::abs(d) > 1e-9 * m[0][0] * m[1][1] * m[2][2]) || m[0][0] < 3) return {z0, 0, 0};
    std::array<double, 3> c{};
    for (int k = 0; k < 3; ++k) {
        double a[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) a[i][j] = j == k ? v[i] : m[i][j];
        c[std::size_t(k)] = det3(a) / d;
    }
    c[0] += z0;
    return c;
}

/// Continues every NaN cell within @p margin cells of a height (see the header).
void continueBorders(Grid& g, const GridContinuationOptions& o, GridContinuationResult& result)
{
    const int m = o.margin;
    if (m <= 0 || std::none_of(g.z.begin(), g.z.end(), [](float v) { return std::isnan(v); })) return;
    // The offsets to search for the nearest height, nearest first (ties in row-major order).
    std::vector<std::array<int, 2>> offsets;
    for (int dy = -m; dy <= m; ++dy)
        for (int dx = -m; dx <= m; ++dx)
            if (dx != 0 || dy != 0) offsets.push_back({dx, dy});
    const auto d2 = [&](const std::array<int, 2>& a) {
        return (a[0] * o.cellWidth) * (a[0] * o.cellWidth) + (a[1] * o.cellHeight) * (a[1] * o.cellHeight);
    };
    std::stable_sort(offsets.begin(), offsets.end(), [&](const auto& a, const auto& b) { return d2(a) < d2(b); });
    // Chessboard distance to the nearest height (at most m + 1), to skip cells farther than
    // the margin: per row the distance along it (`along`), per column the rows to the nearest
    // row with a height within m along it (kept in `near` first), then per cell without a
    // height the least over the rows from there on of max(|dy|, that row's distance). Rows
    // and strips of columns in parallel; a cell deep in a nodata area costs no more than one
    // with a height.
    const int far = m + 1;
    std::vector<int> along(g.z.size(), far), near(g.z.size(), far);
    tbb::parallel_for(0, g.rows, [&](int y) {
        int* d = &along[g.at(0, y)];
        const float* z = &g.z[g.at(0, y)];
        for (int x = 0, last = -far; x < g.cols; ++x) {
            if (!std::isnan(z[x])) last = x;
            d[x] = std::min(far, x - last);
        }
        for (int x = g.cols - 1, next = g.cols - 1 + far; x >= 0; --x) {
            if (!std::isnan(z[x])) next = x;
            d[x] = std::min(d[x], next - x);
        }
    });
    constexpr int kStrip = 256;
    tbb::parallel_for(0, (g.cols + kStrip - 1) / kStrip, [&](int strip) {
        const int x0 = strip * kStrip, x1 = std::min(g.cols, x0 + kStrip);
        for (int y = 0; y < g.rows; ++y)
            for (int x = x0; x < x1; ++x)
                near[g.at(x, y)] = along[g.at(x, y)] <= m ? 0 : y > 0 ? std::min(far, near[g.at(x, y - 1)] + 1) : far;
        for (int y = g.rows - 2; y >= 0; --y)
            for (int x = x0; x < x1; ++x) near[g.at(x, y)] = std::min(near[g.at(x, y)], near[g.at(x, y + 1)] + 1);
    });
    tbb::parallel_for(0, g.rows, [&](int y) {
        for (int x = 0; x < g.cols; ++x) {
            const std::size_t c = g.at(x, y);
            if (along[c] == 0) {
                near[c] = 0;
                continue;
            }
            // Rows nearer than near[c] have no height within m along them: no better there.
            int d = along[c];
            for (int dy = std::max(1, near[c]); dy <= m && dy < d; ++dy) {
                if (y - dy >= 0) d = std::min(d, std::max(dy, along[g.at(x, y - dy)]));
                if (y + dy < g.rows) d = std::min(d, std::max(dy, along[g.at(x, y + dy)]));
            }
            near[c] = d;
        }
    });
    const std::vector<float> z = g.z;  // heights and filled gaps: what the continuation reads
    // Row by row in parallel: a cell's value depends on z only (each thread keeps the planes
    // it has fitted; a plane is the same whoever fits it).
    tbb::enumerable_thread_specific<std::unordered_map<std::size_t, std::array<double, 3>>> planesOfThread;
    std::vector<std::size_t> continuedInRow(std::size_t(g.rows), 0);
    tbb::parallel_for(0, g.rows, [&](int y) {
        auto& planes = planesOfThread.local();
        for (int x = 0; x < g.cols; ++x) {
            const std::size_t c = g.at(x, y);
            if (!std::isnan(z[c]) || near[c] > m) continue;
            // No height within the chessboard distance's square: start at that distance.
            const double skip = double(near[c]) * std::min(o.cellWidth, o.cellHeight);
            const auto first = std::lower_bound(offsets.begin(), offsets.end(), skip * skip * (1 - 1e-12),
                                                [&](const std::array<int, 2>& a, double v) { return d2(a) < v; });
            for (auto it = first; it != offsets.end(); ++it) {
                const std::array<int, 2>& off = *it;
                const int bx = x + off[0], by = y + off[1];
                if (!g.inside(bx, by) || std::isnan(z[g.at(bx, by)])) continue;
                const std::size_t b = g.at(bx, by);
                auto plane = planes.find(b);
                if (plane == planes.end())
                    plane = planes.emplace(b, fitPlane(z, g, bx, by, o.cellWidth, o.cellHeight, o.fitRadius)).first;
                const std::array<double, 3>& p = plane->second;
                const double ex = -off[0] * o.cellWidth, ey = -off[1] * o.cellHeight;  // the cell from b
                double h = p[0] + p[1] * ex + p[2] * ey;
                const int mx = bx + off[0], my = by + off[1];  // its mirror point through b
                if (g.inside(mx, my) && !std::isnan(z[g.at(mx, my)]))
                    h += 0.5 * (double(z[g.at(mx, my)]) - (p[0] - p[1] * ex - p[2] * ey));
                g.z[c] = float(h);
                g.kind[c] = GridCell::Continued;
                ++continuedInRow[std::size_t(y)];
                break;
            }
        }
    });
    for (const std::size_t n : continuedInRow) result.cellsContinued += n;
}

} // namespace

GridContinuationResult continueGrid(const HeightGrid& heights, const GridContinuationOptions& options)
{
    if (heights.z.size() != std::size_t(heights.cols) * std::size_t(heights.rows))
        throw InvalidInputError("the height grid's size does not match its columns and rows");
    if (options.margin < 0) throw InvalidInputError("the margin of a continued grid must not be negative");
    GridContinuationResult result;
    const int m = options.margin;
    HeightGrid& out = result.grid;
    out.cols = heights.cols + 2 * m, out.rows = heights.rows + 2 * m;
    out.z.assign(std::size_t(out.cols) * std::size_t(out.rows), kNaN);
    result.kind.assign(out.z.size(), GridCell::None);
    tbb::parallel_for(0, heights.rows, [&](int r) {
        for (int c = 0; c < heights.cols; ++c) {
            const std::size_t i = std::size_t(r + m) * std::size_t(out.cols) + std::size_t(c + m);
            out.z[i] = heights.at(c, r);
            if (!std::isnan(out.z[i])) result.kind[i] = GridCell::Height;
        }
    });
    Grid g{out.cols, out.rows, out.z, result.kind};
    // Holes that reach the input's edge are open there: they reach the margin's squares.
    if (options.maxHolePerimeter > 0) fillGaps(g, options.cellWidth, options.cellHeight, options.maxHolePerimeter, result);
    if (options.continueBorders) continueBorders(g, options, result);
    return result;
}

} // namespace msii
