#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/mat3.h"
#include "delta/core/rotation.h"
#include "delta/core/triangle.h"
#include "delta/core/vec3.h"

namespace delta {

/// Three 0-based vertex indices; their order gives the triangle's orientation (counter-clockwise
/// seen from outside on an outward-oriented mesh). A repeated index makes a degenerate triangle.
using TriangleIndices = std::array<std::uint32_t, 3>;

/// An indexed triangle mesh: vertices (double precision) and index triples. Owns its data.
///
/// Invariants, checked on construction (else `delta::Error` naming the element and its value):
/// at least one triangle, every coordinate finite, every index below the vertex count, fewer
/// than 2³² vertices. Zero-area (degenerate) triangles and unreferenced vertices are kept: every
/// query accepts them. Any finite coordinates make a valid Mesh, and its measures (surfaceArea,
/// signedVolume, massProperties: rescaled by powers of two) answer for any of them or throw where
/// the answer is beyond a double; the proximity queries answer exactly within the coordinate
/// range of mesh/coordinate_range.h (±2²⁰⁰, and a mesh not all below 2⁻²⁰⁰ in magnitude) and
/// throw delta::Error naming the mesh, the value and the range outside it. Transforms keep the
/// invariants: one whose result would not be finite throws and leaves the mesh as it was.
///
/// Example:
///
///     delta::Mesh tetra({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
///                       {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
///     tetra.rotate(delta::Quaternion::fromAxisAngle({0, 0, 1}, 0.5)).translate({1, 0, 0});
///
/// Threading: const member functions may be called from any number of threads at once; a
/// transform needs exclusive access (no concurrent reader or writer).
class Mesh {
 public:
  /// Takes the arrays over and checks the invariants above; throws delta::Error naming the first
  /// offending vertex or triangle and its value ("mesh: vertex 3 has a coordinate that is not
  /// finite: (nan, 0, 0)", "mesh: triangle 7 refers to vertex 12, but there are only 10
  /// vertices", "mesh: has no triangles").
  Mesh(std::vector<Vec3> vertices, std::vector<TriangleIndices> triangles);

  /// The vertices, in the order given (views valid until the mesh is transformed or destroyed).
  std::span<const Vec3> vertices() const noexcept { return vertices_; }
  /// The index triples, in the order given: triangle ids everywhere in Δ are positions here.
  std::span<const TriangleIndices> triangles() const noexcept { return triangles_; }
  std::size_t vertexCount() const noexcept { return vertices_.size(); }
  /// At least 1.
  std::size_t triangleCount() const noexcept { return triangles_.size(); }

  /// The vertices of triangle `index` (< triangleCount(), unchecked).
  Triangle triangle(std::size_t index) const noexcept {
    const TriangleIndices& t = triangles_[index];
    return {vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]};
  }

  /// The axis-aligned box of all vertices (referenced or not).
  Aabb bounds() const noexcept;

  /// Bytes this mesh holds on the heap (vertex and index arrays).
  std::size_t memoryBytes() const noexcept;

  // Transforms. Each returns *this, so they chain. The pivot of a scale or rotation is the
  // point that stays fixed; the default is the origin. Each throws delta::Error for a non-finite
  // argument or pivot, and when a vertex would become non-finite (naming it); the mesh is then
  // unchanged. Indices, and so triangle ids, never change. Prepared forms made before
  // (TriangleSoA, QueryMesh) do not follow: prepare again, or move a QueryMesh rigidly instead.

  /// Moves every vertex by `offset`.
  Mesh& translate(const Vec3& offset);
  /// Uniform scale by `factor` > 0 about `pivot` (delta::Error otherwise).
  Mesh& scale(double factor, const Vec3& pivot = {});
  /// Per-axis scale by `factors` (each finite and > 0, delta::Error otherwise) about `pivot`:
  /// no mirror images, so the orientation of the triangles is kept.
  Mesh& stretch(const Vec3& factors, const Vec3& pivot = {});
  /// Rotation by a quaternion of any non-zero length (normalised first; delta::Error for a zero
  /// or non-finite one) about `pivot`.
  Mesh& rotate(const Quaternion& rotation, const Vec3& pivot = {});
  /// Rotation by `radians` about the line through `pivot` with direction `axis` (right-handed;
  /// delta::Error for a zero axis).
  Mesh& rotate(const Vec3& axis, double radians, const Vec3& pivot = {});
  /// Rotation by a 3×3 matrix; see Quaternion::fromMatrix for what is accepted.
  Mesh& rotate(const Mat3& rotation, const Vec3& pivot = {});
  /// Applies p ↦ R p + t to every vertex (R normalised first).
  Mesh& transform(const RigidTransform& motion);

 private:
  template <typename Map>
  Mesh& mapVertices(const Map& map, const char* operation);

  std::vector<Vec3> vertices_;
  std::vector<TriangleIndices> triangles_;
};

}  // namespace delta
