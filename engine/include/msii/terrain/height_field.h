#pragma once
/// @file height_field.h
/// @brief V and S of a DEM straight from its heights, without a level set (docs/method.md,
/// Height fields). For a cell p at height z₀ and a ball of radius r, every point x of the
/// plane within r of p has the ball's vertical chord [z₀ − h, z₀ + h], h = √(r² − |x − p|²),
/// of which clamp(z(x) − z₀ + h, 0, 2h) lies below the terrain (the solid is the ground), so
/// - V(r) = ∫_{|x − p| < r} clamp(z(x) − z₀ + h(x), 0, 2h(x)) dx,
/// - S(r) = dV/dr / (4π r²): the volume inside a ball grows by the area of its sphere inside.
/// The integral is a sum over the cells of the disc: each cell o contributes its area inside
/// the disc, A_o, times clamp(z_o − z₀ + h̄_o, 0, 2h̄_o), with h̄_o = H_o/A_o the mean of h over
/// that area (A_o and H_o = ∫ h computed once per radius, exactly where the rim cuts a
/// cell). On a plane this is the half ball exactly (V̂ = ½), and the sum of the heights over
/// whole cells is the integral of the DEM's mesh (its triangles between cell centres) over
/// them. S comes from V at r(1 ± δ), normalised by the same difference of the ball's
/// volume (heightFieldSphereStep).

#include <msii/core/feature_set.h>
#include <msii/core/run_context.h>

#include <array>
#include <cstddef>
#include <vector>

