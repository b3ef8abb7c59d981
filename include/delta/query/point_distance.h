#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string_view>
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
  bool inside = false;  ///< inside the mesh (signed queries only; see PointQuery::sign)
  /// Sign::winding queries only: the generalized winding number lies within
  /// PointQuery::windingTolerance of ½, where inside and outside are a coin toss (across a hole,
  /// where two sheets cross); `inside` then still says w > ½. False for pseudonormal queries.
  bool ambiguous = false;

  bool found() const noexcept { return triangle != kNoTriangle; }
  /// The distance, negative inside (signed queries).
  double signedDistance() const noexcept { return inside ? -distance : distance; }
};

/// How a signed query decides inside from outside.
enum class Sign {
  /// The angle-weighted pseudonormal of the closest feature (Bærentzen and Aanæs 2005): O(1)
  /// once the closest point is known and exact off the surface, but only for a closed,
  /// consistently oriented mesh that does not cross itself; other meshes are refused.
  pseudonormal,
  /// The generalized winding number w (Jacobson et al. 2013) exceeds ½, taken relative to the
  /// mesh's orientation (query_mesh.h): defined for any mesh — open (holes), self-intersecting,
  /// a soup of patches. Evaluated by the hierarchical dipole expansion of Barill et al., "Fast
  /// Winding Numbers for Soups and Clouds" (SIGGRAPH 2018), over the QueryMesh's tree with a
  /// rigorous error bound, and over all triangles exactly where that bound leaves the side of ½
  /// in doubt: the sign is always that of the exact winding number (the O(n) sum of
  /// delta::windingNumber), up to its rounding. On a closed mesh that bounds a solid
  /// (boundsSolid(): it crosses itself nowhere, selfIntersections(), and its parts nest as a
  /// solid's boundary, partNesting() — no inside-out part outside the others or shell inside a
  /// shell of the same orientation, whose winding numbers are −1 or 2, no parts touching at a
  /// vertex; both found by the first such query) the winding number off the surface is 0 or 1
  /// and the pseudonormal sign is its sign, exactly also within rounding of a face, where solid
  /// angles are not: that is what runs there, at the pseudonormal's cost.
  winding,
};

/// "pseudonormal" or "winding".
///
/// Threading: a pure function.
const char* signName(Sign sign) noexcept;

/// The Sign signName() names `text`; nullopt for anything else.
///
/// Threading: a pure function.
std::optional<Sign> parseSign(std::string_view text) noexcept;

/// What a points–mesh query asks.
///
/// Threading: a value type; no shared state.
struct PointQuery {
  /// Answer only points closer than ε (strictly: the kernel's squared distance below ε·ε as a
  /// double rounds it, so a point whose squared distance rounds to that double is not answered
  /// even where the exact ε² is a hair larger; the distance reported, a rounded square root, may
  /// equal ε); the others get distance +∞ and no triangle.
  /// A finite ε lets the search stop near the root for points far from the mesh. Any positive ε
  /// is taken as given: one whose square underflows (below about 1e-154) is compared with the
  /// distance itself, not its square.
  double epsilon = std::numeric_limits<double>::infinity();
  /// Also decide inside/outside, as `sign` says. Sign::pseudonormal (the mesh must be closed and
  /// not cross itself): by the angle-weighted pseudonormal of the feature (vertex, edge or face)
  /// the closest point lies on, which is exact for any point off the surface, with the
  /// generalized winding number where rounding leaves that in doubt. Sign::winding: by the
  /// winding number, for any mesh. Within rounding of a closed mesh's surface (a distance below
  /// 2⁻⁴⁰ of the closest point's magnitude and the triangle's size, 0 included), where the
  /// closest point's own rounding turns the offset from it and the solid angles lose their sign,
  /// either rule decides exactly: a ray's crossings counted with exact orientation predicates.
  /// A point exactly on the surface is not inside; one off it by less than the distance's
  /// rounding (distance 0) is signed by its exact side. (Where a coordinate involved is below
  /// 2⁻²⁵⁰ but not 0 the exact predicates do not hold, and the rules above decide as they can.)
  bool signedDistance = false;
  /// How signedDistance decides (ignored without it). Sign::pseudonormal, the default, refuses
  /// a mesh that is not closed, one that crosses itself (selfIntersections() > 0: there the
  /// pseudonormals give wrong signs near the crossings) and one whose parts do not nest
  /// (partNesting(): a misoriented part, a pinched vertex; the pseudonormals name the wrong side
  /// near them), with a delta::Error that names Sign::winding, which answers all three.
  Sign sign = Sign::pseudonormal;
  /// Sign::winding: a point is `ambiguous` where |w − ½| ≤ windingTolerance (in [0, ½); NaN and
  /// others: delta::Error). The default 0.05 flags points near a hole's rim or a crossing whose
  /// winding number is within 5% of the threshold.
  double windingTolerance = 0.05;
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
/// it exactly). A mesh that intersects itself is refused by pseudonormal signs (they are wrong
/// near the crossings) and signed by Sign::winding: inside where the winding number exceeds ½.
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
/// and the range), or `signedDistance` with Sign::pseudonormal is asked of a mesh that is not
/// closed (the error says how: boundary, non-manifold or misoriented edges) or that crosses
/// itself (the error gives the number of crossing pairs); both errors name Sign::winding, which
/// signs any mesh. Also for a windingTolerance outside [0, ½). No points: an empty result.
///
/// The first pseudonormal query of a QueryMesh finds its self-intersections (selfIntersections,
/// O(n log n), kept), the first winding query builds the tree's winding moments (O(n), kept).
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

/// The same, written into `out` (as long as `points`) without allocating the answers: for codes
/// that query batch after batch (new grid vertices each refinement step). An ε-limited batch's
/// working buffers (about 130 bytes a point the bound grid leaves in doubt) stay with the calling
/// thread for its next batch, up to 64 MiB, so that a code querying batch after batch does not
/// fault fresh pages in each time. When it throws for a bad point, `out` may already hold some
/// answers (the points are validated while the batch is screened).
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
/// outward face normal), and, for a closed mesh, `overlap` = the point lies inside (by
/// pseudonormals, or, where the closed mesh crosses itself, by winding number: the first call
/// finds its self-intersections).
///
/// Throws delta::Error as distances() does, and when ε is not finite.
///
/// Threading: as distances().
std::vector<ContactPoint> contacts(const QueryMesh& mesh, std::span<const Vec3> points,
                                   double epsilon);

}  // namespace delta::contactdetection
