// Two doubles to a vector register, for loops whose lanes are independent (the DEM's batched
// contact law and turns): SSE2 on x86-64, Advanced SIMD on AArch64, through GCC's and Clang's
// vector extension. Every operation rounds each lane as its scalar operation does, so code written
// with these gives each lane the bits of the scalar code it mirrors, operation for operation.
#pragma once

#include <cmath>
#include <cstddef>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

#include "delta/core/vec3.h"

namespace delta::detail {

/// Two doubles, one a lane (GCC's and Clang's vector extension: +, −, ×, ÷ and comparisons lane
/// by lane, each rounded as the scalar operation).
using Two = double __attribute__((vector_size(16)));
/// A comparison's answer: all ones in a lane where it holds.
using TwoMask = long long __attribute__((vector_size(16)));

[[gnu::always_inline]] inline Two splat(double value) noexcept {
  return Two{value, value};
}

/// √ lane by lane, correctly rounded as std::sqrt.
[[gnu::always_inline]] inline Two squareRoot(Two v) noexcept {
#if defined(__SSE2__)
  return reinterpret_cast<Two>(_mm_sqrt_pd(reinterpret_cast<__m128d>(v)));
#elif defined(__aarch64__) && defined(__ARM_NEON)
  return reinterpret_cast<Two>(vsqrtq_f64(reinterpret_cast<float64x2_t>(v)));
#else
  return Two{std::sqrt(v[0]), std::sqrt(v[1])};
#endif
}

/// Two Vec3, a coordinate to a vector; the operations are Vec3's, in its order.
struct Two3 {
  Two x, y, z;

  /// a in lane 0, b in lane 1, put together in registers: a lane written to memory on its own and
  /// read back in a vector waits for the store (no store forwards into a wider load).
  static Two3 of(const Vec3& a, const Vec3& b) noexcept {
    return {Two{a.x, b.x}, Two{a.y, b.y}, Two{a.z, b.z}};
  }

  Vec3 lane(std::size_t k) const noexcept { return {x[k], y[k], z[k]}; }
};

[[gnu::always_inline]] inline Two3 operator+(const Two3& a, const Two3& b) noexcept {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
[[gnu::always_inline]] inline Two3 operator-(const Two3& a, const Two3& b) noexcept {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
[[gnu::always_inline]] inline Two3 operator*(const Two3& a, Two s) noexcept {
  return {a.x * s, a.y * s, a.z * s};
}
[[gnu::always_inline]] inline Two dot(const Two3& a, const Two3& b) noexcept {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
[[gnu::always_inline]] inline Two3 cross(const Two3& a, const Two3& b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
[[gnu::always_inline]] inline Two length(const Two3& v) noexcept {
  return squareRoot(dot(v, v));
}
/// a where `mask` holds, b elsewhere.
[[gnu::always_inline]] inline Two3 select(TwoMask mask, const Two3& a, const Two3& b) noexcept {
  return {mask ? a.x : b.x, mask ? a.y : b.y, mask ? a.z : b.z};
}

}  // namespace delta::detail
