#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/aligned_allocator.h"
#include "delta/core/vec3.h"
#include "delta/kernels/detail/batch_views.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/topology.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/part_nesting.h"
#include "delta/query/self_intersections.h"

#include "bound_grid.h"
#include "winding_tree.h"

namespace delta::detail {

/// Children per tree node and triangles per leaf.
inline constexpr std::size_t kFanout = 8;

/// Eight boxes side by side (Embree's `bvh_node_aabb.h` layout): one cache-line-aligned block per
/// node whose children the point queries test together, 192 bytes instead of 384. Single
/// precision less an origin (the tree's: FloatTriangles::origin, the mesh box's centre, so that
/// a mesh far from the origin keeps boxes as fine as near it), rounded outward, so a box here
/// contains the double box it stands for, less the origin, up to the rounding of that difference
/// (far below the slack the boxes grew by), and its distance from a point less the origin
/// (computed in double) never exceeds that box's; empty slots have lower > upper (+∞, −∞) and lie
/// infinitely far away.
struct alignas(64) BoxOctet {
  float lowerX[kFanout], lowerY[kFanout], lowerZ[kFanout];
  float upperX[kFanout], upperY[kFanout], upperZ[kFanout];
};
using BoxOctets = std::vector<BoxOctet, AlignedAllocator<BoxOctet, 64>>;

/// The octet of `boxes[first, first + kFanout)` (fewer at the end: the rest empty), less `origin`.
BoxOctet octetOf(const std::vector<Aabb>& boxes, std::size_t first, const Vec3& origin) noexcept;

/// The squared distances from `point` to the eight boxes of an octet. (A plain loop: measured
/// faster than eight-lane vectors, whose float-to-double conversions and blends cost more than
/// the compares they replace.)
inline void distancesSquared(const BoxOctet& boxes, const Vec3& point,
                             double (&out)[kFanout]) noexcept {
  for (std::size_t i = 0; i < kFanout; ++i) {
    const double dx = std::max(
        std::max(double{boxes.lowerX[i]} - point.x, point.x - double{boxes.upperX[i]}), 0.0);
    const double dy = std::max(
        std::max(double{boxes.lowerY[i]} - point.y, point.y - double{boxes.upperY[i]}), 0.0);
    const double dz = std::max(
        std::max(double{boxes.lowerZ[i]} - point.z, point.z - double{boxes.upperZ[i]}), 0.0);
    out[i] = dx * dx + dy * dy + dz * dz;
  }
}

/// Bit i set where values[i] ≤ limit (never for NaN), made without a branch: the descents test
/// eight children or triangles at once, whose outcomes a branch apiece would mispredict.
[[gnu::always_inline]] inline unsigned notAboveMask(const double (&values)[kFanout],
                                                    double limit) noexcept {
  unsigned mask = 0;
  for (std::size_t i = 0; i < kFanout; ++i)
    mask |= static_cast<unsigned>(values[i] <= limit) << i;
  return mask;
}

/// The leaves' oriented cylinders and cones, eight side by side (one block per node of level 1,
/// beside its BoxOctet): each leaf's triangles lie within heights [low, high] along `normal`
/// (single precision, not quite unit: n) from the centre c of the leaf's box in the octet, and
/// within radius + taper·h of the axis through c along n at height h (a cylinder where taper is
/// 0). A far point's search reaches the leaves around its nearest point, whose boxes, as thick as
/// they are wide wherever the surface is not axis-aligned, come closer to it than their
/// triangles; the cylinder of a patch nearly flat is about as thin as the patch, and the cone of
/// a fan's wedge of slivers is as thin as the wedge at every height (a cylinder around it is as
/// wide as its rim, and a point near the fan's centre lies within the cylinders of every wedge).
/// For a point p, w = p − c, h = n·w, s = n·n, the lateral l = w − n·h/s and the gap
/// g = |l| − radius − taper·h, every point y of the leaf, at height h + x, has |l_y| ≤ radius +
/// taper·(h + x), so |p − y|² ≥ x²/s + max(g − taper·x, 0)² (Pythagoras along n / √s and across
/// it), a convex function of x whose least value over x ∈ [low − h, high − h] bounds distance²:
/// at x = clamp(step·max(g, 0), low − h, high − h), step = taper/(1/s + taper²) (its unconstrained
/// minimum; for a cylinder x = 0 clamped, the bound max(low − h, h − high, 0)²/s + max(g, 0)²).
/// `step` is stored rounded to single precision: a minimum taken a relative 2⁻²⁴ off its place
/// raises the bound by at most 2⁻⁴⁸·k² of itself (k = taper·√s, at most 1), far within the
/// shrink. Built from the double vertices and widened by the slack, rounded outward; empty slots'
/// boxes make c NaN, whose bound the caller ignores.
struct alignas(64) CylinderOctet {
  float normalX[kFanout], normalY[kFanout], normalZ[kFanout];
  float low[kFanout], high[kFanout], radius[kFanout];
  float taper[kFanout], step[kFanout];
};
using CylinderOctets = std::vector<CylinderOctet, AlignedAllocator<CylinderOctet, 64>>;

/// out[i] = max(out[i], the cylinder bound of child i of `boxes`/`cylinders` shrunk by `shrink`):
/// `shrink` (a distance) must exceed the rounding of the bound and of the exact kernel's distance
/// (node_bounds.h's cylinderShrink). A NaN bound (empty slot) leaves out[i] as it was.
inline void raiseByCylinders(const BoxOctet& boxes, const CylinderOctet& cylinders,
                             const Vec3& point, double shrink, double (&out)[kFanout]) noexcept {
  for (std::size_t i = 0; i < kFanout; ++i) {
    const double nx = cylinders.normalX[i], ny = cylinders.normalY[i], nz = cylinders.normalZ[i];
    const double wx = point.x - (double{boxes.lowerX[i]} + double{boxes.upperX[i]}) * 0.5;
    const double wy = point.y - (double{boxes.lowerY[i]} + double{boxes.upperY[i]}) * 0.5;
    const double wz = point.z - (double{boxes.lowerZ[i]} + double{boxes.upperZ[i]}) * 0.5;
    const double inverse = 1.0 / (nx * nx + ny * ny + nz * nz);
    const double h = nx * wx + ny * wy + nz * wz;
    const double along = h * inverse;
    const double lx = wx - nx * along, ly = wy - ny * along, lz = wz - nz * along;
    const double taper = cylinders.taper[i];
    const double gap =
        std::sqrt(lx * lx + ly * ly + lz * lz) - double{cylinders.radius[i]} - taper * h - shrink;
    const double x = std::min(std::max(double{cylinders.step[i]} * std::max(gap, 0.0),
                                       double{cylinders.low[i]} - shrink - h),
                              double{cylinders.high[i]} + shrink - h);
    const double across = std::max(gap - taper * x, 0.0);
    const double bound = x * x * inverse + across * across;
    out[i] = std::max(out[i], bound);
  }
}

/// A node's oriented slab: the unit mean normal of its triangles (their area vectors' sum) and
/// the extent of its vertices along it, widened by the slack. A patch nearly flat is thin along
/// its normal where its axis-aligned box is not: two patches facing each other across a small
/// gap have overlapping boxes but slabs apart (the mesh–mesh queries' node test, see
/// dual_traversal.h's slabGap).
struct NodeSlab {
  Vec3 normal{0, 0, 1};
  double low = 0.0, high = 0.0;
};

/// The sorted triangles in single precision, less the mesh box's centre, a leaf's eight in one
/// block of 288 bytes (FloatLeavesView): what the point queries' leaf bounds read, 36 bytes a
/// triangle where the doubles took 72 (point_lanes.h widens the bounds by `rounding`). Padding
/// triangles are NaN.
struct FloatTriangles {
  std::vector<float, AlignedAllocator<float, 64>> coordinates;
  Vec3 origin;
  double rounding = 0.0;  ///< δ: no vertex is farther from its double (less the origin)

