#include "edges.h"

#include <algorithm>
#include <cstddef>

namespace delta::detail {
namespace {

bool hasRepeatedIndex(const TriangleIndices& t) noexcept {
  return t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
}

}  // namespace

std::vector<DirectedEdge> sortedDirectedEdges(const Mesh& mesh) {
  // A counting sort by the smaller vertex index (one pass to count, one to place), then a sort
  // of each vertex's few edges by the larger index: O(n) but for the rare high-valence vertex,
  // several times faster than one comparison sort of all the edges.
  // (a, a, b) traverses a→b and b→a: a zero-width fold whose two traversals pair with each
  // other, so it neither opens nor joins the surface. It is skipped, as is (a, a, a).
  std::vector<std::size_t> bucketStart(mesh.vertexCount() + 1, 0);
  for (const TriangleIndices& t : mesh.triangles()) {
    if (hasRepeatedIndex(t)) continue;
    for (int k = 0; k < 3; ++k)
      ++bucketStart[std::min(t[k], t[(k + 1) % 3]) + 1];
  }
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v)
    bucketStart[v + 1] += bucketStart[v];

  std::vector<DirectedEdge> edges(bucketStart.back());
  std::vector<std::size_t> next(bucketStart.begin(), bucketStart.end() - 1);
  for (const TriangleIndices& t : mesh.triangles()) {
    if (hasRepeatedIndex(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t from = t[k];
      const std::uint32_t to = t[(k + 1) % 3];
      const std::uint32_t low = std::min(from, to);
      const std::uint32_t high = std::max(from, to);
      edges[next[low]++] = {(std::uint64_t{low} << 32) | high, from > to};
    }
  }
  const auto byKey = [](const DirectedEdge& a, const DirectedEdge& b) { return a.key < b.key; };
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v)
    std::sort(edges.begin() + static_cast<std::ptrdiff_t>(bucketStart[v]),
              edges.begin() + static_cast<std::ptrdiff_t>(bucketStart[v + 1]), byKey);
  return edges;
}

}  // namespace delta::detail
