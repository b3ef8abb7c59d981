#include "bound_grid.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>

#include "delta/core/parallel.h"

namespace delta::detail {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// At most this many cells, and along one axis (for the transform's integers; see
/// transformLine).
constexpr std::size_t kMostCells = std::size_t{1} << 30;
constexpr std::size_t kMostAlongAxis = std::size_t{1} << 20;
/// Work per parallel chunk of the build: a few hundred microseconds.
constexpr std::size_t kCellsPerChunk = std::size_t{1} << 15;
constexpr std::size_t kRowsPerChunk = 512;
constexpr std::size_t kTrianglesPerChunk = 4096;
/// Squared cell distances are capped here, where the code saturates. Capping the input of each
/// pass at K caps its output at K and changes nothing below K (a pass maps min(f, K) to
/// min(pass(f), K)), so the transform stays exact where it is not saturated, and every value
/// fits an int32.
constexpr std::int32_t kCap = 128 * 128;
static_assert(kSquaredCellsOfCode[255] == kCap);
static_assert([] {
  for (std::size_t code = 1; code < 256; ++code)
    if (!(kSquaredCellsOfCode[code - 1] < kSquaredCellsOfCode[code])) return false;
  return kSquaredCellsOfCode[0] == 0.0 && kSquaredCellsOfCode[1] == 1.0;
}());

/// The cells a grid of side `side` needs over extents `extent`: at least one along each axis.
double cellsFor(const Vec3& extent, double side) noexcept {
  double cells = 1.0;
  for (std::size_t axis = 0; axis < 3; ++axis)
    cells *= std::max(std::ceil(extent[axis] / side), 1.0);
  return cells;
}

/// The first pass of the transform, along x, where the occupancy is still 0 or kCap: each cell
/// gets max(0, d − 1)², d its distance in cells to the nearest occupied cell of its line (two
/// sweeps; no parabolas needed yet).
void transformRows(std::vector<std::int32_t>& squared, std::size_t rowLength) {
  constexpr std::int64_t kNone = std::int64_t{1} << 40;
  const auto length = static_cast<std::int64_t>(rowLength);
  const std::size_t rows = squared.size() / rowLength;
  parallelFor(0, rows, kRowsPerChunk, [&](std::size_t firstRow, std::size_t endRow) {
    for (std::size_t r = firstRow; r < endRow; ++r) {
      std::int32_t* row = squared.data() + r * rowLength;
      std::int64_t previous = -kNone;
      for (std::int64_t i = 0; i < length; ++i) {
        if (row[i] == 0) previous = i;
        row[i] = static_cast<std::int32_t>(std::min<std::int64_t>(i - previous, kCap));
      }
      if (previous < 0) continue;  // no occupied cell: every distance stays capped
      std::int64_t next = kNone;
      for (std::int64_t i = length - 1; i >= 0; --i) {
        if (row[i] == 0) next = i;
        const std::int64_t gap = std::min<std::int64_t>(row[i], next - i) - 1;
        row[i] = gap <= 0 ? 0 : static_cast<std::int32_t>(std::min<std::int64_t>(gap * gap, kCap));
      }
    }
  });
}

/// Scratch for the later passes: a tile of lines, and the lower envelope of one line (parabola k
/// is the lowest from startNumerators[k] / startDenominators[k] on, for k > 0).
struct LineScratch {
  std::vector<std::int32_t> tile;
  std::vector<std::int32_t> values;
  std::vector<std::int64_t> vertices, heights, startNumerators, startDenominators;

