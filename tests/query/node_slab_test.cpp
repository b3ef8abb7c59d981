// The mesh–mesh queries' node test (query/detail/dual_traversal.h's slabGap over the slabs of
// query_mesh_data.h): never above the distance between the two nodes' triangles, for nodes of
// every level of a mesh and of its moved copy, at gaps from overlapping to apart; and useful
// (it proves most far pairs apart).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "delta/io/mesh_io.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/dual_traversal.h"
#include "query/detail/query_mesh_data.h"

namespace delta::detail {
namespace {

/// The sorted triangles a node of level `level` holds.
std::pair<std::size_t, std::size_t> rangeOf(const QueryMeshData& data, std::size_t level,
                                            std::size_t node) {
  std::size_t span = kFanout;
  for (std::size_t l = 0; l < level; ++l)
    span *= kFanout;
  return {node * span, std::min((node + 1) * span, data.size())};
}

TEST(NodeSlab, GapNeverExceedsTheTrianglesDistance) {
  const Mesh mesh = io::load(std::filesystem::path(DELTA_DATA_DIR) / "meshes" / "fandisk.off");
  QueryMesh first(mesh), second(mesh);
  const double size = mesh.bounds().diagonal();
  std::mt19937_64 random(5);
  int proved = 0, pairs = 0;
  for (double shift : {0.0, 0.02, 0.3}) {
    second.setPose(RigidTransform::translationBy({shift * size, 0.01 * size, 0}) *
                   RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, 2, 3}, 0.4),
                                                 mesh.bounds().center()));
    const QueryMeshData &a = first.data(), &b = second.data();
    const MatrixMotion motion = matrixMotion(first.inversePose() * second.pose());
    const MovedTree tree(b.levels, &motion);
    for (std::size_t round = 0; round < test::scaledCount(300); ++round) {
      const std::size_t la = random() % 2, lb = random() % 2;
      const std::size_t na = random() % a.levels[la].size(), nb = random() % b.levels[lb].size();
      const double gap = slabGap(a.slabs[la][na], a.levels[la][na], tree.moved(b.slabs[lb][nb]),
                                 tree.box(lb, nb), a.slack + b.slack);
      const auto [fa, ta] = rangeOf(a, la, na);
      const auto [fb, tb] = rangeOf(b, lb, nb);
      double nearest = std::numeric_limits<double>::infinity();
      for (std::size_t i = fa; i < ta; ++i)
        for (std::size_t j = fb; j < tb; ++j)
          nearest = std::min(nearest, std::sqrt(kernels::triangleDistanceBruteForce(
                                                    a.triangle(i), motion.apply(b.triangle(j)))
                                                    .distanceSquared));
      ASSERT_LE(gap, nearest) << "shift " << shift << ", nodes " << la << ":" << na << ", " << lb
                              << ":" << nb;
      ++pairs;
      proved += gap > 0.0;
    }
  }
  EXPECT_GT(proved, pairs / 2);  // random pairs lie mostly apart, and the test sees it
}

}  // namespace
}  // namespace delta::detail