  FloatLeavesView view() const noexcept {
    FloatLeavesView view{};
    view.leaves = coordinates.data();
    view.rounding = rounding;
    view.offset = maxAbs(origin);
    return view;
  }
  std::size_t memoryBytes() const noexcept { return coordinates.capacity() * sizeof(float); }
};

/// `count` triangles, triangleAt(k), in single precision less `origin`.
template <typename TriangleAt>
FloatTriangles floatTriangles(std::size_t count, const TriangleAt& triangleAt, const Vec3& origin) {
  FloatTriangles result;
  result.origin = origin;
  result.coordinates.assign((count + 7) / 8 * 72, std::numeric_limits<float>::quiet_NaN());
  double largest = 0.0;  // the largest coordinate less the origin
  for (std::size_t k = 0; k < count; ++k) {
    const Triangle t = triangleAt(k);
    const Vec3 corners[3] = {t.a - origin, t.b - origin, t.c - origin};
    for (std::size_t vertex = 0; vertex < 3; ++vertex)
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double value = corners[vertex][axis];
        largest = std::max(largest, std::abs(value));
        result.coordinates[k / 8 * 72 + (3 * vertex + axis) * 8 + k % 8] =
            static_cast<float>(value);
      }
  }
  // Per coordinate the subtraction rounds by 2⁻⁵³ and the float by 2⁻²⁴ of it (or 2⁻¹⁵⁰ where
  // subnormal); √3 of that a vertex. Beyond single precision nothing is known.
  result.rounding =
      largest < 1e38 ? 0x1p-22 * largest + 0x1p-140 : std::numeric_limits<double>::infinity();
  return result;
}

