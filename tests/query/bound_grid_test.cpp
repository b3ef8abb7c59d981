#include "query/detail/bound_grid.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "delta/core/format.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/primitives.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/probe_points.h"

namespace delta::detail {
namespace {

using test::unit;

const std::filesystem::path kMeshes = std::filesystem::path(DELTA_DATA_DIR) / "meshes";

/// The reference: the smallest squared distance the kernel computes over all triangles.
double bruteForceSquared(const TriangleSoA& triangles, const Vec3& point) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < triangles.size(); ++t)
    best = std::min(best,
                    kernels::closestPointOnTriangle(point, triangles.triangle(t)).distanceSquared);
  return best;
}

Aabb boundsOf(const TriangleSoA& triangles) {
  Aabb box;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    box.extend(triangles.triangle(t).bounds());
  return box;
}

TriangleSoA soaOf(const std::vector<Triangle>& triangles) {
  TriangleSoA soa;
  soa.assign(triangles);
  return soa;
}

/// `count` points uniform in the box grown by `growth` of its extent on every side (a flat axis
/// grown by `growth` of the diagonal), then the vertices and edge midpoints of every `every`th
/// triangle (six a triangle, in order from triangle 0).
std::vector<Vec3> probes(const TriangleSoA& triangles, std::size_t count, double growth,
                         std::uint64_t seed, std::size_t every = 1) {
  const Aabb box = boundsOf(triangles);
  Vec3 margin = box.extent() * growth;
  for (std::size_t axis = 0; axis < 3; ++axis)
    margin[axis] = std::max(margin[axis], growth * box.diagonal());
  const Vec3 lower = box.lower - margin, size = box.extent() + margin * 2.0;
  std::mt19937_64 random(seed);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < count; ++i)
    points.push_back(lower +
                     Vec3{size.x * unit(random), size.y * unit(random), size.z * unit(random)});
  for (std::size_t t = 0; t < triangles.size(); t += every) {
    const Triangle triangle = triangles.triangle(t);
    for (const Vec3& on : {triangle.a, triangle.b, triangle.c, (triangle.a + triangle.b) * 0.5,
                           (triangle.b + triangle.c) * 0.5, (triangle.c + triangle.a) * 0.5})
      points.push_back(on);
  }
  return points;
}

struct BoundCheck {
  std::size_t positive = 0;  ///< points with a bound above 0
  double tightest = 0.0;     ///< the largest bound / distance (not squared)
};

/// Every bound is at most the brute-force squared distance `exact[i]` of `points[i]`; says which
/// point fails, at full precision.
BoundCheck expectNeverAbove(const BoundGrid& grid, const std::vector<Vec3>& points,
                            const std::vector<double>& exact) {
  BoundCheck check;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double bound = grid.lowerBoundSquared(points[i]);
    EXPECT_LE(bound, exact[i]) << "point " << toString(points[i]) << ", cell side "
                               << toString(grid.cellSize());
    if (bound > 0.0) {
      ++check.positive;
      check.tightest = std::max(check.tightest, std::sqrt(bound / exact[i]));
    }
  }
  return check;
}

/// The brute-force squared distances of `points` (computed once for the grids they check).
std::vector<double> bruteForceSquared(const TriangleSoA& triangles,
                                      const std::vector<Vec3>& points) {
  std::vector<double> exact;
  for (const Vec3& point : points)
    exact.push_back(bruteForceSquared(triangles, point));
  return exact;
}

BoundCheck expectNeverAbove(const TriangleSoA& triangles, const BoundGrid& grid,
                            const std::vector<Vec3>& points) {
  return expectNeverAbove(grid, points, bruteForceSquared(triangles, points));
}

