#include "delta/mesh/topology.h"

#include <gtest/gtest.h>

#include <vector>

#include "delta/mesh/primitives.h"

namespace delta {
namespace {

const std::vector<Vec3> kTetraVertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const std::vector<TriangleIndices> kTetraTriangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

TEST(Topology, ClosedTetra) {
  const Topology topology = analyzeTopology(Mesh(kTetraVertices, kTetraTriangles));
  EXPECT_EQ(topology.edges, 6u);
  EXPECT_EQ(topology.boundaryEdges, 0u);
  EXPECT_EQ(topology.nonManifoldEdges, 0u);
  EXPECT_EQ(topology.misorientedEdges, 0u);
  EXPECT_TRUE(topology.closed);
  EXPECT_TRUE(topology.manifold);
  EXPECT_TRUE(topology.consistentlyOriented);
}

TEST(Topology, OpenTetraHasThreeBoundaryEdges) {
  std::vector<TriangleIndices> open = kTetraTriangles;
  open.pop_back();
  const Topology topology = analyzeTopology(Mesh(kTetraVertices, open));
  EXPECT_EQ(topology.edges, 6u);
  EXPECT_EQ(topology.boundaryEdges, 3u);
  EXPECT_FALSE(topology.closed);
  EXPECT_TRUE(topology.manifold);
  EXPECT_TRUE(topology.consistentlyOriented);
}

TEST(Topology, FlippedFaceMisorientsItsThreeEdges) {
  std::vector<TriangleIndices> flipped = kTetraTriangles;
  std::swap(flipped[3][1], flipped[3][2]);
  const Topology topology = analyzeTopology(Mesh(kTetraVertices, flipped));
  EXPECT_EQ(topology.misorientedEdges, 3u);
  EXPECT_TRUE(topology.closed);
  EXPECT_TRUE(topology.manifold);
  EXPECT_FALSE(topology.consistentlyOriented);
}

TEST(Topology, ThreeTrianglesOnOneEdgeAreNonManifold) {
  const Mesh fan({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                 {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  const Topology topology = analyzeTopology(fan);
  EXPECT_EQ(topology.edges, 7u);
  EXPECT_EQ(topology.nonManifoldEdges, 1u);
  EXPECT_EQ(topology.boundaryEdges, 6u);
  EXPECT_FALSE(topology.manifold);
  EXPECT_FALSE(topology.closed);
  EXPECT_FALSE(topology.consistentlyOriented);
}

TEST(Topology, RepeatedIndexTrianglesAddNoEdges) {
  // A fold (a, a, b) and a point (a, a, a) added to a closed tetra leave it closed and manifold.
  std::vector<TriangleIndices> withFolds = kTetraTriangles;
  withFolds.push_back({0, 0, 1});
  withFolds.push_back({2, 3, 3});
  withFolds.push_back({1, 1, 1});
  const Topology topology = analyzeTopology(Mesh(kTetraVertices, withFolds));
  EXPECT_EQ(topology.edges, 6u);
  EXPECT_EQ(topology.nonManifoldEdges, 0u);
  EXPECT_TRUE(topology.closed);
  EXPECT_TRUE(topology.consistentlyOriented);

  // A sliver whose coincident vertices were joined: the quad's two halves still share their
  // edge once each way.
  const Mesh welded({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                    {{0, 1, 2}, {0, 2, 3}, {0, 2, 0}});
  const Topology weldedTopology = analyzeTopology(welded);
  EXPECT_EQ(weldedTopology.edges, 5u);
  EXPECT_EQ(weldedTopology.boundaryEdges, 4u);
  EXPECT_TRUE(weldedTopology.manifold);
  EXPECT_TRUE(weldedTopology.consistentlyOriented);

  // Nothing but a point-triangle: no edges, so not closed.
  const Topology point = analyzeTopology(Mesh({{0, 0, 0}}, {{0, 0, 0}}));
  EXPECT_EQ(point.edges, 0u);
  EXPECT_FALSE(point.closed);
}

TEST(Topology, DuplicatedTriangleIsMisoriented) {
  // The same triangle twice: each edge has two incident triangles traversing it the same way.
  const Topology topology =
      analyzeTopology(Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {1, 2, 0}}));
  EXPECT_EQ(topology.edges, 3u);
  EXPECT_EQ(topology.misorientedEdges, 3u);
  EXPECT_TRUE(topology.closed);
  EXPECT_FALSE(topology.consistentlyOriented);
}

TEST(Topology, PrimitivesAreClosedAndConsistent) {
  for (const Mesh& mesh : {primitives::icosphere(3), primitives::box(), primitives::cylinder(),
                           primitives::granulate(1)}) {
    const Topology topology = analyzeTopology(mesh);
    EXPECT_TRUE(topology.closed);
    EXPECT_TRUE(topology.consistentlyOriented);
    // Euler: a closed genus-0 triangle mesh has E = 3F/2 and V − E + F = 2.
    EXPECT_EQ(2 * topology.edges, 3 * mesh.triangleCount());
    EXPECT_EQ(mesh.vertexCount() + mesh.triangleCount(), topology.edges + 2);
  }
  const Topology quad = analyzeTopology(primitives::quad());
  EXPECT_EQ(quad.boundaryEdges, 4u);
  EXPECT_FALSE(quad.closed);
}

}  // namespace
}  // namespace delta
