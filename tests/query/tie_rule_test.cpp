// The tie rule of the point queries (query/point_distance.h): among equally near triangles the
// smallest triangle id is named. Points exactly on a vertex or on an edge are at distance 0 from
// every triangle that has that vertex or edge; the kernel gives them exactly 0 (its exact
// boundary test, kernels/point_triangle.h), so the tie goes to the smallest id in the loop over
// all triangles, in the tree's descent under every ISA, and in the public query.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <random>
#include <sstream>
#include <vector>

#include "delta/io/mesh_io.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

const std::filesystem::path kMeshes = std::filesystem::path(DELTA_DATA_DIR) / "meshes";

/// A point on a vertex or an edge, and the triangles that have it.
struct SharedPoint {
  Vec3 point;
  std::vector<std::uint32_t> incident;
};

/// `count` vertices of `mesh` (spread over its vertex list), each with the triangles using it.
std::vector<SharedPoint> vertexPoints(const Mesh& mesh, std::size_t count) {
  std::vector<std::vector<std::uint32_t>> using_(mesh.vertexCount());
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t)
    for (std::uint32_t v : mesh.triangles()[t])
      if (using_[v].empty() || using_[v].back() != t) using_[v].push_back(t);
  std::vector<SharedPoint> points;
  const std::size_t step = std::max<std::size_t>(1, mesh.vertexCount() / count);
  for (std::size_t v = 0; v < mesh.vertexCount() && points.size() < count; v += step)
    if (using_[v].size() >= 2) points.push_back({mesh.vertices()[v], using_[v]});
  return points;
}

/// Midpoints of edges shared by two triangles, where the midpoint is exact (a + b and its half
/// round nothing, so the point lies exactly on the edge), up to `count` of them.
std::vector<SharedPoint> edgePoints(const Mesh& mesh, std::size_t count) {
  std::vector<SharedPoint> points;
  for (std::uint32_t t = 0; t < mesh.triangleCount() && points.size() < count; t += 7) {
    const TriangleIndices& corners = mesh.triangles()[t];
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t from = corners[e], to = corners[(e + 1) % 3];
      const Vec3 a = mesh.vertices()[from], b = mesh.vertices()[to];
      const Vec3 middle = (a + b) * 0.5;
      bool exact = true;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double sum = a[axis] + b[axis];
        exact = exact && sum - a[axis] == b[axis] && sum - b[axis] == a[axis] &&
                middle[axis] * 2.0 == sum;
      }
      if (!exact || middle == a || middle == b) continue;
      // Every triangle with both ends (the edge's two triangles on a manifold mesh).
      std::vector<std::uint32_t> incident;
      for (std::uint32_t u = 0; u < mesh.triangleCount(); ++u) {
        int ends = 0;
        for (std::uint32_t v : mesh.triangles()[u])
          ends += v == from || v == to;
        if (ends >= 2) incident.push_back(u);
      }
      if (incident.size() >= 2) points.push_back({middle, incident});
      break;
    }
  }
  return points;
}

/// The loop over all triangles: the smallest (distance², id).
std::uint32_t byAllTriangles(const Mesh& mesh, const Vec3& point, double& distanceSquared) {
  std::uint32_t best = kNoTriangle;
  distanceSquared = std::numeric_limits<double>::infinity();
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
    const double d = kernels::closestPointOnTriangle(point, mesh.triangle(t)).distanceSquared;
    if (d < distanceSquared) distanceSquared = d, best = t;
  }
  return best;
}

void expectSmallestIdNamed(const Mesh& mesh, const std::vector<SharedPoint>& points,
                           const char* name) {
  ASSERT_GE(points.size(), 8u) << name;
  const QueryMesh query(mesh);
  std::vector<Vec3> plain;
  for (const SharedPoint& shared : points)
    plain.push_back(shared.point);
  const std::vector<PointDistance> found = distances(query, plain);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::uint32_t expected =
        *std::min_element(points[i].incident.begin(), points[i].incident.end());
    double squared = 0.0;
    const std::uint32_t loop = byAllTriangles(mesh, points[i].point, squared);
    EXPECT_EQ(squared, 0.0) << name << ", point " << i;
    EXPECT_EQ(loop, expected) << name << ", point " << i << ": the loop over all triangles";
    EXPECT_EQ(found[i].distance, 0.0) << name << ", point " << i;
    EXPECT_EQ(found[i].closest, points[i].point) << name << ", point " << i;
    wrong += found[i].triangle != expected;
    if (found[i].triangle != expected) {  // what each incident triangle's kernel said
      std::ostringstream said;
      said.precision(17);
      for (std::uint32_t t : points[i].incident) {
        const auto r = kernels::closestPointOnTriangle(points[i].point, mesh.triangle(t));
        said << " triangle " << t << ": d² " << r.distanceSquared << ", feature "
             << static_cast<int>(r.feature) << ";";
      }
      ADD_FAILURE() << name << ", point " << i << " named triangle " << found[i].triangle
                    << ", not " << expected << ";" << said.str();
    }
    for (kernels::Isa isa : kernels::supportedIsas()) {
      const detail::Nearest nearest = detail::nearestTriangle(
          query.data(), points[i].point, std::numeric_limits<double>::infinity(), isa);
      EXPECT_EQ(nearest.triangle, expected)
          << name << ", point " << i << ", " << kernels::name(isa);
      EXPECT_EQ(nearest.distanceSquared, 0.0) << name << ", point " << i;
    }
    // Within ε, and with the single-point overload: the same.
    EXPECT_EQ(distance(query, points[i].point, {.epsilon = 1e-3}).triangle, expected);
  }
  EXPECT_EQ(wrong, 0u) << name << ": of " << points.size() << " points, " << wrong
                       << " name another triangle than the smallest id";
}

