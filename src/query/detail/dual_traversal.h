#pragma once

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

/// The boxes of a tree's nodes carried into another frame: each the box of the moved box (centre
/// moved, half extents through |R|), so it contains every moved point of the original.
std::vector<std::vector<Aabb>> movedLevels(const std::vector<std::vector<Aabb>>& levels,
                                           const MatrixMotion& motion);

/// Every pair of leaves, one of each tree, whose boxes are not `reach` apart along any axis, by a
/// simultaneous descent of both trees that splits the larger node. `secondLevels` are the second
/// tree's boxes in the first's frame (its own levels, or movedLevels of them). In no particular
/// order; each pair once.
std::vector<LeafPair> leafPairsWithin(const std::vector<std::vector<Aabb>>& firstLevels,
                                      const std::vector<std::vector<Aabb>>& secondLevels,
                                      double reach);

}  // namespace delta::detail
