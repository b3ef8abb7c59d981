#pragma once

#include "delta/core/sphere.h"
#include "delta/core/triangle.h"
#include "delta/core/vec3.h"

namespace delta::kernels {

/// Closest points between a sphere's surface and another geometry.
///
/// Threading: a value type; no shared state.
struct SphereContactResult {
  double gap = 0.0;      ///< surface-to-surface distance; negative by the depth when they overlap
  Vec3 p;                ///< on the sphere's surface, toward the other geometry
  Vec3 q;                ///< on the other geometry (for a sphere, on its surface)
  Vec3 normal;           ///< unit vector from the other geometry toward the first sphere's centre
  bool overlap = false;  ///< gap < 0
};

/// Sphere–sphere. Concentric spheres get the normal +x (any direction is correct). Lengths are
/// computed with scaling, so centres 1e-300 or 1e300 apart work too (but centres whose
/// difference overflows, as ±1.8e308, give NaN). gap = |c₁ − c₂| − r₁ − r₂:
/// negative, by the depth, where the balls overlap (one inside the other included). Radii are
/// not checked: a radius of 0 is a point; the queries that take spheres require positive ones.
///
/// Threading: a pure function; safe from any thread.
SphereContactResult sphereSphere(const Sphere& first, const Sphere& second) noexcept;

/// Sphere–triangle (solid triangle). A centre on the triangle gets the face normal (for a
/// triangle of zero area within rounding, |(b − a) × (c − a)| ≤ 4ε·L², L its longest edge: any
/// unit vector orthogonal to its longest edge, or +x for a point).
///
/// "On the triangle" means within 1024ε of the scale (the centre's distance from triangle.a plus
/// the longest edge), where the direction to the closest point is rounding noise (beside an edge
/// the face's own test is that uncertain); the face normal is then (b − a) × (c − a), normalised.
/// Otherwise the normal is the unit vector from the closest point (`q`) to the centre, gap =
/// |centre − q| − radius. A zero-area triangle is its longest edge or its point
/// (closestPointOnTriangle).
///
/// Range: the answers hold, never NaN, for coordinates, radii and triangle sizes between 2⁻²⁰⁰
/// and 2²⁰⁰ in magnitude (coordinate_range.h; the queries check it, the kernel does not): beyond
/// it squares and products of degree 4 underflow or overflow, and an answer can be wrong (an
/// audit: 0.2 of the distance for a triangle 1e-100 across), or NaN where coordinate differences
/// overflow.
///
/// Threading: a pure function; safe from any thread.
SphereContactResult sphereTriangle(const Sphere& sphere, const Triangle& triangle) noexcept;

/// A triangle made ready for many sphereTriangle calls: what the kernel computes of the
/// triangle alone (its edges in a frame at its first corner, the accurate normal and its unit
/// vector, whether it is flat), computed once. sphereTriangle(sphere, PreparedTriangle(t)) is
/// sphereTriangle(sphere, t), bit for bit; it saves the triangle's part of the work where one
/// triangle meets a sphere step after step (contactdetection::SphereContactCache).
///
/// Threading: a value type; no shared state.
class PreparedTriangle {
 public:
  PreparedTriangle() = default;
  explicit PreparedTriangle(const Triangle& triangle) noexcept;

 private:
  friend SphereContactResult sphereTriangle(const Sphere& sphere,
                                            const PreparedTriangle& triangle) noexcept;
  Vec3 origin_;                       ///< the first corner, a
  Vec3 b_, c_;                        ///< b − a and c − a
  Vec3 edge_;                         ///< (c − a) − (b − a), rounded as the kernel rounds it
  Vec3 normal_;                       ///< (b − a) × (c − a), accurate
  Vec3 unitNormal_;                   ///< normal_ normalised (zero where flat)
  double normalLengthSquared_ = 0.0;  ///< |normal|²
  double longestEdgeSquared_ = 0.0;   ///< the longest edge's squared length
  double longestEdge_ = 0.0;          ///< its length
  bool flat_ = true;                  ///< zero area within rounding
};

/// sphereTriangle on a prepared triangle: the same answer, bit for bit.
///
/// Threading: a pure function; safe from any thread.
SphereContactResult sphereTriangle(const Sphere& sphere, const PreparedTriangle& triangle) noexcept;

}  // namespace delta::kernels
