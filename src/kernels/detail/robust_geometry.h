#pragma once

// Private building blocks of the scalar robust kernels (point–triangle, segment–segment,
// triangle–triangle brute force, sphere): closest points in a local frame, with the one
// quantity that plain double arithmetic gets badly wrong, a thin triangle's normal, computed to
// full relative precision.
//
// Why the normal: a sliver of length L and height h has |n| ≈ L·h, but the rounding of a plain
// cross product is ε·L², so its direction is off by ε·L/h (1e-6 rad for h = 1e-10·L) and every
// height above its plane by that times the distance. Computed from error-free edge differences
// (Knuth's TwoSum) and Kahan's fused difference of products, n is exact to a few ulps of itself,
// so the triangle the kernels reason about is the input triangle up to rounding of its vertices,
// ε·L, whatever its shape.

#include <algorithm>
#include <cmath>
#include <limits>

#include "delta/core/triangle.h"
#include "delta/core/vec3.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/coordinate_range.h"

#include "exact_predicates.h"

namespace delta::detail {

inline constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

/// a·b − c·d to within 2 ulps of the result, however much cancels (Kahan; needs a true fused
/// multiply–add, which std::fma is).
inline double differenceOfProducts(double a, double b, double c, double d) noexcept {
  const double cd = c * d;
  const double roundingOfCd = std::fma(-c, d, cd);
  return std::fma(a, b, -cd) + roundingOfCd;
}

/// x − y as an unevaluated sum high + low, exactly (Knuth's TwoSum).
struct ExactDifference {
  Vec3 high;
  Vec3 low;
};

inline double twoDifferenceLow(double x, double y, double high) noexcept {
  const double yVirtual = x - high;
  const double xVirtual = high + yVirtual;
  return (x - xVirtual) + (yVirtual - y);
}

inline ExactDifference exactDifference(const Vec3& x, const Vec3& y) noexcept {
  const Vec3 high = x - y;
  return {high,
          {twoDifferenceLow(x.x, y.x, high.x), twoDifferenceLow(x.y, y.y, high.y),
           twoDifferenceLow(x.z, y.z, high.z)}};
}

/// u × v to a few ulps of each component (the products are exact under fma).
inline Vec3 accurateCross(const Vec3& u, const Vec3& v) noexcept {
  return {differenceOfProducts(u.y, v.z, u.z, v.y), differenceOfProducts(u.z, v.x, u.x, v.z),
          differenceOfProducts(u.x, v.y, u.y, v.x)};
}

/// Whether a plain cross product u × v is already accurate: its rounding is about ε·|u|·|v|, so
/// when the sine of the angle between u and v exceeds 1/√2 its relative error is below 3ε.
/// (Most pairs pass; the exact path costs fused multiply–adds, library calls on a baseline
/// x86-64 build.)
inline bool wellConditioned(const Vec3& product, const Vec3& u, const Vec3& v) noexcept {
  return lengthSquared(product) >= 0.5 * lengthSquared(u) * lengthSquared(v);
}

/// u × v to a few ulps of itself: the plain cross product when that is good enough, otherwise
/// accurateCross.
inline Vec3 crossToFewUlps(const Vec3& u, const Vec3& v) noexcept {
  const Vec3 plain = cross(u, v);
  return wellConditioned(plain, u, v) ? plain : accurateCross(u, v);
}

/// (b − a) × (c − a) to a few ulps of itself. For a thin triangle: of the exact differences, the
/// leading cross product accurately, plus the first-order terms of the differences' rounding
/// (the second-order term is below ε²·|b − a|·|c − a|).
inline Vec3 accurateNormal(const Vec3& a, const Vec3& b, const Vec3& c) noexcept {
  const Vec3 u0 = b - a, v0 = c - a, plain = cross(u0, v0);
  if (wellConditioned(plain, u0, v0)) return plain;
  const ExactDifference u = exactDifference(b, a), v = exactDifference(c, a);
  return accurateCross(u.high, v.high) + (cross(u.high, v.low) + cross(u.low, v.high));
}

/// A triangle in a local frame (its coordinates relative to a nearby origin), with what the
/// kernels need of it.
struct LocalTriangle {
  Vec3 vertex[3];
  Vec3 edge[3];  ///< vertex[i + 1] − vertex[i] (rounded)
  Vec3 normal;   ///< (vertex[1] − vertex[0]) × (vertex[2] − vertex[0]), accurate
  double normalLengthSquared = 0.0;
  double longestEdgeSquared = 0.0;
  /// Zero area within rounding (|n| ≤ 4ε·L², the triangle is within 4ε·L of a segment): it is
  /// then treated as the union of its edges, which is exact for a zero-area triangle.
  bool flat = true;
};

inline LocalTriangle makeLocalTriangle(const Vec3& a, const Vec3& b, const Vec3& c) noexcept {
  LocalTriangle t;
  t.vertex[0] = a;
  t.vertex[1] = b;
  t.vertex[2] = c;
  t.edge[0] = b - a;
  t.edge[1] = c - b;
  t.edge[2] = a - c;
  t.longestEdgeSquared =
      std::max({lengthSquared(t.edge[0]), lengthSquared(t.edge[1]), lengthSquared(t.edge[2])});
  t.normal = accurateNormal(a, b, c);
  t.normalLengthSquared = lengthSquared(t.normal);
  const double flatBound = 4.0 * kEpsilon * t.longestEdgeSquared;
  t.flat = !(t.normalLengthSquared > flatBound * flatBound);
  return t;
}

/// The point s0 + t·(s1 − s0), t ∈ [0, 1], closest to p (t = 0 for a zero-length segment).
struct SegmentPoint {
  Vec3 point;
  double t = 0.0;
  double distanceSquared = 0.0;
};

inline SegmentPoint closestOnSegment(const Vec3& p, const Vec3& s0, const Vec3& s1,
                                     const Vec3& direction) noexcept {
  const double squaredLength = lengthSquared(direction);
  double t = 0.0;
  if (squaredLength > 0.0) t = std::clamp(dot(p - s0, direction) / squaredLength, 0.0, 1.0);
  const Vec3 point = t == 1.0 ? s1 : s0 + direction * t;
  return {point, t, lengthSquared(p - point)};
}

/// The signed areas n·(eᵢ × (p − vᵢ)) of p against the edges of a local triangle, a opposite
/// vertex 0 (edge 1), b opposite vertex 1 (edge 2), c opposite vertex 2 (edge 0).
struct FaceAreas {
  double a = 0.0, b = 0.0, c = 0.0;
};

/// |v.x| + |v.y| + |v.z|, summed in that order (the exact lanes sum their magnitudes alike).
inline double normOne(const Vec3& v) noexcept {
  return (std::abs(v.x) + std::abs(v.y)) + std::abs(v.z);
}

/// The largest error of the face area n·(e × w) of insideLocalFace, e an edge and w = p − v from
/// its first corner, against the exact area of the exact triangle and point the local ones stand
/// for: 64ε·|n|₁·(|e|₁·(|p|₁ + L) + L·|w|₁), `size` = |n|₁, `point` = |p|₁ and L the longest
/// edge. Derived: p, the corner and the edge's ends are off by at most ε·|p| and εL (their
/// differences from the frame's origin rounded), so w by ε(|w| + |p| + L) and e by ε(|e| + 2L);
/// the accurate normal by 8ε of itself; the cross and dot products round by 6ε of |n|·|e|·|w|:
/// in all ε|n|·(17|e|·(|p| + L) + 2L·|w|). Per edge: an edge's own rounding, 2εL, turns its line
/// by 2εL/|e|, which only points far along it feel (a needle's short edge); one bound for the
/// three edges took points over a needle's face within 10⁻¹³·L²/h of its short edge (h long)
/// for points off the face and measured them to a long edge, up to h/2 too far. Written out once
/// here and once in lanes (query/detail/exact_lanes_body.h), in the same operations, so that
/// both give the same bits.
inline double faceAreaBound(const Vec3& e, const Vec3& w, double size, double point,
                            double longest) noexcept {
  return 64.0 * kEpsilon * size * (normOne(e) * (point + longest) + longest * normOne(w));
}

/// Where the projection of p onto a local triangle falls (sideOfLocalFace).
enum class FaceSide : unsigned char {
  kOutside,  ///< beyond an edge's line by more than its area's rounding, or a flat triangle
  kInside,   ///< inside every edge's line by more than its area's rounding
  kNearEdge  ///< neither: within the rounding of one or more edges' lines (`nearEdges`)
};

/// Where the projection of p onto a local triangle falls, with the areas that decide it (set for
/// kInside; for kNearEdge those of the edges in `nearEdges`, bit k for edge k, and of the edges
/// beyond their bounds): kInside where every area n·(e_k × (p − v_k)) exceeds its rounding
/// (faceAreaBound), kOutside for a flat triangle or where one lies below minus its rounding (or
/// is NaN), kNearEdge otherwise: the projection lies within that rounding of those edges' lines,
/// on either side (the exact signs decide, exactFaceAreaSign). Beyond an edge's end, near the tip
/// of a needle whose edges' lines meet at an angle below the rounding, the face's answer would be
/// the distance to the plane, not to the tip: a point 2.9e-11 from the tip of a needle 1 long and
/// 1e-12 high measured 1.0e-11 (and won a search against a triangle 2e-11 away); such a point is
/// never kInside, and exactly beyond the tip it is outside an edge's line.
inline FaceSide sideOfLocalFace(const Vec3& p, const LocalTriangle& t, FaceAreas& areas,
                                unsigned& nearEdges) noexcept {
  nearEdges = 0;
  if (t.flat) return FaceSide::kOutside;
  const double size = normOne(t.normal), point = normOne(p);
  const double longest = std::sqrt(t.longestEdgeSquared);
  double* area[3] = {&areas.c, &areas.a, &areas.b};  // edge k's area, opposite vertex k + 2
  for (int k = 0; k < 3; ++k) {
    const Vec3 w = p - t.vertex[k];
    *area[k] = dot(t.normal, cross(t.edge[k], w));
    const double bound = faceAreaBound(t.edge[k], w, size, point, longest);
    if (*area[k] > bound) continue;
    if (!(*area[k] >= -bound)) return FaceSide::kOutside;
    nearEdges |= 1u << k;
  }
  return nearEdges == 0 ? FaceSide::kInside : FaceSide::kNearEdge;
}

/// Whether the projection of p onto a non-flat local triangle falls inside it by more than the
/// areas' rounding (sideOfLocalFace's kInside), with the areas that decide it.
inline bool insideLocalFace(const Vec3& p, const LocalTriangle& t, FaceAreas& areas) noexcept {
  unsigned nearEdges = 0;
  return sideOfLocalFace(p, t, areas, nearEdges) == FaceSide::kInside;
}

/// Whether p's projection onto the triangle's plane lies strictly inside each edge k in
/// `nearEdges` (bit k: edge k from corner k to corner k + 1), decided exactly on the given
/// coordinates (exactFaceAreaSign): where the rounded face test leaves it within rounding of
/// those edges' lines. Measured to the edges there, a point over the face came out up to about
/// 2⁸ε·(|p − a| + 2L) too far (an audit found 205ε·(size + distance) beside the edges of strips
/// and fans, the tests' sweep 783ε). False on an edge's line (the edge's distance is then the
/// plane's), and where the exact signs do not apply (a coordinate below
/// kSmallestExactCoordinate but not 0, or beyond the coordinate range): the edges then answer
/// to that rounding.
inline bool insideNearEdges(const Vec3& p, const Triangle& triangle, unsigned nearEdges) {
  for (const Vec3& v : {p, triangle.a, triangle.b, triangle.c})
    if (!inCoordinateRange(v) || !detail::predicatesExactAt(v)) return false;
  const Vec3* corner[3] = {&triangle.a, &triangle.b, &triangle.c};
  for (int k = 0; k < 3; ++k)
    if ((nearEdges >> k & 1u) != 0u &&
        detail::exactFaceAreaSign(triangle.a, triangle.b, triangle.c, *corner[k],
                                  *corner[(k + 1) % 3], p) <= 0)
      return false;
  return true;
}

/// The projection of p onto a non-flat local triangle whose face region it lies in, from the
/// areas n·(e × (p − v)) of sideOfLocalFace: barycentrics from the areas normalised, each taken
/// as at least 0 (an area within its rounding of 0 may have rounded below it).
inline kernels::PointTriangleResult projectOntoLocalFace(const Vec3& p, const LocalTriangle& t,
                                                         const FaceAreas& areas) noexcept {
  const double a = std::fmax(areas.a, 0.0), b = std::fmax(areas.b, 0.0),
               c = std::fmax(areas.c, 0.0);
  const double sum = a + b + c;
  const Vec3 foot = p - t.normal * (dot(t.normal, p - t.vertex[0]) / t.normalLengthSquared);
  return {lengthSquared(p - foot), foot, sum > 0.0 ? b / sum : 0.0, sum > 0.0 ? c / sum : 0.0,
          kernels::TriangleFeature::Face};
}

/// The projection of p onto a non-flat local triangle when it falls inside (the face region of
/// closestOnLocalTriangle); false otherwise, or for a flat triangle. Triangle–triangle distance
/// needs only this of its vertex–face candidates: a vertex whose closest point is on an edge is
/// an end of two edges, and the edge–edge candidates already cover that distance.
inline bool closestOnLocalFace(const Vec3& p, const LocalTriangle& t,
                               kernels::PointTriangleResult& result) noexcept {
  FaceAreas areas;
  if (!insideLocalFace(p, t, areas)) return false;
  result = projectOntoLocalFace(p, t, areas);
  return true;
}

/// The closest point of p on the three edges of a local triangle (the answer of
/// closestOnLocalTriangle where p's projection falls outside, or the triangle is flat), with its
/// barycentrics and feature.
inline kernels::PointTriangleResult closestOnLocalEdges(const Vec3& p,
                                                        const LocalTriangle& t) noexcept {
  // The nearest edge; edge i runs from vertex i to vertex i + 1.
  kernels::PointTriangleResult best;
  const Vec3* v = t.vertex;
  best.distanceSquared = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const SegmentPoint s = closestOnSegment(p, v[i], v[(i + 1) % 3], t.edge[i]);
    if (!(s.distanceSquared < best.distanceSquared)) continue;
    best.distanceSquared = s.distanceSquared;
    best.closest = s.point;
    switch (i) {
      case 0:  // a → b
        best.u = s.t, best.v = 0.0;
        best.feature = s.t == 0.0   ? kernels::TriangleFeature::VertexA
                       : s.t == 1.0 ? kernels::TriangleFeature::VertexB
                                    : kernels::TriangleFeature::EdgeAB;
        break;
      case 1:  // b → c
        best.u = 1.0 - s.t, best.v = s.t;
        best.feature = s.t == 0.0   ? kernels::TriangleFeature::VertexB
                       : s.t == 1.0 ? kernels::TriangleFeature::VertexC
                                    : kernels::TriangleFeature::EdgeBC;
        break;
      default:  // c → a
        best.u = 0.0, best.v = 1.0 - s.t;
        best.feature = s.t == 0.0   ? kernels::TriangleFeature::VertexC
                       : s.t == 1.0 ? kernels::TriangleFeature::VertexA
                                    : kernels::TriangleFeature::EdgeCA;
        break;
    }
  }
  return best;
}

