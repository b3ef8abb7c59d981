#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::detail {

/// The squared distance, in cells², that a stored byte stands for: the byte itself up to 127
/// (exact, to 11.3 cells), then steps of 3.9% (1.9% in distance) up to 128² (128 cells) at 255.
/// A cell stores the largest code not above its squared distance.
inline constexpr std::array<double, 256> kSquaredCellsOfCode = [] {
  std::array<double, 256> table{};
  double squared = 128.0;
  for (std::size_t code = 0; code < 128; ++code)
    table[code] = static_cast<double>(code);
  for (std::size_t code = 128; code < 255; ++code) {
    table[code] = static_cast<double>(static_cast<std::int64_t>(squared));  // ⌊·⌋
    squared *= 1.0389441;                                                   // 128^(1/127)
  }
  table[255] = 128.0 * 128.0;
  return table;
}();

/// What a lookup in a BoundGrid reads (BoundGrid::view), for the batch sieves that run it in
/// vector lanes (grid_sieve.h): the same arithmetic as lowerBoundSquared, which calls it.
struct GridView {
  /// The grid's box: the mesh's box grown by a margin for rounding. Points are clamped to it.
  double lower[3], upper[3];
  double inverseCellSize;
  double shrink;              ///< the factor (just below 1) that allows for rounding
  double cellSquaredShrunk;   ///< h²·shrink: a stored squared distance's unit
  std::uint32_t lastCell[3];  ///< dims − 1 along each axis (cells along an axis ≤ 2²⁰)
  std::uint32_t stride[3];    ///< cells ≤ 2³⁰: every offset fits 32 bits
  /// One byte a cell, x fastest, then y, then z, followed by kCellPadding bytes (a four-byte
  /// gather at the last cell stays inside).
  const std::uint8_t* cells;

  /// The cell `point` maps to along each axis (lowerBoundSquared's), for a grid that is not
  /// empty.
  std::array<std::uint32_t, 3> cellOf(const Vec3& point) const noexcept {
    const double coordinates[3] = {point.x, point.y, point.z};
    std::array<std::uint32_t, 3> cell{};
    for (std::size_t axis = 0; axis < 3; ++axis)
      cell[axis] = indexAlong(axis, clamp(axis, coordinates[axis]));
    return cell;
  }

  /// `coordinate` clamped to the box along `axis`. This argument order sends a NaN to the
  /// lower face (a valid cell).
  [[gnu::always_inline]] double clamp(std::size_t axis, double coordinate) const noexcept {
    return std::min(std::max(lower[axis], coordinate), upper[axis]);
  }
  /// The cell along `axis` of a clamped coordinate: in [0, dims·(1 + 2⁻⁵²)] before the
  /// minimum, so the truncation fits 32 bits.
  [[gnu::always_inline]] std::uint32_t indexAlong(std::size_t axis, double clamped) const noexcept {
    return std::min(static_cast<std::uint32_t>((clamped - lower[axis]) * inverseCellSize),
                    lastCell[axis]);
  }

  /// lowerBoundSquared's answer, for a grid that is not empty.
  [[gnu::always_inline]] double lowerBoundSquared(const Vec3& point) const noexcept {
    // The mesh lies in the box, so for q, the point clamped to the box, and any m of the mesh,
    // |p − m|² ≥ |p − q|² + |q − m|² (the angle at q is not acute).
    double outsideSquared = 0.0;
    std::uint32_t cell = 0;
    // Not point[axis]: the point tables inline what they call, and Vec3's operator[] is not
    // always_inline (with the sanitizers, clang left it out of line).
    const double coordinates[3] = {point.x, point.y, point.z};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double clamped = clamp(axis, coordinates[axis]);
      const double gap = coordinates[axis] - clamped;  // a NaN stays in the gap
      outsideSquared += gap * gap;
      cell += indexAlong(axis, clamped) * stride[axis];
    }
    return outsideSquared * shrink + kSquaredCellsOfCode[cells[cell]] * cellSquaredShrunk;
  }
};

/// Bytes after a grid's last cell (GridView::cells).
inline constexpr std::size_t kCellPadding = 4;

