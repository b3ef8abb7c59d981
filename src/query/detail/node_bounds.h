#pragma once

// The point queries' node bounds (query_mesh_data.h's boxes and leaf cylinders), in builds of
// the same arithmetic: plain loops for any ISA, and registers of eight lanes (AVX-512), two of
// four (AVX2) or four of two (AArch64's Advanced SIMD, in its NEON and SVE tables) where the
// translation unit is compiled for them (the point tables, query/isa/point_table.cpp). Each is a
// lower bound of the squared distance from the point to every triangle below the node, as computed
// by the exact kernel; tests compare every ISA's with it (through the tables).

#include <algorithm>
#include <bit>
#include <cstddef>
#include <limits>

#include "delta/core/vec3.h"

#include "query_mesh_data.h"

#if defined(__AVX2__) && defined(__FMA__)
#define DELTA_NODE_BOUNDS_AVX2
#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
#define DELTA_NODE_BOUNDS_AVX512
#endif
#include "intrinsics.h"
#endif
// On AArch64 Advanced SIMD is the baseline: every table has it, and the point tables of more
// than one lane (NEON's, SVE's) use it; the scalar table keeps the plain loops.
#if defined(__aarch64__) && defined(__ARM_NEON) && defined(DELTA_ISA_LANES) && DELTA_ISA_LANES > 1
#define DELTA_NODE_BOUNDS_NEON
#include <arm_neon.h>
#endif

