#pragma once

#include <cstddef>
#include <memory>

#include "delta/core/aabb.h"
#include "delta/core/rotation.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/topology.h"
#include "delta/mesh/triangle_soa.h"

namespace delta {

namespace detail {
struct QueryMeshData;
}

/// A mesh prepared for queries: its triangles in the tree's order (the vertices in double, through
/// indices, for the exact kernels; a single-precision copy less the box's centre for the vector
/// leaf bounds, which allow for its rounding), a bounding-volume tree over them (eight triangles
/// to a leaf, eight nodes to a parent, each node with its box (for the point queries also in
/// single precision less the same centre: a mesh far from the origin is searched about as fast as
/// one at it) and an oriented slab — its triangles' mean normal and their extent along it, which
/// separates nearly parallel patches whose boxes overlap, and each leaf an oriented cylinder around
/// that normal, which keeps a far point's search out of the leaves whose boxes come closer than
/// their triangles; built top-down by binary splits of the centroids at the axis and child boundary
/// of least surface area heuristic), a uniform grid over its box with a lower bound of the distance
/// to the mesh in every cell (one byte a cell, about two cells a triangle: queries with a limit ε
/// reject most points farther than ε with one read, the seed's early "no contact"), and, for a
/// closed mesh, the angle-weighted pseudonormals of its vertices and edges (Bærentzen and Aanæs,
/// "Signed distance computation using the angle weighted pseudonormal", IEEE TVCG 2005) that sign a
/// distance in O(1) once the closest point is known, made by the first query that needs them
/// (thread-safe; 24 bytes a triangle that unsigned queries never pay), and, made likewise by the
/// first query that needs them, its self-intersections (query/self_intersections.h), its
/// parts' nesting (query/part_nesting.h) and per tree node the moments of the hierarchical
/// winding number (Sign::winding, about 20 bytes a triangle). About 85 bytes a triangle in all
/// before the pseudonormals.
///
/// Built once, in O(n log n), and then queried any number of times (query/point_distance.h,
/// query/contacts.h). Like a TriangleSoA it is a snapshot: moving the Mesh afterwards does not
/// move it. Triangle ids in every answer are the mesh's triangle order.
///
/// `closed()` — every edge shared by exactly two triangles that traverse it oppositely — is what
/// pseudonormal signs and the "inside both meshes" overlap marker need (with no
/// self-intersections and no misoriented parts: boundsSolid()); winding-number signs take any
/// mesh. An inside-out closed mesh (negative
/// signed volume) is handled: inside is where its winding number is −1. An open mesh's
/// orientation, for winding signs, is the sign of its signed volume about its box's centre.
///
/// A QueryMesh can be moved rigidly (`transform`) in O(1): the tree, the pseudonormals and
/// everything built from them move with it, nothing is rebuilt — queries carry points into the
/// frame the mesh was prepared in and answers back out. Copies share the prepared data and each
/// has its own pose, so particles of one shape in a DEM code share one QueryMesh's data. A
/// motion that is not rigid (a scale, a stretch) needs a new QueryMesh from the moved Mesh.
///
/// Any valid Mesh may be prepared: degenerate triangles, unreferenced vertices, open or
/// non-manifold surfaces and self-intersections are kept as they are (closed() is then false
/// where the topology says so, and only unsigned queries are defined). Throws delta::Error for a
/// mesh with no triangles (which a Mesh cannot be) or with 2³² − 1 triangles or more, and for one
/// outside the coordinate range the queries answer exactly (mesh/coordinate_range.h): a
/// coordinate beyond ±2²⁰⁰ (1.6e60), or every coordinate below 2⁻²⁰⁰ (6.2e-61) in magnitude; the
/// message gives the mesh's box and the range. Queries check a moved mesh where it is.
///
/// Threading: the prepared data is immutable and shared; any number of threads may query one
/// QueryMesh (or copies of it) at once. `transform` changes only this object's pose: not while
/// other threads query this same object. Copies cost a reference count.
class QueryMesh {
 public:
  /// Prepares `mesh` (O(n log n); copies what it needs, the Mesh may then change or go).
  explicit QueryMesh(const Mesh& mesh);