/// The angle-weighted pseudonormals of a closed mesh's vertices (not normalised), and per
/// triangle its neighbours, whose face normals make the edge pseudonormals: 24 bytes a triangle.
struct Pseudonormals {
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<Vec3> vertices;  ///< per vertex of QueryMeshData::vertices
  /// Per sorted triangle: the sorted triangle across its edges ab, bc, ca, or kNone (a fold's
  /// edges, which have no partner).
  std::vector<std::array<std::uint32_t, 3>> across;

  std::size_t memoryBytes() const noexcept {
    return vertices.capacity() * sizeof(Vec3) +
           across.capacity() * sizeof(std::array<std::uint32_t, 3>);
  }
};

/// The connected pieces of a mesh (vertices joined by the triangles' edges), for the overlap
/// query's test of a piece that the other mesh's surface does not cross: a representative vertex
/// and the box of each (prepared frame), and its triangles (sorted ids), grouped.
struct MeshComponents {
  std::vector<std::uint32_t> ofVertex;  ///< per vertex of QueryMeshData::vertices (unused: 0)
  std::vector<std::uint32_t> representative;
  std::vector<Aabb> boxes;
  std::vector<std::uint32_t> offsets;    ///< component c has triangles[offsets[c], offsets[c + 1])
  std::vector<std::uint32_t> triangles;  ///< sorted ids
  std::size_t count() const noexcept { return representative.size(); }
  std::size_t memoryBytes() const noexcept {
    return (ofVertex.capacity() + representative.capacity() + offsets.capacity() +
            triangles.capacity()) *
               sizeof(std::uint32_t) +
           boxes.capacity() * sizeof(Aabb);
  }
};

/// What a QueryMesh holds (see query_mesh.h).
struct QueryMeshData {
  /// The triangles in tree order: sorted triangle k (the mesh's triangle order[k]) has the
  /// corners vertices[corners[k][0, 1, 2]]: the mesh's vertices that triangles use, renumbered in
  /// the order the tree meets them, so a leaf's lie together.
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> corners;
  std::vector<std::uint32_t> order;
  /// The same triangles in single precision for the point queries' leaf bounds.
  FloatTriangles lanes;
  /// levels[0]: the leaves' boxes (leaf i holds sorted triangles [8i, 8i + 8)); levels[l]: node i
  /// has the children [8i, 8i + 8) of level l − 1; levels.back() holds the root alone. Boxes are
  /// grown by `slack` on every side, so a box's distance never exceeds a computed triangle
  /// distance inside it (rounding included).
  std::vector<std::vector<Aabb>> levels;
  /// The same tree for the point queries: childOctets[l][i] holds the boxes of node i of level
  /// l + 1's children (levels[l][8i, 8i + 8)), less lanes.origin: the octets' bounds take a point
  /// less it too.
  std::vector<BoxOctets> childOctets;
  /// Per node of level 1, its leaves' cylinders (childOctets[0]'s boxes give their centres).
  CylinderOctets leafCylinders;
  /// Per node of `levels`, its oriented slab (the same indexing).
  std::vector<std::vector<NodeSlab>> slabs;
  /// Per cell of a uniform grid over the box, a lower bound of the distance to the mesh: the
  /// ε-limited queries reject most points farther than ε with one read (bound_grid.h).
  BoundGrid boundGrid;
  Topology topology;
  /// The first triangle (its index and corners) below kSmallestTriangleExtent across and not one
  /// point, which the mesh–mesh queries refuse (detail::requireTrianglesSpan).
  std::optional<std::pair<std::size_t, Triangle>> tinyTriangle;
  bool closed = false;
  double orientation = 1.0;  ///< −1 for an inside-out closed mesh
  /// A closed mesh's volumeSign (its orientation's source; nothing where it is not exact).
  std::optional<int> exactVolumeSign;
  Aabb bounds;
  /// The farthest vertex from bounds.center(), rounded up: a moved mesh's points move at most
  /// as far as that ball's (the contact caches' bound).
  double radius = 0.0;
  double slack = 0.0;