namespace msii {

/// The largest relative step δ of heightFieldSphereStep: the discs of S reach to r(1 + δ).
inline constexpr double kHeightFieldSphereStep = 0.05;

/// Sectors of a disc about its centre (quadrants, from the −x axis on, turning towards −y):
/// the pieces of C are bounded sector by sector (DiscSamples). Terrain mostly slopes one way,
/// so the largest |z_o − z₀| over a quadrant is often well below that over the whole disc.
/// On a 1000² lidar-like DEM at R = 10 cells, four sectors took 0.86 of the kernel's time
/// with one; eight or sixteen took longer than four (their squares overlap more sectors, and
/// their bounds took longer than the pieces they skipped).
inline constexpr int kHeightFieldSectors = 4;

/// S from V at r(1 ± δ): δ = a quarter of a cell over r, within [1/80, 1/20]. The central
/// difference errs by (δr)²/6 of V‴ over V′, and V‴ grows where a wall or a bank of about a
/// cell's width crosses the sphere, so the step is held to a fraction of a cell; a smaller
/// one would carry more of the sums' own error (divided by 2δ), which on a disc of a few
/// cells is the larger part (docs/method.md, Height fields).
inline double heightFieldSphereStep(double r, double cell)
{
    const double step = 0.25 * cell / r;
    return step < 0.0125 ? 0.0125 : (step > kHeightFieldSphereStep ? kHeightFieldSphereStep : step);
}

/// Heights on a grid: row-major, NaN where there are none.
struct HeightGrid {
    int cols = 0, rows = 0;
    std::vector<float> z;
    float at(int col, int row) const { return z[std::size_t(row) * std::size_t(cols) + std::size_t(col)]; }
};

/// Cells [col, col + cols) × [row, row + rows) of a grid.
struct GridRect {
    int col = 0, row = 0, cols = 0, rows = 0;
};

struct HeightFieldOptions {
    std::vector<double> radii;   ///< ascending, in the grid's units (metres)
    double cellWidth = 1;        ///< distance between cell centres along a row (x)
    double cellHeight = 1;       ///< and along a column (y)
    bool computeVolume = true;   ///< V̂
    bool computeSphere = true;   ///< Ŝ
    /// The radii whose values are wanted (radius indices); empty = all. The others get no
    /// column and cost nothing (a DEM's default bands need four of N).
    std::vector<int> wanted;
    /// Cells summed together at most, per vector: 0 or 16 = the processor's widest (16 with
    /// AVX-512, else 8); 8 takes two vectors of eight where it would take one of sixteen, as a
    /// processor without AVX-512 does (the values are the same, bit for bit: for tests).
    int vectorLanes = 0;
};

struct HeightFieldResult {
    std::vector<double> radii;  ///< as given
    /// [j][k] for own cell k (row-major in the own rectangle): V/|B_r| and S/(4π r²), plane ½;
    /// NaN where a cell of the ball has no height; column j empty where radius j is not wanted.
    FeatureColumns volume, sphere;
    double seconds = 0;
};

/// The disc of radius r about a cell, for V(r) = Σ_o W_o (z_o − z₀) + ⅔πr³ + C (docs/method.md,
/// Height fields):
/// - the taps: each cell o whose hat function (1 at o, 0 at the other cell centres, linear on
///   the DEM's triangles) reaches into the disc, with W_o = ∫ over the disc of that hat
///   function. Σ_o W_o z_o is the integral of the DEM's mesh over the disc, exactly, and
///   ∫ h = ⅔πr³ (the half ball): together V where no chord is clamped;
/// - the pieces, for C = ∫ clamp(b, 0, 2h) − b, b = z − z₀ + h: the disc's cells split s × s
///   (s from the radius: a small disc holds few cells), each with its area A inside the disc,
///   the mean of the chord's half-length h over that area (H/A) and its height from up to
///   three cell centres with weights (the DEM's triangle under the piece's centre, the
///   diagonal from (col + 1, row) to (col, row + 1)). C is non-zero only where |z − z₀| > h,
///   near the rim or past a wall; the pieces are grouped by sector of the disc (the quadrant
///   of their centres' direction) and sorted by h̄ within each, so that a cell's sum over a
///   sector stops at the first piece whose h̄ exceeds every |z − z₀| of the sector's squares
///   (the 2 × 2 cells that hold its pieces' heights).
struct DiscSamples {
    double radius = 0;
    int split = 1;  ///< s
    int reach = 0;  ///< rows and columns of cells either side that the taps read, at most
    std::vector<int> cellColumn, cellRow;  ///< the taps' cell offsets
    std::vector<float> cellWeight;         ///< their W_o
    std::vector<float> area, meanHalfChord;  ///< the pieces, by sector, h̄ ascending within one
    std::array<std::vector<int>, 3> tapColumn, tapRow;  ///< cell offsets of the pieces' heights
    std::array<std::vector<float>, 3> tapWeight;
    std::array<std::size_t, kHeightFieldSectors> sectorEnd{};  ///< where each sector's pieces end
    /// Per sector, the squares of 2 × 2 cells (by their first cell's offsets, within the reach)
    /// that hold the heights of its pieces: [squareEnd[q − 1], squareEnd[q]) for sector q.
    std::vector<int> squareColumn, squareRow;
    std::array<std::size_t, kHeightFieldSectors> squareEnd{};
    std::size_t size() const { return area.size(); }
};

/// The pieces of cells per cell axis for radius @p r on cells of @p cellWidth ×
/// @p cellHeight: enough that the disc spans about kDiscPieces of them across its radius.
int discSplit(double r, double cellWidth, double cellHeight);

/// The disc of radius @p r on a grid of cells @p cellWidth × @p cellHeight: the hat
/// functions' integrals W_o (whole triangles in closed form, the squares the rim cuts in
/// 64 × 64 parts), and the pieces of cells split @p split × @p split (even; 2 × 2 of them as one
/// where h exceeds r/4 throughout; A and H by adaptive
/// quadrature across x of the closed forms across y, exactly where the rim cuts a piece).
DiscSamples discSamples(double r, double cellWidth, double cellHeight, int split);

/// The squares of four cell centres (cells (c, r) to (c + 1, r + 1) from the disc's centre
/// cell) that reach into the disc of radius @p r, with their areas inside it: the DEM's mesh
/// within the disc, by square (for filled_share).
struct DiscSquares {
    std::vector<int> column, row;
    std::vector<double> area;
};
DiscSquares discSquares(double r, double cellWidth, double cellHeight);

/// V̂ and Ŝ of the cells @p own of @p grid. Every cell within the largest radius (and its
/// twentieth) of an own cell must have a height for that cell to get values.
/// @throw InvalidInputError for radii that are not ascending and positive, a cell size that
/// is not positive, or own cells outside the grid.
HeightFieldResult computeHeightField(const HeightGrid& grid, const GridRect& own, const HeightFieldOptions& options,
                                     RunContext* context = nullptr);

} // namespace msii
