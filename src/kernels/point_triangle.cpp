#include "delta/kernels/point_triangle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>

#include "detail/robust_geometry.h"

namespace delta::kernels {

namespace {

/// Knuth's TwoSum: the rounding error of a + b = sum, exactly.
double twoSumLow(double a, double b, double sum) noexcept {
  const double bVirtual = sum - a;
  const double aVirtual = sum - bVirtual;
  return (a - aVirtual) + (b - bVirtual);
}

/// Whether the exact sum of `terms` is zero: Shewchuk's Grow-Expansion ("Adaptive precision
/// floating-point arithmetic and fast robust geometric predicates", 1997) keeps the running sum
/// as a nonoverlapping expansion with zero components dropped, which is zero exactly when no
/// component is left.
template <std::size_t N>
bool sumIsZero(const std::array<double, N>& terms) noexcept {
  std::array<double, N> expansion{};
  std::size_t size = 0;
  for (const double term : terms) {
    double running = term;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < size; ++i) {
      const double sum = running + expansion[i];
      const double low = twoSumLow(running, expansion[i], sum);
      if (low != 0.0) expansion[kept++] = low;
      running = sum;
    }
    if (running != 0.0) expansion[kept++] = running;
    size = kept;
  }
  return size == 0;
}

/// x − y exactly, as high + low.
std::array<double, 2> exactDifference(double x, double y) noexcept {
  const double high = x - y;
  return {high, twoSumLow(x, -y, high)};
}

/// Whether u_i·r_j − u_j·r_i is exactly zero, u and r given exactly as two-term differences:
/// eight products, each split exactly into its rounded value and error (a fused multiply–add).
bool crossComponentIsZero(const std::array<double, 2>& ui, const std::array<double, 2>& rj,
                          const std::array<double, 2>& uj,
                          const std::array<double, 2>& ri) noexcept {
  std::array<double, 16> terms{};
  std::size_t at = 0;
  for (const double a : ui)
    for (const double b : rj) {
      const double product = a * b;
      terms[at++] = product;
      terms[at++] = std::fma(a, b, -product);
    }
  for (const double a : uj)
    for (const double b : ri) {
      const double product = a * b;
      terms[at++] = -product;
      terms[at++] = -std::fma(a, b, -product);
    }
  return sumIsZero(terms);
}

/// Whether `p` lies exactly (in exact arithmetic on the doubles given) on the segment [s0, s1]:
/// inside its box and on its line, (s1 − s0) × (p − s0) = 0 by exact expansions. Differences
/// below 2⁻³⁰⁰ are scaled up by a power of two first (exact): their products, and the products'
/// errors, would underflow, and a point 1e-203 off a segment 1e-200 long was on it.
bool exactlyOnSegment(const Vec3& p, const Vec3& s0, const Vec3& s1) noexcept {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (!(std::fmin(s0[axis], s1[axis]) <= p[axis] && p[axis] <= std::fmax(s0[axis], s1[axis])))
      return false;
  std::array<std::array<double, 2>, 3> u, r;
  double largest = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    u[axis] = exactDifference(s1[axis], s0[axis]);
    r[axis] = exactDifference(p[axis], s0[axis]);
    largest = std::fmax(largest, std::fmax(std::abs(u[axis][0]), std::abs(r[axis][0])));
  }
  if (largest > 0.0 && largest < 0x1p-300) {
    const int exponent = -std::ilogb(largest);
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (std::size_t part = 0; part < 2; ++part) {
        u[axis][part] = std::ldexp(u[axis][part], exponent);
        r[axis][part] = std::ldexp(r[axis][part], exponent);
      }
  }
  return crossComponentIsZero(u[1], r[2], u[2], r[1]) &&
         crossComponentIsZero(u[2], r[0], u[0], r[2]) &&
         crossComponentIsZero(u[0], r[1], u[1], r[0]);
}

/// Whether `p` lies exactly on an edge (or is a vertex) of `triangle`.
bool onBoundary(const Vec3& p, const Triangle& triangle) noexcept {
  return exactlyOnSegment(p, triangle.a, triangle.b) ||
         exactlyOnSegment(p, triangle.b, triangle.c) || exactlyOnSegment(p, triangle.c, triangle.a);
}

/// closestPoint for a tiny triangle (its edges from `triangle.a`, `u` and `v`, of squares
/// below kTinyTriangleSquared): the kernel on `p` and the triangle less their first vertex
/// scaled up by a power of two to about 1 (exact), and its answer scaled back. Nothing
/// where the triangle is one point (its distances are between points) or where the point lies so
/// far that even the scale its distance allows leaves the triangle tiny: a flat triangle's
/// answer then differs by less than its size, far below an ulp of the distance.
PointTriangleResult closestPoint(const Vec3& p, const Triangle& triangle, const Vec3& givenPoint,
                                 const Triangle& given) noexcept;

