#pragma once

#include <cstdint>
#include <vector>

#include "delta/mesh/mesh.h"

namespace delta::detail {

/// One triangle's edge between two distinct vertex indices, keyed by the unordered index pair
/// (smaller index in the high 32 bits) so that the two traversals of a shared edge sort together.
struct DirectedEdge {
  std::uint64_t key = 0;
  bool reversed = false;  ///< traversed from the larger index to the smaller
};

constexpr std::uint32_t edgeFirstVertex(std::uint64_t key) noexcept {
  return static_cast<std::uint32_t>(key >> 32);
}
constexpr std::uint32_t edgeSecondVertex(std::uint64_t key) noexcept {
  return static_cast<std::uint32_t>(key & 0xffffffffu);
}

/// The edges of every triangle with three distinct indices, sorted by key so that all
/// traversals of one undirected edge are adjacent. A triangle with a repeated index is skipped:
/// (a, a, b) is a zero-width fold whose traversals a→b and b→a pair with each other (a sliver
/// whose two vertices import joined), so counting them would make its neighbours' shared edge
/// look non-manifold. O(n) for bounded vertex valence, O(n log n) at worst.
std::vector<DirectedEdge> sortedDirectedEdges(const Mesh& mesh);

}  // namespace delta::detail