/// The grid at several resolutions (0.5 to 64 cells a triangle) is never above the distance, and
/// is not vacuous: a quarter of the points get a positive bound, some one within 10%. The points
/// on the surface of every fourth triangle in slow builds (each costs a loop over every triangle).
void expectSafeAndUseful(const TriangleSoA& triangles, std::size_t count, std::uint64_t seed) {
  const Aabb box = boundsOf(triangles);
  const std::vector<Vec3> points = probes(triangles, count, 0.2, seed, test::kSlowBuild ? 4 : 1);
  const std::vector<double> exact = bruteForceSquared(triangles, points);
  for (const double cellsPerTriangle : {0.5, 4.0, 64.0}) {
    SCOPED_TRACE("cells per triangle " + toString(cellsPerTriangle));
    const BoundGrid grid(triangles, box, cellsPerTriangle);
    const BoundCheck check = expectNeverAbove(grid, points, exact);
    EXPECT_GT(check.positive, count / 4);
    EXPECT_GT(check.tightest, 0.9);
  }
}

TEST(BoundGrid, EmptyIsZeroEverywhere) {
  const BoundGrid none;
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.lowerBoundSquared({1e300, -3.0, 0.5}), 0.0);
  EXPECT_EQ(none.memoryBytes(), 0u);
  const BoundGrid noTriangles(TriangleSoA{}, Aabb{{0, 0, 0}, {1, 1, 1}});
  EXPECT_TRUE(noTriangles.empty());
  EXPECT_EQ(noTriangles.lowerBoundSquared({5.0, 5.0, 5.0}), 0.0);
}

TEST(BoundGrid, NeverAboveTheDistanceOnPrimitives) {
  for (const Mesh& mesh : {primitives::icosphere(3), primitives::box({2.0, 1.0, 0.5}),
                           primitives::granulate(7, {1.0, 0.6, 0.3}, 80)}) {
    SCOPED_TRACE(std::to_string(mesh.triangleCount()) + " triangles");
    expectSafeAndUseful(flatten(mesh), test::scaledCount(2000), 11);
  }
}

TEST(BoundGrid, NeverAboveTheDistanceForASingleTriangle) {
  expectSafeAndUseful(soaOf({{{0.1, 0.2, 0.3}, {1.3, 0.4, -0.2}, {0.5, 1.1, 0.9}}}), 2000, 12);
}

TEST(BoundGrid, NeverAboveTheDistanceForAPlanarQuad) {
  // A flat box: one cell along z; the bound above and below is the height, by Pythagoras.
  const TriangleSoA triangles = flatten(primitives::quad(2.0, 1.0, {0.5, 0.5, 3.0}));
  expectSafeAndUseful(triangles, 2000, 13);
  const BoundGrid grid(triangles, boundsOf(triangles));
  EXPECT_EQ(grid.dims()[2], 1u);
  EXPECT_NEAR(grid.lowerBoundSquared({0.5, 0.5, 5.0}), 4.0, 1e-6);
}

TEST(BoundGrid, NeverAboveTheDistanceForFansOfThinTriangles) {
  // The rows of cells a triangle marks come from its extent within each row (clipped), not from
  // its box: a fan's thin triangles from a disc's centre to its rim, flat and tilted, and a
  // cone's, whose boxes hold many cells the triangles miss.
  for (const double tilt : {0.0, 0.3}) {
    for (const double height : {0.0, 0.7}) {
      std::vector<Triangle> fan;
      const std::size_t spokes = 400;
      for (std::size_t k = 0; k < spokes; ++k) {
        const double a0 = 2.0 * std::numbers::pi * static_cast<double>(k) / spokes;
        const double a1 = 2.0 * std::numbers::pi * static_cast<double>(k + 1) / spokes;
        const auto rim = [tilt](double angle) {
          return Vec3{std::cos(angle), std::sin(angle), tilt * std::cos(angle)};
        };
        fan.push_back({{0.0, 0.0, height}, rim(a0), rim(a1)});
      }
      SCOPED_TRACE("tilt " + toString(tilt) + ", height " + toString(height));
      expectSafeAndUseful(soaOf(fan), 2000, 14);
    }
  }
}