  /// The number of triangles.
  std::size_t size() const noexcept { return corners.size(); }
  /// Sorted triangle `k` (< size(), unchecked).
  [[gnu::always_inline]] Triangle triangle(std::size_t k) const noexcept {
    const TriangleIndices& c = corners[k];
    return {vertices[c[0]], vertices[c[1]], vertices[c[2]]};
  }

  /// The triangles in the mesh's order (QueryMesh::triangles()), made on the first call (the
  /// queries never need them: most users never pay their 72 bytes a triangle). Thread-safe.
  const TriangleSoA& meshOrder() const;
  /// Whether meshOrder() has been made (then its bytes count in QueryMesh::memoryBytes()).
  bool meshOrderMade() const noexcept { return meshOrderMade_.load(std::memory_order_acquire); }

  /// The pseudonormal of feature `slot` (0–2 vertices a, b, c; 3–5 edges ab, bc, ca) of sorted
  /// triangle `sorted`, of a closed mesh. The pseudonormals are made on the first call (only
  /// signed queries need them, 24 bytes a triangle). Thread-safe.
  Vec3 pseudonormal(std::uint32_t sorted, std::size_t slot) const;
  /// Whether the pseudonormals have been made (then their bytes count in memoryBytes()).
  bool pseudonormalsMade() const noexcept {
    return pseudonormalsMade_.load(std::memory_order_acquire);
  }
  /// The pseudonormals and the triangles across each edge, made on the first call (inline once
  /// made: the overlap query walks across edges a few hundred times a DEM pair).
  const Pseudonormals& pseudonormals() const {
    if (pseudonormalsMade()) [[likely]]
      return pseudonormals_;
    return makePseudonormals();
  }

  /// The mesh's self-intersections (query/self_intersections.h), found on the first call and
  /// kept. Thread-safe.
  const SelfIntersections& selfIntersections() const;
  /// How the closed mesh's parts nest (part_nesting.h), found on the first call and kept.
  /// Thread-safe.
  const PartNesting& partNesting() const;
  /// The tree's winding-number moments (winding_tree.h), made on the first call (only winding
  /// signs need them, about 20 bytes a triangle). Thread-safe.
  const WindingTree& windingTree() const;
  /// The mesh's connected pieces (MeshComponents), made on the first call (only the overlap
  /// query needs them, about 12 bytes a triangle). Thread-safe.
  const MeshComponents& components() const;
  bool componentsMade() const noexcept { return componentsMade_.load(std::memory_order_acquire); }
  /// Whether windingTree() has been made (then its bytes count in memoryBytes()).
  bool windingTreeMade() const noexcept { return windingTreeMade_.load(std::memory_order_acquire); }

 private:
  const Pseudonormals& makePseudonormals() const;

  mutable std::once_flag meshOrderOnce_;
  mutable TriangleSoA meshOrder_;
  mutable std::atomic<bool> meshOrderMade_{false};
  mutable std::once_flag pseudonormalsOnce_;
  mutable Pseudonormals pseudonormals_;
  mutable std::atomic<bool> pseudonormalsMade_{false};
  mutable std::once_flag selfIntersectionsOnce_;
  mutable SelfIntersections selfIntersections_;
  mutable std::once_flag partNestingOnce_;
  mutable PartNesting partNesting_;
  mutable std::once_flag windingTreeOnce_;
  mutable WindingTree windingTree_;
  mutable std::atomic<bool> windingTreeMade_{false};
  mutable std::once_flag componentsOnce_;
  mutable MeshComponents components_;
  mutable std::atomic<bool> componentsMade_{false};
};

