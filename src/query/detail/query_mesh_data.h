#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <mutex>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/aligned_allocator.h"
#include "delta/core/vec3.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/topology.h"
#include "delta/mesh/triangle_soa.h"

#include "bound_grid.h"

namespace delta::detail {

/// Children per tree node and triangles per leaf.
inline constexpr std::size_t kFanout = 8;

/// Eight boxes side by side (Embree's `bvh_node_aabb.h` layout): one cache-line-aligned block per
/// node whose children the point queries test together, 192 bytes instead of 384. Single
/// precision, rounded outward, so a box here contains the double box it stands for and its
/// distance (computed in double) never exceeds that box's; empty slots have lower > upper (+∞,
/// −∞) and lie infinitely far away.
struct alignas(64) BoxOctet {
  float lowerX[kFanout], lowerY[kFanout], lowerZ[kFanout];
  float upperX[kFanout], upperY[kFanout], upperZ[kFanout];
};
using BoxOctets = std::vector<BoxOctet, AlignedAllocator<BoxOctet, 64>>;

/// The octet of `boxes[first, first + kFanout)` (fewer at the end: the rest empty).
BoxOctet octetOf(const std::vector<Aabb>& boxes, std::size_t first) noexcept;

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

/// A node's oriented slab: the unit mean normal of its triangles (their area vectors' sum) and
/// the extent of its vertices along it, widened by the slack. A patch nearly flat is thin along
/// its normal where its axis-aligned box is not: two patches facing each other across a small
/// gap have overlapping boxes but slabs apart (the mesh–mesh queries' node test, see
/// dual_traversal.h's slabGap).
struct NodeSlab {
  Vec3 normal{0, 0, 1};
  double low = 0.0, high = 0.0;
};

/// The angle-weighted pseudonormals of a closed mesh's vertices and edges (not normalised), each
/// stored once: 72 bytes a triangle where a copy per triangle took 144.
struct Pseudonormals {
  std::vector<Vec3> vertices;  ///< per mesh vertex
  std::vector<Vec3> edges;     ///< per edge shared by two triangles; edges[0] = 0 (no partner)
  /// Per sorted triangle: its vertices a, b, c (into `vertices`), then its edges ab, bc, ca (into
  /// `edges`).
  std::vector<std::array<std::uint32_t, 6>> ofTriangle;

  /// The pseudonormal of feature `slot` (0–2 vertices a, b, c; 3–5 edges ab, bc, ca) of sorted
  /// triangle `sorted`.
  const Vec3& of(std::uint32_t sorted, std::size_t slot) const noexcept {
    const std::uint32_t index = ofTriangle[sorted][slot];
    return slot < 3 ? vertices[index] : edges[index];
  }
  std::size_t memoryBytes() const noexcept {
    return (vertices.capacity() + edges.capacity()) * sizeof(Vec3) +
           ofTriangle.capacity() * sizeof(std::array<std::uint32_t, 6>);
  }
};

/// What a QueryMesh holds (see query_mesh.h).
struct QueryMeshData {
  TriangleSoA sorted;  ///< tree order: sorted[k] is the mesh's triangle order[k]
  std::vector<std::uint32_t> order;
  /// levels[0]: the leaves' boxes (leaf i holds sorted triangles [8i, 8i + 8)); levels[l]: node i
  /// has the children [8i, 8i + 8) of level l − 1; levels.back() holds the root alone. Boxes are
  /// grown by `slack` on every side, so a box's distance never exceeds a computed triangle
  /// distance inside it (rounding included).
  std::vector<std::vector<Aabb>> levels;
  /// The same tree for the point queries: childOctets[l][i] holds the boxes of node i of level
  /// l + 1's children (levels[l][8i, 8i + 8)); leafOctets[i] the boxes of leaf i's triangles,
  /// grown by `slack` like the leaves.
  std::vector<BoxOctets> childOctets;
  BoxOctets leafOctets;
  /// Per node of `levels`, its oriented slab (the same indexing).
  std::vector<std::vector<NodeSlab>> slabs;
  /// The pseudonormals of the vertices and edges, for signs. Empty unless the mesh is closed.
  Pseudonormals pseudonormals;
  /// Per cell of a uniform grid over the box, a lower bound of the distance to the mesh: the
  /// ε-limited queries reject most points farther than ε with one read (bound_grid.h).
  BoundGrid boundGrid;
  Topology topology;
  bool closed = false;
  double orientation = 1.0;  ///< −1 for an inside-out closed mesh
  Aabb bounds;
  double slack = 0.0;

  /// The triangles in the mesh's order (QueryMesh::triangles()), made from `sorted` on the first
  /// call (the queries never need them: most users never pay their 72 bytes a triangle).
  /// Thread-safe.
  const TriangleSoA& meshOrder() const;
  /// Whether meshOrder() has been made (then its bytes count in QueryMesh::memoryBytes()).
  bool meshOrderMade() const noexcept { return meshOrderMade_.load(std::memory_order_acquire); }

 private:
  mutable std::once_flag meshOrderOnce_;
  mutable TriangleSoA meshOrder_;
  mutable std::atomic<bool> meshOrderMade_{false};
};

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

/// Whether `point` lies inside the closed mesh, given its nearest triangle: the sign of the
/// offset from the closest point along the pseudonormal of the feature it lies on, or, where that
/// is too close to zero to trust, the generalized winding number. False on the surface
/// (distance 0). The mesh must be closed.
bool insideAt(const QueryMeshData& mesh, const Vec3& point, const Nearest& nearest) noexcept;

}  // namespace delta::detail
