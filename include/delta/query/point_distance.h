#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/core/vec3.h"
#include "delta/query/query_mesh.h"

namespace delta::contactdetection {

/// The triangle id of a point that has no answer (further than ε).
inline constexpr std::uint32_t kNoTriangle = std::numeric_limits<std::uint32_t>::max();

/// A point's distance to a mesh.
///
/// Threading: a value type; no shared state.
struct PointDistance {
  /// The (unsigned) distance to the closest point of the mesh; +∞ for a point further than ε.
  double distance = std::numeric_limits<double>::infinity();
  Vec3 closest;  ///< the closest point of the mesh
  /// The triangle it lies on: the smallest id of a tie, such as a point exactly on a vertex or
  /// an edge, which every triangle sharing it is at distance 0 from.
  std::uint32_t triangle = kNoTriangle;
  bool inside = false;  ///< inside the closed mesh (signed queries only)

  bool found() const noexcept { return triangle != kNoTriangle; }
  /// The distance, negative inside (signed queries).
  double signedDistance() const noexcept { return inside ? -distance : distance; }
};

/// What a points–mesh query asks.
///
/// Threading: a value type; no shared state.
struct PointQuery {
  /// Answer only points closer than ε (strictly); the others get distance +∞ and no triangle.
  /// A finite ε lets the search stop near the root for points far from the mesh.
  double epsilon = std::numeric_limits<double>::infinity();
  /// Also decide inside/outside (the mesh must be closed): by the angle-weighted pseudonormal of
  /// the feature (vertex, edge or face) the closest point lies on, which is exact for any point
  /// off the surface, with the generalized winding number where rounding leaves that in doubt.
  /// A point on the surface (distance 0) is not inside.
  bool signedDistance = false;
};

/// The distance from every point to the mesh, in input order: the exact minimum over all
/// triangles of kernels::closestPointOnTriangle — the same distance, closest point and triangle
/// (ties to the smallest id) as a loop over every triangle — found by nearest-first descent of
/// the QueryMesh's tree, in parallel over the points (core/parallel.h). Deterministic: the same
/// answer for any thread count.
///
/// Degenerate input: zero-area triangles are the segments or points they are; coincident points
/// get the same answer; a point on the surface gets distance 0 (within rounding) and is not
/// inside; a point exactly on a vertex or an edge gets distance exactly 0, itself as the closest
/// point and the smallest id of the triangles sharing it (kernels::closestPointOnTriangle decides
/// it exactly). A closed mesh that intersects itself has no well-defined inside: its signs are
/// those of the closest feature's pseudonormal; a point outside the mesh's box is outside.
///
/// Coordinates (mesh/coordinate_range.h): every point, where it is and carried into the mesh's
/// prepared frame by its pose, must lie within ±2²⁰⁰ (kLargestCoordinate, 1.6e60), where squared
/// distances cannot overflow; answers are then finite and exact as above. At the small end, where
/// the squared distance underflows (below 2⁻⁹⁶⁰, distances under 1.5e-154), the triangles that
/// tie at 0 are compared by their distances at a power-of-two scale (kernels::distanceAtScale),
/// so a point 1e-301 off a triangle of size 1e-300 is at 1e-301 and signed, not on the surface;
/// off a triangle of size 1 such a gap is below the kernel's rounding, and 0 is the answer.
///
/// Throws delta::Error when ε is NaN or not positive, a point has a non-finite coordinate or one
/// beyond ±2²⁰⁰ where it is or in the mesh's frame (the error names its index, the coordinates
/// and the range), or `signedDistance` is asked of a mesh that is not closed (the error says how:
/// boundary, non-manifold or misoriented edges). No points: an empty result.
///
/// Threading: reads its inputs only; any number of threads may query one QueryMesh at once (in
/// an enclosing OpenMP parallel region each call runs serially on its own thread).
std::vector<PointDistance> distances(const QueryMesh& mesh, std::span<const Vec3> points,
                                     const PointQuery& query = {});

/// The same, for points given as three coordinate arrays of equal length (structure of arrays;
/// delta::Error for different lengths).
std::vector<PointDistance> distances(const QueryMesh& mesh, std::span<const double> x,
                                     std::span<const double> y, std::span<const double> z,
                                     const PointQuery& query = {});

/// The same, written into `out` (as long as `points`) without allocating: for codes that query
/// batch after batch (new grid vertices each refinement step). When it throws for a bad point,
/// `out` may already hold some answers (the points are validated while the batch is screened).
void distances(const QueryMesh& mesh, std::span<const Vec3> points, const PointQuery& query,
               std::span<PointDistance> out);

/// The same, with an upper bound of each point's distance to the mesh (+∞ where none is known):
/// the search prunes with it from the start instead of first finding a near triangle. For
/// points whose distance was known before the mesh moved, |d| plus the largest displacement of
/// the mesh bounds the new distance (ib::AdaptiveGrid asks this way). The answers are those of
/// distances() whatever the bounds: a bound below the distance costs a second search, not a
/// wrong answer.
///
/// Throws as distances() does, and for a negative or NaN bound, or spans of different lengths.
void distances(const QueryMesh& mesh, std::span<const Vec3> points,
               std::span<const double> upperBounds, const PointQuery& query,
               std::span<PointDistance> out);

/// One point, on the calling thread; the same answer as distances() gives it, and the same
/// errors.
PointDistance distance(const QueryMesh& mesh, const Vec3& point, const PointQuery& query = {});

/// Points–mesh contacts: every point closer than ε to the mesh, in point order, as a contact
/// point whose first geometry is the point (id = its index, P = the point) and second the mesh
/// (Q = the closest point, `second` = its triangle): x = (P + Q)/2, normal = P − x, distance
/// |P − Q|, direction the unit vector from Q to P (for a point on the surface, the triangle's
/// outward face normal), and, for a closed mesh, `overlap` = the point lies inside.
///
/// Throws delta::Error as distances() does, and when ε is not finite.
///
/// Threading: as distances().
std::vector<ContactPoint> contacts(const QueryMesh& mesh, std::span<const Vec3> points,
                                   double epsilon);

}  // namespace delta::contactdetection