std::optional<PointTriangleResult> closestOnTinyTriangle(const Vec3& p, const Triangle& triangle,
                                                         const Vec3& u, const Vec3& v,
                                                         const Vec3& givenPoint,
                                                         const Triangle& given) noexcept {
  const double extent = std::fmax(maxAbs(u), maxAbs(v));
  if (!(extent > 0.0)) return std::nullopt;
  const Vec3 r = p - triangle.a;
  int exponent = -std::ilogb(extent);
  // The scaled point's squared distance must not overflow: |r|·2^exponent below 2⁵¹⁰.
  if (const double reach = maxAbs(r); reach > 0.0)
    exponent = std::min(exponent, 510 - std::ilogb(reach));
  if (std::ldexp(extent, exponent) < 0x1p-140) return std::nullopt;
  PointTriangleResult result =
      closestPoint(ldexp(r, exponent), {{}, ldexp(u, exponent), ldexp(v, exponent)}, givenPoint,
                   given);  // not tiny now
  const bool onTriangle = result.distanceSquared == 0.0;
  result.distanceSquared = std::ldexp(result.distanceSquared, -2 * exponent);
  result.closest = onTriangle ? p : triangle.a + ldexp(result.closest, -exponent);
  return result;
}

/// closestPointOnTriangle(p, triangle), where the side of an edge's line that the rounded face
/// test leaves in doubt is decided exactly on `givenPoint` and `given`: the same point and
/// triangle, or those it was made from by a translation and a power-of-two scale
/// (distanceAtScale, the tiny triangles' path), so that every form decides the band alike (the
/// local copies' rounded differences could fall on the other side of the line: a point in a
/// face's plane measured 1.9e-18 at scale and 0 by the kernel).
PointTriangleResult closestPoint(const Vec3& p, const Triangle& triangle, const Vec3& givenPoint,
                                 const Triangle& given) noexcept {
  // In the frame of the first vertex: the differences of nearby coordinates are exact, so the
  // answer is as accurate relative to the triangle's size far from the origin as near it.
  const Vec3& origin = triangle.a;
  const detail::LocalTriangle local =
      detail::makeLocalTriangle({}, triangle.b - origin, triangle.c - origin);
  if (local.longestEdgeSquared < kTinyTriangleSquared) [[unlikely]]
    if (const std::optional<PointTriangleResult> tiny =
            closestOnTinyTriangle(p, triangle, local.vertex[1], local.vertex[2], givenPoint, given))
      return *tiny;
  const Vec3 r = p - origin;
  detail::FaceAreas areas;
  unsigned nearEdges = 0;
  detail::FaceSide side = detail::sideOfLocalFace(r, local, areas, nearEdges);
  if (side == detail::FaceSide::kNearEdge)
    side = detail::insideNearEdges(givenPoint, given, nearEdges) ? detail::FaceSide::kInside
                                                                 : detail::FaceSide::kOutside;
  PointTriangleResult result = side == detail::FaceSide::kInside
                                   ? detail::projectOntoLocalFace(r, local, areas)
                                   : detail::closestOnLocalEdges(r, local);
  result.closest += origin;
  // A point exactly on a vertex or an edge is at distance 0 from every triangle that has it, but
  // the projection above leaves a rounding error's distance that differs between them (a plain
  // n·r of a vertex of the face is not exactly 0): so the tie between incident triangles would
  // go to whichever rounded lowest, not to the smallest id. Where the distance is within
  // rounding of 0, exact arithmetic decides whether p lies on the triangle's boundary.
  if (result.distanceSquared > 0.0 &&
      result.distanceSquared <= kExactBoundaryCheck * local.longestEdgeSquared &&
      onBoundary(p, triangle)) {
    result.distanceSquared = 0.0;
  }
  // On the triangle (within rounding): the point is its own closest point, not the foot
  // rounded by the origin's addition.
  if (result.distanceSquared == 0.0) result.closest = p;
  return result;
}

}  // namespace

PointTriangleResult closestPointOnTriangle(const Vec3& p, const Triangle& triangle) noexcept {
  return closestPoint(p, triangle, p, triangle);
}

double distanceAtScale(const Vec3& p, const Triangle& triangle) noexcept {
  if (onBoundary(p, triangle)) return 0.0;  // as closestPointOnTriangle decides it
  const Vec3 r = p - triangle.a, u = triangle.b - triangle.a, v = triangle.c - triangle.a;
  const double largest = std::fmax(maxAbs(r), std::fmax(maxAbs(u), maxAbs(v)));
  if (!(largest > 0.0)) return 0.0;  // p and the triangle are one point
  if (!std::isfinite(largest))
    return std::sqrt(closestPointOnTriangle(p, triangle).distanceSquared);
  // The kernel on the differences it takes itself, scaled to about 1 (exact): the same
  // operations, each scaled, wherever nothing underflows.
  // By ldexp on each coordinate: below 2⁻¹⁰²² (subnormal differences) the factor 2^−exponent
  // itself would be beyond a double, and the distance came out +∞.
  const int exponent = std::ilogb(largest);
  const PointTriangleResult result = closestPoint(
      ldexp(r, -exponent), {{}, ldexp(u, -exponent), ldexp(v, -exponent)}, p, triangle);
  return std::ldexp(std::sqrt(result.distanceSquared), exponent);
}

}  // namespace delta::kernels
