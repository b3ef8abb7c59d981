#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "delta/mesh/mesh.h"

#include "union_find.h"

namespace delta::detail {

/// The parts of a triangle mesh: its vertices joined along the triangles' edges.
struct VertexParts {
  /// Per vertex its part, numbered in the order the triangles' corners first meet them (so the
  /// numbering does not depend on the union–find's roots); vertices no triangle uses: 0.
  std::vector<std::uint32_t> ofVertex;
  std::size_t count = 0;
};

/// The parts of the mesh of `vertexCount` vertices and `triangles` (mass properties sum each
/// about its own centre; the overlap query places each that no triangle pair reaches).
inline VertexParts vertexParts(std::size_t vertexCount,
                               std::span<const TriangleIndices> triangles) {
  std::vector<std::uint32_t> parent;
  UnionFind<std::uint32_t> sets(parent);
  sets.reset(vertexCount);
  for (const TriangleIndices& t : triangles) {
    sets.join(t[1], t[0]);
    sets.join(t[2], t[0]);
  }
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> partOfRoot(vertexCount, kNone);
  VertexParts parts;
  parts.ofVertex.assign(vertexCount, 0);
  for (const TriangleIndices& t : triangles)
    for (const std::uint32_t v : t) {
      std::uint32_t& part = partOfRoot[sets.find(v)];
      if (part == kNone) part = static_cast<std::uint32_t>(parts.count++);
      parts.ofVertex[v] = part;
    }
  return parts;
}

}  // namespace delta::detail
