#pragma once

#include <cstddef>
#include <string>

#include "delta/mesh/mesh.h"

namespace delta {

/// How the triangles of a mesh fit together along their edges (vertices are identified by
/// index: import joins identical vertices, so coincident but unjoined vertices count as distinct).
///
/// Threading: a value type; no shared state.
struct Topology {
  std::size_t edges = 0;             ///< distinct undirected edges
  std::size_t boundaryEdges = 0;     ///< edges with one incident triangle
  std::size_t nonManifoldEdges = 0;  ///< edges with three or more incident triangles
  std::size_t misorientedEdges = 0;  ///< two-triangle edges traversed in the same direction
  bool closed = false;    ///< there are edges, and every one has exactly two incident triangles
  bool manifold = false;  ///< no edge has more than two incident triangles
  bool consistentlyOriented =
      false;  ///< manifold, and neighbours traverse each shared edge oppositely
};

/// What keeps a mesh from being closed and consistently oriented, for error messages:
/// "4 boundary, 0 non-manifold and 0 misoriented edges of 12".
///
/// Threading: a pure function.
std::string describeDefects(const Topology& topology);

/// Edge-based analysis in O(n log n) at worst, O(n) for bounded valence: the directed edges are
/// bucketed by their smaller vertex index and sorted within each bucket (no map per edge).
///
/// A triangle with a repeated index contributes no edge: (a, a, b) traverses a→b and then b→a,
/// a zero-width fold whose two traversals pair with each other. That is what import makes of a
/// sliver whose two coincident vertices it joins; its neighbours' shared edge stays manifold and
/// the mesh stays closed. (a, a, a) has no edge at all. Topology only: a closed mesh may still
/// intersect itself (nothing here compares positions). Two copies of a triangle over the same
/// vertices make its edges non-manifold (where other triangles share them too) or misoriented
/// (in the same orientation); back to back and alone they are closed and consistently oriented
/// (a flat part: massProperties refuses it as enclosing no volume, partNesting reports it
/// flat).
///
/// Threading: reads the mesh only; safe to call concurrently.
Topology analyzeTopology(const Mesh& mesh);

}  // namespace delta