namespace delta::detail {

/// The pruning bound a node's box is held against: `prune` grown by 2⁻⁴⁰ of itself (capped at the
/// largest double, so that an empty slot, at +∞, stays out). A box's distance rounds by a few
/// ulps of itself and of the point's offset from the octets' origin, which the boxes' slack (a
/// share of the mesh's size) covers only for points within about 2¹⁷ sizes of the mesh: from a
/// point 1e15 away the box of a leaf whose triangle ties the best came out an ulp above it with
/// fused multiply–adds (AVX2, AVX-512) and not without, and the smallest id was lost on those
/// ISAs. The growth, 256 times those ulps, keeps every box of a tie in the search at any distance.
inline double admitting(double prune) noexcept {
  return std::min(prune + prune * 0x1p-40, std::numeric_limits<double>::max());
}

/// What the cylinder bounds of a search from `point` shrink by (raiseByCylinders): 2⁻³⁸ of the
/// point's and the mesh's coordinates and extent, thousands of times the rounding of the bound
/// (a few ulps of them) and of the exact kernel's distance.
inline double cylinderShrink(const QueryMeshData& mesh, const Vec3& point) noexcept {
  return 0x1p-38 * maxAbs(point) + 0.25 * mesh.slack;  // slack: 2⁻³⁶ of the mesh's
}

/// The squared distances of a node's children, in plain loops that any ISA compiles:
/// query_mesh_data.h's box distances, raised by the cylinders where the children are leaves.
/// Each writes the eight bounds and returns the mask of those not above `prune`.
struct PlainBounds {
  static unsigned children(const BoxOctet& boxes, const Vec3& point, double prune,
                           double (&out)[kFanout]) noexcept {
    distancesSquared(boxes, point, out);
    return notAboveMask(out, prune);
  }
  static unsigned leaves(const BoxOctet& boxes, const CylinderOctet& cylinders, const Vec3& point,
                         double shrink, double prune, double (&out)[kFanout]) noexcept {
    distancesSquared(boxes, point, out);
    raiseByCylinders(boxes, cylinders, point, shrink, out);
    return notAboveMask(out, prune);
  }
  /// A leaf's triangles after their vector bounds: `prune` lowered to the least upper bound of
  /// those present (not the padding; never NaN), the lower bounds clamped at 0 (NaN, nothing
  /// known: 0, in doubt); returns the mask of those present whose lower bound is not above it.
  static unsigned candidates(double (&lower)[kFanout], const double (&upper)[kFanout],
                             unsigned present, double& prune) noexcept {
    for (std::size_t i = 0; i < kFanout; ++i) {
      if (upper[i] < prune && (present >> i & 1)) prune = upper[i];
      lower[i] = lower[i] > 0.0 ? lower[i] : 0.0;
    }
    return notAboveMask(lower, prune) & present;
  }
};

#if defined(DELTA_NODE_BOUNDS_AVX512)

/// The same bounds, each in one eight-lane register: GCC 12 made the plain loops two halves of
/// four lanes, with a compare and a blend for each maximum. The same operations but for the
/// contraction of the sums of squares (a distance one rounding closer; the slack covers it).
struct Avx512Bounds {
  static __m512d widened(const float (&values)[kFanout]) {
    return _mm512_cvtps_pd(_mm256_load_ps(values));
  }
  static __m512d boxes(const BoxOctet& boxes, const Vec3& point) {
    const __m512d zero = _mm512_setzero_pd();
    const __m512d px = _mm512_set1_pd(point.x), py = _mm512_set1_pd(point.y),
                  pz = _mm512_set1_pd(point.z);
    // max(lower − p, p − upper, 0) per axis (∞ for the empty slots, lower > upper)
    const __m512d dx = _mm512_max_pd(_mm512_max_pd(_mm512_sub_pd(widened(boxes.lowerX), px),
                                                   _mm512_sub_pd(px, widened(boxes.upperX))),
                                     zero);
    const __m512d dy = _mm512_max_pd(_mm512_max_pd(_mm512_sub_pd(widened(boxes.lowerY), py),
                                                   _mm512_sub_pd(py, widened(boxes.upperY))),
                                     zero);
    const __m512d dz = _mm512_max_pd(_mm512_max_pd(_mm512_sub_pd(widened(boxes.lowerZ), pz),
                                                   _mm512_sub_pd(pz, widened(boxes.upperZ))),
                                     zero);
    return _mm512_fmadd_pd(dx, dx, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dz, dz)));
  }
  static unsigned notAbove(__m512d bounds, double prune, double (&out)[kFanout]) {
    _mm512_storeu_pd(out, bounds);
    return _mm512_cmp_pd_mask(bounds, _mm512_set1_pd(prune), _CMP_LE_OQ);
  }
  static unsigned children(const BoxOctet& octet, const Vec3& point, double prune,
                           double (&out)[kFanout]) noexcept {
    return notAbove(boxes(octet, point), prune, out);
  }
  /// Whether any leaf of the octet has a cone (query_mesh_data.h's CylinderOctet): an octet of
  /// cylinders only (every leaf of a smooth surface) takes the cylinders' bound, five operations
  /// shorter than the cones' (W2 2.5% faster).
  static bool tapered(const CylinderOctet& cylinders) {
    return _mm256_movemask_ps(_mm256_cmp_ps(_mm256_load_ps(cylinders.taper), _mm256_setzero_ps(),
                                            _CMP_NEQ_OQ)) != 0;
  }
  /// raiseByCylinders (query_mesh_data.h), lane for lane.
  static unsigned leaves(const BoxOctet& octet, const CylinderOctet& cylinders, const Vec3& point,
                         double shrink, double prune, double (&out)[kFanout]) noexcept {
    const __m512d box = boxes(octet, point);
    const __m512d half = _mm512_set1_pd(0.5), zero = _mm512_setzero_pd(),
                  by = _mm512_set1_pd(shrink);
    const __m512d wx = _mm512_sub_pd(
        _mm512_set1_pd(point.x),
        _mm512_mul_pd(_mm512_add_pd(widened(octet.lowerX), widened(octet.upperX)), half));
    const __m512d wy = _mm512_sub_pd(
        _mm512_set1_pd(point.y),
        _mm512_mul_pd(_mm512_add_pd(widened(octet.lowerY), widened(octet.upperY)), half));
    const __m512d wz = _mm512_sub_pd(
        _mm512_set1_pd(point.z),
        _mm512_mul_pd(_mm512_add_pd(widened(octet.lowerZ), widened(octet.upperZ)), half));
    const __m512d nx = widened(cylinders.normalX), ny = widened(cylinders.normalY),
                  nz = widened(cylinders.normalZ);
    const __m512d inverse =
        _mm512_div_pd(_mm512_set1_pd(1.0),
                      _mm512_fmadd_pd(nx, nx, _mm512_fmadd_pd(ny, ny, _mm512_mul_pd(nz, nz))));
    const __m512d h = _mm512_fmadd_pd(nx, wx, _mm512_fmadd_pd(ny, wy, _mm512_mul_pd(nz, wz)));
    const __m512d along = _mm512_mul_pd(h, inverse);
    const __m512d lx = _mm512_fnmadd_pd(nx, along, wx), ly = _mm512_fnmadd_pd(ny, along, wy),
                  lz = _mm512_fnmadd_pd(nz, along, wz);
    const __m512d lateral =
        _mm512_sqrt_pd(_mm512_fmadd_pd(lx, lx, _mm512_fmadd_pd(ly, ly, _mm512_mul_pd(lz, lz))));
    __m512d cylinder;
    if (!tapered(cylinders)) {
      // Cylinders only (the leaves of a smooth surface): their bound in five operations fewer.
      const __m512d across =
          _mm512_max_pd(_mm512_sub_pd(_mm512_sub_pd(lateral, widened(cylinders.radius)), by), zero);
      const __m512d height =
          _mm512_max_pd(_mm512_sub_pd(_mm512_max_pd(_mm512_sub_pd(widened(cylinders.low), h),
                                                    _mm512_sub_pd(h, widened(cylinders.high))),
                                      by),
                        zero);
      cylinder =
          _mm512_fmadd_pd(_mm512_mul_pd(height, height), inverse, _mm512_mul_pd(across, across));
    } else {
      // raiseByCylinders' gap, clamped height offset x and what is left across
      const __m512d taper = widened(cylinders.taper);
      const __m512d gap = _mm512_sub_pd(
          _mm512_fnmadd_pd(taper, h, _mm512_sub_pd(lateral, widened(cylinders.radius))), by);
      const __m512d x = _mm512_min_pd(
          _mm512_max_pd(_mm512_mul_pd(widened(cylinders.step), _mm512_max_pd(gap, zero)),
                        _mm512_sub_pd(_mm512_sub_pd(widened(cylinders.low), by), h)),
          _mm512_sub_pd(_mm512_add_pd(widened(cylinders.high), by), h));
      const __m512d across = _mm512_max_pd(_mm512_fnmadd_pd(taper, x, gap), zero);
      cylinder = _mm512_fmadd_pd(_mm512_mul_pd(x, x), inverse, _mm512_mul_pd(across, across));
    }
    return notAbove(_mm512_max_pd(cylinder, box), prune, out);  // the box where it is NaN
  }
  static unsigned candidates(double (&lower)[kFanout], const double (&upper)[kFanout],
                             unsigned present, double& prune) noexcept {
    const __m512d above = _mm512_loadu_pd(upper);
    const __mmask8 below = _mm512_mask_cmp_pd_mask(static_cast<__mmask8>(present), above,
                                                   _mm512_set1_pd(prune), _CMP_LT_OQ);
    prune = std::min(prune, _mm512_mask_reduce_min_pd(below, above));  // +∞ where none
    return notAbove(_mm512_max_pd(_mm512_loadu_pd(lower), _mm512_setzero_pd()), prune, lower) &
           present;
  }
};
#endif