TEST(BoundGrid, AFanOfManySliversIsBuiltInBoundedWork) {
  // Each of a fan's slivers crosses a row of cells from the centre to the rim: at the cells asked
  // (2 a triangle), 16,384 slivers crossed 90 rows each, and 262,144 slivers took 2.4 s to mark.
  // The grid coarsens until its rows come to at most 64 a triangle, and stays a safe bound.
  std::vector<Triangle> fan;
  const std::size_t spokes = 16384;
  for (std::size_t k = 0; k < spokes; ++k) {
    const double a0 = 2.0 * std::numbers::pi * static_cast<double>(k) / spokes;
    const double a1 = 2.0 * std::numbers::pi * static_cast<double>(k + 1) / spokes;
    fan.push_back(
        {{0.0, 0.0, 0.0}, {std::cos(a0), std::sin(a0), 0.0}, {std::cos(a1), std::sin(a1), 0.0}});
  }
  const TriangleSoA triangles = soaOf(fan);
  const BoundGrid grid(triangles, boundsOf(triangles));
  const double rowsPerSliver = static_cast<double>(grid.dims()[1]) * 0.5;  // centre to rim
  EXPECT_LE(rowsPerSliver, 64.0);
  EXPECT_GE(rowsPerSliver, 16.0);  // no coarser than the work allows
  const std::vector<Vec3> points = probes(triangles, 300, 0.2, 15, 512);
  const BoundCheck check = expectNeverAbove(triangles, grid, points);
  EXPECT_GT(check.positive, 300u / 4);
  // A regular mesh's grid is the one asked for (CellCountAndMemoryAsAsked).
}

TEST(BoundGrid, NeverAboveTheDistanceForDegenerateTriangles) {
  // Zero area: a point, repeated vertices (a segment), collinear vertices, a needle; plus one
  // proper triangle far from them, so that the grid has room between.
  const std::vector<Triangle> triangles = {
      {{0.2, 0.2, 0.2}, {0.2, 0.2, 0.2}, {0.2, 0.2, 0.2}},
      {{0.0, 0.0, 0.0}, {1.0, 1.0, 0.0}, {1.0, 1.0, 0.0}},
      {{0.0, 1.0, 1.0}, {0.5, 0.5, 1.0}, {1.0, 0.0, 1.0}},
      {{0.0, 0.0, 2.0}, {2.0, 2.0, 2.0 + 1e-12}, {1.0, 1.0, 2.0}},
      {{3.0, 3.0, 3.0}, {4.0, 3.0, 3.0}, {3.0, 4.0, 3.5}}};
  expectSafeAndUseful(soaOf(triangles), 2000, 14);
  // All of them at one point: a box of one point, one cell of side 0.
  const Vec3 p{0.25, -1.5, 7.0};
  const TriangleSoA point = soaOf({{p, p, p}, {p, p, p}});
  const BoundGrid grid(point, boundsOf(point));
  EXPECT_EQ(grid.cellCount(), 1u);
  std::mt19937_64 random(15);
  std::vector<Vec3> around = {p};
  for (int i = 0; i < 500; ++i)
    around.push_back(p + Vec3{unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5});
  const BoundCheck check = expectNeverAbove(point, grid, around);
  EXPECT_EQ(check.positive, 500u);
  EXPECT_GT(check.tightest, 0.999);
}

TEST(BoundGrid, NeverAboveTheDistanceFarFromTheOrigin) {
  expectSafeAndUseful(flatten(primitives::icosphere(2, 1.0, {1e6, -2e6, 1e6})), 2000, 16);
  const TriangleSoA small = flatten(primitives::granulate(3, {0.01, 0.02, 0.005}, 60));
  expectSafeAndUseful(small.transformed(RigidTransform::translationBy({1e6, 1e6, -1e6})), 2000, 17);
}

TEST(BoundGrid, NeverAboveTheDistanceForATinyMesh) {
  expectSafeAndUseful(flatten(primitives::icosphere(2, 1e-6, {1.0, 2.0, 3.0})), 2000, 18);
  expectSafeAndUseful(flatten(primitives::box({1e-6, 2e-6, 5e-7})), 2000, 19);
}

