#pragma once

#include <cstdint>

#include "delta/core/triangle.h"
#include "delta/core/vec3.h"

namespace delta::kernels {

/// The feature of a triangle (a, b, c) that a closest point lies on. A closest point at a vertex
/// is a vertex feature, on an edge between its ends an edge feature, inside the face Face.
enum class TriangleFeature : std::uint8_t {
  VertexA,
  VertexB,
  VertexC,
  EdgeAB,
  EdgeBC,
  EdgeCA,
  Face
};

/// The point of a triangle closest to a query point.
///
/// Threading: a value type; no shared state.
struct PointTriangleResult {
  double distanceSquared = 0.0;
  Vec3 closest;  ///< = a + u·(b − a) + v·(c − a)
  double u = 0.0;
  double v = 0.0;
  TriangleFeature feature = TriangleFeature::Face;
};

/// Squared distances at most this times the longest edge's square are checked exactly for a
/// point on the triangle's boundary (closestPointOnTriangle): 2⁻⁸⁰·L², some 2²⁴ times the square
/// of the kernel's rounding error (a few ε·L) for such a point, so that none escapes the check.
inline constexpr double kExactBoundaryCheck = 0x1p-80;

/// A triangle whose longest edge's square is below this (edges below 2⁻¹⁵⁰: only near the origin,
/// in a mesh that also has larger ones) is solved scaled up by a power of two
/// (closestPointOnTriangle): its normal's square and the flatness bound's, of degree 4, underflow
/// from about 2⁻²⁴⁰ on, and a triangle 1e-100 across was taken for flat (a point over its face
/// measured to its edges, 2.7 times too far).
inline constexpr double kTinyTriangleSquared = 0x1p-300;

/// Closest point on a solid triangle to `p`, by Voronoi regions of the vertices, edges and face
/// (Ericson, Real-Time Collision Detection, 5.1.5). A zero-area triangle degrades to its longest
/// edge (a segment) or to a point; the result is never NaN for finite input.
///
/// Precisely: the face is chosen when the projection of `p` lies inside all three edges, and the
/// closest point is then that projection (`feature` Face); otherwise it is the closest point of
/// the nearest edge (an edge feature, or a vertex feature when it is an end of that edge). The
/// side of each edge's line comes from the rounded area that decides it where that lies beyond
/// its rounding, and from an exact sign of the given coordinates where it does not (a projection
/// within that rounding of an edge's line), for coordinates within the coordinate range and 0 or
/// at least 2⁻²⁵⁰ in magnitude; for others the edges answer there, up to about
/// 2⁸ε·(|p − a| + 2L) too far. (Beyond the tip of a needle the edges' lines lie within rounding
/// of each other: a point there measured to the face's plane came out up to 10⁷ times the
/// accuracy below too close.) `u, v ≥ 0` and `u + v ≤ 1` (to an ulp) always.
///
/// Robustness: computed in the frame of `triangle.a`, with the face normal accurate to a few ulps
/// of itself (error-free edge differences and fused multiply–adds), so slivers are handled: the
/// distance is within a few ε·(size + distance) of the exact distance of the stored input, near
/// the origin or at 1e6 (points within rounding of edges' lines, triangles turned at offsets up
/// to 1e3: 5ε·(size + distance) at most in the tests' sweep, where the rounded face test alone
/// gave up to 783ε). A triangle whose area is zero within rounding (|normal| ≤ 4ε·L², L its
/// longest edge) is the union of its edges. For a needle of height h the closest point stays
/// accurate, but (u, v) carry the needle's conditioning, an error of order ε·L/h (the point
/// a + u·(b − a) + v·(c − a) can then be off by ε·L²/h along the needle).
///
/// A point on the triangle (within rounding) gets distance 0, or a rounding error's, and itself
/// as the closest point. A point exactly on a vertex or an edge (in exact arithmetic on the
/// doubles given) gets distance exactly 0 and itself as the closest point, so that the triangles
/// sharing that vertex or edge tie and a search names the smallest id: where the computed
/// squared distance is at most kExactBoundaryCheck·L² (L the longest edge, far above the
/// rounding), an exact test (Shewchuk's expansions) decides whether the point lies on one of the
/// three edges. (A point exactly inside the face keeps the projection's rounding error.)
/// A tiny triangle (longest edge's square below kTinyTriangleSquared) is solved scaled up by a
/// power of two (exact) to about 1, the point with it, and the answer scaled back: as accurate
/// relative to its size as any other (its squared distance may underflow, not its closest point).
/// Coordinates must be finite and, for the accuracy above, within ±kLargestCoordinate
/// (mesh/coordinate_range.h: 2²⁰⁰; the queries check it): distanceSquared overflows to +∞ for
/// distances beyond about 1e154, and the edge tests, of degree 4, beyond 1e77. A square below about
/// 1e-308 loses precision to underflow (distanceAtScale does not).
///
/// Threading: a pure function; safe from any thread.
PointTriangleResult closestPointOnTriangle(const Vec3& p, const Triangle& triangle) noexcept;

/// The distance closestPointOnTriangle gives, √distanceSquared, computed where its square does
/// not underflow: 0 for a point exactly on the triangle's boundary (as the kernel decides it),
/// otherwise the kernel run on `p` and the triangle less its first vertex (the differences it
/// takes itself) scaled by a power of two to about the triangle's size (exact), and scaled back.
/// Bit for bit √distanceSquared wherever nothing underflows; below (a triangle and a gap both
/// smaller than about 1e-150) it keeps the kernel's accuracy, a few ε·(size + distance), where
/// the square loses it or is 0: a point 1e-300 off a triangle of size 1e-300 is at 1e-300, not
/// 0. (Off a triangle of size 1, 1e-300 is far below that accuracy, and 0 is its answer.)
///
/// Threading: a pure function; safe from any thread.
double distanceAtScale(const Vec3& p, const Triangle& triangle) noexcept;

}  // namespace delta::kernels
