#pragma once

// A point against the eight triangles of a tree leaf at once: lower and upper bounds of the
// squared distances, for the point queries to skip the exact scalar kernel on triangles that
// cannot beat the best distance found so far, and to prune with the upper bounds before any
// exact kernel runs. Eight lanes as Pack<H, 8 / H> (H doubles a register of the ISA: 1, 2, 4 or
// 8), instantiated once per ISA like the other batched kernels.
//
// Why bounds and not the distance itself: the answers of the point queries are, bit for bit,
// those of kernels::closestPointOnTriangle, which the vector code does not reproduce (other
// operation order, a plain normal). So it computes the same closest point approximately and
// subtracts and adds a margin far above its rounding error; the scalar kernel then decides among
// the triangles the bounds leave in doubt.
//
// The triangles come in single precision, less an origin (FloatLeavesView): each vertex within δ
// (`rounding`) of the double one it stands for, half the bytes of doubles to stream. A triangle
// whose vertices move by at most δ moves by at most δ (every point of it is the same convex
// combination), so its distance d from the point and the float triangle's d_f differ by at most
// δ, and d² lies within 2δ·d_f + δ² of d_f². As d_f ≤ |p − a| ≤ √3·s (s below), the bounds
// widen by 4δ·s (and the upper one by δ² more): no square root.
//
// Error: in the frame of vertex a, r = p − a and the edges are rounded by ε·(|p| + |a|), and the
// rest is a short chain of products of magnitude ≤ s = |r| + L (L the longest edge) with a
// relative error of a few ε, except the face distance, whose plain normal is off by ε / sin α
// (α the angle at a). Lanes with sin α < 2⁻¹⁰ (slivers, zero-area triangles) get their box's
// distance as the lower bound and their edges' as the upper one (the distance to an edge is
// never below the triangle's), so the total error stays below about 40·2¹⁰·ε·s·(s + |a| + |p −
// a|) = 9·10⁻¹²·s·(s + …), which the margin 2⁻²⁶·3·s∞·(s∞ + A∞) (max-norms, 3 ≥ the ratio of the
// squared norms; A∞ the vertex's coordinates less the origin) exceeds 1,600-fold. The exact
// kernel, which works on the vertices with the origin added back, rounds its differences by ε of
// the differences themselves (r = p − a, b − a: one rounding each, relative to the result), not
// of the coordinates: the origin's offset O enters its error only through the rounding of p
// less the origin, ε·(|p − origin|), already in s. The margin still takes 2⁻³⁶·3·s∞·O for it,
// 400,000 times ε·s·O; with O at the full 2⁻²⁶ (1e8 from the origin: 4.5·s) the bounds of a mesh
// far away admitted every triangle, and its queries were 2.6 times slower at 1e8.

#include <cstddef>

#include "delta/kernels/detail/batch_views.h"
#include "delta/kernels/detail/lanes.h"

