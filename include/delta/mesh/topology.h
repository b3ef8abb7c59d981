#pragma once

#include <cstddef>

#include "delta/mesh/mesh.h"

namespace delta {

/// How the triangles of a mesh fit together along their edges (vertices are identified by
/// index: import joins identical vertices, so coincident but unjoined vertices count as distinct).
struct Topology {
  std::size_t edges = 0;             ///< distinct undirected edges
  std::size_t boundaryEdges = 0;     ///< edges with one incident triangle
  std::size_t nonManifoldEdges = 0;  ///< edges with three or more incident triangles
  std::size_t misorientedEdges = 0;  ///< two-triangle edges traversed in the same direction
  bool closed = false;               ///< every edge has exactly two incident triangles
  bool manifold = false;             ///< no edge has more than two incident triangles
  bool consistentlyOriented =
      false;  ///< manifold, and neighbours traverse each shared edge oppositely
};

/// Edge-based analysis in O(n log n). A degenerate triangle with a repeated index contributes
/// only its edges between distinct indices.
Topology analyzeTopology(const Mesh& mesh);

}  // namespace delta