/// A node of QueryMeshData's tree: `index` of levels[`level`].
struct TreeEntry {
  std::size_t level, index;
};

/// Calls visit(k) for each sorted triangle k whose leaf box meets `box` (closed boxes, the
/// mesh's frame), leaf by leaf, in the same order on every call, until a call returns false;
/// returns whether none did. `stack` is the caller's scratch (its capacity kept between calls).
template <class Visit>
bool forTrianglesMeeting(const QueryMeshData& mesh, const Aabb& box, std::vector<TreeEntry>& stack,
                         const Visit& visit) {
  if (mesh.levels.empty()) return true;
  stack.assign(1, {mesh.levels.size() - 1, 0});
  while (!stack.empty()) {
    const TreeEntry entry = stack.back();
    stack.pop_back();
    if (intersection(mesh.levels[entry.level][entry.index], box).empty()) continue;
    const std::size_t first = entry.index * kFanout;
    if (entry.level == 0) {
      const std::size_t last = std::min(first + kFanout, mesh.size());
      for (std::size_t k = first; k < last; ++k)
        if (!visit(static_cast<std::uint32_t>(k))) return false;
      continue;
    }
    const std::size_t last = std::min(first + kFanout, mesh.levels[entry.level - 1].size());
    for (std::size_t child = last; child-- > first;)  // popped in ascending order
      stack.push_back({entry.level - 1, child});
  }
  return true;
}

/// The closest triangle to a point.
struct Nearest {
  double distanceSquared = std::numeric_limits<double>::infinity();
  std::uint32_t triangle = std::numeric_limits<std::uint32_t>::max();  ///< mesh order
  std::uint32_t sorted = 0;                                            ///< tree order
  kernels::PointTriangleResult closest;
  bool found() const noexcept { return triangle != std::numeric_limits<std::uint32_t>::max(); }
};

/// The triangle closest to `point` among those closer than √limitSquared (strictly), by
/// nearest-first descent of the tree; the smallest triangle id wins a tie, so the answer is that
/// of a loop over all triangles in id order. Not found when none is that close.
Nearest nearestTriangle(const QueryMeshData& mesh, const Vec3& point, double limitSquared) noexcept;
/// The same, with the descent and leaf bounds of `isa` (lowered to a supported one) instead of
/// kernels::defaultIsa()'s: the same answer for every ISA (tests compare them).
Nearest nearestTriangle(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                        kernels::Isa isa) noexcept;

/// The distance-bound grid's sieve of `count` points (mesh frame), in the lanes of
/// kernels::defaultIsa() or of `isa` (the same answer on every ISA): the offsets of the points
/// whose grid bound (BoundGrid::lowerBoundSquared) is not above `limit`, ascending, into `kept`
/// (room for `count`), and their number. Clears `inRange` where a point is not
/// inCoordinateRange (coordinate_range.h), and leaves it otherwise.
std::size_t sieveByGrid(const GridView& grid, const Vec3* points, std::size_t count, double limit,
                        std::uint32_t* kept, bool& inRange) noexcept;
std::size_t sieveByGrid(const GridView& grid, const Vec3* points, std::size_t count, double limit,
                        std::uint32_t* kept, bool& inRange, kernels::Isa isa) noexcept;

/// Below this squared distance (2⁻⁹⁶⁰) a square may have lost precision to underflow, or be 0
/// for a distance below about 1e-162 (coordinate_range.h).
inline constexpr double kUnderflowingSquare = 0x1p-960;

/// The distance from `point` to its nearest triangle (found): √distanceSquared, or, where the
/// square may have underflowed, the same kernel run on the triangle and the point less its
/// first vertex (the differences it takes itself) scaled by a power of two to about 1, which is
/// exact: the kernel's distance at a scale where its square does not underflow, so that a point
/// 1e-300 off a face is not reported on it.
inline double distanceOf(const QueryMeshData& mesh, const Vec3& point,
                         const Nearest& nearest) noexcept {
  if (!(nearest.distanceSquared < kUnderflowingSquare)) return std::sqrt(nearest.distanceSquared);
  return kernels::distanceAtScale(point, mesh.triangle(nearest.sorted));
}

