#pragma once

#include <cstddef>
#include <span>

#include "delta/core/aligned_allocator.h"
#include "delta/core/rotation.h"
#include "delta/core/triangle.h"

namespace delta {

class Mesh;

/// The flattened mesh (the seed's "flatten"): a plain stream of vertex triples, structure of
/// arrays, with no indices. Every kernel reads this form.
///
/// Layout: nine streams, one per vertex slot v ∈ {0, 1, 2} and axis a ∈ {x, y, z}, each holding
/// `paddedSize()` doubles; triangle i is
///
///     (x0[i], y0[i], z0[i]), (x1[i], y1[i], z1[i]), (x2[i], y2[i], z2[i])
/// in the mesh's triangle order and orientation (triangle i of the SoA is triangle i of the
/// mesh). All streams live in one block; each starts on a 64-byte boundary, and `paddedSize()` is
/// `size()` rounded up to a multiple of kLaneMultiple (8 doubles, one AVX-512 register), so a SIMD
/// loop over [0, paddedSize()) loads whole aligned registers with no gather and no remainder loop.
/// The padding triangles have NaN coordinates: every comparison with them is false, so they can
/// never pass a distance test or become a minimum; kernels must still discard lanes ≥ size().
///
/// Vertices shared by several triangles are replicated (72 bytes per triangle, topology is gone).
/// A TriangleSoA is a snapshot: moving the mesh afterwards does not move it; flatten again.
///
/// Threading: immutable after construction; any number of threads may read it at once.
class TriangleSoA {
 public:
  static constexpr std::size_t kAlignment = 64;
  static constexpr std::size_t kLaneMultiple = kAlignment / sizeof(double);

  /// No triangles (size() and paddedSize() 0): a value to assign() to. Queries refuse it.
  TriangleSoA() = default;
  /// The mesh's triangles, degenerate ones included, in its order. Allocates 72 bytes a
  /// triangle, padding included.
  explicit TriangleSoA(const Mesh& mesh);

  /// The number of triangles (without padding).
  std::size_t size() const noexcept { return size_; }
  /// size() rounded up to a multiple of kLaneMultiple: the length of every stream.
  std::size_t paddedSize() const noexcept { return paddedSize_; }

  /// The stream of coordinate `axis` (0 = x, 1 = y, 2 = z) of vertex slot `vertex` (0, 1, 2):
  /// paddedSize() doubles, 64-byte aligned.
  const double* stream(int vertex, int axis) const noexcept {
    return data_.data() + static_cast<std::size_t>(vertex * 3 + axis) * paddedSize_;
  }

  /// Triangle `index` (< size(), unchecked) gathered back into a value.
  Triangle triangle(std::size_t index) const noexcept {
    return {vertex(0, index), vertex(1, index), vertex(2, index)};
  }

  /// Fills the streams with `triangles` (in order), reusing the storage when it is large enough:
  /// scratch for a few triangles moved into another frame, without an allocation per use. An
  /// empty span leaves no triangles. Coordinates are not checked (the kernels assume finite
  /// ones). Needs exclusive access, like any assignment.
  void assign(std::span<const Triangle> triangles);

  /// A copy with every vertex moved by `motion` (rotation, then translation), padding kept NaN:
  /// O(n), for comparing meshes that are prepared once and then moved rigidly.
  TriangleSoA transformed(const RigidTransform& motion) const;

  /// Bytes held on the heap.
  std::size_t memoryBytes() const noexcept { return data_.capacity() * sizeof(double); }

 private:
  Vec3 vertex(int slot, std::size_t index) const noexcept {
    return {stream(slot, 0)[index], stream(slot, 1)[index], stream(slot, 2)[index]};
  }

  std::size_t size_ = 0;
  std::size_t paddedSize_ = 0;
  AlignedDoubles data_;
};

/// The seed's flatten operator: `TriangleSoA(mesh)`.
///
/// Threading: reads the mesh only; safe to call concurrently.
inline TriangleSoA flatten(const Mesh& mesh) {
  return TriangleSoA(mesh);
}

}  // namespace delta
