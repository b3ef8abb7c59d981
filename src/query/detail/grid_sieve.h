#pragma once

// The distance-bound grid's sieve of a block of points (point_distance.cpp's answerAll), in
// builds of the same arithmetic: a plain loop that any ISA compiles, and lanes of eight (AVX-512)
// or four (AVX2) where the translation unit is compiled for them (the point tables,
// query/isa/point_table.cpp). Every build keeps the same points: each lane computes
// GridView::lowerBoundSquared's operations in its order, without fusing, and its clamps send a
// NaN where the scalar std::max and std::min do.

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "delta/core/vec3.h"
#include "delta/mesh/coordinate_range.h"

#include "bound_grid.h"

#if defined(__AVX2__) && defined(__FMA__)
#define DELTA_GRID_SIEVE_AVX2
#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
#define DELTA_GRID_SIEVE_AVX512
#endif
#include "intrinsics.h"
#endif

namespace delta::detail {

/// The points [first, count) of sievePoints, one at a time; `kept` and its count `held` go on.
[[gnu::always_inline]] inline std::size_t sievePlain(const GridView& grid, const Vec3* points,
                                                     std::size_t first, std::size_t count,
                                                     double limit, std::uint32_t* kept,
                                                     std::size_t held, bool& inRange) noexcept {
  bool fine = true;
  for (std::size_t i = first; i < count; ++i) {
    const Vec3& p = points[i];  // inCoordinateRange, here where the tables inline it
    fine = fine && std::fabs(p.x) <= kLargestCoordinate && std::fabs(p.y) <= kLargestCoordinate &&
           std::fabs(p.z) <= kLargestCoordinate;
    // Without a branch on the answer, which a tenth of the points take the other way at random:
    // every offset is written, the next overwriting it unless the point is in doubt.
    kept[held] = static_cast<std::uint32_t>(i);
    held += !(grid.lowerBoundSquared(points[i]) > limit);
  }
  if (!fine) inRange = false;
  return held;
}

#if defined(DELTA_GRID_SIEVE_AVX2)
/// The absolute values of four lanes.
[[gnu::always_inline]] inline __m256d absolute4(__m256d v) noexcept {
  return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
}
#endif

/// The offsets i < count of `points` (in the mesh's prepared frame) whose grid bound is not
/// above `limit` (a NaN bound keeps its point), ascending, into `kept` (room for `count`);
/// returns how many. Clears `inRange` where a point is not inCoordinateRange (a NaN, an
/// infinity, a coordinate beyond the range), and leaves it otherwise.
[[gnu::always_inline]] inline std::size_t sievePoints(const GridView& grid, const Vec3* points,
                                                      std::size_t count, double limit,
                                                      std::uint32_t* kept, bool& inRange) noexcept {
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  std::size_t i = 0, held = 0;
#if defined(DELTA_GRID_SIEVE_AVX512)
  // Eight points a step: their 24 coordinates in three registers, spread to x, y, z.
  const __m512i xFirst = _mm512_setr_epi64(0, 3, 6, 9, 12, 15, 0, 0);
  const __m512i xLast = _mm512_setr_epi64(0, 0, 0, 0, 0, 0, 2, 5);
  const __m512i yFirst = _mm512_setr_epi64(1, 4, 7, 10, 13, 0, 0, 0);
  const __m512i yLast = _mm512_setr_epi64(0, 0, 0, 0, 0, 0, 3, 6);
  const __m512i zFirst = _mm512_setr_epi64(2, 5, 8, 11, 14, 0, 0, 0);
  const __m512i zLast = _mm512_setr_epi64(0, 0, 0, 0, 0, 1, 4, 7);
  const __m512d largest = _mm512_set1_pd(kLargestCoordinate);
  const __m512d sign = _mm512_set1_pd(-0.0);
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (; i + 8 <= count; i += 8) {
    const double* at = &points[i].x;
    const __m512d v0 = _mm512_loadu_pd(at), v1 = _mm512_loadu_pd(at + 8),
                  v2 = _mm512_loadu_pd(at + 16);
    __m512d axes[3];
    axes[0] = _mm512_mask_permutexvar_pd(_mm512_permutex2var_pd(v0, xFirst, v1), 0xC0, xLast, v2);
    axes[1] = _mm512_mask_permutexvar_pd(_mm512_permutex2var_pd(v0, yFirst, v1), 0xE0, yLast, v2);
    axes[2] = _mm512_mask_permutexvar_pd(_mm512_permutex2var_pd(v0, zFirst, v1), 0xE0, zLast, v2);
    __m512d outsideSquared = _mm512_setzero_pd();
    __m256i cell = _mm256_setzero_si256();
    __mmask8 fine = 0xFF;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const __m512d coordinate = axes[axis];
      fine &= _mm512_cmp_pd_mask(_mm512_andnot_pd(sign, coordinate), largest, _CMP_LE_OQ);
      // max(x, lower) is lower for a NaN x, as std::max(lower, x) is; min keeps it.
      const __m512d clamped =
          _mm512_min_pd(_mm512_max_pd(coordinate, _mm512_set1_pd(grid.lower[axis])),
                        _mm512_set1_pd(grid.upper[axis]));
      const __m512d gap = _mm512_sub_pd(coordinate, clamped);
      outsideSquared = _mm512_add_pd(outsideSquared, _mm512_mul_pd(gap, gap));
      const __m256i index = _mm512_cvttpd_epu32(
          _mm512_mul_pd(_mm512_sub_pd(clamped, _mm512_set1_pd(grid.lower[axis])),
                        _mm512_set1_pd(grid.inverseCellSize)));
      cell = _mm256_add_epi32(
          cell,
          _mm256_mullo_epi32(
              _mm256_min_epu32(index, _mm256_set1_epi32(static_cast<int>(grid.lastCell[axis]))),
              _mm256_set1_epi32(static_cast<int>(grid.stride[axis]))));
    }
    // Four bytes from each cell's (the grid's padding keeps the last in bounds); its own is the
    // lowest.
    const __m256i code =
        _mm256_and_si256(_mm256_i32gather_epi32(reinterpret_cast<const int*>(grid.cells), cell, 1),
                         _mm256_set1_epi32(0xFF));
    const __m512d squaredCells = _mm512_i32gather_pd(code, kSquaredCellsOfCode.data(), 8);
    const __m512d bound =
        _mm512_add_pd(_mm512_mul_pd(outsideSquared, _mm512_set1_pd(grid.shrink)),
                      _mm512_mul_pd(squaredCells, _mm512_set1_pd(grid.cellSquaredShrunk)));
    const __mmask8 keep = _mm512_cmp_pd_mask(bound, _mm512_set1_pd(limit), _CMP_NGT_UQ);
    if (fine != 0xFF) inRange = false;
    // Compressed in a register and stored whole (held + 8 ≤ i + 8 ≤ count: in the room): a
    // compressing store to memory is microcoded on Zen 4 and 5, a third of the sieve's time.
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(kept + held),
                        _mm256_maskz_compress_epi32(
                            keep, _mm256_add_epi32(lanes, _mm256_set1_epi32(static_cast<int>(i)))));
    held += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(keep)));
  }
