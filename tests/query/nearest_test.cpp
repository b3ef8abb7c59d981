// The nearest-triangle descent under every instruction set (query/isa/point_table.cpp: one
// descent built once per ISA, each with its ISA's node and leaf bounds and exact lanes): the same
// answer as a loop over every triangle, bit for bit, whatever the ISA and whatever limit.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "delta/io/mesh_io.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/point_kernels.h"
#include "query/detail/query_mesh_data.h"
#include "query/probe_points.h"

namespace delta::detail {
namespace {

void expectEveryIsaLikeAllTriangles(const Mesh& mesh, const char* name,
                                    std::vector<Vec3> points = {}) {
  const QueryMesh query(mesh);
  if (points.empty()) points = test::probes(mesh, test::scaledCount(300), 3);
  // Each point's answer by every triangle, once for all the ISAs.
  std::vector<double> distances(points.size(), std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> triangles(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      const double d = kernels::closestPointOnTriangle(points[i], mesh.triangle(t)).distanceSquared;
      if (d < distances[i]) {
        distances[i] = d;
        triangles[i] = t;
      }
    }
  for (kernels::Isa isa : kernels::supportedIsas()) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec3& p = points[i];
      const double expected = distances[i];
      const std::uint32_t triangle = triangles[i];
      const Nearest found =
          nearestTriangle(query.data(), p, std::numeric_limits<double>::infinity(), isa);
      ASSERT_EQ(found.distanceSquared, expected) << name << ", " << kernels::name(isa);
      ASSERT_EQ(found.triangle, triangle) << name << ", " << kernels::name(isa);
      // A limit just above the distance still finds it; one at it (strict) does not.
      const double above = std::nextafter(expected, std::numeric_limits<double>::infinity());
      EXPECT_EQ(nearestTriangle(query.data(), p, above, isa).triangle, triangle);
      if (expected > 0.0) {
        EXPECT_FALSE(nearestTriangle(query.data(), p, expected, isa).found());
      }
    }
  }
}

TEST(NearestDescent, EveryIsaGivesTheAnswerOfEveryTriangle) {
  Mesh far = primitives::granulate(3, {1, 0.4, 0.2}, 200);
  far.translate({1e6, -3e6, 2e5});
  expectEveryIsaLikeAllTriangles(primitives::icosphere(3), "icosphere");
  expectEveryIsaLikeAllTriangles(primitives::box({1, 2, 3}), "box (ties)");
  expectEveryIsaLikeAllTriangles(primitives::quad(2, 1), "quad");
  expectEveryIsaLikeAllTriangles(far, "granulate at 1e6");
  expectEveryIsaLikeAllTriangles(primitives::icosphere(2, 1e-7, {3, 1, 2}), "tiny icosphere");
  expectEveryIsaLikeAllTriangles(
      io::load(std::filesystem::path(DELTA_DATA_DIR) / "meshes" / "fandisk.off"), "fandisk");
}

TEST(NearestDescent, ManyExactTiesWaitForTheExactKernel) {
  // Above the apex of a cone of 100 triangles the apex is every triangle's closest point, at
  // exactly the same distance: far more triangles than the descent holds back at once wait for
  // the exact kernel (it settles them in rounds), and the tie goes to the smallest id. Near the
  // centre of a sphere, many are within a percent of the nearest.
  std::vector<Vec3> vertices = {{0, 0, 0}};
  std::vector<TriangleIndices> triangles;
  constexpr std::uint32_t kRing = 100;
  for (std::uint32_t i = 0; i < kRing; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / kRing;
    vertices.push_back({std::cos(angle), std::sin(angle), -0.3});
    triangles.push_back({0, 1 + (i + 37) % kRing, 1 + (i + 38) % kRing});  // ids not in ring order
  }
  expectEveryIsaLikeAllTriangles(Mesh(std::move(vertices), std::move(triangles)), "cone apex",
                                 {{0, 0, 1}, {0, 0, 0.5}, {0, 0, 1e-9}});
  expectEveryIsaLikeAllTriangles(primitives::icosphere(3), "icosphere centre",
                                 {{0, 0, 0}, {1e-9, -2e-9, 3e-9}, {1e-3, 0, 0}, {0, 0.05, 0.01}});
}

/// Clusters of points (within `spread` of a centre near the surface) and limits: for each, the
/// leaves gathered from the cluster's box (as point_distance.cpp's gatherNear) give every point
/// the descent's answer, bit for bit, on every ISA; a limit so large that too many leaves are
/// near gathers none.
void expectClustersLikeTheDescent(const Mesh& mesh, const char* name, double spread) {
  const QueryMesh query(mesh);
  const QueryMeshData& data = query.data();
  std::mt19937_64 random(29);
  const double diagonal = mesh.bounds().diagonal();
  LeafCandidates near;
  std::size_t gathered = 0, refused = 0;
  for (std::size_t cluster = 0; cluster < 40; ++cluster) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    const Vec3 centre =
        t.centroid() + normalized(t.areaVector()) * (spread * (test::unit(random) - 0.5));
    std::vector<Vec3> points;
    Aabb box;
    for (std::size_t i = 0; i < 9; ++i) {
      const Vec3 p = i == 0 ? t.a
                            : centre + Vec3{test::unit(random) - 0.5, test::unit(random) - 0.5,
                                            test::unit(random) - 0.5} *
                                           spread;
      points.push_back(p);
      box.extend(p);
    }
    for (const double epsilon :
         {1e-3 * diagonal, 0.02 * diagonal, 0.2 * diagonal, 3.0 * diagonal}) {
      const double radius = (epsilon + 0.5 * box.diagonal()) * (1.0 + 0x1p-20);
      for (kernels::Isa isa : kernels::supportedIsas()) {
        if (!near.collect(data, box.center(), radius * radius, isa)) {
          ++refused;
          EXPECT_EQ(near.size(), 0u);
          continue;
        }
        ++gathered;
        for (const Vec3& p : points)
          for (const double limit : {epsilon * epsilon, 0.25 * epsilon * epsilon}) {
            const Nearest expected = nearestTriangle(data, p, limit, isa);
            const Nearest found = nearestAmong(data, p, limit, near, isa);
            ASSERT_EQ(found.found(), expected.found()) << name << ", " << kernels::name(isa);
            ASSERT_EQ(found.distanceSquared, expected.distanceSquared) << name;
            ASSERT_EQ(found.triangle, expected.triangle) << name;
            ASSERT_EQ(found.closest.closest, expected.closest.closest) << name;
          }
      }
    }
  }
  if (data.levels.size() == 1) {
    EXPECT_EQ(gathered, 0u) << name;  // one leaf: searched from the root, which is the leaf
  } else {
    EXPECT_GT(gathered, 0u) << name;
  }
  if (mesh.triangleCount() > kFanout * kMostCandidates) {
    EXPECT_GT(refused, 0u) << name;  // every leaf is near at the largest limit
  }
}

TEST(NearestDescent, LeavesGatheredForAClusterGiveTheDescentsAnswers) {
  Mesh far = primitives::granulate(3, {1, 0.4, 0.2}, 400);
  far.translate({1e6, -3e6, 2e5});
  expectClustersLikeTheDescent(primitives::box({1, 2, 3}), "box (ties)", 0.05);
  expectClustersLikeTheDescent(primitives::quad(2, 1), "quad (one leaf)", 0.05);
  expectClustersLikeTheDescent(primitives::icosphere(4), "icosphere", 0.05);
  expectClustersLikeTheDescent(far, "granulate at 1e6", 0.02);
  expectClustersLikeTheDescent(
      io::load(std::filesystem::path(DELTA_DATA_DIR) / "meshes" / "armadillo.off"), "armadillo",
      2.0);
}

}  // namespace
}  // namespace delta::detail
