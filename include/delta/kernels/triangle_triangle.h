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
///   points where an edge pierces the other triangle and the candidates closer than τ. For
///   triangles crossing along a segment this is the middle of that segment; for coplanar
///   overlapping triangles a point of the overlap. (a1, a2) and (a3, a4) are its barycentrics on
///   A and on B.
/// - Otherwise the nearest of the 15 candidates (the first in the order A's vertices to B, B's
///   vertices to A, A's edge i to B's edge j, on ties); distanceSquared = |p − q|² > 0. Parallel
///   faces and parallel edges return one closest pair of the many.
/// - Zero-area triangles (area zero within rounding) are the union of their edges; a triangle
///   whose three vertices coincide is a point.
/// Accuracy: the distance is within a few ε·(size + distance) of the exact distance of the
/// stored input, near the origin or far from it (the work is done in the frame of first.a),
/// but for an edge piercing the other triangle within the rounding of its signs and of its
/// crossing point of the boundary (trianglesIntersect; the crossing point's rounding grows as the
/// edge lies closer to the plane), which is measured to that boundary: up to 2.2e-12 of the
/// size in an audit's sweeps of 240,000 needle and sliver pairs (two such pairs);
/// p and q lie on their triangles to that accuracy plus the rounding of their own coordinates.
/// Never NaN for finite input (coordinates below about 1e150).
///
/// Threading: a pure function; safe from any thread.
TriangleDistanceResult triangleDistanceBruteForce(const Triangle& first,
                                                  const Triangle& second) noexcept;

/// Whether two solid triangles share a point (touching counts).
///
/// Decided by sign tests relative to the triangles' size, in the frame of first.a. The triangles
/// intersect when neither triangle's plane has all three vertices of the other further than τ on
/// one side (Möller's rejection test), and either
/// - an edge of one pierces the other's interior: its ends further than τ from that plane, on
///   opposite sides, and the crossing point inside all three edges by more than the rounding of
///   the signs (taken with the accurate normal) and of the point, or
/// - one of the 15 vertex–face and edge–edge distances is at most τ (touching, and every
///   coplanar case).
/// τ = 32·ε·R, R the largest coordinate of the six vertices in that frame (about 7e-15 of the
/// size for nearby triangles): pairs closer than τ count as touching. This is the same decision
/// as triangleDistanceBruteForce's `intersect`, so it holds exactly when that distance is 0.
/// Identical, coplanar overlapping and degenerate triangles are decided by the same rules (a
/// point-like triangle intersects a triangle it lies on). A segment crossing a triangle's plane
/// within that rounding of its boundary is not taken for a piercing: beyond a needle's tip the
/// lines of its long edges lie within rounding of each other, and segments 4.9e-8 beyond the tip
/// of a needle 1e-12 high were called intersecting. The price is at the other side of the
/// boundary: an edge piercing near it is measured to it (an audit found 2.5e-14 for L = 1.3
/// across a needle's width, and 4.5e-9 for L = 2048 at a shallow crossing 1e9 from the origin,
/// where the triangles meet).
///
/// Threading: a pure function; safe from any thread.
bool trianglesIntersect(const Triangle& first, const Triangle& second) noexcept;

}  // namespace delta::kernels
