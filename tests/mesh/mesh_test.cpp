#include "delta/mesh/mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "delta/core/error.h"

namespace delta {
namespace {

Mesh tetrahedron() {
  return Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

std::string errorOf(auto&& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "no error";
}

void expectNear(const Vec3& actual, const Vec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

TEST(Mesh, KeepsVerticesAndTriangles) {
  const Mesh mesh = tetrahedron();
  EXPECT_EQ(mesh.vertexCount(), 4u);
  EXPECT_EQ(mesh.triangleCount(), 4u);
  const Triangle t = mesh.triangle(1);
  EXPECT_EQ(t.a, (Vec3{0, 0, 0}));
  EXPECT_EQ(t.b, (Vec3{1, 0, 0}));
  EXPECT_EQ(t.c, (Vec3{0, 0, 1}));
  EXPECT_EQ(mesh.bounds().lower, (Vec3{0, 0, 0}));
  EXPECT_EQ(mesh.bounds().upper, (Vec3{1, 1, 1}));
  EXPECT_GE(mesh.memoryBytes(), 4 * sizeof(Vec3) + 4 * sizeof(TriangleIndices));
}

TEST(Mesh, RejectsInvalidInputNamingTheElement) {
  EXPECT_EQ(errorOf([] { Mesh({{0, 0, 0}}, {}); }), "mesh: has no triangles");
  const std::string nan = errorOf([] {
    Mesh({{0, 0, 0}, {1, std::nan(""), 0}, {0, 1, 0}}, {{0, 1, 2}});
  });
  EXPECT_NE(nan.find("vertex 1"), std::string::npos) << nan;
  EXPECT_NE(nan.find("nan"), std::string::npos) << nan;
  const std::string inf = errorOf([] {
    Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, -std::numeric_limits<double>::infinity()}}, {{0, 1, 2}});
  });
  EXPECT_NE(inf.find("vertex 2"), std::string::npos) << inf;
  const std::string range = errorOf([] {
    Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {2, 1, 3}});
  });
  EXPECT_NE(range.find("triangle 1 refers to vertex 3"), std::string::npos) << range;
}

TEST(Mesh, KeepsDegenerateTriangles) {
  const Mesh mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}, {0, 0, 0}});
  EXPECT_EQ(mesh.triangleCount(), 2u);
  EXPECT_EQ(mesh.triangle(1).area(), 0.0);
}

TEST(Mesh, TranslatesScalesStretches) {
  Mesh mesh = tetrahedron();
  mesh.translate({1, 2, 3});
  EXPECT_EQ(mesh.vertices()[3], (Vec3{1, 2, 4}));
  mesh.scale(2.0, {1, 2, 3});
  EXPECT_EQ(mesh.vertices()[3], (Vec3{1, 2, 5}));
  EXPECT_EQ(mesh.vertices()[1], (Vec3{3, 2, 3}));
  mesh.stretch({1, 3, 0.5}, {1, 2, 3});
  EXPECT_EQ(mesh.vertices()[2], (Vec3{1, 8, 3}));
  EXPECT_EQ(mesh.vertices()[3], (Vec3{1, 2, 4}));
}

TEST(Mesh, RotatesByAxisAngleQuaternionAndMatrixAlike) {
  const Vec3 axis{1, -2, 0.5};
  const double angle = 2.1;
  const Vec3 pivot{0.5, 0.5, -3};
  Mesh byAxis = tetrahedron();
  byAxis.rotate(axis, angle, pivot);
  Mesh byQuaternion = tetrahedron();
  byQuaternion.rotate(Quaternion::fromAxisAngle(axis, angle), pivot);
  Mesh byMatrix = tetrahedron();
  byMatrix.rotate(Quaternion::fromAxisAngle(axis, angle).matrix(), pivot);
  for (std::size_t i = 0; i < 4; ++i) {
    expectNear(byQuaternion.vertices()[i], byAxis.vertices()[i], 1e-14);
    expectNear(byMatrix.vertices()[i], byAxis.vertices()[i], 1e-14);
    // a rotation keeps the distance to the pivot
    EXPECT_NEAR(distance(byAxis.vertices()[i], pivot), distance(tetrahedron().vertices()[i], pivot),
                1e-14);
  }
  Mesh quarter = tetrahedron();
  quarter.rotate({0, 0, 1}, std::numbers::pi / 2);
  expectNear(quarter.vertices()[1], {0, 1, 0}, 1e-15);
}

TEST(Mesh, ComposedRigidTransformEqualsTheSequence) {
  const RigidTransform first{Quaternion::fromAxisAngle({0, 1, 1}, 0.3), {1, 0, 0}};
  const RigidTransform second{Quaternion::fromAxisAngle({1, 0, 0}, -2.0), {0, -4, 2}};
  Mesh sequence = tetrahedron();
  sequence.transform(first).transform(second);
  Mesh composed = tetrahedron();
  composed.transform(second * first);
  for (std::size_t i = 0; i < 4; ++i)
    expectNear(composed.vertices()[i], sequence.vertices()[i], 1e-14);
  composed.transform((second * first).inverse());
  for (std::size_t i = 0; i < 4; ++i)
    expectNear(composed.vertices()[i], tetrahedron().vertices()[i], 1e-14);
}

TEST(Mesh, RejectedTransformLeavesTheMeshUnchanged) {
  Mesh mesh = tetrahedron();
  EXPECT_THROW(mesh.translate({NAN, 0, 0}), Error);
  EXPECT_THROW(mesh.scale(0.0), Error);
  EXPECT_THROW(mesh.scale(-1.0), Error);
  EXPECT_THROW(mesh.stretch({1, INFINITY, 1}), Error);
  EXPECT_THROW(mesh.rotate(Vec3{0, 0, 0}, 1.0), Error);
  EXPECT_THROW(mesh.rotate(Mat3::diagonal({-1, 1, 1})), Error);
  EXPECT_THROW(mesh.rotate(Quaternion{0, 0, 0, 0}), Error);
  // a move that would overflow to infinity
  const std::string overflow = errorOf([&] {
    mesh.translate({1.7e308, 0, 0}).translate({1.7e308, 0, 0});
  });
  EXPECT_NE(overflow.find("not finite"), std::string::npos) << overflow;
  Mesh expected = tetrahedron();
  expected.translate({1.7e308, 0, 0});
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_EQ(mesh.vertices()[i], expected.vertices()[i]);
}

TEST(Mesh, RigidTransformNormalisesItsQuaternion) {
  Mesh mesh = tetrahedron();
  mesh.transform({Quaternion{2, 0, 0, 0}, {0, 0, 0}});  // 2 = 2·identity: still the identity
  for (std::size_t i = 0; i < 4; ++i)
    expectNear(mesh.vertices()[i], tetrahedron().vertices()[i], 1e-15);
}

}  // namespace
}  // namespace delta
