#include "delta/mesh/triangle_soa.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "delta/mesh/mesh.h"

namespace delta {
namespace {

Mesh randomMesh(std::size_t triangles, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-10, 10);
  std::vector<Vec3> vertices(triangles + 2);
  for (Vec3& v : vertices)
    v = {uniform(random), uniform(random), uniform(random)};
  std::vector<TriangleIndices> indices(triangles);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(vertices.size() - 1));
  for (auto& t : indices)
    t = {pick(random), pick(random), pick(random)};
  return Mesh(std::move(vertices), std::move(indices));
}

TEST(TriangleSoA, HoldsTheMeshTrianglesInOrder) {
  for (std::size_t count : {1, 7, 8, 9, 64, 1001}) {
    const Mesh mesh = randomMesh(count, count);
    const TriangleSoA flat = flatten(mesh);
    ASSERT_EQ(flat.size(), count);
    for (std::size_t i = 0; i < count; ++i) {
      const Triangle expected = mesh.triangle(i);
      const Triangle actual = flat.triangle(i);
      EXPECT_EQ(actual.a, expected.a);
      EXPECT_EQ(actual.b, expected.b);
      EXPECT_EQ(actual.c, expected.c);
      EXPECT_EQ(flat.stream(2, 1)[i], expected.c.y);
    }
  }
}

TEST(TriangleSoA, StreamsAreAlignedAndPaddedWithNaN) {
  for (std::size_t count : {1, 8, 13}) {
    const TriangleSoA flat = flatten(randomMesh(count, 3));
    EXPECT_EQ(flat.paddedSize() % TriangleSoA::kLaneMultiple, 0u);
    EXPECT_GE(flat.paddedSize(), count);
    EXPECT_LT(flat.paddedSize(), count + TriangleSoA::kLaneMultiple);
    for (int vertex = 0; vertex < 3; ++vertex)
      for (int axis = 0; axis < 3; ++axis) {
        const double* stream = flat.stream(vertex, axis);
        EXPECT_EQ(reinterpret_cast<std::uintptr_t>(stream) % TriangleSoA::kAlignment, 0u);
        for (std::size_t i = count; i < flat.paddedSize(); ++i) {
          EXPECT_TRUE(std::isnan(stream[i]));
          EXPECT_FALSE(stream[i] * stream[i] < 1e300);  // a padded lane passes no distance test
        }
      }
    EXPECT_GE(flat.memoryBytes(), 9 * flat.paddedSize() * sizeof(double));
  }
}

TEST(TriangleSoA, IsASnapshotAndCopiesDeeply) {
  Mesh mesh = randomMesh(5, 11);
  const TriangleSoA before = flatten(mesh);
  TriangleSoA copy = before;
  mesh.translate({1, 0, 0});
  EXPECT_EQ(copy.triangle(4).a, before.triangle(4).a);
  EXPECT_NE(flatten(mesh).triangle(4).a, before.triangle(4).a);
  EXPECT_NE(copy.stream(0, 0), before.stream(0, 0));
}

TEST(TriangleSoA, TransformedIsTheFlattenedMovedMeshBitForBit) {
  const Mesh mesh = randomMesh(37, 5);
  const RigidTransform motion{Quaternion::fromAxisAngle({1, -2, 0.5}, 2.1), {1e3, -4, 0.25}};
  const TriangleSoA moved = flatten(mesh).transformed(motion);
  const TriangleSoA expected = flatten(Mesh(mesh).transform(motion));
  ASSERT_EQ(moved.size(), expected.size());
  ASSERT_EQ(moved.paddedSize(), expected.paddedSize());
  for (int vertex = 0; vertex < 3; ++vertex)
    for (int axis = 0; axis < 3; ++axis)
      for (std::size_t i = 0; i < moved.paddedSize(); ++i) {
        const double a = moved.stream(vertex, axis)[i], b = expected.stream(vertex, axis)[i];
        if (i < moved.size())
          ASSERT_EQ(a, b) << vertex << axis << i;
        else
          ASSERT_TRUE(std::isnan(a));
      }
}

}  // namespace
}  // namespace delta
