#pragma once

#include "delta/core/triangle.h"
#include "delta/core/vec3.h"

/// The geometry kernels: closest points of a point and a triangle, of two segments, of two
/// triangles (three solvers, batched with SIMD) and of spheres. All noexcept: they take plain
/// numbers, validate nothing, allocate nothing (but PairResults::reserve) and spawn no threads.
namespace delta::kernels {

/// The closest points of two solid triangles A = (a, b, c) and B = (a, b, c).
///
/// Threading: a value type; no shared state.
struct TriangleDistanceResult {
  double distanceSquared = 0.0;
  Vec3 p;  ///< on A: A.a + a1·(A.b − A.a) + a2·(A.c − A.a)
  Vec3 q;  ///< on B: B.a + a3·(B.b − B.a) + a4·(B.c − B.a)
  double a1 = 0.0, a2 = 0.0, a3 = 0.0, a4 = 0.0;  ///< the seed's four barycentric unknowns
  bool intersect = false;  ///< the triangles share at least one point (distance 0)
};

/// Triangle–triangle distance by brute force (the seed's robust if-based kernel): if the
/// triangles intersect, distance 0, `intersect = true` and p = q a point of their intersection;
/// otherwise the minimum over the 6 vertex–face and 9 edge–edge candidates. Zero-area triangles
/// degrade to segment or point cases. Every tolerance is relative to the triangles' size.
///
/// Precisely:
/// - Intersecting (see trianglesIntersect; touching counts): distanceSquared = 0, p = q = the
///   midpoint of the two intersection witnesses furthest apart, where the witnesses are the
///   points where an edge pierces the other triangle and the candidates closer than τ (and,
///   where the triangles meet only within the rounding of those tests, the points where the
///   edges that meet the other triangle exactly cross its plane, else the nearest candidates'
///   midpoint). For triangles crossing along a segment this is the middle of that segment; for
///   coplanar overlapping triangles a point of the overlap. (a1, a2) and (a3, a4) are its
///   barycentrics on A and on B.
/// - Otherwise the nearest of the 15 candidates (the first in the order A's vertices to B, B's
///   vertices to A, A's edge i to B's edge j, on ties); distanceSquared = |p − q|² > 0. Parallel
///   faces and parallel edges return one closest pair of the many.
/// - Zero-area triangles (area zero within rounding) are the union of their edges; a triangle
///   whose three vertices coincide is a point.
/// Accuracy: the distance is within a few ε·(size + distance) of the exact distance of the
/// stored input, near the origin or far from it (the work is done in the frame of first.a), and
/// 0 for every pair that meets exactly (trianglesIntersect); p and q lie on their triangles to
/// that accuracy plus the rounding of their own coordinates.
/// Never NaN for finite input (coordinates below about 1e150).
///
/// Threading: a pure function; safe from any thread.
TriangleDistanceResult triangleDistanceBruteForce(const Triangle& first,
                                                  const Triangle& second) noexcept;

/// Whether two solid triangles share a point (touching counts).
///
/// True for every pair that meets exactly, and for pairs closer than τ. Decided first by sign
/// tests relative to the triangles' size, in the frame of first.a: the triangles intersect when
/// neither triangle's plane has all three vertices of the other further than τ on one side
/// (Möller's rejection test), and either
/// - an edge of one pierces the other's interior: its ends further than τ from that plane, on
///   opposite sides, and the crossing point inside all three edges by more than the rounding of
///   the signs (taken with the accurate normal) and of the point, or
/// - one of the 15 vertex–face and edge–edge distances is at most τ (touching, and every
///   coplanar case).
/// Where neither holds but no plane separates them, exact orientation signs of the coordinates
/// as given decide (Shewchuk's filter, then exact arithmetic: kernels/detail/exact_predicates.h):
/// the pairs that meet only within the rounding of the tests above, as an edge crossing a
/// needle within the rounding of its boundary (where the rounded tests measured a gap: 9.4e-12
/// at L = 7.1, 4.5e-9 at L = 2048 1e9 from the origin, in an audit's sweeps) or a vertex on a
/// face whose distances round to more than τ. The exact signs need every coordinate 0 or of
/// magnitude within [2⁻²⁵⁰, 2²⁰⁰] (below, their products could underflow); for a coordinate
/// outside that, and for two triangles both of exactly zero area, the rounded tests alone
/// answer.
/// τ = 32·ε·R, R the largest coordinate of the six vertices in that frame (about 7e-15 of the
/// size for nearby triangles): pairs closer than τ count as touching, so the answer differs
/// from the exact one only by pairs apart by less than τ, called intersecting. This is the same
/// decision as triangleDistanceBruteForce's `intersect`, so it holds exactly when that distance
/// is 0. Identical, coplanar overlapping and degenerate triangles are decided by the same rules
/// (a point-like triangle intersects a triangle it lies on). A segment crossing a triangle's
/// plane within the rounding of its boundary is not taken for a piercing by the rounded test:
/// beyond a needle's tip the lines of its long edges lie within rounding of each other, and
/// segments 4.9e-8 beyond the tip of a needle 1e-12 high were called intersecting.
///
/// Threading: a pure function; safe from any thread.
bool trianglesIntersect(const Triangle& first, const Triangle& second) noexcept;

}  // namespace delta::kernels
