#pragma once

// The exact point–triangle kernel in lanes, for the nearest-triangle search of the ISA this file
// is compiled for (query/isa/point_table.cpp, once per ISA): every lane's squared distance is,
// bit for bit, what kernels::closestPointOnTriangle computes for that triangle. The kernel is
// written once (exact_lanes_body.h) over a handful of primitives, defined here for the ISA the
// compiler targets (its predefined macros: AVX-512, AVX2 with FMA, NEON); kExactLanes is their
// width, 0 where there are none.
//
// Why bit for bit: the search's answer is that of the loop over all triangles with the scalar
// kernel, ties to the smallest id. Here each lane runs the scalar kernel's operations on its own
// triangle in the same order, with the same roundings: IEEE sums, products, quotients and fused
// multiply–adds round alike in a lane and in a scalar register, the data-dependent branches
// become selects whose both arms are computed, and the point table is compiled without
// contracting a·b + c into fused operations (src/CMakeLists.txt), as the scalar kernel is; where
// the scalar kernel runs its exact boundary test, the lane takes its value. Only zeros' signs may
// differ (the scalar kernel adds a few signed zeros that change nothing else), and no squared
// distance depends on them.
//
// Only for a per-ISA translation unit: everything here is in its namespace,
// delta::detail::DELTA_ISA.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "delta/kernels/point_triangle.h"

#include "intrinsics.h"
#include "query_mesh_data.h"

#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__) && defined(__FMA__)
#define DELTA_EXACT_LANES_AVX512
#elif defined(__AVX2__) && defined(__FMA__)
#define DELTA_EXACT_LANES_AVX2
#elif defined(__aarch64__) && defined(__ARM_NEON)
#define DELTA_EXACT_LANES_NEON
#endif

namespace delta::detail::DELTA_ISA {

#if defined(DELTA_EXACT_LANES_AVX512)

namespace lanes {

using Lanes = __m512d;  // eight doubles, with GCC's and Clang's vector operators
using Mask = __mmask8;
constexpr std::size_t kWidth = 8;

[[gnu::always_inline]] inline Lanes splat(double value) {
  return _mm512_set1_pd(value);
}
[[gnu::always_inline]] inline Lanes load(const double* values) {
  return _mm512_load_pd(values);
}
[[gnu::always_inline]] inline void store(double* values, const Lanes& lanes) {
  _mm512_store_pd(values, lanes);
}
[[gnu::always_inline]] inline Lanes fmadd(const Lanes& a, const Lanes& b, const Lanes& c) {
  return _mm512_fmadd_pd(a, b, c);
}
[[gnu::always_inline]] inline Lanes squareRoot(const Lanes& a) {
  return _mm512_sqrt_pd(a);
}
[[gnu::always_inline]] inline Lanes select(Mask mask, const Lanes& yes, const Lanes& no) {
  return _mm512_mask_blend_pd(mask, no, yes);
}
[[gnu::always_inline]] inline Mask both(Mask a, Mask b) {
  return a & b;
}
[[gnu::always_inline]] inline unsigned bits(Mask mask) {
  return mask;
}
[[gnu::always_inline]] inline Mask greaterOrEqual(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_GE_OQ);
}
[[gnu::always_inline]] inline Mask greater(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_GT_OQ);
}
[[gnu::always_inline]] inline Mask less(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_LT_OQ);
}
[[gnu::always_inline]] inline Mask lessOrEqual(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_LE_OQ);
}
[[gnu::always_inline]] inline Mask equal(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_EQ_OQ);
}

#include "exact_lanes_body.h"

}  // namespace lanes

#elif defined(DELTA_EXACT_LANES_AVX2)

namespace lanes {

using Lanes = __m256d;  // four doubles
using Mask = __m256d;   // all ones in the lanes set
constexpr std::size_t kWidth = 4;

[[gnu::always_inline]] inline Lanes splat(double value) {
  return _mm256_set1_pd(value);
}
[[gnu::always_inline]] inline Lanes load(const double* values) {
  return _mm256_load_pd(values);
}
[[gnu::always_inline]] inline void store(double* values, const Lanes& lanes) {
  _mm256_store_pd(values, lanes);
}
[[gnu::always_inline]] inline Lanes fmadd(const Lanes& a, const Lanes& b, const Lanes& c) {
  return _mm256_fmadd_pd(a, b, c);
}
[[gnu::always_inline]] inline Lanes squareRoot(const Lanes& a) {
  return _mm256_sqrt_pd(a);
}
[[gnu::always_inline]] inline Lanes select(const Mask& mask, const Lanes& yes, const Lanes& no) {
  return _mm256_blendv_pd(no, yes, mask);
}
[[gnu::always_inline]] inline Mask both(const Mask& a, const Mask& b) {
  return _mm256_and_pd(a, b);
}
[[gnu::always_inline]] inline unsigned bits(const Mask& mask) {
  return static_cast<unsigned>(_mm256_movemask_pd(mask));
}
[[gnu::always_inline]] inline Mask greaterOrEqual(const Lanes& a, const Lanes& b) {
  return _mm256_cmp_pd(a, b, _CMP_GE_OQ);
}
[[gnu::always_inline]] inline Mask greater(const Lanes& a, const Lanes& b) {
  return _mm256_cmp_pd(a, b, _CMP_GT_OQ);
}
[[gnu::always_inline]] inline Mask less(const Lanes& a, const Lanes& b) {
  return _mm256_cmp_pd(a, b, _CMP_LT_OQ);
}
[[gnu::always_inline]] inline Mask lessOrEqual(const Lanes& a, const Lanes& b) {
  return _mm256_cmp_pd(a, b, _CMP_LE_OQ);
}
[[gnu::always_inline]] inline Mask equal(const Lanes& a, const Lanes& b) {
  return _mm256_cmp_pd(a, b, _CMP_EQ_OQ);
}

#include "exact_lanes_body.h"

}  // namespace lanes

