#include "delta/query/winding_number.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "delta/mesh/primitives.h"

namespace delta {
namespace {

TEST(WindingNumber, OneInsideZeroOutsideAClosedMesh) {
  const TriangleSoA box = flatten(primitives::box({2, 2, 2}));
  EXPECT_NEAR(windingNumber(box, {0, 0, 0}), 1.0, 1e-12);
  EXPECT_NEAR(windingNumber(box, {0.999, -0.5, 0.3}), 1.0, 1e-9);
  EXPECT_NEAR(windingNumber(box, {1.001, -0.5, 0.3}), 0.0, 1e-9);
  EXPECT_NEAR(windingNumber(box, {5, 7, -3}), 0.0, 1e-12);
  // in line with edges and vertices, where a single ray's parity goes wrong
  EXPECT_NEAR(windingNumber(box, {0, 0, 0.5}), 1.0, 1e-12);
  EXPECT_NEAR(windingNumber(box, {3, 3, 3}), 0.0, 1e-12);
  EXPECT_NEAR(windingNumber(box, {3, 0, 0}), 0.0, 1e-12);
  EXPECT_TRUE(inside(box, {0.2, 0.2, 0.2}));
  EXPECT_FALSE(inside(box, {2, 0, 0}));
}

TEST(WindingNumber, AgreesWithTheSphereOnRandomPoints) {
  const double radius = 1.0;
  const TriangleSoA sphere = flatten(primitives::icosphere(3, radius, {1e3, 0, 0}));
  std::mt19937_64 random(17);
  std::uniform_real_distribution<double> uniform(-1.5, 1.5);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 offset{uniform(random), uniform(random), uniform(random)};
    const double r = length(offset);
    if (std::fabs(r - radius) < 0.02) continue;  // between the facets and the true sphere
    const bool expected = r < radius;
    EXPECT_EQ(inside(sphere, Vec3{1e3, 0, 0} + offset), expected) << r;
    ++checked;
  }
  EXPECT_GT(checked, 1500);
}

TEST(WindingNumber, InsideOutIsMinusOneAndAnOpenSurfaceIsFractional) {
  Mesh box = primitives::box();
  std::vector<TriangleIndices> flipped(box.triangles().begin(), box.triangles().end());
  for (TriangleIndices& t : flipped)
    std::swap(t[1], t[2]);
  const Mesh insideOut(std::vector<Vec3>(box.vertices().begin(), box.vertices().end()), flipped);
  EXPECT_NEAR(windingNumber(flatten(insideOut), {0, 0, 0}), -1.0, 1e-12);
  // a square seen from just above its centre covers almost half of the sphere of directions
  const TriangleSoA square = flatten(primitives::quad(2, 2));
  EXPECT_NEAR(windingNumber(square, {0, 0, -1e-6}), 0.5, 1e-5);
  EXPECT_NEAR(windingNumber(square, {0, 0, 1e-6}), -0.5, 1e-5);
}

TEST(WindingNumber, DegenerateTrianglesAddNothing) {
  const TriangleSoA flat =
      flatten(Mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {5, 5, 5}}, {{0, 1, 2}, {3, 3, 3}}));
  EXPECT_EQ(windingNumber(flat, {0.5, 1, 0}), 0.0);
  EXPECT_EQ(windingNumber(flat, {1, 0, 0}), 0.0);  // on the degenerate triangle: no NaN
}

}  // namespace
}  // namespace delta
