#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "delta/core/vec3.h"
#include "delta/query/pair_cache.h"
#include "delta/query/query_mesh.h"

/// @file
/// Region overlap of two closed meshes: where their surfaces cross (the intersection curves) and
/// the solid they share (A ∩ B: its volume, centroid, and the surface integrals a volume-based
/// contact law needs).

namespace delta::contactdetection {

/// One piece of an intersection curve: where triangle `triangleA` of the first mesh crosses
/// triangle `triangleB` of the second (ids in the meshes' triangle order), from `start` to `end`
/// (world frame). Oriented so that, seen from outside the first mesh, the part of its triangle
/// inside the second mesh lies to the left (along n_A × n_B).
///
/// Threading: a value type; no shared state.
struct IntersectionSegment {
  Vec3 start;
  Vec3 end;
  std::uint32_t triangleA = 0;
  std::uint32_t triangleB = 0;
};

/// A chain of segments, end to start: an intersection curve. `points` has one more entry than
/// `segments` has ids; a closed curve's last point repeats its first.
///
/// Threading: a value type; no shared state.
struct IntersectionCurve {
  std::vector<Vec3> points;
  std::vector<std::uint32_t> trianglesA;  ///< per segment, the first mesh's triangle
  std::vector<std::uint32_t> trianglesB;  ///< per segment, the second mesh's triangle
  std::size_t region = 0;                 ///< index into Overlap::regions
  bool closed = true;
  double length = 0.0;
};

/// The integrals over one connected piece of A ∩ B (or over all of it).
///
/// `areaVector` is ∫ n dA over the part of ∂A inside B (n the outward normal of A): the
/// direction the overlap pushes B out of A. The part of ∂B inside A has the opposite vector
/// (∂(A ∩ B) is closed), returned as `areaVectorB` for checking. `moment` is ∫ (x − centroid) ×
/// n dA over the same part of ∂A; about another point p it is moment + (centroid − p) ×
/// areaVector. For a volume-based contact law with energy w(V): the force on B is w′(V)·
/// areaVector, the torque on B about its centre c is w′(V)·(moment + (centroid − c) ×
/// areaVector), and A gets the opposites (both are derivatives of V under a rigid motion of B).
/// Where faces of A and B lie in one plane (the sides of aligned boxes stacked face to face), V
/// is not differentiable: moving B either way along that plane's normal shrinks it (faces facing
/// the same way) or leaves it (facing each other). Each displacement of B (±t, overlap()) gives
/// the derivative one way: two aligned cubes 2·10⁻² across overlapping by 10⁻³ along z give
/// (±2e-5, ±2e-5, 4e-4). overlap() answers their mean, (0, 0, 4e-4), which does not depend on
/// the order of the meshes (OverlapOptions::symmetric; Overlap::coplanar, Overlap::oneSided).
/// It is the mean of two directions of displacement, not of all: where a patch of coplanar
/// faces joins a region only through a zero-volume sliver that a displacement along another
/// axis makes, the mean may differ in a scene mirrored or turned (an audit of unions of unit
/// cubes: 25 of 6,750 scenes with coplanar faces, by up to the patch's area).
///
/// Threading: a value type; no shared state.
struct OverlapRegion {
  double volume = 0.0;
  Vec3 centroid;  ///< of the solid (world frame)
  Vec3 areaVector;
  Vec3 areaVectorB;
  Vec3 moment;
  double curveLength = 0.0;   ///< of the intersection curves bounding this region
  std::size_t triangles = 0;  ///< of both meshes, wholly or partly on this region's boundary
};

/// What overlap() finds. `total` sums the regions (its centroid is the volume-weighted mean, its
/// moment about that centroid).
///
/// Threading: a value type; no shared state.
struct Overlap {
  OverlapRegion total;
  /// Largest volume first. A region is bounded by one connected set of surface pieces: the
  /// surface around a cavity inside a region (a hollow mesh) is a separate piece of negative
  /// volume, which `total` includes and no region does. Where coplanar faces met, pieces meeting
  /// only at an edge or a point may be joined under one displacement and not under the other;
  /// with OverlapOptions::symmetric the regions that do not match are then answered as one.
  std::vector<OverlapRegion> regions;
  std::vector<IntersectionCurve> curves;
  std::size_t segments = 0;  ///< intersection segments found (curves or not)
  /// Pieces of contact that enclose no volume, left out of `regions` and `total` and counted
  /// here. Surfaces that only touch (faces lying on one another, a vertex on a face) give either
  /// such a piece or nothing, as the symbolic displacement of B (along +x first) moves B into A
  /// or away from it: two unit cubes side by side give 1 with B on A's −x side, 0 on its +x side.
  /// A region whose volume is within the rounding its points may carry counts here too: 16
  /// ulps of its faces' area and of their boundaries' length times their distance from the
  /// query's reference point near the overlap, times the magnitude the points round at (their
  /// coordinates about that point); its volume and sign would not be sure. Two unit cubes
  /// overlapping by a slab 10⁻¹¹ deep still give their region; by one 2⁻⁵⁰ deep (8.9e-16),
  /// only as exact as that where their coordinates are, they touch, and so does a slab 10⁻¹²
  /// deep between faces of many triangles (the scale grows with their boundaries' length).
  std::size_t touching = 0;
  /// Pairs of triangles, one of each mesh, that lie in one plane and whose boxes meet: there the
  /// displacement alone decides which side each lies on, and the surface integrals of a region
  /// depend on its direction (OverlapRegion). Counted under +t.
  std::size_t coplanar = 0;
  /// The surface integrals (areaVector, areaVectorB, moment, of the regions and the total) are
  /// the one displacement's, +t, though coplanar faces met: OverlapOptions::symmetric was off,
  /// the query the other way round was refused (a coordinate at the edge of the range in the
  /// other mesh's frame), or the regions left unmatched on the two sides differ in volume (never
  /// seen: they are one solid). False where they are the mean of both, or where no coplanar faces
  /// met (both give the same).
  bool oneSided = false;
  bool any() const noexcept { return !regions.empty(); }
};

/// What overlap() computes beyond the integrals.
///
/// Threading: a value type; no shared state.
struct OverlapOptions {
  /// Chain the segments into curves (Overlap::curves). The integrals do not need them; a DEM
  /// step turns this off.
  bool curves = true;
  /// Where coplanar faces met in a region (Overlap::coplanar), the surface integrals are the mean
  /// of the two displacements' (±t), region by region: a second query with the meshes swapped,
  /// made afresh (the cache serves the first). Regions are matched by centroid; those that do
  /// not match (pieces meeting only at an edge or a point, joined one way and not the other)
  /// are joined on each side into one region. Volumes, centroids, curves and counts are +t's
  /// but for such a join. Off: +t's alone, as every other answer of the query
  /// (Overlap::oneSided).
  bool symmetric = true;
};

/// The overlap of two closed meshes, each where its pose puts it (world coordinates: each
/// vertex moved as Mesh::transform moves it).
///
/// Exact topology: which side of a triangle's plane a vertex lies on, which way a segment passes
/// an edge and in which order an edge crosses the other mesh's triangles are decided by exact
/// predicates (a floating-point filter, exact arithmetic where it cannot decide), with the
/// second mesh displaced by an infinitesimal translation (symbolic perturbation) so that no
/// vertex lies on a face and no edges meet: touching surfaces, coplanar faces, shared vertices
/// and edge-on-edge crossings are resolved consistently, every curve is closed and every
/// triangle's inside part well defined. The volume is continuous under that translation, so it
/// is the exact volume of the unperturbed meshes up to the rounding of the numbers. Its
/// derivatives under a motion of B, the surface integrals, are one-sided where faces of both lie
/// in one plane: there they are the mean of the translation's and its opposite's (the meshes
/// swapped; OverlapOptions::symmetric), so that they do not depend on which mesh comes first
/// nor on the translation's direction. The numbers
/// (crossing points, areas, volumes) are computed in double in frames local to each triangle, so
/// they keep their accuracy at any offset.
///
/// How: the trees of both meshes are descended together to the pairs of triangles whose boxes
/// meet; each pair gives at most one segment, and they are crossed by increasing triangle ids
/// (so the result does not depend on the descent's order). Each triangle's part inside the other
/// mesh is bounded by its edges' inside parts and its segments; integrals over it come from that
/// boundary alone (Green's theorem), so no polygon is ever built. Which vertices lie inside is
/// propagated along the edges from those outside the other mesh's box (each crossing flips it);
/// a connected piece with none (a mesh wholly inside the other's box) takes one exact ray test.
///
/// An inside-out mesh (negative signed volume) bounds the same solid as its reversal: its
/// triangles are read reversed. Throws delta::Error where a mesh is not closed and consistently
/// oriented (naming its defects), crosses itself (selfIntersections), or lies outside the
/// coordinate range, and where a vertex the query meets has a coordinate below 2⁻²⁵⁰ (about
/// 5.5e-76) but not 0, where it stands (after its pose): there the exact predicates' products
/// of coordinate differences would underflow and could give a wrong sign.
///
/// Threading: reads both meshes only; any number of threads may call it at once. Serial. Each
/// thread keeps slot maps as large as the largest meshes it has compared (three 4-byte entries
/// per vertex or triangle, per side), so that a query costs in proportion to the triangles near
/// the overlap, not to the meshes' sizes.
Overlap overlap(const QueryMesh& a, const QueryMesh& b, const OverlapOptions& options = {});

/// What a pair of meshes that meets again and again (a DEM pair, step after step) keeps from one
/// overlap() to the next: the pairs of triangles that could cross until the second mesh has
/// moved against the first by `skin`. Made by a descent of both trees that keeps each pair of
/// triangles whose boxes lie within the skin of each other and that neither one's plane
/// separates by more; while the two meshes have moved less than the skin against each other
/// since (PairCache, query/pair_cache.h; moving both together costs nothing), only those pairs
/// are placed and crossed: no descent, no leaf boxes, no triangles placed that meet nothing; and
/// meshes that shared nothing when it was made, with no triangles within the skin of each other
/// (a DEM pair in the broad phase's list but not touching), cost no more than that test. A
/// larger skin keeps the cache longer and holds more pairs.
///
/// Threading: a value type; one cache belongs to one pair, used by one thread at a time.
class OverlapCache : public PairCache {
 public:
  /// An empty cache (made at the first call that finds the meshes' boxes meeting) that keeps
  /// the triangle pairs within `skin`; a skin that is not finite and positive makes every call
  /// a fresh query.
  explicit OverlapCache(double skin = 0.0) noexcept : PairCache(skin) {}