  /// Moves the mesh rigidly: its pose becomes `motion` ∘ pose (`motion`'s rotation
  /// renormalised). O(1). Throws delta::Error for a non-finite translation, a zero or non-finite
  /// rotation, or a resulting pose whose translation (or its inverse's) overflows a double,
  /// leaving the pose unchanged. (A pose beyond the coordinate range is kept; the queries
  /// refuse the mesh there.)
  QueryMesh& transform(const RigidTransform& motion);
  /// Puts the mesh at `pose` (from the frame it was prepared in): a rotation that is a unit
  /// quaternion to within 8ε is kept bit for bit (so that setPose(other.pose()) puts this mesh
  /// exactly where `other` is), any other is renormalised. O(1). Throws as transform().
  QueryMesh& setPose(const RigidTransform& pose);
  /// Where the mesh is: the map from the frame it was prepared in to where it is now.
  const RigidTransform& pose() const noexcept { return pose_; }
  /// The inverse of pose(): from world coordinates into the prepared frame.
  const RigidTransform& inversePose() const noexcept { return inversePose_; }
  /// Whether a pose has been set, by transform() or setPose() (even the identity).
  bool moved() const noexcept { return moved_; }
  /// Whether a quick test made when the pose was set finds the mesh's box, moved by its pose,
  /// within the coordinate range (mesh/coordinate_range.h); false means only that the pair
  /// queries check it exactly.
  bool placedSurelyInRange() const noexcept { return placedSurelyInRange_; }

  /// The number of triangles.
  std::size_t size() const noexcept;
  /// The mesh it was prepared from, in the frame it was prepared in: its triangles in their
  /// order, over the vertices they use (renumbered in the order the tree meets them; vertices no
  /// triangle uses are gone). A QueryMesh prepared from it answers every query as this one does
  /// at the same pose (what pickling a QueryMesh in Python relies on). O(n); may throw
  /// std::bad_alloc.
  Mesh mesh() const;
  /// The flattened triangles in the mesh's order, in the frame the mesh was prepared in (apply
  /// pose() for where they are now). Made on the first call (72 bytes a triangle, shared by the
  /// copies; the queries do not need them) and kept; thread-safe. May throw std::bad_alloc.
  const TriangleSoA& triangles() const;
  const Topology& topology() const noexcept;
  /// Closed and consistently oriented. Pseudonormal signs also need the mesh to bound a solid
  /// (boundsSolid: no self-intersections, no misoriented parts); winding signs take any mesh.
  bool closed() const noexcept;
  /// The box of all vertices, in the prepared frame.
  const Aabb& bounds() const noexcept;
  /// Bytes held on the heap (the triangles in tree order, and in mesh order once triangles() has
  /// made them; tree boxes; the distance-bound grid; the pseudonormals once a signed query has
  /// made them; the winding-number moments once a Sign::winding query has made them; the connected
  /// pieces once an overlap query has made them).
  std::size_t memoryBytes() const noexcept;

  /// The prepared data, for the query implementations.
  const detail::QueryMeshData& data() const noexcept { return *data_; }
  /// The same, shared: what keeps it alive (a ContactCache holds it, so that no other mesh's
  /// data can come to the same address while it names it).
  const std::shared_ptr<const detail::QueryMeshData>& sharedData() const noexcept { return data_; }

 private:
  /// Puts the mesh at `pose` (its rotation already checked) with its inverse; delta::Error naming
  /// `what` where either translation is not finite, the pose then unchanged.
  QueryMesh& place(const RigidTransform& pose, const char* what);

  std::shared_ptr<const detail::QueryMeshData> data_;
  RigidTransform pose_;
  RigidTransform inversePose_;
  bool moved_ = false;
  bool placedSurelyInRange_ = true;  ///< at the identity: checked when prepared
};

}  // namespace delta
