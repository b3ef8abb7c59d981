#include "delta/kernels/sphere.h"

#include <cmath>

#include "detail/robust_geometry.h"

namespace delta::kernels {
namespace {

/// |v| without overflow or underflow for any finite v.
double safeLength(const Vec3& v) noexcept {
  const double largest = maxAbs(v);
  return largest > 0.0 ? largest * length(v / largest) : 0.0;
}

/// v / |v| for a non-zero finite v, scaled first so that tiny and huge vectors work too.
Vec3 unit(const Vec3& v) noexcept {
  const Vec3 w = v / maxAbs(v);
  return w / length(w);
}

/// A unit vector orthogonal to the non-zero vector d.
Vec3 orthogonalUnit(const Vec3& d) noexcept {
  const Vec3 w = unit(d);
  const Vec3 axis = std::fabs(w.x) <= std::fabs(w.y) && std::fabs(w.x) <= std::fabs(w.z)
                        ? Vec3{1, 0, 0}
                        : (std::fabs(w.y) <= std::fabs(w.z) ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  return unit(cross(w, axis));  // |w × axis| ≥ √(2/3): the smallest component of w is ≤ 1/√3
}

/// Centres closer than this to the triangle (relative to the frame's scale) count as on it.
constexpr double kOnTriangleUlps = 8.0;

}  // namespace

SphereContactResult sphereSphere(const Sphere& first, const Sphere& second) noexcept {
  const Vec3 difference = first.center - second.center;
  const double gap = safeLength(difference) - first.radius - second.radius;
  const Vec3 normal = maxAbs(difference) > 0.0 ? unit(difference) : Vec3{1, 0, 0};
  return {gap, first.center - normal * first.radius, second.center + normal * second.radius, normal,
          gap < 0.0};
}

SphereContactResult sphereTriangle(const Sphere& sphere, const Triangle& triangle) noexcept {
  const Vec3& origin = triangle.a;
  const detail::LocalTriangle local =
      detail::makeLocalTriangle({}, triangle.b - origin, triangle.c - origin);
  const Vec3 center = sphere.center - origin;
  const PointTriangleResult closest = detail::closestOnLocalTriangle(center, local);
  const Vec3 away = center - closest.closest;
  const double distance = safeLength(away);

  Vec3 normal;
  const double scale = maxAbs(center) + std::sqrt(local.longestEdgeSquared);
  if (distance > kOnTriangleUlps * detail::kEpsilon * scale) {
    normal = unit(away);
  } else if (!local.flat) {
    normal = unit(local.normal);
  } else if (local.longestEdgeSquared > 0.0) {
    const Vec3* e = local.edge;
    const Vec3& longest = lengthSquared(e[0]) >= lengthSquared(e[1])
                              ? (lengthSquared(e[0]) >= lengthSquared(e[2]) ? e[0] : e[2])
                              : (lengthSquared(e[1]) >= lengthSquared(e[2]) ? e[1] : e[2]);
    normal = orthogonalUnit(longest);
  } else {
    normal = {1, 0, 0};  // the triangle is a point
  }
  const double gap = distance - sphere.radius;
  return {gap, sphere.center - normal * sphere.radius, closest.closest + origin, normal, gap < 0.0};
}

}  // namespace delta::kernels
