#include "delta/mesh/topology.h"

#include <vector>

#include "detail/edges.h"

namespace delta {

std::string describeDefects(const Topology& topology) {
  return std::to_string(topology.boundaryEdges) + " boundary, " +
         std::to_string(topology.nonManifoldEdges) + " non-manifold and " +
         std::to_string(topology.misorientedEdges) + " misoriented edges of " +
         std::to_string(topology.edges);
}

Topology analyzeTopology(const Mesh& mesh) {
  const std::vector<detail::DirectedEdge> edges = detail::sortedDirectedEdges(mesh);
  Topology topology;
  for (std::size_t first = 0; first < edges.size();) {
    std::size_t reversed = 0;
    std::size_t last = first;
    for (; last < edges.size() && edges[last].key == edges[first].key; ++last)
      if (edges[last].reversed) ++reversed;
    const std::size_t incident = last - first;
    ++topology.edges;
    if (incident == 1) ++topology.boundaryEdges;
    if (incident >= 3) ++topology.nonManifoldEdges;
    if (incident == 2 && reversed != 1) ++topology.misorientedEdges;
    first = last;
  }
  topology.manifold = topology.nonManifoldEdges == 0;
  topology.closed = topology.edges > 0 && topology.boundaryEdges == 0 && topology.manifold;
  topology.consistentlyOriented = topology.manifold && topology.misorientedEdges == 0;
  return topology;
}

}  // namespace delta