TEST(BoundGrid, NeverAboveTheDistanceJustOffTheSurface) {
  // Points at 0 to 10% of the diagonal off vertices, edge midpoints and centroids, along the
  // face normal both ways, on a fine grid: where the rounding margins matter.
  for (const Mesh& mesh : {primitives::box({2.0, 1.0, 0.5}, {3.0, -1.0, 2.0}),
                           primitives::icosphere(2, 1.0, {1e3, 0.0, 0.0}),
                           primitives::quad(1.0, 1.0, {0.25, 0.5, -2.0})}) {
    const TriangleSoA triangles = flatten(mesh);
    const double diagonal = mesh.bounds().diagonal();
    std::vector<Vec3> points;
    // Every triangle in an optimised build, every fourth under the sanitizers.
    for (std::size_t t = 0; t < triangles.size(); t += test::kSlowBuild ? 4 : 1) {
      const Triangle triangle = triangles.triangle(t);
      const Vec3 normal = normalized(triangle.areaVector());
      for (const Vec3& on : {triangle.a, (triangle.a + triangle.b) * 0.5, triangle.centroid()})
        for (const double offset : {0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 1e-2, 1e-1})
          for (const double side : {-1.0, 1.0})
            points.push_back(on + normal * (side * offset * diagonal));
    }
    const std::vector<double> exact = bruteForceSquared(triangles, points);
    for (const double cellsPerTriangle : {2.0, 64.0}) {
      const BoundGrid grid(triangles, mesh.bounds(), cellsPerTriangle);
      const BoundCheck check = expectNeverAbove(grid, points, exact);
      EXPECT_GT(check.positive, 0u);
    }
  }
}

TEST(BoundGrid, NanRejectsNothing) {
  const TriangleSoA triangles = flatten(primitives::icosphere(2));
  const BoundGrid grid(triangles, boundsOf(triangles));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Vec3& point : {Vec3{nan, 0.0, 0.0}, Vec3{5.0, nan, 0.0}, Vec3{0.0, 0.0, nan}})
    EXPECT_FALSE(grid.lowerBoundSquared(point) > 0.0) << toString(point);
}

TEST(BoundGrid, TheSameOnOneThreadAsOnMany) {
  const Mesh mesh = io::load(kMeshes / "bunny00.off");
  const TriangleSoA triangles = flatten(mesh);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const BoundGrid serial(triangles, mesh.bounds());
  omp_set_num_threads(std::max(threads, 4));
  const BoundGrid parallel(triangles, mesh.bounds());
  omp_set_num_threads(threads);
  ASSERT_EQ(serial.dims(), parallel.dims());
  for (const Vec3& point : probes(triangles, 20000, 0.1, 22))
    ASSERT_EQ(serial.lowerBoundSquared(point), parallel.lowerBoundSquared(point))
        << toString(point);
}

TEST(BoundGrid, NeverAboveTheDistanceOnArmadillo) {
  // Brute force costs O(triangles) a point: it checks 100 points; the point query (whose
  // distance is the brute-force one, tested in point_distance_test.cpp) checks 20000 random
  // points and the vertices and edge midpoints of every 10th triangle.
  const Mesh mesh = io::load(kMeshes / "armadillo.off");
  const QueryMesh prepared(mesh);
  const TriangleSoA& triangles = prepared.triangles();
  std::vector<Vec3> points = probes(triangles, 20000, 0.2, 20);
  ASSERT_EQ(points.size(), 20000 + 6 * triangles.size());  // read by triangle below
  std::vector<Vec3> sample(points.begin(), points.begin() + 20000);
  for (std::size_t t = 0; t < triangles.size(); t += 10)
    for (std::size_t k = 0; k < 6; ++k)
      sample.push_back(points[20000 + 6 * t + k]);
  const BoundGrid grid(triangles, mesh.bounds());
  const std::vector<contactdetection::PointDistance> exact =
      contactdetection::distances(prepared, sample);
  std::size_t positive = 0;
  for (std::size_t i = 0; i < sample.size(); ++i) {
    const double bound = grid.lowerBoundSquared(sample[i]);
    // The query's distance squared again: off by an ulp or two, far within the bound's slack.
    EXPECT_LE(bound, exact[i].distance * exact[i].distance) << "point " << toString(sample[i]);
    if (bound > 0.0) ++positive;
  }
  EXPECT_GT(positive, 10000u);
  const BoundCheck check =
      expectNeverAbove(triangles, grid, std::vector<Vec3>(sample.begin(), sample.begin() + 100));
  EXPECT_GT(check.positive, 50u);
  EXPECT_GT(check.tightest, 0.9);
}

