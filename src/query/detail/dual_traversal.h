#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/mat3.h"
#include "delta/core/rotation.h"
#include "delta/core/triangle.h"

#include "query_mesh_data.h"

namespace delta::detail {

/// A leaf of each of two trees (indices into their levels[0]).
struct LeafPair {
  std::uint32_t first;
  std::uint32_t second;
};

/// A rigid motion as a matrix, applied exactly as Mesh::transform applies it (so a prepared
/// mesh moved by a pose meets another one at the same coordinates as the moved Mesh would).
struct MatrixMotion {
  Mat3 rotation;
  Vec3 translation;
  Vec3 apply(const Vec3& p) const noexcept { return rotation * p + translation; }
  Triangle apply(const Triangle& t) const noexcept { return {apply(t.a), apply(t.b), apply(t.c)}; }
};
MatrixMotion matrixMotion(const RigidTransform& motion);

/// A tree's node boxes as seen from another frame, moved on demand: a query that visits a few
/// nodes of a large tree (a particle near a big obstacle) pays for those, not for the whole tree.
/// A moved box is the box of the moved box (centre moved, half extents through |R|), so it
/// contains every moved point of the original; the rounding of the moved centre is a few ulps of
/// the coordinates, covered by the boxes' slack (query_mesh_data.h). Without a motion the boxes
/// are the tree's own.
class MovedTree {
 public:
  MovedTree(const std::vector<std::vector<Aabb>>& levels, const MatrixMotion* motion) noexcept;

  Aabb box(std::size_t level, std::size_t node) const noexcept {
    const Aabb& box = levels_[level][node];
    if (!motion_) return box;
    const Vec3 centre = motion_->apply(box.center());
    const Vec3 half = magnitude_ * (box.extent() * 0.5);
    return {centre - half, centre + half};
  }
  std::size_t levelCount() const noexcept { return levels_.size(); }
  std::size_t nodeCount(std::size_t level) const noexcept { return levels_[level].size(); }

 private:
  const std::vector<std::vector<Aabb>>& levels_;
  const MatrixMotion* motion_;
  Mat3 magnitude_;  ///< |R| entry by entry
};

/// A triangle's plane, for the mesh–mesh queries' cheapest exact early-out: a triangle whose three
/// vertices lie on one side of it, all farther than the reach, is farther than the reach from
/// the plane's triangle (the box tests cannot see this for nearly touching surfaces, whose
/// triangles' boxes overlap by the thousand). Not usable for a sliver or a zero-area triangle
/// (angle at a below 2⁻¹⁰), whose plain normal's direction is off by ε / sin α.
struct SeparatingPlane {
  Vec3 normal;  ///< unit
  Vec3 origin;  ///< the triangle's first vertex
  /// The triangle's largest absolute coordinate, the scale of the rounding of a signed distance
  /// to its plane, or of one of its vertices to another plane.
  double magnitude = 0.0;
  double size = 0.0;  ///< its longest edge from the origin
  bool usable = false;
};

inline SeparatingPlane separatingPlane(const Triangle& t) noexcept {
  const Vec3 u = t.b - t.a, v = t.c - t.a, n = cross(u, v);
  const double nn = lengthSquared(n);
  SeparatingPlane plane;
  plane.magnitude =
      std::max({std::abs(t.a.x), std::abs(t.a.y), std::abs(t.a.z), std::abs(t.b.x), std::abs(t.b.y),
                std::abs(t.b.z), std::abs(t.c.x), std::abs(t.c.y), std::abs(t.c.z)});
  plane.usable = nn > 0x1p-20 * lengthSquared(u) * lengthSquared(v);
  if (!plane.usable) return plane;
  plane.normal = n * (1.0 / std::sqrt(nn));
  plane.origin = t.a;
  plane.size = std::sqrt(std::max(lengthSquared(u), lengthSquared(v)));
  return plane;
}

/// Whether every vertex of `t` (whose largest absolute coordinate is `magnitude`) lies farther
/// than `reach` from the plane, all on one side; with a margin of 2⁻³⁰ of the coordinates'
/// magnitude, thousands of times the rounding of the signed distances (a few ε of the
/// coordinates, and 2¹⁰·ε of the distance for the normal), so a pair within reach is never taken
/// for separated.
inline bool separated(const SeparatingPlane& plane, const Triangle& t, double magnitude,
                      double reach) noexcept {
  if (!plane.usable) return false;
  const double beyond = reach + 0x1p-30 * (plane.magnitude + plane.size + magnitude);
  const double a = dot(plane.normal, t.a - plane.origin), b = dot(plane.normal, t.b - plane.origin),
               c = dot(plane.normal, t.c - plane.origin);
  return (a > beyond && b > beyond && c > beyond) || (a < -beyond && b < -beyond && c < -beyond);
}

/// Every pair of leaves, one of each tree, whose boxes are not `reach` apart along any axis, by a
/// simultaneous descent of both trees that splits the larger node. `second` is the second tree
/// seen from the first's frame. In no particular order; each pair once.
std::vector<LeafPair> leafPairsWithin(const std::vector<std::vector<Aabb>>& firstLevels,
                                      const MovedTree& second, double reach);

}  // namespace delta::detail
