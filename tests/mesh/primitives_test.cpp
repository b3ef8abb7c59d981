#include "delta/mesh/primitives.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/memory.h"
#include "delta/mesh/detail/convex_hull.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/topology.h"

namespace delta {
namespace {

constexpr double kPi = std::numbers::pi;

void expectClosedAndOutward(const Mesh& mesh) {
  const Topology topology = analyzeTopology(mesh);
  EXPECT_TRUE(topology.closed);
  EXPECT_TRUE(topology.consistentlyOriented);
  EXPECT_GT(signedVolume(mesh), 0.0);
}

/// No two vertices share a position (the mesh is joined), and every vertex is used.
void expectJoined(const Mesh& mesh) {
  std::vector<Vec3> sorted(mesh.vertices().begin(), mesh.vertices().end());
  const auto less = [](const Vec3& a, const Vec3& b) {
    return a.x != b.x ? a.x < b.x : (a.y != b.y ? a.y < b.y : a.z < b.z);
  };
  std::sort(sorted.begin(), sorted.end(), less);
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
  std::vector<bool> used(mesh.vertexCount(), false);
  for (const TriangleIndices& t : mesh.triangles())
    for (std::uint32_t index : t)
      used[index] = true;
  EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
}

/// Every vertex is on or behind every face's plane, to a tolerance relative to the mesh size.
void expectConvex(const Mesh& mesh) {
  const double tolerance = 1e-12 * mesh.bounds().diagonal();
  double worst = -std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const Triangle face = mesh.triangle(t);
    const Vec3 normal = normalized(face.areaVector());
    if (normal == Vec3{}) continue;  // a zero-area face has no plane to test against
    for (const Vec3& v : mesh.vertices())
      worst = std::max(worst, dot(v - face.a, normal));
  }
  EXPECT_LE(worst, tolerance);
}

std::string messageOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

void expectErrorNaming(const std::function<void()>& call, const std::string& parameter,
                       const std::string& value) {
  const std::string message = messageOf(call);
  EXPECT_NE(message.find(parameter), std::string::npos) << message;
  EXPECT_NE(message.find(value), std::string::npos) << message;
}

TEST(Primitives, IcosphereCountsAndVolumeBounds) {
  const double r = 2.0;
  const Vec3 center{1, -1, 0.5};
  for (int level = 0; level <= 5; ++level) {
    SCOPED_TRACE(level);
    const Mesh sphere = primitives::icosphere(level, r, center);
    const std::size_t faces = 20u << (2 * level);
    EXPECT_EQ(sphere.triangleCount(), faces);
    EXPECT_EQ(sphere.vertexCount(), faces / 2 + 2);
    expectClosedAndOutward(sphere);
    expectJoined(sphere);
    double inscribed = r;
    for (std::size_t t = 0; t < sphere.triangleCount(); ++t) {
      const Triangle face = sphere.triangle(t);
      inscribed = std::min(inscribed, dot(face.a - center, normalized(face.areaVector())));
    }
    for (const Vec3& v : sphere.vertices())
      EXPECT_NEAR(distance(v, center), r, 1e-14 * r);
    // Inside the circumscribed ball, around the inscribed one.
    const double volume = signedVolume(sphere);
    EXPECT_LE(volume, 4.0 / 3.0 * kPi * r * r * r);
    EXPECT_GE(volume, 4.0 / 3.0 * kPi * inscribed * inscribed * inscribed);
  }
}

TEST(Primitives, IcosphereFinestLevel) {
  const Mesh sphere = primitives::icosphere(8);
  EXPECT_EQ(sphere.triangleCount(), 20u * 65536u);
  EXPECT_EQ(sphere.vertexCount(), 10u * 65536u + 2u);
  const Topology topology = analyzeTopology(sphere);
  EXPECT_TRUE(topology.closed);
  EXPECT_TRUE(topology.consistentlyOriented);
}

TEST(Primitives, BoxIsExact) {
  const Vec3 size{1, 2, 3};
  const Vec3 center{10, 20, 30};
  const Mesh box = primitives::box(size, center);
  EXPECT_EQ(box.triangleCount(), 12u);
  EXPECT_EQ(box.vertexCount(), 8u);
  expectClosedAndOutward(box);
  expectJoined(box);
  expectConvex(box);
  EXPECT_EQ(box.bounds().lower, (Vec3{9.5, 19, 28.5}));
  EXPECT_EQ(box.bounds().upper, (Vec3{10.5, 21, 31.5}));
  EXPECT_NEAR(signedVolume(box), 6.0, 1e-12);
}

TEST(Primitives, CylinderIsAnExactPrism) {
  for (int n : {3, 4, 7, 32, 100}) {
    SCOPED_TRACE(n);
    const double r = 0.75;
    const double h = 2.5;
    const Mesh cylinder = primitives::cylinder(r, h, n, {1, 2, 3});
    EXPECT_EQ(cylinder.triangleCount(), 4u * n);
    EXPECT_EQ(cylinder.vertexCount(), 2u * n + 2);
    expectClosedAndOutward(cylinder);
    expectJoined(cylinder);
    expectConvex(cylinder);
    const double prism = 0.5 * n * r * r * std::sin(2 * kPi / n) * h;
    EXPECT_NEAR(signedVolume(cylinder), prism, 1e-14 * prism * n);
    EXPECT_NEAR(cylinder.bounds().lower.z, 3 - 0.5 * h, 1e-15);
    EXPECT_NEAR(cylinder.bounds().upper.z, 3 + 0.5 * h, 1e-15);
  }
}

TEST(Primitives, QuadFacesUpAndIsOpen) {
  const Mesh quad = primitives::quad(2, 3, {0, 0, 5});
  EXPECT_EQ(quad.triangleCount(), 2u);
  EXPECT_EQ(quad.vertexCount(), 4u);
  for (std::size_t t = 0; t < 2; ++t) {
    const Vec3 n = quad.triangle(t).areaVector();
    EXPECT_GT(n.z, 0.0);
    EXPECT_EQ(n.x, 0.0);
    EXPECT_EQ(n.y, 0.0);
  }
  EXPECT_EQ(quad.bounds().lower, (Vec3{-1, -1.5, 5}));
  EXPECT_EQ(quad.bounds().upper, (Vec3{1, 1.5, 5}));
  const Topology topology = analyzeTopology(quad);
  EXPECT_FALSE(topology.closed);
  EXPECT_EQ(topology.boundaryEdges, 4u);
  EXPECT_TRUE(topology.consistentlyOriented);
}

TEST(Primitives, DefaultGranulateHasEightyTriangles) {
  const Mesh granulate = primitives::granulate(12345);
  EXPECT_EQ(granulate.vertexCount(), 42u);
  EXPECT_EQ(granulate.triangleCount(), 80u);
  expectClosedAndOutward(granulate);
}

TEST(Primitives, GranulateIsAConvexHullInsideItsEllipsoid) {
  const Vec3 axes{2.0, 1.0, 0.5};
  const double ellipsoid = 4.0 / 3.0 * kPi * axes.x * axes.y * axes.z;
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    SCOPED_TRACE(seed);
    const Mesh granulate = primitives::granulate(seed, axes, 60);
    expectClosedAndOutward(granulate);
    expectJoined(granulate);
    expectConvex(granulate);
    // Euler for a closed triangulated sphere: F = 2V − 4.
    EXPECT_EQ(granulate.triangleCount(), 2 * granulate.vertexCount() - 4);
    for (const Vec3& v : granulate.vertices())
      EXPECT_NEAR(std::pow(v.x / axes.x, 2) + std::pow(v.y / axes.y, 2) + std::pow(v.z / axes.z, 2),
                  1.0, 1e-14);
    const double volume = signedVolume(granulate);
    EXPECT_LE(volume, ellipsoid);
    EXPECT_GE(volume, 0.5 * ellipsoid);
  }
}

