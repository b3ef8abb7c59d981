// The exact point–triangle kernel on eight triangles at once, for the nearest-triangle search
// on AVX-512 and on AVX2 (nearest.cpp; AVX2 in two registers of four): every lane's squared
// distance is, bit for bit, what kernels::closestPointOnTriangle computes for that triangle.
// The kernel is written once (exact_lanes_body.h) and built per ISA below.
//
// Why bit for bit: the search's answer is that of the loop over all triangles with the scalar
// kernel, ties to the smallest id. Here each lane runs the scalar kernel's operations on its own
// triangle in the same order, with the same roundings: IEEE sums, products, quotients and fused
// multiply–adds round alike in a lane and in a scalar register, the data-dependent branches
// become selects whose both arms are computed, and this file is compiled without contracting
// a·b + c into fused operations (CMakeLists.txt), which the scalar kernel, built for baseline
// x86-64, never has; where the scalar kernel runs its exact boundary test, the lane takes its
// value. Only zeros' signs may differ (the scalar kernel adds a few signed zeros that change
// nothing else), and no squared distance depends on them.
#include "exact_lanes.h"

#if defined(DELTA_X86_ISAS)
#include <immintrin.h>

#include <algorithm>
#include <limits>

#include "delta/kernels/point_triangle.h"

namespace delta::detail {
namespace {

namespace avx512 {

#define DELTA_EXACT_TARGET [[gnu::target("avx512f,avx512dq,avx512vl,fma"), gnu::always_inline]]
#define DELTA_EXACT_KERNEL_TARGET [[gnu::target("avx512f,avx512dq,avx512vl,fma")]]

using Lanes = __m512d;  // eight doubles, with GCC's and Clang's vector operators
using Mask = __mmask8;
constexpr std::size_t kWidth = 8;

DELTA_EXACT_TARGET inline Lanes splat(double value) {
  return _mm512_set1_pd(value);
}
DELTA_EXACT_TARGET inline Lanes load(const double* values) {
  return _mm512_load_pd(values);
}
DELTA_EXACT_TARGET inline void store(double* values, const Lanes& lanes) {
  _mm512_store_pd(values, lanes);
}
DELTA_EXACT_TARGET inline Lanes fmadd(const Lanes& a, const Lanes& b, const Lanes& c) {
  return _mm512_fmadd_pd(a, b, c);
}
DELTA_EXACT_TARGET inline Lanes select(Mask mask, const Lanes& yes, const Lanes& no) {
  return _mm512_mask_blend_pd(mask, no, yes);
}
template <int Predicate>
DELTA_EXACT_TARGET inline Mask compare(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, Predicate);
}
DELTA_EXACT_TARGET inline Mask both(Mask a, Mask b) {
  return a & b;
}
DELTA_EXACT_TARGET inline unsigned bits(Mask mask) {
  return mask;
}

#include "exact_lanes_body.h"

#undef DELTA_EXACT_TARGET
#undef DELTA_EXACT_KERNEL_TARGET

}  // namespace avx512

namespace avx2 {

#define DELTA_EXACT_TARGET [[gnu::target("avx2,fma"), gnu::always_inline]]
#define DELTA_EXACT_KERNEL_TARGET [[gnu::target("avx2,fma")]]

using Lanes = __m256d;  // four doubles
using Mask = __m256d;   // all ones in the lanes set
constexpr std::size_t kWidth = 4;

DELTA_EXACT_TARGET inline Lanes splat(double value) {
  return _mm256_set1_pd(value);
}
DELTA_EXACT_TARGET inline Lanes load(const double* values) {
  return _mm256_load_pd(values);
}
DELTA_EXACT_TARGET inline void store(double* values, const Lanes& lanes) {
  _mm256_store_pd(values, lanes);
}
DELTA_EXACT_TARGET inline Lanes fmadd(const Lanes& a, const Lanes& b, const Lanes& c) {
  return _mm256_fmadd_pd(a, b, c);
}
DELTA_EXACT_TARGET inline Lanes select(const Mask& mask, const Lanes& yes, const Lanes& no) {
  return _mm256_blendv_pd(no, yes, mask);
}
template <int Predicate>
DELTA_EXACT_TARGET inline Mask compare(const Lanes& a, const Lanes& b) {
  return _mm256_cmp_pd(a, b, Predicate);
}
DELTA_EXACT_TARGET inline Mask both(const Mask& a, const Mask& b) {
  return _mm256_and_pd(a, b);
}
DELTA_EXACT_TARGET inline unsigned bits(const Mask& mask) {
  return static_cast<unsigned>(_mm256_movemask_pd(mask));
}

#include "exact_lanes_body.h"

#undef DELTA_EXACT_TARGET
#undef DELTA_EXACT_KERNEL_TARGET

}  // namespace avx2

}  // namespace

[[gnu::target("avx512f,avx512dq,avx512vl,fma")]] void exactDistancesSquared8(
    const QueryMeshData& mesh, const Vec3& point, const std::uint32_t* sorted, std::size_t count,
    double* out) noexcept {
  avx512::distances(mesh, point, sorted, count, out);
}

[[gnu::target("avx2,fma")]] void exactDistancesSquared8Avx2(const QueryMeshData& mesh,
                                                            const Vec3& point,
                                                            const std::uint32_t* sorted,
                                                            std::size_t count,
                                                            double* out) noexcept {
  avx2::distances(mesh, point, sorted, std::min<std::size_t>(count, 4), out);
  if (count > 4) avx2::distances(mesh, point, sorted + 4, count - 4, out + 4);
}

}  // namespace delta::detail

#endif
