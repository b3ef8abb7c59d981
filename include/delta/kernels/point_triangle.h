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

/// Closest point on a solid triangle to `p`, by Voronoi regions of the vertices, edges and face
/// (Ericson, Real-Time Collision Detection, 5.1.5). A zero-area triangle degrades to its longest
/// edge (a segment) or to a point; the result is never NaN for finite input.
///
/// Precisely: the face is chosen when the projection of `p` lies inside all three edges, and the
/// closest point is then that projection (`feature` Face, also for a point exactly on an edge of
/// the face); otherwise it is the closest point of the nearest edge (an edge feature, or a vertex
/// feature when it is an end of that edge). `u, v ≥ 0` and `u + v ≤ 1` (to an ulp) always.
///
/// Robustness: computed in the frame of `triangle.a`, with the face normal accurate to a few ulps
/// of itself (error-free edge differences and fused multiply–adds), so slivers are handled: the
/// distance is within a few ε·(size + distance) of the exact distance of the stored input, near
/// the origin or at 1e6. A triangle whose area is zero within rounding (|normal| ≤ 4ε·L², L its
/// longest edge) is the union of its edges. For a needle of height h the closest point stays
/// accurate, but (u, v) carry the needle's conditioning, an error of order ε·L/h (the point
/// a + u·(b − a) + v·(c − a) can then be off by ε·L²/h along the needle).
///
/// A point on the triangle (within rounding) gets distance 0, or a rounding error's, and itself
/// as the closest point. Coordinates must be finite; distanceSquared overflows to +∞ for
/// distances beyond about 1e154.
///
/// Threading: a pure function; safe from any thread.
PointTriangleResult closestPointOnTriangle(const Vec3& p, const Triangle& triangle) noexcept;

}  // namespace delta::kernels
