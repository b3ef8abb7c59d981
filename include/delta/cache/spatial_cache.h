#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/triangle_soa.h"

namespace delta {

namespace detail {
struct SpatialCacheState;
struct SpatialCacheAccess;
}  // namespace detail

/// How a SpatialCache is built and refined.
///
/// Threading: a value type; no shared state.
struct CacheOptions {
  std::size_t maxCandidates = 32;  ///< split a cell that may meet the surface while it has more
                                   ///< candidates than this (≥ 1) …
  int maxDepth = 10;     ///< … and is shallower than this (0–20; the root has depth 0)
  double margin = 0.25;  ///< the root cube extends the mesh box by this fraction of its largest
                         ///< extent per side (finite, ≥ 0)
};

/// The seed's spatial cache: an octree wrapped around one mesh, exact by construction.
///
/// Every cell C is an axis-aligned cube with centre c and half-diagonal h. With d(c) the exact
/// distance from c to the mesh (the minimum of kernels::closestPointOnTriangle over the
/// triangles), every point p of C has d(c) − h ≤ d(p) ≤ d(c) + h, so each cell stores
/// - `lowerBound` L = max(0, d(c) − h): no point of the cell is closer to the mesh than L (a
///   query with ε ≤ L is answered "no contact" at that cell, see `beyond`);
/// - `upperBound` U = d(c) + h: every point of the cell is within U of the mesh;
/// - its candidates: the ids of every triangle whose box is within U of the cell (box–box
///   distance). The nearest triangle of any point of the cell is within U of it, so it is a
///   candidate; every triangle that overlaps the cell (box distance 0) is one too, whether or not
///   a vertex lies inside (the seed linked a triangle to a cell only through its vertices).
///   And for ε ≤ U, every triangle closer than ε to some point of the cell is a candidate.
/// Both bounds carry a rounding slack of 10⁻¹²·(root side + d(c)) (L lower, U higher), larger
/// than the kernel's error, so that they hold for the computed distances too and no nearest
/// triangle is ever dropped by rounding (the answers of `nearestTriangle` are bitwise those of a
/// loop over all triangles).
///
/// The root is a cube centred on the mesh's box, of side (largest extent of the box)·(1 +
/// 2·margin) (a mesh whose vertices all coincide is given extent 1). Its candidates are all
/// triangles within its U. A cell is split into 8 equal children while
///   it has more than `maxCandidates` candidates, its depth is below `maxDepth`, and it may
///   meet the surface (lowerBound == 0, i.e. d(c) ≤ h).
/// A child's candidates are a subset of its parent's and the nearest triangle of its centre is
/// among them, so refining a cell reads only its own candidate list: O(candidates), local. The
/// tree is a deterministic function of the mesh and the options: refined on demand by `leafAt`
/// or a priori by `refineAll`, a cell is the same.
///
/// Why cells away from the surface are not split: there the candidate lists shrink only in
/// proportion to the cell, not to its area (a cell of half-diagonal h at distance D from a
/// surface of curvature radius R keeps every triangle within about D + 2h of its centre, a cap of
/// about 4π·h·R·D/(R + D)), so a list of 32 is reached only at cells far smaller than the
/// triangles, and splitting them for it fills the volume with cells (an icosphere of 5120
/// triangles: 17 million cells at depth 8, still over the criterion). Such cells keep exact
/// bounds and candidates: `beyond` answers there from L or from the candidate boxes, but a
/// `nearestTriangle` there costs one box test per candidate (hundreds to thousands; all the
/// triangles in a large cell near the root).
///
/// Triangle ids are the indices of the TriangleSoA given. The cache keeps a pointer to that
/// TriangleSoA and reads it for its whole life, without copying it: the TriangleSoA must outlive
/// the cache and must not be assigned to meanwhile. A moved mesh needs a new TriangleSoA and a
/// new cache.
///
/// Threading: every const member function (leafAt included, which may refine) and the free
/// functions below may be called from any number of threads at once, concurrently with
/// `refineAll` and `allowRefinement`; refinement is free of data races (each cell publishes its
/// children once, completely built, through an atomic pointer; a striped mutex is taken only to
/// refine; readers never lock) and every thread sees the same tree. Moving, move-assigning and
/// destroying need exclusive access. Leaf spans stay valid while the cache lives.
class SpatialCache {
 public:
  /// The root only; cells are refined on demand by leafAt() while refinement is allowed.
  /// Throws delta::Error for an empty TriangleSoA, more than 2³² − 1 triangles, a mesh outside
  /// the coordinate range (mesh/coordinate_range.h: a coordinate beyond ±2²⁰⁰, or all below
  /// 2⁻²⁰⁰), or invalid options (maxCandidates 0, maxDepth outside 0–20, margin negative or not
  /// finite).
  explicit SpatialCache(const TriangleSoA& triangles, const CacheOptions& options = {});
  ~SpatialCache();
  SpatialCache(const SpatialCache&) = delete;
  SpatialCache& operator=(const SpatialCache&) = delete;
  /// Moves are cheap (the tree stays where it is; Leaf spans stay valid). A moved-from cache
  /// may only be destroyed or assigned to.
  SpatialCache(SpatialCache&&) noexcept;
  SpatialCache& operator=(SpatialCache&&) noexcept;