  LineScratch(std::size_t length, std::size_t lines)
      : tile(length * lines),
        values(length),
        vertices(length),
        heights(length),
        startNumerators(length),
        startDenominators(length) {}
};

/// One line of a later pass, in place: f(i) ← min_k f(k) + max(0, |i − k| − 1)². Since
/// max(0, |x| − 1)² = min over y ∈ {−1, 0, 1} of (x − y)² for an integer x, that is a minimum
/// over three cells (the dilation) followed by the lower envelope of the parabolas
/// f(k) + (i − k)² (Felzenszwalb & Huttenlocher, "Distance transforms of sampled functions",
/// 2004). The parabolas' intersections are kept as fractions of integers and compared by cross
/// multiplication: exact, so that no rounding can pick a wrong parabola and overstate a bound
/// (numerators stay below 2^41 and denominators below 2^21 for lines of at most 2^20 cells). A
/// line left all capped by the dilation is left as it is.
void transformLine(std::int32_t* line, std::size_t length, LineScratch& scratch) noexcept {
  std::int32_t* f = scratch.values.data();
  std::int32_t lowestOfLine = kCap;
  for (std::size_t i = 0; i < length; ++i) {
    std::int32_t lowest = line[i];
    if (i > 0) lowest = std::min(lowest, line[i - 1]);
    if (i + 1 < length) lowest = std::min(lowest, line[i + 1]);
    f[i] = lowest;
    lowestOfLine = std::min(lowestOfLine, lowest);
  }
  if (lowestOfLine == kCap) return;
  std::int64_t* vertices = scratch.vertices.data();
  std::int64_t* heights = scratch.heights.data();
  std::int64_t* numerators = scratch.startNumerators.data();
  std::int64_t* denominators = scratch.startDenominators.data();
  const auto size = static_cast<std::int64_t>(length);
  std::int64_t top = 0;
  vertices[0] = 0;
  heights[0] = f[0];
  for (std::int64_t q = 1; q < size; ++q) {
    const std::int64_t height = f[q];
    // Parabola q lies below parabola v from (f(q) + q² − f(v) − v²) / 2(q − v) on; the top is
    // dropped when that is not after the top's own start.
    std::int64_t numerator, denominator;
    while (true) {
      const std::int64_t v = vertices[top];
      numerator = height + q * q - heights[top] - v * v;
      denominator = 2 * (q - v);
      if (top == 0 || numerator * denominators[top] > numerators[top] * denominator) break;
      --top;
    }
    ++top;
    vertices[top] = q;
    heights[top] = height;
    numerators[top] = numerator;
    denominators[top] = denominator;
  }
  std::int64_t k = 0;
  for (std::int64_t i = 0; i < size; ++i) {
    while (k < top && numerators[k + 1] < i * denominators[k + 1])
      ++k;
    line[i] = static_cast<std::int32_t>((i - vertices[k]) * (i - vertices[k]) + heights[k]);
  }
}

/// Every line of the grid along `axis` (1 or 2) through transformLine, kTileWidth neighbouring
/// lines (along x) at a time: copied out and back whole cache lines at a time, where one line
/// alone would touch a cache line (and, along z, a page) a cell.
void transformAxis(std::vector<std::int32_t>& squared, const std::array<std::size_t, 3>& dims,
                   const std::array<std::size_t, 3>& strides, std::size_t axis) {
  constexpr std::size_t kTileWidth = 16;
  const std::size_t length = dims[axis], stride = strides[axis];
  if (length == 1) return;  // one cell: the pass is the identity
  const std::size_t across = axis == 1 ? 2 : 1;
  // Chunks of slabs (planes of lines), each with its scratch.
  const std::size_t slabCells = dims[0] * length;
  parallelFor(0, dims[across], std::max<std::size_t>(1, kCellsPerChunk / slabCells),
              [&](std::size_t firstSlab, std::size_t endSlab) {
                LineScratch scratch(length, kTileWidth);
                for (std::size_t j = firstSlab; j < endSlab; ++j)
                  for (std::size_t x = 0; x < dims[0]; x += kTileWidth) {
                    const std::size_t width = std::min(kTileWidth, dims[0] - x);
                    std::int32_t* corner = squared.data() + x + j * strides[across];
                    for (std::size_t i = 0; i < length; ++i)
                      for (std::size_t line = 0; line < width; ++line)
                        scratch.tile[line * length + i] = corner[i * stride + line];
                    for (std::size_t line = 0; line < width; ++line)
                      transformLine(scratch.tile.data() + line * length, length, scratch);
                    for (std::size_t i = 0; i < length; ++i)
                      for (std::size_t line = 0; line < width; ++line)
                        corner[i * stride + line] = scratch.tile[line * length + i];
                  }
              });
}

/// Where the grid lies, for the marking: cell (i, j, k) is the box
/// lower + [i, i + 1]·side × [j, j + 1]·side × [k, k + 1]·side, exactly.
struct Frame {
  std::array<double, 3> lower;
  double side = 0.0;
  double inverseSide = 0.0;
  std::array<std::size_t, 3> dims, strides;
};

/// The side of the cubic cells of a grid over `extent` with at most `target` cells: the
/// smallest such, by bisection (the count does not grow with the side), and at most
/// kMostAlongAxis cells along an axis. Cubic cells fit a flat or long box as well as a cube.
double sideFor(const Vec3& extent, double target) noexcept {
  const double longest = std::max({extent.x, extent.y, extent.z});
  double side = longest, tooSmall = longest / (target + 1.0);
  for (int step = 0; step < 200; ++step) {
    const double middle = tooSmall + (side - tooSmall) * 0.5;
    if (middle <= tooSmall || middle >= side) break;
    (cellsFor(extent, middle) <= target ? side : tooSmall) = middle;
  }
  return std::max(side, longest / static_cast<double>(kMostAlongAxis - 1));
}

/// Sets to 0 every cell of `squared` that a triangle may touch: the cells of its box, grown by
/// `reach` cells, that its plane passes through (so that a large tilted triangle does not fill
/// its whole box).
///
/// Rounding: a coordinate maps to a cell by ⌊(x − lower)/h⌋, off by at most 3ε·n of a cell (n the
/// most cells along an axis); `reach` is above that, and the plane test allows for its own
/// rounding, so each triangle lies in the exact boxes of its marked cells.
/// A point in cell units of a grid (cell c covers [c, c + 1) along each axis).
struct CellPoint {
  double x, y, z;
};

/// Keeps the part of the convex polygon `in` (`count` corners) on the side of the plane
/// coordinate `axis` (1: y, 2: z) = `bound` that `keepAbove` names (Sutherland–Hodgman); the
/// corners into `out` (room for count + 1), their number returned.
int clipPolygon(const CellPoint* in, int count, CellPoint* out, int axis, double bound,
                bool keepAbove) noexcept {
  const auto offset = [axis, bound, keepAbove](const CellPoint& p) {
    const double value = axis == 1 ? p.y : p.z;
    return keepAbove ? value - bound : bound - value;
  };
  int kept = 0;
  for (int k = 0; k < count; ++k) {
    const CellPoint& from = in[k];
    const CellPoint& to = in[(k + 1) % count];
    const double a = offset(from), b = offset(to);
    if (a >= 0.0) out[kept++] = from;
    if ((a < 0.0 && b > 0.0) || (a > 0.0 && b < 0.0)) {
      const double t = a / (a - b);
      out[kept++] = {from.x + (to.x - from.x) * t, from.y + (to.y - from.y) * t,
                     from.z + (to.z - from.z) * t};
    }
  }
  return kept;
}

/// The x extent of the part of triangle `corners` (cell units) within the row of cells
/// [y − pad, y + 1 + pad] × [z − pad, z + 1 + pad], widened by `pad`; empty (low > high) where
/// it misses the row.
std::array<double, 2> rowExtent(const CellPoint (&corners)[3], double y, double z,
                                double pad) noexcept {
  CellPoint first[8], second[8];
  int count = clipPolygon(corners, 3, first, 1, y - pad, true);
  count = clipPolygon(first, count, second, 1, y + 1.0 + pad, false);
  count = clipPolygon(second, count, first, 2, z - pad, true);
  count = clipPolygon(first, count, second, 2, z + 1.0 + pad, false);
  std::array<double, 2> extent{kInfinity, -kInfinity};
  for (int k = 0; k < count; ++k) {
    extent[0] = std::min(extent[0], second[k].x - pad);
    extent[1] = std::max(extent[1], second[k].x + pad);
  }
  return extent;
}

void markOccupied(const TriangleSoA& triangles, const Frame& frame,
                  std::vector<std::int32_t>& squared) {
  const auto most = static_cast<double>(std::max({frame.dims[0], frame.dims[1], frame.dims[2]}));
  const double reach = 1e-9 + 8.0 * kEpsilon * (most + 1.0);
  const double gridRounding = 16.0 * kEpsilon * (most + 1.0) * frame.side;
  // ⌊x⌋ for x > −1 by truncating x + 1 (std::floor is a libm call without SSE4.1); the + 1
  // rounds by at most ε·n, within `reach`.
  const auto cellRange = [&frame, reach](double low, double high, std::size_t axis) {
    const auto last = static_cast<std::int64_t>(frame.dims[axis]) - 1;
    const double scale = frame.inverseSide;
    const auto first =
        static_cast<std::int64_t>((low - frame.lower[axis]) * scale - reach + 1.0) - 1;
    const auto end =
        static_cast<std::int64_t>((high - frame.lower[axis]) * scale + reach + 1.0) - 1;
    return std::array<std::size_t, 2>{
        static_cast<std::size_t>(std::clamp<std::int64_t>(first, 0, last)),
        static_cast<std::size_t>(std::clamp<std::int64_t>(end, 0, last))};
  };
  // Triangles in parallel: two may mark one cell, hence the (relaxed) atomic stores.
  const auto mark = [&squared](std::size_t cell) {
    std::atomic_ref<std::int32_t>(squared[cell]).store(0, std::memory_order_relaxed);
  };
  parallelFor(0, triangles.size(), kTrianglesPerChunk, [&](std::size_t first, std::size_t end) {
    for (std::size_t t = first; t < end; ++t) {
      const Triangle triangle = triangles.triangle(t);
      const Aabb box = triangle.bounds();
      const auto rangeX = cellRange(box.lower.x, box.upper.x, 0);
      const auto rangeY = cellRange(box.lower.y, box.upper.y, 1);
      const auto rangeZ = cellRange(box.lower.z, box.upper.z, 2);
      if (rangeX[0] == rangeX[1] && rangeY[0] == rangeY[1] && rangeZ[0] == rangeZ[1]) {
        mark(rangeX[0] + rangeY[0] * frame.strides[1] + rangeZ[0] * frame.strides[2]);
        continue;
      }
      // A box of centre C and half side h/2 meets the plane through a with normal n only if
      // |n·(C − a)| ≤ (h/2)·|n|₁. With rounding: the computed normal is off by at most 9ε·L²
      // (L ≥ every edge), which moves points of the triangle off its plane by 9ε·L³; C − a and
      // the dot product are off by a few ε of the grid's size. A zero normal tests nothing.
      const Vec3 normal = triangle.areaVector();
      const Vec3 offset = Vec3{frame.lower[0], frame.lower[1], frame.lower[2]} - triangle.a;
      const double size = length(box.extent());
      const double tolerance = (std::abs(normal.x) + std::abs(normal.y) + std::abs(normal.z)) *
                                   (frame.side * (0.5 + 1e-3) + gridRounding) +
                               16.0 * kEpsilon * size * size * size;
      const auto centre = [&frame](std::size_t cell) {
        return (static_cast<double>(cell) + 0.5) * frame.side;
      };
      // Each row of cells along x from the triangle's extent within it (clipped in cell
      // units, widened by `pad`, far more than the clipping's rounding): a long thin triangle
      // (a fan's, from a disc's centre to its rim) visits the cells along it, not every cell of
      // its box (a fan of 200,000 took 13.6 s to build that way).
      CellPoint corners[3];
      const Vec3* vertices[3] = {&triangle.a, &triangle.b, &triangle.c};
      for (std::size_t k = 0; k < 3; ++k)
        corners[k] = {(vertices[k]->x - frame.lower[0]) * frame.inverseSide,
                      (vertices[k]->y - frame.lower[1]) * frame.inverseSide,
                      (vertices[k]->z - frame.lower[2]) * frame.inverseSide};
      const double pad = 1e-6 + 64.0 * kEpsilon * (most + 1.0);
      for (std::size_t z = rangeZ[0]; z <= rangeZ[1]; ++z)
        for (std::size_t y = rangeY[0]; y <= rangeY[1]; ++y) {
          const std::array<double, 2> along =
              rowExtent(corners, static_cast<double>(y), static_cast<double>(z), pad);
          if (!(along[0] <= along[1])) continue;
          // ⌊x⌋ by truncating x + 1 (x > −1 within the clamp), as cellRange.
          const auto firstX = static_cast<std::size_t>(std::clamp<std::int64_t>(
              static_cast<std::int64_t>(std::max(along[0], -0.5) + 1.0) - 1,
              static_cast<std::int64_t>(rangeX[0]), static_cast<std::int64_t>(rangeX[1])));
          const auto lastX = static_cast<std::size_t>(std::clamp<std::int64_t>(
              static_cast<std::int64_t>(std::min(along[1], static_cast<double>(rangeX[1]) + 1.0) +
                                        1.0) -
                  1,
              static_cast<std::int64_t>(rangeX[0]), static_cast<std::int64_t>(rangeX[1])));
          const double partial =
              normal.y * (offset.y + centre(y)) + normal.z * (offset.z + centre(z));
          const std::size_t row = y * frame.strides[1] + z * frame.strides[2];
          for (std::size_t x = firstX; x <= lastX; ++x)
            if (std::abs(normal.x * (offset.x + centre(x)) + partial) <= tolerance) mark(row + x);
        }
    }
  });
}

/// The rows of cells (along x) markOccupied visits for the triangles at cells of side `side`:
/// each triangle's box's rows, y by z, its cells rounded outward, plus one for rounding.
double rowsVisited(const TriangleSoA& triangles, double side) noexcept {
  double rows = 0.0;
  const double inverse = 1.0 / side;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Aabb box = triangles.triangle(t).bounds();
    rows += (std::floor((box.upper.y - box.lower.y) * inverse) + 2.0) *
            (std::floor((box.upper.z - box.lower.z) * inverse) + 2.0);
  }
  return rows;
}