TEST(Primitives, GranulateIsDeterministic) {
  const Mesh a = primitives::granulate(7, {1, 2, 3}, 100);
  const Mesh b = primitives::granulate(7, {1, 2, 3}, 100);
  ASSERT_EQ(a.vertexCount(), b.vertexCount());
  ASSERT_EQ(a.triangleCount(), b.triangleCount());
  EXPECT_TRUE(std::equal(a.vertices().begin(), a.vertices().end(), b.vertices().begin()));
  EXPECT_TRUE(std::equal(a.triangles().begin(), a.triangles().end(), b.triangles().begin()));
  const Mesh c = primitives::granulate(8, {1, 2, 3}, 100);
  EXPECT_FALSE(a.vertexCount() == c.vertexCount() &&
               std::equal(a.vertices().begin(), a.vertices().end(), c.vertices().begin()));
}

TEST(Primitives, GranulateSurvivesNearlyDegenerateInput) {
  // Few points, many close points, and flat or needle-like ellipsoids whose points are close to
  // coplanar or collinear.
  const Mesh tetra = primitives::granulate(3, {1, 1, 1}, 4);
  EXPECT_EQ(tetra.triangleCount(), 4u);
  expectClosedAndOutward(tetra);
  const std::vector<std::pair<Vec3, int>> cases = {{{1, 1, 1}, 3000},
                                                   {{1, 1, 1e-6}, 500},
                                                   {{1e-6, 1, 1e-6}, 500},
                                                   {{1e6, 1e6, 1e6}, 100},
                                                   {{1e-6, 1e-6, 1e-6}, 100}};
  for (const auto& [axes, points] : cases) {
    SCOPED_TRACE(points);
    const Mesh granulate = primitives::granulate(11, axes, points);
    const Topology topology = analyzeTopology(granulate);
    EXPECT_TRUE(topology.closed);
    EXPECT_TRUE(topology.consistentlyOriented);
    EXPECT_GT(signedVolume(granulate), 0.0);
    expectConvex(granulate);
  }
}