/// The closest point of a local triangle to p, with its barycentrics (point ≈ v0 + u·(v1 − v0) +
/// v·(v2 − v0)) and feature.
///
/// The face is chosen when the projection of p lies inside all three edges by more than the
/// areas' rounding (each n·(e × (p − v)) beyond its faceAreaBound); the point is then p's
/// projection along the accurate normal. Otherwise the nearest of the three edges, which is the
/// answer whenever the projection is outside, and within rounding of it where the projection lies
/// inside within rounding of an edge. (closestPointOnTriangle decides that band by exact signs of
/// the given coordinates, which a local triangle no longer holds; the triangle–triangle kernel's
/// points on both triangles take this rounded form.)
///
/// Barycentrics of a face point come from the same three signed areas, normalised, so they lie
/// in the triangle (to an ulp); for a needle of height h they carry the needle's conditioning, an
/// error of ε·L/h (the point itself does not).
inline kernels::PointTriangleResult closestOnLocalTriangle(const Vec3& p,
                                                           const LocalTriangle& t) noexcept {
  kernels::PointTriangleResult best;
  if (closestOnLocalFace(p, t, best)) return best;
  return closestOnLocalEdges(p, t);
}

/// Closest points of segments p0 + s·(p1 − p0) and q0 + t·(q1 − q0), s, t ∈ [0, 1].
struct SegmentPair {
  Vec3 p;
  Vec3 q;
  double s = 0.0;
  double t = 0.0;
  double distanceSquared = 0.0;
};

