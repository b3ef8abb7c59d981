#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "delta/core/vec3.h"

namespace delta::detail {

/// Vertices merged by exact position.
struct JoinedVertices {
  std::vector<Vec3> vertices;           ///< the distinct positions, in order of first appearance
  std::vector<std::uint32_t> newIndex;  ///< for each input vertex, its index in `vertices`
};

/// Joins vertices whose three coordinates compare equal (0.0 and -0.0 are one position). The
/// input must be finite: NaN equals nothing. Throws delta::Error past 2³² − 1 distinct positions.
///
/// Expected O(n): an open-addressing hash table on the coordinates' bit patterns, kept at most
/// half full by doubling (amortised O(1) an insertion). Unlike assimp's
/// aiProcess_JoinIdenticalVertices it ignores normals and texture coordinates (an STL facet's
/// corners carry the facet's normal) and works across meshes.
JoinedVertices joinIdenticalVertices(std::span<const Vec3> vertices);

}  // namespace delta::detail