/// `side`, or the least larger side (by bisection, to 1%) at which markOccupied visits at most
/// kRowsPerTriangle rows a triangle on average: a mesh of long thin triangles (a disc as a fan
/// of slivers from its centre, as CAD exports cylinders' caps) crosses a row of cells with each,
/// so that a grid of k cells a triangle took n·√(kn) rows: 2.4 s for a fan of 262,144 slivers,
/// where an icosphere of 327,680 triangles took 0.24 s. A coarser grid bounds such a mesh less
/// tightly; meshes of triangles about as long as the cells are left as they are.
double withinMarkingWork(const TriangleSoA& triangles, double side, const Vec3& extent) noexcept {
  constexpr double kRowsPerTriangle = 64.0;
  const double budget = kRowsPerTriangle * static_cast<double>(triangles.size());
  if (rowsVisited(triangles, side) <= budget) return side;
  double enough = std::max({extent.x, extent.y, extent.z});  // one cell along the longest axis
  double tooSmall = side;
  while (enough > 1.01 * tooSmall) {
    const double middle = 0.5 * (enough + tooSmall);
    (rowsVisited(triangles, middle) <= budget ? enough : tooSmall) = middle;
  }
  return enough;
}

/// The codes of the squared distances (kSquaredCellsOfCode): the largest that stands for at most
/// each, followed by kCellPadding zero bytes.
std::vector<std::uint8_t> encode(const std::vector<std::int32_t>& squared) {
  std::array<std::uint8_t, kCap + 1> codeOf{};
  std::size_t code = 0;
  for (std::size_t d = 0; d <= kCap; ++d) {
    while (code < 255 && kSquaredCellsOfCode[code + 1] <= static_cast<double>(d))
      ++code;
    codeOf[d] = static_cast<std::uint8_t>(code);
  }
  std::vector<std::uint8_t> codes(squared.size() + kCellPadding, 0);
  parallelFor(0, squared.size(), kCellsPerChunk, [&](std::size_t first, std::size_t end) {
    for (std::size_t i = first; i < end; ++i)
      codes[i] = codeOf[static_cast<std::size_t>(squared[i])];
  });
  return codes;
}

}  // namespace