  /// The triangle pairs it holds.
  std::size_t size() const noexcept { return pairs_.size(); }
  /// Asks the processor to fetch what the next call reads first (a caller's loop over its
  /// pairs calls it one pair ahead).
  void prefetch() const noexcept { __builtin_prefetch(pairs_.data()); }

 private:
  friend Overlap overlap(const QueryMesh& a, const QueryMesh& b, const OverlapOptions& options,
                         OverlapCache& cache);
  /// The query with B displaced by +t alone (overlap.cpp), through `cache`.
  static Overlap oneWay(const QueryMesh& a, const QueryMesh& b, const OverlapOptions& options,
                        OverlapCache& cache);
  /// (first, second) sorted triangle indices, first << 32 | second, increasing.
  std::vector<std::uint64_t> pairs_;
  /// Made for meshes that shared nothing, with no pairs: they share nothing while it holds.
  bool apart_ = false;
};

/// overlap(a, b, options), the same overlap bit for bit, through `cache`: made anew when empty,
/// made for other meshes, or when the second mesh has moved against the first by more than the
/// skin allows since; otherwise only the triangle pairs it holds are crossed (every pair that
/// crosses now lay within the skin when it was made, and the pairs are crossed in the same order
/// either way: by increasing indices). Meshes whose boxes do not meet leave it as it is. Where
/// coplanar faces make the answer symmetric, the opposite displacement's query is made afresh.
///
/// Throws as overlap(a, b, options).
///
/// Threading: as overlap(); `cache` is the caller's, one thread at a time.
Overlap overlap(const QueryMesh& a, const QueryMesh& b, const OverlapOptions& options,
                OverlapCache& cache);

}  // namespace delta::contactdetection
