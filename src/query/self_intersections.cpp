#include "delta/query/self_intersections.h"

#include <algorithm>
#include <array>

#include "delta/core/parallel.h"
#include "delta/kernels/triangle_triangle.h"

#include "detail/query_mesh_data.h"

namespace delta {
namespace {

/// Closed boxes that share a point.
bool overlap(const Aabb& a, const Aabb& b) noexcept {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (a.lower[axis] > b.upper[axis] || b.lower[axis] > a.upper[axis]) return false;
  return true;
}

/// Triangles that share a corner, by index or by coordinates.
bool adjacent(const detail::QueryMeshData& mesh, std::size_t first, std::size_t second) noexcept {
  const TriangleIndices& a = mesh.corners[first];
  const TriangleIndices& b = mesh.corners[second];
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      if (a[i] == b[j] || mesh.vertices[a[i]] == mesh.vertices[b[j]]) return true;
  return false;
}

using Pair = std::pair<std::uint32_t, std::uint32_t>;

/// One leaf's crossings with itself and the leaves after it.
struct LeafCrossings {
  std::size_t count = 0;
  std::vector<Pair> pairs;  ///< its smallest kListedPairs
};

/// The crossings of leaf `leaf` with itself and with every later leaf whose box overlaps its
/// own, found by a descent of the tree from the root (each unordered pair of leaves once).
LeafCrossings crossingsOf(const detail::QueryMeshData& mesh, std::size_t leaf) {
  LeafCrossings found;
  const std::size_t from = leaf * detail::kFanout;
  const std::size_t to = std::min(from + detail::kFanout, mesh.size());
  std::array<Triangle, detail::kFanout> triangles;
  std::array<Aabb, detail::kFanout> boxes;
  for (std::size_t k = from; k < to; ++k) {
    triangles[k - from] = mesh.triangle(k);
    boxes[k - from] = triangles[k - from].bounds();
  }
  const Aabb& box = mesh.levels[0][leaf];
  const auto testLeaf = [&](std::size_t other) {
    const std::size_t otherFrom = other * detail::kFanout;
    const std::size_t otherTo = std::min(otherFrom + detail::kFanout, mesh.size());
    for (std::size_t q = otherFrom; q < otherTo; ++q) {
      const Triangle t = mesh.triangle(q);
      const Aabb tBox = t.bounds();
      for (std::size_t p = from; p < std::min(to, other == leaf ? q : to); ++p) {
        if (!overlap(boxes[p - from], tBox) || adjacent(mesh, p, q)) continue;
        if (!kernels::trianglesIntersect(triangles[p - from], t)) continue;
        ++found.count;
        found.pairs.emplace_back(std::min(mesh.order[p], mesh.order[q]),
                                 std::max(mesh.order[p], mesh.order[q]));
      }
    }
  };
  // Leaves are numbered in tree order: a node covers a contiguous range of them, so subtrees
  // wholly before `leaf` are skipped.
  struct Entry {
    std::size_t level, index;
  };
  std::vector<Entry> stack{{mesh.levels.size() - 1, 0}};
  while (!stack.empty()) {
    const Entry entry = stack.back();
    stack.pop_back();
    if (!overlap(mesh.levels[entry.level][entry.index], box)) continue;
    if (entry.level == 0) {
      if (entry.index >= leaf) testLeaf(entry.index);
      continue;
    }
    std::size_t span = 1;  // leaves under one child
    for (std::size_t l = 1; l < entry.level; ++l)
      span *= detail::kFanout;
    const std::size_t first = entry.index * detail::kFanout;
    const std::size_t last = std::min(first + detail::kFanout, mesh.levels[entry.level - 1].size());
    for (std::size_t c = first; c < last; ++c)
      if ((c + 1) * span > leaf) stack.push_back({entry.level - 1, c});
  }
  std::sort(found.pairs.begin(), found.pairs.end());
  if (found.pairs.size() > SelfIntersections::kListedPairs)
    found.pairs.resize(SelfIntersections::kListedPairs);
  return found;
}

SelfIntersections findSelfIntersections(const detail::QueryMeshData& mesh) {
  const std::size_t leaves = mesh.levels[0].size();
  std::vector<LeafCrossings> perLeaf(leaves);
  parallelFor(0, leaves, 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t leaf = begin; leaf < end; ++leaf)
      perLeaf[leaf] = crossingsOf(mesh, leaf);
  });
  SelfIntersections result;
  for (LeafCrossings& leaf : perLeaf) {
    result.count += leaf.count;
    result.pairs.insert(result.pairs.end(), leaf.pairs.begin(), leaf.pairs.end());
  }
  std::sort(result.pairs.begin(), result.pairs.end());
  if (result.pairs.size() > SelfIntersections::kListedPairs)
    result.pairs.resize(SelfIntersections::kListedPairs);
  return result;
}

}  // namespace

namespace detail {

const SelfIntersections& QueryMeshData::selfIntersections() const {
  std::call_once(selfIntersectionsOnce_,
                 [this] { selfIntersections_ = findSelfIntersections(*this); });
  return selfIntersections_;
}

}  // namespace detail

const SelfIntersections& selfIntersections(const QueryMesh& mesh) {
  return mesh.data().selfIntersections();
}

}  // namespace delta