#if defined(DELTA_NODE_BOUNDS_AVX2)
/// The same bounds on AVX2: each of Avx512Bounds' eight-lane operations as two registers of four
/// lanes (lanes 0–3, then 4–7), the same operations in the same order, so the same bounds.
struct Avx2Bounds {
  /// Lanes H to H + 3 of `values`, widened.
  template <std::size_t H>
  static __m256d widened(const float (&values)[kFanout]) {
    return _mm256_cvtps_pd(_mm_load_ps(values + H));
  }
  template <std::size_t H>
  static __m256d boxes(const BoxOctet& boxes, const Vec3& point) {
    const __m256d zero = _mm256_setzero_pd();
    const __m256d px = _mm256_set1_pd(point.x), py = _mm256_set1_pd(point.y),
                  pz = _mm256_set1_pd(point.z);
    const __m256d dx = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(widened<H>(boxes.lowerX), px),
                                                   _mm256_sub_pd(px, widened<H>(boxes.upperX))),
                                     zero);
    const __m256d dy = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(widened<H>(boxes.lowerY), py),
                                                   _mm256_sub_pd(py, widened<H>(boxes.upperY))),
                                     zero);
    const __m256d dz = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(widened<H>(boxes.lowerZ), pz),
                                                   _mm256_sub_pd(pz, widened<H>(boxes.upperZ))),
                                     zero);
    return _mm256_fmadd_pd(dx, dx, _mm256_fmadd_pd(dy, dy, _mm256_mul_pd(dz, dz)));
  }
  /// Stores both halves in `out`; the mask of the lanes not above `prune`.
  static unsigned notAbove(__m256d low, __m256d high, double prune, double (&out)[kFanout]) {
    _mm256_storeu_pd(out, low);
    _mm256_storeu_pd(out + 4, high);
    const __m256d limit = _mm256_set1_pd(prune);
    return static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(low, limit, _CMP_LE_OQ))) |
           static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(high, limit, _CMP_LE_OQ))) << 4;
  }
  static unsigned children(const BoxOctet& octet, const Vec3& point, double prune,
                           double (&out)[kFanout]) noexcept {
    return notAbove(boxes<0>(octet, point), boxes<4>(octet, point), prune, out);
  }
  /// Avx512Bounds::tapered.
  static bool tapered(const CylinderOctet& cylinders) {
    return _mm256_movemask_ps(_mm256_cmp_ps(_mm256_load_ps(cylinders.taper), _mm256_setzero_ps(),
                                            _CMP_NEQ_OQ)) != 0;
  }
  /// Avx512Bounds::leaves of lanes H to H + 3.
  template <std::size_t H>
  static __m256d leafBounds(const BoxOctet& octet, const CylinderOctet& cylinders,
                            const Vec3& point, double shrink, bool cones) {
    const __m256d box = boxes<H>(octet, point);
    const __m256d half = _mm256_set1_pd(0.5), zero = _mm256_setzero_pd(),
                  by = _mm256_set1_pd(shrink);
    const __m256d wx = _mm256_sub_pd(
        _mm256_set1_pd(point.x),
        _mm256_mul_pd(_mm256_add_pd(widened<H>(octet.lowerX), widened<H>(octet.upperX)), half));
    const __m256d wy = _mm256_sub_pd(
        _mm256_set1_pd(point.y),
        _mm256_mul_pd(_mm256_add_pd(widened<H>(octet.lowerY), widened<H>(octet.upperY)), half));
    const __m256d wz = _mm256_sub_pd(
        _mm256_set1_pd(point.z),
        _mm256_mul_pd(_mm256_add_pd(widened<H>(octet.lowerZ), widened<H>(octet.upperZ)), half));
    const __m256d nx = widened<H>(cylinders.normalX), ny = widened<H>(cylinders.normalY),
                  nz = widened<H>(cylinders.normalZ);
    const __m256d inverse =
        _mm256_div_pd(_mm256_set1_pd(1.0),
                      _mm256_fmadd_pd(nx, nx, _mm256_fmadd_pd(ny, ny, _mm256_mul_pd(nz, nz))));
    const __m256d h = _mm256_fmadd_pd(nx, wx, _mm256_fmadd_pd(ny, wy, _mm256_mul_pd(nz, wz)));
    const __m256d along = _mm256_mul_pd(h, inverse);
    const __m256d lx = _mm256_fnmadd_pd(nx, along, wx), ly = _mm256_fnmadd_pd(ny, along, wy),
                  lz = _mm256_fnmadd_pd(nz, along, wz);
    const __m256d lateral =
        _mm256_sqrt_pd(_mm256_fmadd_pd(lx, lx, _mm256_fmadd_pd(ly, ly, _mm256_mul_pd(lz, lz))));
    __m256d cylinder;
    if (!cones) {
      const __m256d across = _mm256_max_pd(
          _mm256_sub_pd(_mm256_sub_pd(lateral, widened<H>(cylinders.radius)), by), zero);
      const __m256d height =
          _mm256_max_pd(_mm256_sub_pd(_mm256_max_pd(_mm256_sub_pd(widened<H>(cylinders.low), h),
                                                    _mm256_sub_pd(h, widened<H>(cylinders.high))),
                                      by),
                        zero);
      cylinder =
          _mm256_fmadd_pd(_mm256_mul_pd(height, height), inverse, _mm256_mul_pd(across, across));
    } else {
      const __m256d taper = widened<H>(cylinders.taper);
      const __m256d gap = _mm256_sub_pd(
          _mm256_fnmadd_pd(taper, h, _mm256_sub_pd(lateral, widened<H>(cylinders.radius))), by);
      const __m256d x = _mm256_min_pd(
          _mm256_max_pd(_mm256_mul_pd(widened<H>(cylinders.step), _mm256_max_pd(gap, zero)),
                        _mm256_sub_pd(_mm256_sub_pd(widened<H>(cylinders.low), by), h)),
          _mm256_sub_pd(_mm256_add_pd(widened<H>(cylinders.high), by), h));
      const __m256d across = _mm256_max_pd(_mm256_fnmadd_pd(taper, x, gap), zero);
      cylinder = _mm256_fmadd_pd(_mm256_mul_pd(x, x), inverse, _mm256_mul_pd(across, across));
    }
    return _mm256_max_pd(cylinder, box);  // the box where it is NaN
  }
  static unsigned leaves(const BoxOctet& octet, const CylinderOctet& cylinders, const Vec3& point,
                         double shrink, double prune, double (&out)[kFanout]) noexcept {
    const bool cones = tapered(cylinders);  // the whole octet's, as AVX-512 decides it
    return notAbove(leafBounds<0>(octet, cylinders, point, shrink, cones),
                    leafBounds<4>(octet, cylinders, point, shrink, cones), prune, out);
  }
  static unsigned candidates(double (&lower)[kFanout], const double (&upper)[kFanout],
                             unsigned present, double& prune) noexcept {
    const __m256d limit = _mm256_set1_pd(prune);
    unsigned below =
        static_cast<unsigned>(
            _mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(upper), limit, _CMP_LT_OQ))) |
        static_cast<unsigned>(
            _mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(upper + 4), limit, _CMP_LT_OQ)))
            << 4;
    for (below &= present; below != 0; below &= below - 1)
      prune = std::min(prune, upper[std::countr_zero(below)]);
    const __m256d zero = _mm256_setzero_pd();
    return notAbove(_mm256_max_pd(_mm256_loadu_pd(lower), zero),
                    _mm256_max_pd(_mm256_loadu_pd(lower + 4), zero), prune, lower) &
           present;
  }
};
#endif

