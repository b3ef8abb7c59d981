#include "delta/mesh/measures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/primitives.h"

#include "mesh/test_meshes.h"

namespace delta {
namespace {

constexpr double kPi = std::numbers::pi;

Triangle scaled(const Triangle& t, double factor) {
  return {t.a * factor, t.b * factor, t.c * factor};
}

TEST(Measures, RightTriangleAndTetraAreas) {
  const Mesh triangle({{0, 0, 0}, {3, 0, 0}, {0, 4, 0}}, {{0, 1, 2}});
  EXPECT_DOUBLE_EQ(surfaceArea(triangle), 6.0);
  const Mesh tetra({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  EXPECT_NEAR(surfaceArea(tetra), 1.5 + std::sqrt(3.0) / 2, 1e-15);
  EXPECT_EQ(degenerateTriangleCount(tetra), 0u);
}

TEST(Measures, DegenerateIsScaleInvariant) {
  // Area/L² of 2.5e-14 (below 1e-12) and of 2.5e-11 (above): the same verdict at every scale.
  const Triangle sliver{{0, 0, 0}, {1, 0, 0}, {2, 1e-13, 0}};
  const Triangle thin{{0, 0, 0}, {1, 0, 0}, {2, 1e-10, 0}};
  for (double factor : {1.0, 1e-9, 1e9, 1e-150, 1e150}) {
    EXPECT_TRUE(isDegenerate(scaled(sliver, factor))) << factor;
    EXPECT_FALSE(isDegenerate(scaled(thin, factor))) << factor;
  }
  // Subnormal: the factor 2^−exponent was beyond a double, and every such triangle was
  // "degenerate".
  const Triangle right{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (double factor : {1e-310, 1e-320}) {
    EXPECT_FALSE(isDegenerate(scaled(right, factor))) << factor;
    EXPECT_TRUE(isDegenerate(scaled(Triangle{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, factor))) << factor;
  }
}

TEST(Measures, EdgesBeyondTheLargestDoubleAreMeasuredNotOverflowed) {
  // Legs of 2e308: b − a overflowed to ∞ and the cross product to NaN, "degenerate".
  const Triangle big{{-1e308, 0, 0}, {1e308, 0, 0}, {0, 1e308, 0}};
  EXPECT_FALSE(isDegenerate(big));
  EXPECT_FALSE(isDegenerate(scaled(big, 0.5)));
  EXPECT_TRUE(isDegenerate({{-1e308, 0, 0}, {1e308, 0, 0}, {0, 0, 0}}));
}

TEST(Measures, VerticesNoTriangleUsesAreLeftOutOfTheScale) {
  // One unused vertex far away set the scale: a unit tetrahedron's area came out 0 (1e110), a
  // tetrahedron of 1e-10's edges 0 (1e200).
  const Mesh tetra = test::unitTetrahedron();
  for (const double far : {1e10, 1e110, 1e200, 1e300}) {
    const Mesh withFar = test::withUnusedVertex(tetra, {far, 0, 0});
    EXPECT_EQ(surfaceArea(withFar), surfaceArea(tetra)) << far;
    const EdgeLengths with = edgeLengths(withFar), without = edgeLengths(tetra);
    EXPECT_EQ(with.min, without.min) << far;
    EXPECT_EQ(with.max, without.max) << far;
  }
  const Mesh tiny =
      test::withUnusedVertex(Mesh({{0, 0, 0}, {1e-10, 0, 0}, {0, 3e-10, 0}, {0, 0, 7e-11}},
                                  {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}),
                             {1e200, 0, 0});
  EXPECT_NEAR(edgeLengths(tiny).min, 7e-11, 1e-26);
  EXPECT_NEAR(surfaceArea(tiny), 4.7641351882307254e-20, 1e-34);
}

TEST(Measures, CoincidentAndCollinearVerticesAreDegenerate) {
  EXPECT_TRUE(isDegenerate({{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}));
  EXPECT_TRUE(isDegenerate({{1, 2, 3}, {1, 2, 3}, {4, 5, 6}}));
  EXPECT_TRUE(isDegenerate({{0, 0, 0}, {1, 1, 1}, {3, 3, 3}}));
  EXPECT_FALSE(isDegenerate({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  // Far from the origin the edges, not the coordinates, set the scale.
  EXPECT_FALSE(isDegenerate({{1e9, 1e9, 1e9}, {1e9 + 1, 1e9, 1e9}, {1e9, 1e9 + 1, 1e9}}));
}

TEST(Measures, CountsDegenerateTrianglesIncludingRepeatedIndices) {
  const Mesh mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}},
                  {{0, 1, 2}, {0, 1, 3}, {0, 0, 2}, {1, 1, 1}});
  EXPECT_EQ(degenerateTriangleCount(mesh), 3u);
  EXPECT_DOUBLE_EQ(surfaceArea(mesh), 0.5);
}

TEST(Measures, EdgeLengthsCountSharedEdgesOnce) {
  // Unit square as two triangles: four sides of 1 and one diagonal of √2, the diagonal once.
  const Mesh square({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
  const EdgeLengths lengths = edgeLengths(square);
  EXPECT_DOUBLE_EQ(lengths.min, 1.0);
  EXPECT_DOUBLE_EQ(lengths.max, std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(lengths.mean, (4.0 + std::sqrt(2.0)) / 5.0);
}

TEST(Measures, ZeroLengthEdgesGiveZerosNotNaN) {
  // Coincident but unjoined vertices: three edges of length zero.
  const Mesh collapsed({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}, {{0, 1, 2}});
  EdgeLengths lengths = edgeLengths(collapsed);
  EXPECT_EQ(lengths.min, 0.0);
  EXPECT_EQ(lengths.mean, 0.0);
  EXPECT_EQ(lengths.max, 0.0);
  // Only repeated indices: no edge at all.
  lengths = edgeLengths(Mesh({{1, 1, 1}}, {{0, 0, 0}}));
  EXPECT_EQ(lengths.min, 0.0);
  EXPECT_EQ(lengths.mean, 0.0);
  EXPECT_EQ(lengths.max, 0.0);
  // One zero-length edge among others: it is the minimum.
  const Mesh pinched({{0, 0, 0}, {0, 0, 0}, {1, 0, 0}}, {{0, 1, 2}});
  lengths = edgeLengths(pinched);
  EXPECT_EQ(lengths.min, 0.0);
  EXPECT_DOUBLE_EQ(lengths.max, 1.0);
  EXPECT_DOUBLE_EQ(lengths.mean, 2.0 / 3.0);
}

TEST(Measures, MeshesOfSubnormalSizeAreMeasuredNotNaN) {
  // A mesh below about 1e-308 across was scaled by 2^1030, beyond a double: its edge lengths
  // came out NaN, and its area "(-nan × 2^-2130) overflows". Now the lengths are the unit
  // square's scaled (exact where they are normal), and an area below the normal doubles is
  // refused as an underflow.
  for (const int exponent : {-1000, -1030, -1060}) {
    const Mesh square({{0, 0, 0},
                       {std::ldexp(1.0, exponent), 0, 0},
                       {std::ldexp(1.0, exponent), std::ldexp(1.0, exponent), 0},
                       {0, std::ldexp(1.0, exponent), 0}},
                      {{0, 1, 2}, {0, 2, 3}});
    const EdgeLengths lengths = edgeLengths(square);
    EXPECT_EQ(lengths.min, std::ldexp(1.0, exponent)) << exponent;
    EXPECT_NEAR(lengths.max / std::ldexp(1.0, exponent), std::sqrt(2.0),
                exponent < -1022 ? 1e-4 : 1e-15);
    EXPECT_TRUE(std::isfinite(lengths.mean));
    try {
      (void)surfaceArea(square);
      ADD_FAILURE() << "an area below the normal doubles was answered";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("underflows"), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find("nan"), std::string::npos) << e.what();
    }
  }
}

TEST(Measures, AreasOfPrimitivesMatchAnalyticValues) {
  EXPECT_NEAR(surfaceArea(primitives::box({1, 2, 3})), 22.0, 1e-14);
  EXPECT_NEAR(surfaceArea(primitives::quad(2, 5)), 10.0, 1e-14);

  const int n = 24;
  const double r = 0.7;
  const double h = 1.9;
  const double cap = 0.5 * n * r * r * std::sin(2 * kPi / n);
  const double side = n * 2 * r * std::sin(kPi / n) * h;
  EXPECT_NEAR(surfaceArea(primitives::cylinder(r, h, n)), 2 * cap + side, 1e-13);

  // A convex body inside another has the smaller area: the icosphere lies between the ball of
  // its smallest face distance and its circumscribed ball.
  const Mesh sphere = primitives::icosphere(4, 2.0);
  double inscribed = 2.0;
  for (std::size_t t = 0; t < sphere.triangleCount(); ++t) {
    const Triangle face = sphere.triangle(t);
    inscribed = std::fmin(inscribed, dot(face.a, normalized(face.areaVector())));
  }
  const double area = surfaceArea(sphere);
  EXPECT_LT(area, 4 * kPi * 4.0);
  EXPECT_GT(area, 4 * kPi * inscribed * inscribed);

  const EdgeLengths lengths = edgeLengths(primitives::box({1, 2, 3}));
  EXPECT_DOUBLE_EQ(lengths.min, 1.0);
  EXPECT_DOUBLE_EQ(lengths.max, std::sqrt(13.0));  // the 2×3 face's diagonal
}

}  // namespace
}  // namespace delta