#elif defined(DELTA_EXACT_LANES_NEON)

namespace lanes {

using Lanes = float64x2_t;  // two doubles, with GCC's and Clang's vector operators
using Mask = uint64x2_t;    // all ones in the lanes set
constexpr std::size_t kWidth = 2;

[[gnu::always_inline]] inline Lanes splat(double value) {
  return vdupq_n_f64(value);
}
[[gnu::always_inline]] inline Lanes load(const double* values) {
  return vld1q_f64(values);
}
[[gnu::always_inline]] inline void store(double* values, const Lanes& lanes) {
  vst1q_f64(values, lanes);
}
[[gnu::always_inline]] inline Lanes fmadd(const Lanes& a, const Lanes& b, const Lanes& c) {
  return vfmaq_f64(c, a, b);  // c + a·b, one rounding: std::fma(a, b, c)
}
[[gnu::always_inline]] inline Lanes squareRoot(const Lanes& a) {
  return vsqrtq_f64(a);  // correctly rounded, as std::sqrt
}
[[gnu::always_inline]] inline Lanes select(const Mask& mask, const Lanes& yes, const Lanes& no) {
  return vbslq_f64(mask, yes, no);
}
[[gnu::always_inline]] inline Mask both(const Mask& a, const Mask& b) {
  return vandq_u64(a, b);
}
[[gnu::always_inline]] inline unsigned bits(const Mask& mask) {
  return static_cast<unsigned>((vgetq_lane_u64(mask, 0) & 1) | (vgetq_lane_u64(mask, 1) & 1) << 1);
}
// The ordered comparisons (false where either is NaN), as _CMP_*_OQ.
[[gnu::always_inline]] inline Mask greaterOrEqual(const Lanes& a, const Lanes& b) {
  return vcgeq_f64(a, b);
}
[[gnu::always_inline]] inline Mask greater(const Lanes& a, const Lanes& b) {
  return vcgtq_f64(a, b);
}
[[gnu::always_inline]] inline Mask less(const Lanes& a, const Lanes& b) {
  return vcltq_f64(a, b);
}
[[gnu::always_inline]] inline Mask lessOrEqual(const Lanes& a, const Lanes& b) {
  return vcleq_f64(a, b);
}
[[gnu::always_inline]] inline Mask equal(const Lanes& a, const Lanes& b) {
  return vceqq_f64(a, b);
}

#include "exact_lanes_body.h"

}  // namespace lanes

#endif

#if defined(DELTA_EXACT_LANES_AVX512) || defined(DELTA_EXACT_LANES_AVX2) || \
    defined(DELTA_EXACT_LANES_NEON)
constexpr std::size_t kExactLanes = lanes::kWidth;

/// lanes::distances over up to eight sorted triangles, kExactLanes at a time (all of it inlined:
/// the point table's entries are, point_table.cpp; itself out of line, one copy in settle's
/// loop: inlined there it cost 2.5% of W1).
[[gnu::noinline, gnu::flatten]] inline void exactDistancesSquared8(const QueryMeshData& mesh,
                                                                   const Vec3& point,
                                                                   const std::uint32_t* sorted,
                                                                   std::size_t count,
                                                                   double* out) noexcept {
  for (std::size_t done = 0; done < count; done += kExactLanes)
    lanes::distances(mesh, point, sorted + done, std::min(kExactLanes, count - done), out + done);
}
#else
constexpr std::size_t kExactLanes = 0;

/// No lanes on this ISA: never called (the descent runs the scalar kernel).
inline void exactDistancesSquared8(const QueryMeshData&, const Vec3&, const std::uint32_t*,
                                   std::size_t, double*) noexcept {}
#endif

}  // namespace delta::detail::DELTA_ISA
