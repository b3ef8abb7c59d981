#include "delta/query/winding_number.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace delta {

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
  const double numerator = dot(a, cross(b, c));
  const double denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2.0 * std::atan2(numerator, denominator);
}

double windingNumber(const TriangleSoA& mesh, const Vec3& point) noexcept {
  return windingNumber(
      mesh.size(), [&mesh](std::size_t i) { return mesh.triangle(i); }, point);
}

}  // namespace delta