TEST(Primitives, ConvexHullOfDuplicateAndCoplanarPoints) {
  // A 5×5×5 grid of the unit cube, every point twice: faces full of coplanar points, edges of
  // collinear ones. The hull is the cube: its vertices are corners and its volume is 1.
  std::vector<Vec3> grid;
  for (int copy = 0; copy < 2; ++copy)
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; j <= 4; ++j)
        for (int k = 0; k <= 4; ++k)
          grid.push_back(Vec3{double(i), double(j), double(k)} * 0.25);
  const Mesh cube = detail::convexHull(grid);
  expectClosedAndOutward(cube);
  expectJoined(cube);
  expectConvex(cube);
  EXPECT_NEAR(signedVolume(cube), 1.0, 1e-14);
  for (const Vec3& v : cube.vertices()) {
    EXPECT_TRUE(v.x == 0 || v.x == 1) << v.x;
    EXPECT_TRUE(v.y == 0 || v.y == 1) << v.y;
    EXPECT_TRUE(v.z == 0 || v.z == 1) << v.z;
  }

  // The icosphere's vertices are all on their hull.
  const Mesh sphere = primitives::icosphere(3);
  const Mesh hull = detail::convexHull(sphere.vertices());
  EXPECT_EQ(hull.vertexCount(), sphere.vertexCount());
  EXPECT_EQ(hull.triangleCount(), sphere.triangleCount());
  EXPECT_NEAR(signedVolume(hull), signedVolume(sphere), 1e-12);
}

TEST(Primitives, ConvexHullRejectsInputWithoutAHull) {
  const std::vector<Vec3> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(detail::convexHull(three), Error);
  std::vector<Vec3> flat;
  for (int i = 0; i < 10; ++i)
    flat.push_back({std::cos(i * 0.6), std::sin(i * 0.6), 2.0});
  const std::string message = messageOf([&] { detail::convexHull(flat); });
  EXPECT_NE(message.find("qhull"), std::string::npos) << message;
  std::vector<Vec3> withNaN = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  withNaN[2].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(detail::convexHull(withNaN), Error);
}

