#pragma once

// The exact oracle for the triangle kernels, built on CGAL and independent of Δ's code.
//
// Intersection is decided by CGAL's exact predicates (Epick: interval filters with an exact
// fallback, exact on double input). The distance of two disjoint triangles is the minimum of the
// 6 vertex–triangle and 9 edge–edge distances, built from CGAL's point–segment, segment–segment
// and point–plane distances. CGAL's own Triangle_3–Triangle_3 squared_distance is not the oracle:
// on zero-area triangles its vertex–triangle step gives up and it can return 0 for disjoint
// triangles, and do_intersect has non-degenerate preconditions; the tests use it as a cross-check
// on non-degenerate pairs (`cgalTriangleSquaredDistance`). A zero-area triangle is the union of
// its edges, so it is handled through its edges (segments, or a point when both ends coincide).
//
// Exact rational arithmetic (Simple_cartesian<Gmpq>) costs about 300 µs a pair, too slow for 10^5
// pairs in CI, so the candidates are first evaluated by the same code in interval arithmetic
// (Simple_cartesian<Interval_nt>, which throws when a branch cannot be decided). The answer is the
// interval enclosure's midpoint when the enclosure pins the distance to within
// kCertifiedFraction × (size + distance); otherwise the candidates that may be the minimum are
// recomputed in exact rationals and the exact minimum is rounded to double once.
// `exactSquaredDistanceRational` is the unfiltered version, against which the filter is tested.
// Defined in exact_distance.cpp, so that only that file parses CGAL.

#include "delta/core/triangle.h"
#include "delta/core/vec3.h"

namespace delta::test {

/// The filtered oracle's distance d is within kCertifiedFraction × (size + d) of the exact
/// distance; the tests' tolerance, 1e-12 × size, is 500 times coarser for near pairs (and 10 times
/// for pairs 50 sizes apart, where d itself carries rounding of 1e-16 × d).
inline constexpr double kCertifiedFraction = 2e-15;

/// Whether the two solid triangles share a point, decided exactly (touching counts). Zero-area
/// triangles are the union of their edges.
bool exactIntersect(const Triangle& first, const Triangle& second);

/// The squared distance of the two solid triangles (0 when they intersect), its square root
/// within kCertifiedFraction × (pairSize + distance) of the exact distance (an interval filter,
/// with exact rational arithmetic where the intervals are too wide).
double exactSquaredDistance(const Triangle& first, const Triangle& second);

/// The squared distance from a point to a solid triangle, its square root within
/// kCertifiedFraction × (longest edge + distance) of the exact distance (interval filter, exact
/// rational fallback, as for two triangles).
double exactSquaredDistance(const Vec3& p, const Triangle& triangle);

/// The squared distance between two segments (either may have zero length), certified likewise.
double exactSquaredDistance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1);

/// The unfiltered versions, in exact rational arithmetic rounded to double once, at the end (about
/// 300 µs a triangle pair): what the filters above are tested against.
double exactSquaredDistanceRational(const Triangle& first, const Triangle& second);
double exactSquaredDistanceRational(const Vec3& p, const Triangle& triangle);
double exactSquaredDistanceRational(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1);

/// CGAL's own Triangle_3–Triangle_3 squared distance in exact rationals (about 300 µs a pair),
/// for non-degenerate triangles only; the tests cross-check the oracle above with it.
double cgalTriangleSquaredDistance(const Triangle& first, const Triangle& second);

}  // namespace delta::test