namespace delta::detail {

/// Squared-distance bounds of the eight triangles [first, first + 8) of `block`: lower[i] ≤
/// kernels::closestPointOnTriangle(point + origin, triangle first + i).distanceSquared ≤
/// upper[i], for `point` given less the block's origin; NaN or anything where nothing is known
/// (overflow beyond about 1e77, or δ = ∞): the caller must take a NaN lower bound for 0. A
/// triangle may be skipped only when its lower bound compares greater than the best distance;
/// an upper bound may lower the best distance a search prunes with before any exact kernel runs.
/// False, and nothing written, where the triangles' boxes alone put all eight beyond `prune`
/// (most leaves a descent reaches). Padding triangles give NaN or anything: the caller excludes
/// them.
template <int H>
inline bool pointTriangleBounds8(const FloatLeavesView& block, std::size_t first,
                                 const double (&point)[3], double prune, double (&lower)[8],
                                 double (&upper)[8]) noexcept {
  constexpr int U = 8 / H;
  using P = Pack<H, U>;
  using M = MaskPack<H, U>;
  typedef float Floats __attribute__((vector_size(H * sizeof(float))));
  const float* const eight = block.leaves + first / 8 * 72;  // first is a multiple of 8
  const auto at = [eight](int slot) {
    P r;
    for (int k = 0; k < U; ++k) {
      Floats f;
      __builtin_memcpy(&f, eight + slot * 8 + k * H, sizeof f);
#if defined(__AVX512F__) && !defined(__clang__)
      if constexpr (H == 8) {  // one vcvtps2pd: GCC 12 converts the halves and joins them
        r.v[k] = __builtin_ia32_cvtps2pd512_mask(f, typename Register<H>::Real{},
                                                 static_cast<unsigned char>(0xff), 4);
        continue;
      }
#endif
      r.v[k] = __builtin_convertvector(f, typename Register<H>::Real);
    }
    return r;
  };
  const auto select = [](const M& m, const P& a, const P& b) {
    P r;
    for (int k = 0; k < U; ++k)
      r.v[k] = m.v[k] ? a.v[k] : b.v[k];
    return r;
  };
  // min and max as x86's minpd and maxpd define them (a < b ? a : b, a > b ? a : b: the second
  // operand where either is NaN), which GCC 12 leaves as a compare and a blend where it cannot
  // see the pattern; abs clears the sign bit (one and where the select took three instructions).
  const auto pick = [&select](const P& a, const P& b, bool larger) {
#if defined(__AVX512F__) && !defined(__clang__)
    if constexpr (H == 8) {
      P r;
      for (int k = 0; k < U; ++k)
        r.v[k] = larger ? __builtin_ia32_maxpd512_mask(a.v[k], b.v[k], a.v[k],
                                                       static_cast<unsigned char>(0xff), 4)
                        : __builtin_ia32_minpd512_mask(a.v[k], b.v[k], a.v[k],
                                                       static_cast<unsigned char>(0xff), 4);
      return r;
    }
#endif
    return larger ? select(a > b, a, b) : select(a < b, a, b);
  };
  const auto min = [&pick](const P& a, const P& b) { return pick(a, b, false); };
  const auto max = [&pick](const P& a, const P& b) { return pick(a, b, true); };
  const auto abs = [](const P& a) {
    using Bits = typename Register<H>::Mask;
    using Real = typename Register<H>::Real;
    P r;
    for (int k = 0; k < U; ++k)
      r.v[k] = (Real)((Bits)a.v[k] & 0x7fffffffffffffff);
    return r;
  };
  const P zero = broadcast<H, U>(0.0), one = broadcast<H, U>(1.0);

  const P ax = at(0), ay = at(1), az = at(2);
  const P ux = at(3) - ax, uy = at(4) - ay, uz = at(5) - az;           // b − a
  const P vx = at(6) - ax, vy = at(7) - ay, vz = at(8) - az;           // c − a
  const P rx = point[0] - ax, ry = point[1] - ay, rz = point[2] - az;  // p − a

  // The margin (see the top of this file), with max-norms, and the widening by δ.
  const P s = max(max(abs(rx), abs(ry)), abs(rz)) +
              max(max(max(abs(ux), abs(uy)), max(abs(uz), abs(vx))), max(abs(vy), abs(vz)));
  const P reach = s + max(max(abs(ax), abs(ay)), abs(az)) + block.offset * 0x1p-10;
  const P margin = (broadcast<H, U>(3.0 * 0x1p-26) * reach + 4.0 * block.rounding) * s;
  // The box's distance (relative to a: the box spans min(0, u, v) … max(0, u, v) per axis):
  // where it puts all eight beyond `prune` (most leaves a descent reaches), that is all.
  const auto axisGap = [&](const P& r, const P& u, const P& v) {
    return max(max(min(min(u, v), zero) - r, r - max(max(u, v), zero)), zero);
  };
  const P gx = axisGap(rx, ux, vx), gy = axisGap(ry, uy, vy), gz = axisGap(rz, uz, vz);
  const P box = gx * gx + gy * gy + gz * gz;
  const P boxBelow = box - margin;
  const M beyond = boxBelow > prune;
  typename Register<H>::Mask all = beyond.v[0];
  for (int k = 1; k < U; ++k)
    all &= beyond.v[k];
  bool every = true;  // one test of the whole register where the ISA has it
#if defined(__AVX512F__) && !defined(__clang__)
  if constexpr (H == 8) {
    typedef long long Words __attribute__((vector_size(64)));
    every =
        __builtin_ia32_ptestnmq512((Words)all, (Words)all, static_cast<unsigned char>(0xff)) == 0;
  } else
#endif
    for (int i = 0; i < H; ++i)
      every = every && all[i] != 0;
  if (every) return false;

  // The squared distance to the segment from o (relative to a) along d, for q = r − o.
  const auto segment = [&](const P& qx, const P& qy, const P& qz, const P& dx, const P& dy,
                           const P& dz) {
    const P dd = dx * dx + dy * dy + dz * dz;
    const P t = select(dd > 0.0, (qx * dx + qy * dy + qz * dz) / select(dd > 0.0, dd, one), zero);
    const P c = min(max(t, zero), one);
    const P ex = qx - c * dx, ey = qy - c * dy, ez = qz - c * dz;
    return ex * ex + ey * ey + ez * ez;
  };
  const P wx = vx - ux, wy = vy - uy, wz = vz - uz;  // c − b
  P edges = min(segment(rx, ry, rz, ux, uy, uz), segment(rx, ry, rz, vx, vy, vz));
  edges = min(edges, segment(rx - ux, ry - uy, rz - uz, wx, wy, wz));

  // The face: p projects inside when it lies on the inner side of all three edges.
  const P nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const P nn = nx * nx + ny * ny + nz * nz;
  const P uu = ux * ux + uy * uy + uz * uz, vv = vx * vx + vy * vy + vz * vz;
  const M wellShaped = nn > broadcast<H, U>(0x1p-20) * uu * vv;  // sin α ≥ 2⁻¹⁰
  const auto side = [&](const P& ex, const P& ey, const P& ez, const P& qx, const P& qy,
                        const P& qz) {  // n · (e × q)
    return nx * (ey * qz - ez * qy) + ny * (ez * qx - ex * qz) + nz * (ex * qy - ey * qx);
  };
  const M inside = (side(ux, uy, uz, rx, ry, rz) >= 0.0) &
                   (side(wx, wy, wz, rx - ux, ry - uy, rz - uz) >= 0.0) &
                   (side(-vx, -vy, -vz, rx - vx, ry - vy, rz - vz) >= 0.0);
  const P height = nx * rx + ny * ry + nz * rz;
  const P face = height * height / select(wellShaped, nn, one);
  const P best = select(inside, min(edges, face), edges);
  const P low = select(wellShaped, max(best, box), box) - margin;
  const P above = select(wellShaped, best, edges) + margin + block.rounding * block.rounding;
  __builtin_memcpy(lower, &low.v[0], sizeof lower);
  __builtin_memcpy(upper, &above.v[0], sizeof upper);
  return true;
}

}  // namespace delta::detail
