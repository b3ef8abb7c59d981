#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "delta/query/query_mesh.h"

namespace delta {

/// Where a mesh crosses itself: the pairs of non-adjacent triangles that share a point.
///
/// Threading: a value type; no shared state.
struct SelfIntersections {
  /// The number of crossing pairs, each unordered pair once.
  std::size_t count = 0;
  /// The first kListedPairs of them (fewer if there are fewer), as (smaller id, larger id) in
  /// the mesh's triangle order, sorted: for a message or a test, not for repair.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;

  /// How many pairs `pairs` lists at most.
  static constexpr std::size_t kListedPairs = 16;
  bool any() const noexcept { return count != 0; }
};

/// The pairs of triangles of `mesh` that intersect although they are not adjacent: two
/// triangles are adjacent where they share a vertex, by index or by coordinates (so a soup's
/// neighbours, whose corners are copies, are adjacent too), and a pair is crossing where
/// kernels::trianglesIntersect says they share a point — touching counts, and so does a gap
/// below its tolerance τ (about 7e-15 of the pair's coordinates; coplanar overlapping triangles
/// and a vertex resting on a face are crossings). The count is therefore never below the exact
/// count of non-adjacent pairs at distance 0, and above it only by pairs closer than τ.
///
/// Not counted: crossings between triangles that share a vertex (a fold through a shared vertex
/// or edge, two coincident triangles on the same three vertices): topology.h reports folds and
/// duplicates, and pseudonormal signs stay correct away from them.
///
/// Found by a traversal of the QueryMesh's tree against itself (each leaf against the leaves
/// whose boxes overlap its own, the triangles' boxes first), in parallel over the leaves:
/// O(n log n) for a mesh whose triangles overlap few others' boxes. The answer is geometry-only
/// and kept by the QueryMesh's shared data: the first call finds it (thread-safe), later calls
/// and copies return it at once. Deterministic for any thread count. The pose is irrelevant (a
/// rigid motion moves no triangle relative to another).
///
/// Throws std::bad_alloc only.
///
/// Threading: any number of threads may call it on one QueryMesh (or its copies) at once.
const SelfIntersections& selfIntersections(const QueryMesh& mesh);

}  // namespace delta