  /// One cell, as leafAt() sees it.
  struct Leaf {
    Aabb box;                 ///< the cell (a cube)
    double lowerBound = 0.0;  ///< no point of the cell is closer to the mesh than this
    double upperBound = 0.0;  ///< every point of the cell is at most this far from the mesh
    std::span<const std::uint32_t> candidates;  ///< ascending ids; valid while the cache lives
    int depth = 0;                              ///< 0 for the root
  };

  /// Whether `p` lies inside the root cube (boundary included; false for NaN).
  bool contains(const Vec3& p) const noexcept;

  /// The deepest cell holding `p`, refining on the way every cell that meets the criterion
  /// while refinement is allowed (on-demand refinement); with refinement vetoed, the deepest
  /// existing cell. A point on a face between cells goes to the upper one (the child whose
  /// lower corner it is at). Throws delta::Error when `p` is not contained (see contains()).
  Leaf leafAt(const Vec3& p) const;

  /// The veto: refinement off (phases where many threads share one cache and want no writes)
  /// or on (the default). leafAt() calls that began before a veto may still finish a
  /// refinement they started. refineAll() ignores the veto.
  void allowRefinement(bool allowed) noexcept;
  bool refinementAllowed() const noexcept;

  /// Refines every cell that meets the criterion (the a priori build), level by level, the
  /// cells of a level in parallel (core/parallel.h). Ignores the veto. May run while other
  /// threads call leafAt().
  void refineAll();

  /// Cells built so far (the root included).
  std::size_t cellCount() const noexcept;
  /// Heap bytes: cells, candidate lists and the triangle boxes (one Aabb per triangle).
  std::size_t memoryBytes() const noexcept;
  const CacheOptions& options() const noexcept;
  /// The triangles given to the constructor.
  const TriangleSoA& triangles() const noexcept;
  /// The root cube.
  const Aabb& bounds() const noexcept;

  /// A census of the tree as built so far.
  struct Statistics {
    std::size_t cells = 0;
    std::size_t leaves = 0;
    int depth = 0;                        ///< of the deepest leaf
    std::size_t maxCandidates = 0;        ///< the most candidates of a leaf
    double meanCandidates = 0.0;          ///< per leaf
    std::size_t leavesOverCriterion = 0;  ///< leaves with more than maxCandidates (at maxDepth,
                                          ///< away from the surface, or not refined yet)
  };
  /// Walks the tree (O(cells)); safe during refinement (it counts what is published).
  Statistics statistics() const;

 private:
  friend struct detail::SpatialCacheAccess;
  std::unique_ptr<detail::SpatialCacheState> state_;
};

/// The seed's a priori build: the root refined everywhere to the criterion (refineAll()).
/// SpatialCache is movable, so it is returned by value. Throws as the constructor.
///
/// Threading: reads `triangles` only; safe to call concurrently (and parallel inside).
SpatialCache buildCache(const TriangleSoA& triangles, const CacheOptions& options = {});

/// The nearest triangle of a point.
///
/// Threading: a value type; no shared state.
struct CachedNearest {
  double distanceSquared = 0.0;
  std::uint32_t triangle = 0;            ///< the smallest id among equally near triangles
  kernels::PointTriangleResult closest;  ///< closestPointOnTriangle(p, triangle)
};

/// The exact nearest triangle of `p` through the cache: the minimum of
/// kernels::closestPointOnTriangle over the candidates of leafAt(p) (so it may refine), ties to
/// the smallest id; bitwise the answer of a loop over all triangles in id order in which a
/// strictly smaller squared distance replaces the best. Candidates are visited nearest box
/// first, and one whose box is further than the best distance found (plus a rounding slack of
/// 10⁻¹² of the root side) is skipped without calling the kernel. Throws delta::Error when `p`
/// is not contained.
///
/// Threading: as leafAt().
CachedNearest nearestTriangle(const SpatialCache& cache, const Vec3& p);

/// Whether certainly no triangle is closer to `p` than `epsilon` (every triangle is at least
/// `epsilon` away): true as soon as a cell on the way from the root to leafAt(p) has
/// lowerBound ≥ epsilon (the walk stops there, refining no further: the seed's early "no
/// contact"), or when at the leaf every candidate's box is at least `epsilon` from `p` (the
/// nearest triangle is a candidate; this test makes small meshes, whose few-candidate root is
/// never split, answer too). False means a triangle may, or may not, be closer. Never true for a
/// point closer than epsilon; true for epsilon ≤ 0. Refines on the way as leafAt() does, and
/// costs at most one pass over the leaf's candidate boxes. Throws delta::Error when `p` is not
/// contained or `epsilon` is NaN.
///
/// Threading: as leafAt().
bool beyond(const SpatialCache& cache, const Vec3& p, double epsilon);

}  // namespace delta