TEST(Primitives, GranulatesFromManyThreadsMatchSerialOnes) {
  constexpr int kSeeds = 64;
  std::vector<Mesh> serial;
  for (int seed = 0; seed < kSeeds; ++seed)
    serial.push_back(primitives::granulate(seed, {1, 1.5, 0.7}, 30 + seed));
  constexpr int kThreads = 8;
  std::vector<std::vector<Mesh>> parallel(kThreads);
  std::vector<std::thread> threads;
  for (int thread = 0; thread < kThreads; ++thread)
    threads.emplace_back([thread, &parallel] {
      for (int i = 0; i < kSeeds; ++i) {
        const int seed = (i + 8 * thread) % kSeeds;  // threads work on different seeds at once
        parallel[thread].push_back(primitives::granulate(seed, {1, 1.5, 0.7}, 30 + seed));
      }
    });
  for (std::thread& t : threads)
    t.join();
  for (int thread = 0; thread < kThreads; ++thread)
    for (int i = 0; i < kSeeds; ++i) {
      const Mesh& expected = serial[(i + 8 * thread) % kSeeds];
      const Mesh& actual = parallel[thread][i];
      ASSERT_EQ(actual.vertexCount(), expected.vertexCount());
      ASSERT_EQ(actual.triangleCount(), expected.triangleCount());
      EXPECT_TRUE(std::equal(actual.vertices().begin(), actual.vertices().end(),
                             expected.vertices().begin()));
      EXPECT_TRUE(std::equal(actual.triangles().begin(), actual.triangles().end(),
                             expected.triangles().begin()));
    }
}

TEST(Primitives, InvalidParametersNameTheParameterAndValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  expectErrorNaming([] { primitives::icosphere(9); }, "subdivisions", "9");
  expectErrorNaming([] { primitives::icosphere(-1); }, "subdivisions", "-1");
  expectErrorNaming([] { primitives::icosphere(2, 0.0); }, "radius", "0");
  expectErrorNaming([&] { primitives::icosphere(2, nan); }, "radius", "nan");
  expectErrorNaming([&] { primitives::icosphere(2, 1.0, {inf, 0, 0}); }, "center", "inf");
  expectErrorNaming([] { primitives::box({1, -2, 1}); }, "size", "-2");
  expectErrorNaming([] { primitives::cylinder(-1.5); }, "radius", "-1.5");
  expectErrorNaming([&] { primitives::cylinder(1, inf); }, "height", "inf");
  expectErrorNaming([] { primitives::cylinder(1, 1, 2); }, "segments", "2");
  expectErrorNaming([] { primitives::quad(0, 1); }, "sizeX", "0");
  expectErrorNaming([] { primitives::quad(1, -3); }, "sizeY", "-3");
  expectErrorNaming([] { primitives::granulate(1, {1, 1, 1}, 3); }, "points", "3");
  expectErrorNaming([] { primitives::granulate(1, {1, 0, 1}); }, "semiAxes", "0");
}

TEST(Primitives, SizesBeyondTheirLimitsAreRefusedBeforeAllocating) {
  // 2·n + 2 vertices wrapped in 32 bits and overflowed the heap.
  expectErrorNaming([] { primitives::cylinder(1, 1, 2147483647); }, "segments 2147483647",
                    "above the limit 1073741823");
  expectErrorNaming([] { primitives::cylinder(1, 1, 2147483647); }, "would need about", "206 GB");
  // Within the index limit, refused by memory (where the machine has less than it needs).
  const double cylinderBytes =
      primitives::kMaxCylinderSegments * primitives::kCylinderBytesPerSegment;
  if (cylinderBytes > static_cast<double>(memoryLimitBytes()))
    expectErrorNaming([] { primitives::cylinder(1, 1, primitives::kMaxCylinderSegments); },
                      "segments 1073741823 would need about 103 GB", "memory limit");
  if (2147483647.0 * 512.0 > static_cast<double>(memoryLimitBytes()))
    expectErrorNaming(
        [] {
          primitives::granulate(1, {1, 1, 1}, 2147483647);
        },
        "points 2147483647 would need about", "memory limit");
  EXPECT_EQ(primitives::cylinder(1, 1, 100000).triangleCount(), 400000u);
}

}  // namespace
}  // namespace delta
