#include "delta/kernels/point_triangle.h"

#include "detail/robust_geometry.h"

namespace delta::kernels {

PointTriangleResult closestPointOnTriangle(const Vec3& p, const Triangle& triangle) noexcept {
  // In the frame of the first vertex: the differences of nearby coordinates are exact, so the
  // answer is as accurate relative to the triangle's size far from the origin as near it.
  const Vec3& origin = triangle.a;
  const detail::LocalTriangle local =
      detail::makeLocalTriangle({}, triangle.b - origin, triangle.c - origin);
  PointTriangleResult result = detail::closestOnLocalTriangle(p - origin, local);
  result.closest += origin;
  return result;
}

}  // namespace delta::kernels