/// Ericson's closest points of two segments (Real-Time Collision Detection 5.1.9), with the line
/// parameter s = n·(d2 × r)/|n|², n = d1 × d2 to a few ulps of itself, instead of
/// (b·f − c·e)/(a·e − b²): near parallel, that Gram determinant and numerator cancel to noise
/// (relative error ε/sin²θ), while this s is off by at most ε·|r|/(|d1|·sinθ), which moves the
/// pair along the direction where the distance changes by sinθ, so the distance stays within
/// ε·|r|. Below sinθ = ε the segments are treated as parallel (s = 0); the second, clamping pass
/// then picks a closest pair among the (non-unique) closest pairs.
inline SegmentPair closestOnSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                     const Vec3& q1) noexcept {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = lengthSquared(d1), e = lengthSquared(d2), f = dot(d2, r);
  double s = 0.0, t = 0.0;
  if (!(a > 0.0)) {
    if (e > 0.0) t = std::clamp(f / e, 0.0, 1.0);  // the first is a point
  } else {
    const double c = dot(d1, r);
    if (!(e > 0.0)) {
      s = std::clamp(-c / a, 0.0, 1.0);  // the second is a point
    } else {
      const Vec3 n = crossToFewUlps(d1, d2);
      const double denominator = lengthSquared(n);
      if (denominator > (kEpsilon * a) * (kEpsilon * e))
        s = std::clamp(dot(n, cross(d2, r)) / denominator, 0.0, 1.0);
      t = dot(d2, r + d1 * s) / e;  // the point of the second line closest to p(s)
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((dot(d1, d2) - c) / a, 0.0, 1.0);
      }
    }
  }
  const Vec3 p = s == 1.0 ? p1 : p0 + d1 * s;
  const Vec3 q = t == 1.0 ? q1 : q0 + d2 * t;
  return {p, q, s, t, lengthSquared(p - q)};
}

}  // namespace delta::detail
