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
// Error: in the frame of vertex a, r = p − a and the edges are rounded by ε·(|p| + |a|), and the
// rest is a short chain of products of magnitude ≤ s = |r| + L (L the longest edge) with a
// relative error of a few ε, except the face distance, whose plain normal is off by ε / sin α
// (α the angle at a). Lanes with sin α < 2⁻¹⁰ (slivers, zero-area triangles) get lower bound 0
// and their edges' upper bound (the distance to an edge is never below the triangle's), so
// the total error stays below about 40·2¹⁰·ε·s·(s + |a| + |p − a|) = 9·10⁻¹²·s·(s + …), which
// the margin 2⁻²⁶·3·s∞·(s∞ + A∞) (max-norms, 3 ≥ the ratio of the squared norms) exceeds
// 1,600-fold.

#include <cstddef>

#include "delta/kernels/detail/lanes.h"

namespace delta::detail {

/// Squared-distance bounds of the eight triangles [first, first + 8) of `block`: lower[i] ≤
/// kernels::closestPointOnTriangle(point, triangle first + i).distanceSquared ≤ upper[i], or NaN
/// where nothing is known (overflow beyond about 1e77). A triangle may be skipped only when its
/// lower bound compares greater than the best distance; an upper bound may lower the best
/// distance a search prunes with before any exact kernel runs. The upper bound of a sliver is
/// its nearest edge's (edges need no normal). Padding triangles give NaN or anything: the
/// caller excludes them by their boxes.
template <int H>
inline void pointTriangleBounds8(const double* const (&streams)[9], std::size_t first,
                                 const double (&point)[3], double (&lower)[8],
                                 double (&upper)[8]) noexcept {
  constexpr int U = 8 / H;
  using P = Pack<H, U>;
  using M = MaskPack<H, U>;
  const auto at = [first](const double* stream) {
    P r;
    __builtin_memcpy(&r.v[0], stream + first, sizeof r.v);
    return r;
  };
  const auto select = [](const M& m, const P& a, const P& b) {
    P r;
    for (int k = 0; k < U; ++k)
      r.v[k] = m.v[k] ? a.v[k] : b.v[k];
    return r;
  };
  const auto min = [&select](const P& a, const P& b) { return select(a < b, a, b); };
  const auto max = [&select](const P& a, const P& b) { return select(a > b, a, b); };
  const auto abs = [&select](const P& a) { return select(a < 0.0, -a, a); };
  const P zero = broadcast<H, U>(0.0), one = broadcast<H, U>(1.0);

  const P ax = at(streams[0]), ay = at(streams[1]), az = at(streams[2]);
  const P ux = at(streams[3]) - ax, uy = at(streams[4]) - ay, uz = at(streams[5]) - az;  // b − a
  const P vx = at(streams[6]) - ax, vy = at(streams[7]) - ay, vz = at(streams[8]) - az;  // c − a
  const P rx = point[0] - ax, ry = point[1] - ay, rz = point[2] - az;                    // p − a

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

  // The margin (see the top of this file), with max-norms.
  const P s = max(max(abs(rx), abs(ry)), abs(rz)) +
              max(max(max(abs(ux), abs(uy)), max(abs(uz), abs(vx))), max(abs(vy), abs(vz)));
  const P reach = s + max(max(abs(ax), abs(ay)), abs(az));
  const P margin = broadcast<H, U>(3.0 * 0x1p-26) * s * reach;
  const P below = select(wellShaped, best - margin, zero);
  const P above = select(wellShaped, best, edges) + margin;
  __builtin_memcpy(lower, &below.v[0], sizeof lower);
  __builtin_memcpy(upper, &above.v[0], sizeof upper);
}

}  // namespace delta::detail