#elif defined(DELTA_GRID_SIEVE_AVX2)
  // Four points a step: their 12 coordinates in three registers, spread to x, y, z by blends
  // and one permutation each.
  const __m256d largest = _mm256_set1_pd(kLargestCoordinate);
  for (; i + 4 <= count; i += 4) {
    const double* at = &points[i].x;
    const __m256d v0 = _mm256_loadu_pd(at), v1 = _mm256_loadu_pd(at + 4),
                  v2 = _mm256_loadu_pd(at + 8);
    __m256d axes[3];
    // x0 x3 x6 x9 = v0[0] v0[3] v1[2] v2[1]; y: v0[1] v1[0] v1[3] v2[2]; z: v0[2] v1[1] v2[0] v2[3]
    axes[0] = _mm256_permute4x64_pd(_mm256_blend_pd(_mm256_blend_pd(v0, v1, 0b0100), v2, 0b0010),
                                    0b01'10'11'00);
    axes[1] = _mm256_permute4x64_pd(_mm256_blend_pd(_mm256_blend_pd(v0, v1, 0b1001), v2, 0b0100),
                                    0b10'11'00'01);
    axes[2] = _mm256_permute4x64_pd(_mm256_blend_pd(_mm256_blend_pd(v0, v1, 0b0010), v2, 0b1001),
                                    0b11'00'01'10);
    __m256d outsideSquared = _mm256_setzero_pd();
    __m128i cell = _mm_setzero_si128();
    int fine = 0xF;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const __m256d coordinate = axes[axis];
      fine &= _mm256_movemask_pd(_mm256_cmp_pd(absolute4(coordinate), largest, _CMP_LE_OQ));
      // max(x, lower) is lower for a NaN x, as std::max(lower, x) is; min keeps it.
      const __m256d clamped =
          _mm256_min_pd(_mm256_max_pd(coordinate, _mm256_set1_pd(grid.lower[axis])),
                        _mm256_set1_pd(grid.upper[axis]));
      const __m256d gap = _mm256_sub_pd(coordinate, clamped);
      outsideSquared = _mm256_add_pd(outsideSquared, _mm256_mul_pd(gap, gap));
      // Below 2³¹ (cells along an axis ≤ 2²⁰): the signed truncation is the unsigned one.
      const __m128i index = _mm256_cvttpd_epi32(
          _mm256_mul_pd(_mm256_sub_pd(clamped, _mm256_set1_pd(grid.lower[axis])),
                        _mm256_set1_pd(grid.inverseCellSize)));
      cell = _mm_add_epi32(
          cell, _mm_mullo_epi32(
                    _mm_min_epu32(index, _mm_set1_epi32(static_cast<int>(grid.lastCell[axis]))),
                    _mm_set1_epi32(static_cast<int>(grid.stride[axis]))));
    }
    const __m128i code =
        _mm_and_si128(_mm_i32gather_epi32(reinterpret_cast<const int*>(grid.cells), cell, 1),
                      _mm_set1_epi32(0xFF));
    const __m256d squaredCells = _mm256_i32gather_pd(kSquaredCellsOfCode.data(), code, 8);
    const __m256d bound =
        _mm256_add_pd(_mm256_mul_pd(outsideSquared, _mm256_set1_pd(grid.shrink)),
                      _mm256_mul_pd(squaredCells, _mm256_set1_pd(grid.cellSquaredShrunk)));
    const auto keep = static_cast<unsigned>(
        _mm256_movemask_pd(_mm256_cmp_pd(bound, _mm256_set1_pd(limit), _CMP_NGT_UQ)));
    if (fine != 0xF) inRange = false;
    for (std::size_t lane = 0; lane < 4; ++lane) {
      kept[held] = static_cast<std::uint32_t>(i + lane);
      held += (keep >> lane) & 1u;
    }
  }
#endif
  return sievePlain(grid, points, i, count, limit, kept, held, inRange);
}

}  // namespace delta::detail
