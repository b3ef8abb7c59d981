#include "delta/query/winding_number.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "../kernels/detail/exact_predicates.h"

namespace delta {
namespace {

/// The exact sign of orient(point, t.a, t.b, t.c), its coordinates first scaled by a power of two
/// (exact, the sign unchanged) where they are all below 2⁻¹⁰⁰: the expansions' products would
/// underflow there (exact_predicates.h needs coordinates of 2⁻²⁵⁰ or more).
int exactSign(const Triangle& t, const Vec3& point) {
  const double largest = std::max({maxAbs(t.a), maxAbs(t.b), maxAbs(t.c), maxAbs(point)});
  if (largest > 0.0 && largest < 0x1p-100) {
    const int exponent = -std::ilogb(largest);
    return detail::exactOrientSign(ldexp(point, exponent), ldexp(t.a, exponent),
                                   ldexp(t.b, exponent), ldexp(t.c, exponent));
  }
  return detail::exactOrientSign(point, t.a, t.b, t.c);
}

}  // namespace

double solidAngle(const Triangle& t, const Vec3& point) noexcept {
  Vec3 a = t.a - point, b = t.b - point, c = t.c - point;
  // The angle depends on the directions of a, b, c only. Its products are of degree 3, which
  // overflow from differences of 1e102 on and underflow below 1e-102: out of [2⁻³⁰⁰, 2³⁰⁰] the
  // differences are scaled by a power of two (exact) to about 1, and where they overflowed
  // (coordinates near the largest double) they are taken from the halved coordinates first.
  double largest = std::max({maxAbs(a), maxAbs(b), maxAbs(c)});
  if (!(largest <= 0x1p300 && largest >= 0x1p-300)) {
    if (std::isinf(largest)) {
      const Vec3 half = point * 0.5;
      a = t.a * 0.5 - half, b = t.b * 0.5 - half, c = t.c * 0.5 - half;
      largest = std::max({maxAbs(a), maxAbs(b), maxAbs(c)});
    }
    if (largest > 0.0 && std::isfinite(largest)) {
      // By ldexp: below 2⁻¹⁰²² (subnormal differences) the factor 2^−exponent is beyond a
      // double, and a point inside a tetrahedron 1e-310 across was seen outside.
      const int exponent = -std::ilogb(largest);
      a = ldexp(a, exponent), b = ldexp(b, exponent), c = ldexp(c, exponent);
    }
  }
  const double la = length(a), lb = length(b), lc = length(c);
  // tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|)
  double numerator = dot(a, cross(b, c));
  // a·(b×c) is orient(point, t.a, t.b, t.c): within its rounding of 0 (the point within rounding
  // of the triangle's plane) its sign, which puts Ω near +2π or −2π where the point sees the
  // triangle from in front or behind, is decided exactly (exact_predicates.h), so that a point
  // within rounding of a closed mesh's face is counted on its side. (Its rounding is below
  // Shewchuk's bound, 7.8e-16 times the permanent, itself at most √3·|a||b||c|.)
  if (std::abs(numerator) <= 0x1p-48 * la * lb * lc) [[unlikely]] {
    int sign = detail::filteredOrientSign(a, b, c);
    if (sign == 0) sign = exactSign(t, point);
    numerator = sign == 0 ? 0.0
                          : std::copysign(std::max(std::abs(numerator),
                                                   std::numeric_limits<double>::denorm_min()),
                                          static_cast<double>(sign));
  }
  const double denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2.0 * std::atan2(numerator, denominator);
}

double windingNumber(const TriangleSoA& mesh, const Vec3& point) noexcept {
  return windingNumber(
      mesh.size(), [&mesh](std::size_t i) { return mesh.triangle(i); }, point);
}

}  // namespace delta
