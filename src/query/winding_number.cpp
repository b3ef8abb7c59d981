#include "delta/query/winding_number.h"

#include <cmath>
#include <numbers>

namespace delta {

double solidAngle(const Triangle& t, const Vec3& point) noexcept {
  const Vec3 a = t.a - point, b = t.b - point, c = t.c - point;
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