// Why this bound: a triangle lies in the union of the cells marked for it (markOccupied), so the
// distance from a point of cell c to it is at least the distance between the box of c and the
// nearest marked box, h·√Σ max(0, |c_a − o_a| − 1)²: the Euclidean distance transform of the
// occupancy dilated by one cell. Built in O(cells + marked cells); a finer bound (triangle
// distances per cell) would cost a search per cell, the tree's work.
//
// Rounding on the query side: a point may lie 3ε·n of a cell outside the box of the cell it maps
// to, and the reference kernel errs by a few ε·(size + distance). Where the cell's bound is
// positive it is at least a cell (D ≥ 1), so both are below 64ε·(n + 1) of the bound, which the
// shrink takes off; where it is 0, the distance to the box alone is the bound, and measuring it
// to the box grown by 1e-8 of its diagonal covers the kernel's absolute error.
BoundGrid::BoundGrid(const TriangleSoA& triangles, const Aabb& bounds, double cellsPerTriangle,
                     std::size_t maxCells) {
  const std::size_t count = triangles.size();
  if (count == 0 || bounds.empty()) return;
  assert(cellsPerTriangle > 0.0);
  // The grid covers the box grown by that margin, rounded outward, and points are clamped to
  // it: none maps below cell 0.
  const double margin = 1e-8 * bounds.diagonal();
  std::array<double, 3> lower{}, upper{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    lower[axis] = std::nextafter(bounds.lower[axis] - margin, -kInfinity);
    upper[axis] = std::nextafter(bounds.upper[axis] + margin, kInfinity);
  }
  const Vec3 extent{upper[0] - lower[0], upper[1] - lower[1], upper[2] - lower[2]};
#ifndef NDEBUG
  for (std::size_t t = 0; t < count; ++t) {
    const Aabb box = triangles.triangle(t).bounds();
    assert(bounds.contains(box.lower) && bounds.contains(box.upper));
  }
#endif
  const double target = std::clamp(cellsPerTriangle * static_cast<double>(count), 1.0,
                                   static_cast<double>(std::min(maxCells, kMostCells)));
  // A box of one point gets one cell of side 0: every point maps to it.
  double side = bounds.diagonal() > 0.0 ? sideFor(extent, target) : 0.0;
  if (side > 0.0) side = withinMarkingWork(triangles, side, extent);
  for (std::size_t axis = 0; axis < 3; ++axis)
    dims_[axis] =
        side > 0.0 ? static_cast<std::size_t>(std::max(std::ceil(extent[axis] / side), 1.0)) : 1;
  const std::array<std::size_t, 3> strides{1, dims_[0], dims_[0] * dims_[1]};
  cellSize_ = side;
  const double inverseCellSize = side > 0.0 ? 1.0 / side : 0.0;
  const auto most = static_cast<double>(std::max({dims_[0], dims_[1], dims_[2]}));
  const double shrink = 1.0 - 1e-9 - 64.0 * kEpsilon * (most + 1.0);

  std::vector<std::int32_t> squared(dims_[0] * dims_[1] * dims_[2], kCap);
  markOccupied(triangles, {lower, side, inverseCellSize, dims_, strides}, squared);
  transformRows(squared, dims_[0]);
  transformAxis(squared, dims_, strides, 1);
  transformAxis(squared, dims_, strides, 2);
  cells_ = encode(squared);

  for (std::size_t axis = 0; axis < 3; ++axis) {
    view_.lower[axis] = lower[axis];
    view_.upper[axis] = upper[axis];
    view_.lastCell[axis] = static_cast<std::uint32_t>(dims_[axis] - 1);
    view_.stride[axis] = static_cast<std::uint32_t>(strides[axis]);
  }
  view_.inverseCellSize = inverseCellSize;
  view_.shrink = shrink;
  view_.cellSquaredShrunk = side * side * shrink;
}

}  // namespace delta::detail
