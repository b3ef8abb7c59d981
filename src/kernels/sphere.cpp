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

/// Centres closer than this to the triangle (relative to the frame's scale) count as on it: the
/// face test near an edge (robust_geometry.h's insideLocalFace) defers to the edges within its
/// rounding, about 100 to 400 ulps of the scale for a well-shaped triangle, and a centre on the
/// face there took the direction from the edge, in the face's plane (an audit: a centre 2⁻⁴⁶ from
/// an edge of the unit triangle, on it, got (0, 1, 0) for (0, 0, 1); 8 ulps were the bound then).
constexpr double kOnTriangleUlps = 1024.0;

}  // namespace

SphereContactResult sphereSphere(const Sphere& first, const Sphere& second) noexcept {
  const Vec3 difference = first.center - second.center;
  const double gap = safeLength(difference) - first.radius - second.radius;
  const Vec3 normal = maxAbs(difference) > 0.0 ? unit(difference) : Vec3{1, 0, 0};
  return {gap, first.center - normal * first.radius, second.center + normal * second.radius, normal,
          gap < 0.0};
}

namespace {

/// The kernel on a triangle in its local frame (its first corner at the origin), with
/// `longestEdge` = √(local.longestEdgeSquared) and, for a triangle that is not flat,
/// `unitNormal()` = unit(local.normal) (called only where the face is taken).
///
/// Where the centre projects inside the face (most spheres on a wall), its distance is its height
/// over the plane along the unit normal: one dot product, where the closest point's difference
/// scaled and normalised took seven divisions and a square root in a chain. The height is exact
/// to a few ulps of |centre − a| either way (the normal's rounding and the dot product's).
template <typename UnitNormal>
SphereContactResult sphereLocalTriangle(const Sphere& sphere, const Vec3& origin,
                                        const detail::LocalTriangle& local, double longestEdge,
                                        const UnitNormal& unitNormal) noexcept {
  const Vec3 center = sphere.center - origin;
  const double onTriangle = kOnTriangleUlps * detail::kEpsilon * (maxAbs(center) + longestEdge);
  detail::FaceAreas areas;
  if (detail::insideLocalFace(center, local, areas)) {
    const Vec3 up = unitNormal();
    const double height = dot(up, center);  // the local triangle's first corner is the origin
    const double distance = std::fabs(height);
    const Vec3 normal = distance > onTriangle && height < 0.0 ? -up : up;
    const double gap = distance - sphere.radius;
    return {gap, sphere.center - normal * sphere.radius, (center - up * height) + origin, normal,
            gap < 0.0};
  }
  const PointTriangleResult closest = detail::closestOnLocalEdges(center, local);
  const Vec3 away = center - closest.closest;
  // safeLength(away) and unit(away) from one scaled copy: the same bits, half the divisions.
  const double largest = maxAbs(away);
  const Vec3 scaled = largest > 0.0 ? away / largest : Vec3{};
  const double scaledLength = length(scaled);
  const double distance = largest > 0.0 ? largest * scaledLength : 0.0;

  Vec3 normal;
  if (distance > onTriangle) {
    normal = scaled / scaledLength;
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

detail::LocalTriangle localTriangle(const Triangle& triangle) noexcept {
  return detail::makeLocalTriangle({}, triangle.b - triangle.a, triangle.c - triangle.a);
}

}  // namespace

SphereContactResult sphereTriangle(const Sphere& sphere, const Triangle& triangle) noexcept {
  const detail::LocalTriangle local = localTriangle(triangle);
  return sphereLocalTriangle(sphere, triangle.a, local, std::sqrt(local.longestEdgeSquared),
                             [&local] { return unit(local.normal); });
}

PreparedTriangle::PreparedTriangle(const Triangle& triangle) noexcept : origin_(triangle.a) {
  const detail::LocalTriangle local = localTriangle(triangle);
  b_ = local.vertex[1];
  c_ = local.vertex[2];
  edge_ = local.edge[1];
  normal_ = local.normal;
  normalLengthSquared_ = local.normalLengthSquared;
  longestEdgeSquared_ = local.longestEdgeSquared;
  longestEdge_ = std::sqrt(local.longestEdgeSquared);
  flat_ = local.flat;
  if (!flat_) unitNormal_ = unit(normal_);
}

SphereContactResult sphereTriangle(const Sphere& sphere,
                                   const PreparedTriangle& triangle) noexcept {
  // The local triangle makeLocalTriangle({}, b − a, c − a) gives, with its edges as it forms
  // them (0 − x is not −x for a zero: the signs of zeros stay as they were).
  detail::LocalTriangle local;
  local.vertex[0] = {};
  local.vertex[1] = triangle.b_;
  local.vertex[2] = triangle.c_;
  local.edge[0] = triangle.b_ - Vec3{};
  local.edge[1] = triangle.edge_;
  local.edge[2] = Vec3{} - triangle.c_;
  local.normal = triangle.normal_;
  local.normalLengthSquared = triangle.normalLengthSquared_;
  local.longestEdgeSquared = triangle.longestEdgeSquared_;
  local.flat = triangle.flat_;
  return sphereLocalTriangle(sphere, triangle.origin_, local, triangle.longestEdge_,
                             [&triangle] { return triangle.unitNormal_; });
}

}  // namespace delta::kernels