/// The nearest triangle where the search's winner has a square that may have underflowed
/// (`nearest.distanceSquared` < kUnderflowingSquare): those squares tie at 0 or nearly, or keep
/// only a few bits (subnormal: two triangles 4.5e-162 and 4.19e-162 away had the same square),
/// so the triangles that may be nearer (every one whose square is below kUnderflowingSquare) are
/// compared by their distances at scale (kernels::distanceAtScale), ties to the smallest id.
/// Returns `nearest` itself, at once, where its square is not below kUnderflowingSquare or its
/// distance at scale is 0 (the point lies on it: nothing is nearer, and it is the smallest id of
/// the squares at 0); otherwise the triangles in the leaves within 2⁻⁴⁷⁹ of the point, found
/// through the tree (forTrianglesMeeting).
Nearest resolveUnderflow(const QueryMeshData& mesh, const Vec3& point,
                         const Nearest& nearest) noexcept;

/// Whether `point` lies inside the closed mesh, given its nearest triangle: within rounding of the
/// surface insideNearSurface's exact answer; elsewhere the sign of the offset from the closest
/// point along the pseudonormal of the feature it lies on, or, where that is too close to zero
/// to trust, insideByExactRays, or where they give nothing the generalized winding number. False
/// on the surface. The mesh must be closed.
bool insideAt(const QueryMeshData& mesh, const Vec3& point, const Nearest& nearest) noexcept;

/// Whether `point` lies inside the closed mesh, exactly: the signed sum of a ray's crossings
/// with exact orientation predicates (exact_predicates.h), the ray along ±x, ±y or ±z, or one of
/// those turned by about 2⁻²¹ radians, the first that meets no edge or vertex of the mesh and lies
/// in no triangle's plane (triangles of zero area, exactly, are passed over: they subtend no solid
/// angle): the winding number
/// of a point off the surface (times the orientation: 1 inside). False where the ray starts on
/// the surface. A ray tests only the triangles of the leaves whose boxes its segment meets
/// (forTrianglesMeeting), a few where it crosses the surface a few times. Nothing where a
/// coordinate involved is below 2⁻²⁵⁰ but not 0 (the expansions' products would underflow), or
/// every ray is degenerate.
std::optional<bool> insideByExactRays(const QueryMeshData& mesh, const Vec3& point) noexcept;

/// The exact sign of the volume the closed surface of sorted triangles `part` encloses (+1 for
/// an outward one): its signed volume about its box's centre, scaled by a power of two to about 1
/// (exact), where it exceeds a bound on the sum's rounding; elsewhere the exact sum of its triple
/// products about the origin (a closed surface's volume is the same about any point); 0 for a
/// volume of exactly 0; nothing where a coordinate is below 2⁻²⁵⁰ but not 0 (the exact sum would
/// underflow). May throw std::bad_alloc.
std::optional<int> volumeSign(const QueryMeshData& mesh, std::span<const std::uint32_t> part);

/// The winding number at `point` of the triangles of a closed mesh outside part `part`
/// (`partOf[k]` the part of sorted triangle k): the signed sum of an exact ray's crossings with
/// them, as insideByExactRays counts them, not times the orientation (+1 for each leaving
/// through a face's front). Nothing where the point lies on one of them, where every ray meets
/// an edge or vertex of them or lies in the plane of one, or where a coordinate involved is
/// below 2⁻²⁵⁰ but not 0.
std::optional<int> windingOfOtherParts(const QueryMeshData& mesh, const Vec3& point,
                                       std::span<const std::uint32_t> partOf,
                                       std::uint32_t part) noexcept;

/// Where `point` lies within rounding of the closed mesh's surface (its distance below 2⁻⁴⁰ of
/// the closest point's magnitude and the nearest triangle's extent: there the closest point's own
/// rounding can turn the offset from it, and the winding number's solid angles near the nearest
/// faces lose their sign), whether it lies inside, decided exactly: true inside; false outside or
/// exactly on the surface: on its nearest triangle exactly, else insideByExactRays. Nothing
/// where the point is not that close, or where insideByExactRays gives nothing.
/// `distance` is the point's, distanceOf(mesh, point, nearest), which the callers have.
std::optional<bool> insideNearSurface(const QueryMeshData& mesh, const Vec3& point,
                                      const Nearest& nearest, double distance) noexcept;

}  // namespace delta::detail