#if defined(DELTA_NODE_BOUNDS_NEON)
/// The same bounds in AArch64's Advanced SIMD: each of Avx512Bounds' eight-lane operations as
/// four registers of two lanes (lanes 0–1, 2–3, 4–5, 6–7), the same operations in the same
/// order, with x86's maximum (a > b ? a : b, which gives b where either is NaN) and fused
/// multiply-adds where AVX's are fused: the same bounds.
struct NeonBounds {
  /// Lanes H and H + 1 of `values`, widened.
  template <std::size_t H>
  static float64x2_t widened(const float (&values)[kFanout]) {
    return vcvt_f64_f32(vld1_f32(values + H));
  }
  /// x86's maximum: a where a > b, else b.
  static float64x2_t maximum(float64x2_t a, float64x2_t b) {
    return vbslq_f64(vcgtq_f64(a, b), a, b);
  }
  /// x86's minimum: a where a < b, else b.
  static float64x2_t minimum(float64x2_t a, float64x2_t b) {
    return vbslq_f64(vcltq_f64(a, b), a, b);
  }
  template <std::size_t H>
  static float64x2_t boxes(const BoxOctet& boxes, const Vec3& point) {
    const float64x2_t zero = vdupq_n_f64(0.0);
    const float64x2_t px = vdupq_n_f64(point.x), py = vdupq_n_f64(point.y),
                      pz = vdupq_n_f64(point.z);
    const float64x2_t dx = maximum(
        maximum(vsubq_f64(widened<H>(boxes.lowerX), px), vsubq_f64(px, widened<H>(boxes.upperX))),
        zero);
    const float64x2_t dy = maximum(
        maximum(vsubq_f64(widened<H>(boxes.lowerY), py), vsubq_f64(py, widened<H>(boxes.upperY))),
        zero);
    const float64x2_t dz = maximum(
        maximum(vsubq_f64(widened<H>(boxes.lowerZ), pz), vsubq_f64(pz, widened<H>(boxes.upperZ))),
        zero);
    // dx·dx + (dy·dy + dz·dz), fused as AVX's fmadd(dx, dx, fmadd(dy, dy, dz·dz))
    return vfmaq_f64(vfmaq_f64(vmulq_f64(dz, dz), dy, dy), dx, dx);
  }
  /// The two lanes of a comparison as bits 0 and 1.
  static unsigned bits(uint64x2_t compared) {
    const uint64x2_t ones = vshrq_n_u64(compared, 63);
    return static_cast<unsigned>(vgetq_lane_u64(ones, 0) | vgetq_lane_u64(ones, 1) << 1);
  }
  /// Stores the four registers in `out`; the mask of the lanes not above `prune`.
  static unsigned notAbove(const float64x2_t (&bounds)[4], double prune, double (&out)[kFanout]) {
    const float64x2_t limit = vdupq_n_f64(prune);
    unsigned mask = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      vst1q_f64(out + 2 * k, bounds[k]);
      mask |= bits(vcleq_f64(bounds[k], limit)) << (2 * k);
    }
    return mask;
  }
  static unsigned children(const BoxOctet& octet, const Vec3& point, double prune,
                           double (&out)[kFanout]) noexcept {
    const float64x2_t bounds[4] = {boxes<0>(octet, point), boxes<2>(octet, point),
                                   boxes<4>(octet, point), boxes<6>(octet, point)};
    return notAbove(bounds, prune, out);
  }
  /// Avx512Bounds::tapered.
  static bool tapered(const CylinderOctet& cylinders) {
    const float32x4_t zero = vdupq_n_f32(0.0f);
    const uint32x4_t low = vmvnq_u32(vceqq_f32(vld1q_f32(cylinders.taper), zero));
    const uint32x4_t high = vmvnq_u32(vceqq_f32(vld1q_f32(cylinders.taper + 4), zero));
    return vmaxvq_u32(vorrq_u32(low, high)) != 0;
  }
  /// Avx512Bounds::leaves of lanes H and H + 1.
  template <std::size_t H>
  static float64x2_t leafBounds(const BoxOctet& octet, const CylinderOctet& cylinders,
                                const Vec3& point, double shrink, bool cones) {
    const float64x2_t box = boxes<H>(octet, point);
    const float64x2_t half = vdupq_n_f64(0.5), zero = vdupq_n_f64(0.0), by = vdupq_n_f64(shrink);
    const float64x2_t wx =
        vsubq_f64(vdupq_n_f64(point.x),
                  vmulq_f64(vaddq_f64(widened<H>(octet.lowerX), widened<H>(octet.upperX)), half));
    const float64x2_t wy =
        vsubq_f64(vdupq_n_f64(point.y),
                  vmulq_f64(vaddq_f64(widened<H>(octet.lowerY), widened<H>(octet.upperY)), half));
    const float64x2_t wz =
        vsubq_f64(vdupq_n_f64(point.z),
                  vmulq_f64(vaddq_f64(widened<H>(octet.lowerZ), widened<H>(octet.upperZ)), half));
    const float64x2_t nx = widened<H>(cylinders.normalX), ny = widened<H>(cylinders.normalY),
                      nz = widened<H>(cylinders.normalZ);
    const float64x2_t inverse =
        vdivq_f64(vdupq_n_f64(1.0), vfmaq_f64(vfmaq_f64(vmulq_f64(nz, nz), ny, ny), nx, nx));
    const float64x2_t h = vfmaq_f64(vfmaq_f64(vmulq_f64(nz, wz), ny, wy), nx, wx);
    const float64x2_t along = vmulq_f64(h, inverse);
    // w − n·along, fused as AVX's fnmadd
    const float64x2_t lx = vfmsq_f64(wx, nx, along), ly = vfmsq_f64(wy, ny, along),
                      lz = vfmsq_f64(wz, nz, along);
    const float64x2_t lateral = vsqrtq_f64(vfmaq_f64(vfmaq_f64(vmulq_f64(lz, lz), ly, ly), lx, lx));
    float64x2_t cylinder;
    if (!cones) {
      const float64x2_t across =
          maximum(vsubq_f64(vsubq_f64(lateral, widened<H>(cylinders.radius)), by), zero);
      const float64x2_t height =
          maximum(vsubq_f64(maximum(vsubq_f64(widened<H>(cylinders.low), h),
                                    vsubq_f64(h, widened<H>(cylinders.high))),
                            by),
                  zero);
      cylinder = vfmaq_f64(vmulq_f64(across, across), vmulq_f64(height, height), inverse);
    } else {
      // (lateral − radius) − taper·h and gap − taper·x, fused as AVX's fnmadd
      const float64x2_t taper = widened<H>(cylinders.taper);
      const float64x2_t gap =
          vsubq_f64(vfmsq_f64(vsubq_f64(lateral, widened<H>(cylinders.radius)), taper, h), by);
      const float64x2_t x =
          minimum(maximum(vmulq_f64(widened<H>(cylinders.step), maximum(gap, zero)),
                          vsubq_f64(vsubq_f64(widened<H>(cylinders.low), by), h)),
                  vsubq_f64(vaddq_f64(widened<H>(cylinders.high), by), h));
      const float64x2_t across = maximum(vfmsq_f64(gap, taper, x), zero);
      cylinder = vfmaq_f64(vmulq_f64(across, across), vmulq_f64(x, x), inverse);
    }
    return maximum(cylinder, box);  // the box where it is NaN
  }
  static unsigned leaves(const BoxOctet& octet, const CylinderOctet& cylinders, const Vec3& point,
                         double shrink, double prune, double (&out)[kFanout]) noexcept {
    const bool cones = tapered(cylinders);
    const float64x2_t bounds[4] = {leafBounds<0>(octet, cylinders, point, shrink, cones),
                                   leafBounds<2>(octet, cylinders, point, shrink, cones),
                                   leafBounds<4>(octet, cylinders, point, shrink, cones),
                                   leafBounds<6>(octet, cylinders, point, shrink, cones)};
    return notAbove(bounds, prune, out);
  }
  static unsigned candidates(double (&lower)[kFanout], const double (&upper)[kFanout],
                             unsigned present, double& prune) noexcept {
    const float64x2_t limit = vdupq_n_f64(prune), zero = vdupq_n_f64(0.0);
    unsigned below = 0;
    for (std::size_t k = 0; k < 4; ++k)
      below |= bits(vcltq_f64(vld1q_f64(upper + 2 * k), limit)) << (2 * k);
    for (below &= present; below != 0; below &= below - 1)
      prune = std::min(prune, upper[std::countr_zero(below)]);
    const float64x2_t bounds[4] = {
        maximum(vld1q_f64(lower), zero), maximum(vld1q_f64(lower + 2), zero),
        maximum(vld1q_f64(lower + 4), zero), maximum(vld1q_f64(lower + 6), zero)};
    return notAbove(bounds, prune, lower) & present;
  }
};
#endif

}  // namespace delta::detail
