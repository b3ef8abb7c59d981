#pragma once

#include <cstddef>
#include <memory>

#include "delta/core/aabb.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/topology.h"
#include "delta/mesh/triangle_soa.h"

namespace delta {

namespace detail {
struct QueryMeshData;
}

/// A mesh prepared for queries: its flattened triangles (in the mesh's order, for the kernels), a
/// bounding-volume tree over them (eight triangles to a leaf, eight nodes to a parent, each node
/// with its box; built top-down by splits at the median of the centroids along the longest axis),
/// and, for a closed mesh, the angle-weighted pseudonormals of its vertices and edges (Bærentzen
/// and Aanæs, "Signed distance computation using the angle weighted pseudonormal", IEEE TVCG 2005)
/// that sign a distance in O(1) once the closest point is known.
///
/// Built once, in O(n log n), and then queried any number of times (query/point_distance.h,
/// query/contacts.h). Like a TriangleSoA it is a snapshot: moving the Mesh afterwards does not
/// move it. Triangle ids in every answer are the mesh's triangle order.
///
/// `closed()` — every edge shared by exactly two triangles that traverse it oppositely — is what
/// signed queries and the "inside both meshes" overlap marker need. An inside-out closed mesh
/// (negative signed volume) is handled: inside is where its winding number is −1.
///
/// Throws delta::Error for a mesh with no triangles.
///
/// Threading: immutable after construction; any number of threads may query one QueryMesh at
/// once. Copies share the immutable data (a copy costs a reference count).
class QueryMesh {
 public:
  explicit QueryMesh(const Mesh& mesh);

  /// The number of triangles.
  std::size_t size() const noexcept;
  /// The flattened triangles in the mesh's order.
  const TriangleSoA& triangles() const noexcept;
  const Topology& topology() const noexcept;
  /// Closed and consistently oriented: signed distances and inside tests are defined.
  bool closed() const noexcept;
  /// The box of all vertices.
  const Aabb& bounds() const noexcept;
  /// Bytes held on the heap (triangles twice: in mesh order and in tree order; tree boxes;
  /// pseudonormals of closed meshes).
  std::size_t memoryBytes() const noexcept;

  /// The prepared data, for the query implementations.
  const detail::QueryMeshData& data() const noexcept { return *data_; }

 private:
  std::shared_ptr<const detail::QueryMeshData> data_;
};

}  // namespace delta