TEST(BoundGrid, RejectsMostFarPointsOnArmadillo) {
  // Points uniform in the box grown by 10% a side, ε = 1% of the diagonal: the grid must reject
  // (bound > ε²) most of those farther than ε, and never one closer (the query finds it).
  const Mesh mesh = io::load(kMeshes / "armadillo.off");
  const QueryMesh prepared(mesh);
  const Aabb box = mesh.bounds();
  const double epsilon = 0.01 * box.diagonal();
  std::mt19937_64 random(21);
  const Vec3 lower = box.lower - box.extent() * 0.1, size = box.extent() * 1.2;
  std::vector<Vec3> points;
  for (int i = 0; i < 100000; ++i)
    points.push_back(lower +
                     Vec3{size.x * unit(random), size.y * unit(random), size.z * unit(random)});
  const std::vector<contactdetection::PointDistance> near =
      contactdetection::distances(prepared, points, {.epsilon = epsilon});
  const BoundGrid grid(prepared.triangles(), box);
  std::size_t far = 0, rejected = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const bool reject = grid.lowerBoundSquared(points[i]) > epsilon * epsilon;
    if (near[i].found()) {
      EXPECT_FALSE(reject) << "point " << toString(points[i]) << " at "
                           << toString(near[i].distance);
    } else {
      ++far;
      if (reject) ++rejected;
    }
  }
  const double fraction = static_cast<double>(rejected) / static_cast<double>(far);
  std::printf("armadillo, eps = 1%% of the diagonal: %zu of %zu far points rejected (%.1f%%)\n",
              rejected, far, 100.0 * fraction);
  EXPECT_GT(far, points.size() / 2);
  EXPECT_GE(fraction, 0.8);
}

TEST(BoundGrid, CellCountAndMemoryAsAsked) {
  const Mesh mesh = io::load(kMeshes / "armadillo.off");
  const TriangleSoA triangles = flatten(mesh);
  for (const double cellsPerTriangle : {1.0, 4.0, 8.0}) {
    const BoundGrid grid(triangles, mesh.bounds(), cellsPerTriangle);
    const double asked = cellsPerTriangle * static_cast<double>(triangles.size());
    EXPECT_LE(static_cast<double>(grid.cellCount()), asked);
    EXPECT_GE(static_cast<double>(grid.cellCount()), 0.8 * asked);
    EXPECT_EQ(grid.cellCount(), grid.dims()[0] * grid.dims()[1] * grid.dims()[2]);
    EXPECT_LE(grid.memoryBytes(), grid.cellCount() + 64);  // one byte a cell
    const Vec3 extent = mesh.bounds().extent();
    for (std::size_t axis = 0; axis < 3; ++axis) {
      // Cubic cells that cover the box, with less than one cell to spare.
      EXPECT_GE(static_cast<double>(grid.dims()[axis]) * grid.cellSize(),
                extent[axis] * (1.0 - 1e-12));
      EXPECT_LT(static_cast<double>(grid.dims()[axis] - 1) * grid.cellSize(), extent[axis]);
    }
  }
  const BoundGrid capped(triangles, mesh.bounds(), 8.0, 1000);
  EXPECT_LE(capped.cellCount(), 1000u);
  EXPECT_GE(capped.cellCount(), 700u);
  // A long thin box: cells stay cubic, one across the thin axes.
  const TriangleSoA needle = flatten(primitives::box({100.0, 0.01, 0.01}));
  const BoundGrid thin(needle, boundsOf(needle), 10.0);
  EXPECT_EQ(thin.dims()[1], 1u);
  EXPECT_EQ(thin.dims()[2], 1u);
  EXPECT_LE(thin.cellCount(), 10u * needle.size());
  EXPECT_GE(thin.cellCount(), 8u * needle.size());
}

}  // namespace
}  // namespace delta::detail