/// Points a real-mesh test checks (each against all 52,000 triangles): fewer under the
/// sanitizers, where 300 took 20 s.
constexpr std::size_t kRealMeshPoints = test::kSlowBuild ? 100 : 300;

TEST(TieRule, ArmadilloVerticesNameTheSmallestIncidentId) {
  const Mesh mesh = io::load(kMeshes / "armadillo.off");
  expectSmallestIdNamed(mesh, vertexPoints(mesh, kRealMeshPoints), "armadillo vertices");
}

TEST(TieRule, ArmadilloEdgesNameTheSmallestIncidentId) {
  const Mesh mesh = io::load(kMeshes / "armadillo.off");
  expectSmallestIdNamed(mesh, edgePoints(mesh, kRealMeshPoints), "armadillo edges");
}

TEST(TieRule, SmallMeshVerticesAndEdges) {
  // An icosphere turned and moved off the axes (no coordinate is a round number), so that the
  // projections of its vertices onto incident faces round differently.
  Mesh mesh = primitives::icosphere(2, 1.3);
  mesh.rotate({1, 2, 3}, 0.7).translate({0.1, -2.3, 5.7});
  expectSmallestIdNamed(mesh, vertexPoints(mesh, 200), "icosphere vertices");
  const std::vector<SharedPoint> edges = edgePoints(mesh, 200);
  if (edges.size() >= 10) expectSmallestIdNamed(mesh, edges, "icosphere edges");
  // A mesh with binary-exact coordinates has exact midpoints on every edge.
  const Mesh box = primitives::box({2, 4, 8}, {0.5, 0.25, -1});
  expectSmallestIdNamed(box, vertexPoints(box, 8), "box vertices");
}

TEST(TieRule, KernelGivesZeroOnVerticesAndEdges) {
  // Coordinates whose projections round: a plain n·r of b or c is not 0.
  const Triangle t{{0.1, 0.2, 0.3}, {1.7, -0.3, 0.9}, {0.4, 1.1, -0.2}};
  for (const Vec3& vertex : {t.a, t.b, t.c}) {
    const kernels::PointTriangleResult r = kernels::closestPointOnTriangle(vertex, t);
    EXPECT_EQ(r.distanceSquared, 0.0);
    EXPECT_EQ(r.closest, vertex);
  }
  // An exact midpoint of an edge (binary coordinates), in a triangle far from the axes.
  const Triangle binary{{0.5, 0.25, 3.0}, {1.75, -0.5, 2.5}, {0.125, 1.5, -0.75}};
  const Vec3 middle = (binary.b + binary.c) * 0.5;
  EXPECT_EQ(kernels::closestPointOnTriangle(middle, binary).distanceSquared, 0.0);
  EXPECT_EQ(kernels::closestPointOnTriangle(middle, binary).closest, middle);
}

TEST(TieRule, PointsVeryFarAwayNameTheSmallestIdOnEveryIsa) {
  // A flat 40 × 40 grid at the origin and moved by 1e9, points about 1e15 away: many triangles
  // round to one squared distance, and a leaf box's distance came out an ulp above it with fused
  // multiply–adds (AVX2, AVX-512), far beyond what the boxes' slack covers, so those ISAs lost
  // the smallest id. Every ISA's descent names the loop's triangle.
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  constexpr std::uint32_t n = 40;
  for (std::uint32_t j = 0; j <= n; ++j)
    for (std::uint32_t i = 0; i <= n; ++i)
      vertices.push_back({static_cast<double>(i), static_cast<double>(j), 0.0});
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  std::mt19937_64 random(41);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const double offset : {0.0, 1e9}) {
    Mesh mesh(vertices, triangles);
    mesh.translate({offset, 0.75 * offset, -0.5 * offset});
    const QueryMesh query(mesh);
    std::vector<Vec3> points = {{-1e15, 3, 7}};
    for (int k = 0; k < 60; ++k)
      points.push_back(Vec3{unit(random), unit(random), unit(random)} * 1e15);
    for (const Vec3& p : points) {
      double best = std::numeric_limits<double>::infinity();
      std::uint32_t expected = 0;
      for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
        const double squared = kernels::closestPointOnTriangle(p, mesh.triangle(k)).distanceSquared;
        if (squared < best) best = squared, expected = static_cast<std::uint32_t>(k);
      }
      for (const kernels::Isa isa : kernels::supportedIsas()) {
        const detail::Nearest found =
            detail::nearestTriangle(query.data(), p, std::numeric_limits<double>::infinity(), isa);
        ASSERT_EQ(found.triangle, expected) << kernels::name(isa) << ", offset " << offset;
        ASSERT_EQ(found.distanceSquared, best) << kernels::name(isa);
      }
      EXPECT_EQ(distance(query, p).triangle, expected);
    }
  }
}

}  // namespace
}  // namespace delta::contactdetection