/// A uniform grid of cubic cells over a mesh's box that holds, per cell, a lower bound of the
/// distance from any point of the cell to the mesh: a point farther than ε from the mesh is
/// mostly rejected by one memory read, before any tree descent.
///
/// Per cell one byte (kSquaredCellsOfCode): the squared distance, in cells, from the cell's box
/// to the nearest box of an occupied cell (one a triangle may touch), rounded down. It is the
/// exact Euclidean distance transform of the occupancy dilated by one cell, see bound_grid.cpp.
/// A point outside the box adds its distance to the box by Pythagoras.
///
/// Cost (one thread, measured on armadillo, 52k triangles, and refined_elephant, 89k, at the
/// default 2 cells a triangle): built in 4.3 and 7.1 ms (the QueryMesh beside it: 31 and
/// 51 ms), 2 bytes a triangle, lowerBoundSquared 5.5–6.5 ns a point.
///
/// Threading: built on OpenMP threads (parallelFor; the same grid on any number); immutable
/// afterwards: any number of threads may call lowerBoundSquared at once.
class BoundGrid {
 public:
  /// Cells per triangle when the caller does not say. For ε = 1% of the box diagonal, of the
  /// points uniform in the box grown by 10% a side that lie farther than ε, 1, 2, 4, 8 cells a
  /// triangle reject 89.5, 92.3, 91.3, 93.9% on armadillo (built in 2.9, 4.3, 6.8, 11.7 ms) and
  /// 92.2, 91.2, 93.8, 94.7% on refined_elephant (4.6, 7.1, 11.5, 20.0 ms): past 2, more cells
  /// buy little (the exact share also depends on where ε falls between cell distances).
  static constexpr double kDefaultCellsPerTriangle = 2.0;
  /// At most this many cells (bytes) when the caller does not say.
  static constexpr std::size_t kDefaultMaxCells = std::size_t{1} << 24;

  /// Empty: lowerBoundSquared() is 0 everywhere.
  BoundGrid() = default;

  /// The grid over `triangles` (degenerate ones included), whose vertices must all lie in
  /// `bounds` (the bound relies on it: debug-asserted): the finest grid of cubic cells over
  /// `bounds` with at most `cellsPerTriangle` (> 0) cells a triangle, at most `maxCells` (and
  /// 2^30, and 2^20 along an axis), at least one along each axis (a flat axis gets one). No
  /// triangles give the empty grid. Needs 5 bytes a cell while it builds.
  BoundGrid(const TriangleSoA& triangles, const Aabb& bounds,
            double cellsPerTriangle = kDefaultCellsPerTriangle,
            std::size_t maxCells = kDefaultMaxCells);

  /// A lower bound of the squared distance from `point` to every triangle the grid was built
  /// over, rounding included: never above kernels::closestPointOnTriangle(point, t)
  /// .distanceSquared for any of them. `point` may lie anywhere (inside the box or not); a NaN
  /// coordinate gives NaN (which rejects nothing), an infinite one +∞.
  double lowerBoundSquared(const Vec3& point) const noexcept;

  bool empty() const noexcept { return cells_.empty(); }
  /// The cells along x, y, z (all 0 when empty).
  const std::array<std::size_t, 3>& dims() const noexcept { return dims_; }
  std::size_t cellCount() const noexcept { return dims_[0] * dims_[1] * dims_[2]; }
  /// The side of a cell (0 when empty).
  double cellSize() const noexcept { return cellSize_; }
  /// Bytes held on the heap.
  std::size_t memoryBytes() const noexcept { return cells_.capacity(); }
  /// The lookup's data (not for an empty grid), pointing into this grid.
  GridView view() const noexcept {
    GridView view = view_;
    view.cells = cells_.data();
    return view;
  }

 private:
  GridView view_{};  ///< all but `cells` (a copied grid has cells of its own)
  double cellSize_ = 0.0;
  std::array<std::size_t, 3> dims_{};
  std::vector<std::uint8_t> cells_;  ///< GridView::cells
};

inline double BoundGrid::lowerBoundSquared(const Vec3& point) const noexcept {
  return cells_.empty() ? 0.0 : view().lowerBoundSquared(point);
}

}  // namespace delta::detail
