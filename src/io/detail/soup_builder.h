#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

#include "mesh_readers.h"

namespace delta::detail {

/// Triangulates a polygon given by `corners`, indices into `vertices` (n >= 3; they need not be
/// distinct), appending n − 2 triangles to `out`, oriented as the polygon is (corner order).
/// - A convex polygon (in the plane of its Newell normal, each turn in the same sense or
///   straight) becomes a fan from its first corner: (c0, c1, c2), (c0, c2, c3), ...
/// - A non-convex one is cut by ear clipping in that plane (projected on the two axes the normal
///   is least aligned with): the first ear, in corner order, whose triangle holds no other corner
///   is cut, again and again; what is left when no ear is found (a self-intersecting polygon) is
///   fanned. Ear clipping takes O(n²) steps; a polygon of more than 4096 corners, or one whose
///   normal is zero (all corners on a line), is fanned.
/// Deterministic: the same polygon gives the same triangles.
void triangulatePolygon(std::span<const Vec3> vertices, std::span<const std::uint32_t> corners,
                        std::vector<TriangleIndices>& out);

/// Collects a file's vertices and faces into a TriangleSoup.
///
/// Threading: one object per thread.
class SoupBuilder {
 public:
  /// The file's vertices so far, in order; readers append to it.
  std::vector<Vec3>& vertices() noexcept { return vertices_; }
  const std::vector<Vec3>& vertices() const noexcept { return vertices_; }

  /// Starts a new mesh: statistics.meshes counts the meshes that receive a triangle.
  void beginMesh() noexcept { meshHasTriangles_ = false; }

  /// A face of the file: one corner is a point, two a line, more are triangulated. The caller has
  /// checked every index against vertices().
  void addFace(std::span<const std::uint32_t> corners);

  /// Point or line primitives of the file (OBJ's `p` and `l`).
  void addPoints(std::size_t count) noexcept {
    anyFace_ = true;
    statistics_.pointsSkipped += count;
  }
  void addLines(std::size_t count) noexcept {
    anyFace_ = true;
    statistics_.linesSkipped += count;
  }

  /// The soup: used vertices in file order, triangles renumbered to them. `pointsIfNoFaces`:
  /// vertices count as points when no face, point or line at all was added (a point cloud).
  TriangleSoup finish(bool pointsIfNoFaces);

 private:
  std::vector<Vec3> vertices_;
  std::vector<TriangleIndices> triangles_;
  io::LoadStatistics statistics_;
  bool meshHasTriangles_ = false;
  bool anyFace_ = false;
};

}  // namespace delta::detail
