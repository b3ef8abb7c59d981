// The exact point–triangle kernel on eight triangles at once, for the nearest-triangle search
// on AVX-512 (nearest.cpp): every lane's squared distance is, bit for bit, what
// kernels::closestPointOnTriangle computes for that triangle.
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

#include <limits>

namespace delta::detail {
namespace {

using Lanes = __m512d;  // eight doubles, with GCC's and Clang's vector operators

#define DELTA_EXACT_TARGET [[gnu::target("avx512f,avx512dq,avx512vl,fma"), gnu::always_inline]]

struct Vec {
  Lanes x, y, z;
};

DELTA_EXACT_TARGET inline Lanes splat(double value) {
  return _mm512_set1_pd(value);
}
DELTA_EXACT_TARGET inline Vec minus(const Vec& a, const Vec& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
DELTA_EXACT_TARGET inline Vec plus(const Vec& a, const Vec& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
DELTA_EXACT_TARGET inline Vec times(const Vec& a, const Lanes& s) {
  return {a.x * s, a.y * s, a.z * s};
}
DELTA_EXACT_TARGET inline Lanes dot(const Vec& a, const Vec& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
DELTA_EXACT_TARGET inline Vec cross(const Vec& a, const Vec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// Kahan's a·b − c·d (robust_geometry.h's differenceOfProducts).
DELTA_EXACT_TARGET inline Lanes differenceOfProducts(const Lanes& a, const Lanes& b, const Lanes& c,
                                                     const Lanes& d) {
  const Lanes cd = c * d;
  const Lanes roundingOfCd = _mm512_fmadd_pd(-c, d, cd);
  return _mm512_fmadd_pd(a, b, -cd) + roundingOfCd;
}
DELTA_EXACT_TARGET inline Lanes select(__mmask8 mask, const Lanes& yes, const Lanes& no) {
  return _mm512_mask_blend_pd(mask, no, yes);
}
DELTA_EXACT_TARGET inline Vec select(__mmask8 mask, const Vec& yes, const Vec& no) {
  return {select(mask, yes.x, no.x), select(mask, yes.y, no.y), select(mask, yes.z, no.z)};
}
DELTA_EXACT_TARGET inline __mmask8 greaterOrEqual(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_GE_OQ);
}
DELTA_EXACT_TARGET inline __mmask8 greater(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_GT_OQ);
}
DELTA_EXACT_TARGET inline __mmask8 less(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_LT_OQ);
}
DELTA_EXACT_TARGET inline __mmask8 equal(const Lanes& a, const Lanes& b) {
  return _mm512_cmp_pd_mask(a, b, _CMP_EQ_OQ);
}

/// robust_geometry.h's closestOnSegment, its squared distance: s0 + t·direction, t the clamped
/// projection parameter (0 for a zero-length segment), exactly s1 at t = 1.
DELTA_EXACT_TARGET inline Lanes segmentDistance(const Vec& p, const Vec& s0, const Vec& s1,
                                                const Vec& direction) {
  const Lanes zero = splat(0.0), one = splat(1.0);
  const Lanes squaredLength = dot(direction, direction);
  const __mmask8 long_ = greater(squaredLength, zero);
  // std::clamp(x, 0, 1): x < 0 ? 0 : 1 < x ? 1 : x.
  const Lanes x = dot(minus(p, s0), direction) / select(long_, squaredLength, one);
  Lanes t = select(less(x, zero), zero, select(less(one, x), one, x));
  t = select(long_, t, zero);
  const Vec point = select(equal(t, one), s1, plus(s0, times(direction, t)));
  const Vec offset = minus(p, point);
  return dot(offset, offset);
}

DELTA_EXACT_TARGET inline Lanes lengthSquared(const Vec& v) {
  return dot(v, v);
}

}  // namespace

[[gnu::target("avx512f,avx512dq,avx512vl,fma")]] void exactDistancesSquared8(
    const QueryMeshData& mesh, const Vec3& point, const std::uint32_t* sorted, std::size_t count,
    double* out) noexcept {
  // The lanes' triangles (the padding repeats the first: finite, and ignored).
  alignas(64) double corner[9][8];
  for (std::size_t i = 0; i < 8; ++i) {
    const Triangle t = mesh.triangle(sorted[i < count ? i : 0]);
    const Vec3* vertices[3] = {&t.a, &t.b, &t.c};
    for (std::size_t v = 0; v < 3; ++v)
      for (std::size_t axis = 0; axis < 3; ++axis)
        corner[3 * v + axis][i] = (*vertices[v])[axis];
  }
  const Vec a{_mm512_load_pd(corner[0]), _mm512_load_pd(corner[1]), _mm512_load_pd(corner[2])};
  const Vec b{_mm512_load_pd(corner[3]), _mm512_load_pd(corner[4]), _mm512_load_pd(corner[5])};
  const Vec c{_mm512_load_pd(corner[6]), _mm512_load_pd(corner[7]), _mm512_load_pd(corner[8])};
  const Vec p{splat(point.x), splat(point.y), splat(point.z)};

  // closestPointOnTriangle: the frame of a.
  const Vec u = minus(b, a), v = minus(c, a), r = minus(p, a);
  const Lanes zero = splat(0.0);
  const Vec origin{zero, zero, zero};
  // makeLocalTriangle(0, u, v): the edges, the longest, the accurate normal, flatness.
  const Vec edge0 = minus(u, origin), edge1 = minus(v, u), edge2 = minus(origin, v);
  // std::max({…}) keeps the first of equals and skips what does not compare greater.
  Lanes longest = lengthSquared(edge0);
  longest = select(less(longest, lengthSquared(edge1)), lengthSquared(edge1), longest);
  longest = select(less(longest, lengthSquared(edge2)), lengthSquared(edge2), longest);
  const Vec u0 = minus(u, origin), v0 = minus(v, origin);  // accurateNormal's b − a, c − a
  const Vec plain = cross(u0, v0);
  const __mmask8 wellConditioned =
      greaterOrEqual(lengthSquared(plain), splat(0.5) * lengthSquared(u0) * lengthSquared(v0));
  // The exact differences of b − 0 and c − 0 have zero low parts: accurateCross alone (plus
  // signed zeros).
  const Vec accurate{differenceOfProducts(u0.y, v0.z, u0.z, v0.y),
                     differenceOfProducts(u0.z, v0.x, u0.x, v0.z),
                     differenceOfProducts(u0.x, v0.y, u0.y, v0.x)};
  const Vec normal = select(wellConditioned, plain, accurate);
  const Lanes normalSquared = lengthSquared(normal);
  const Lanes flatBound = splat(4.0 * std::numeric_limits<double>::epsilon()) * longest;
  const __mmask8 notFlat = greater(normalSquared, flatBound * flatBound);

  // closestOnLocalFace: the projection, where it lies inside all three edges.
  const Vec ap = minus(r, origin);
  const Lanes areaC = dot(normal, cross(edge0, ap));
  const Lanes areaA = dot(normal, cross(edge1, minus(r, u)));
  const Lanes areaB = dot(normal, cross(edge2, minus(r, v)));
  const Lanes sum = areaA + areaB + areaC;
  const __mmask8 inside = notFlat & greaterOrEqual(areaC, zero) & greaterOrEqual(areaA, zero) &
                          greaterOrEqual(areaB, zero) & greater(sum, zero);
  const Lanes safeSquared = select(notFlat, normalSquared, splat(1.0));
  const Vec foot = minus(r, times(normal, dot(normal, ap) / safeSquared));
  const Lanes face = lengthSquared(minus(r, foot));

  // The nearest of the three edges (the first strictly smaller squared distance, as the scalar
  // loop takes it).
  Lanes edges = splat(std::numeric_limits<double>::infinity());
  for (const Lanes& distance :
       {segmentDistance(r, origin, u, edge0), segmentDistance(r, u, v, edge1),
        segmentDistance(r, v, origin, edge2)})
    edges = select(less(distance, edges), distance, edges);
  const Lanes squared = select(inside, face, edges);
  // The scalar kernel's exact boundary test (a point exactly on a vertex or an edge gets 0): it
  // runs where the square is positive and within kExactBoundaryCheck·L², the lanes that pass
  // take the scalar kernel's value (rare: a point within rounding of a triangle's boundary).
  const __mmask8 nearBoundary =
      greater(squared, zero) &
      _mm512_cmp_pd_mask(squared, splat(kernels::kExactBoundaryCheck) * longest, _CMP_LE_OQ);
  alignas(64) double result[8];
  _mm512_store_pd(result, squared);
  for (std::size_t i = 0; i < count; ++i)
    out[i] = nearBoundary >> i & 1
                 ? kernels::closestPointOnTriangle(point, mesh.triangle(sorted[i])).distanceSquared
                 : result[i];
}

}  // namespace delta::detail

#undef DELTA_EXACT_TARGET
#endif
