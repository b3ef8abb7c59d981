#pragma once

#include "delta/core/vec3.h"

namespace delta::kernels {

/// The closest points of two segments.
///
/// Threading: a value type; no shared state.
struct SegmentSegmentResult {
  double distanceSquared = 0.0;
  Vec3 p;          ///< on the first segment: p0 + s·(p1 − p0)
  Vec3 q;          ///< on the second segment: q0 + t·(q1 − q0)
  double s = 0.0;  ///< in [0, 1]
  double t = 0.0;  ///< in [0, 1]
};

/// Closest points of segments [p0, p1] and [q0, q1]. Robust for parallel and zero-length
/// segments: parallel segments return one pair of closest points (the set is not unique); a
/// zero-length segment is a point. Never NaN for finite input.
///
/// Precisely (Ericson, Real-Time Collision Detection 5.1.9, with the line parameter taken from
/// cross products instead of the Gram determinant, which cancels completely near parallel):
/// - skew segments: the unique closest pair (intersecting segments: distance 0, p = q their
///   crossing, to rounding);
/// - parallel (sinθ below ε) or near parallel: one closest pair; for overlapping parallel
///   segments a pair straight across, inside the overlap;
/// - p0 = p1: s = 0 and q the closest point of the second segment (likewise t = 0 for q0 = q1;
///   both points: s = t = 0).
/// distanceSquared = |p − q|², within a few ε·(length + distance) of the exact distance,
/// computed in the frame of p0 so that it holds far from the origin too.
///
/// Threading: a pure function; safe from any thread.
SegmentSegmentResult closestPointsOnSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                             const Vec3& q1) noexcept;

}  // namespace delta::kernels
