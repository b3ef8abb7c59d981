#include "delta/dem/particle_shape.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/primitives.h"

namespace delta::dem {
namespace {

TEST(DemParticleShape, BoxInItsCentreOfMassFrame) {
  const ParticleShape shape(primitives::box({2, 4, 6}, {10, 20, 30}), 3.0);
  EXPECT_NEAR(shape.volume(), 48.0, 1e-12);
  EXPECT_NEAR(shape.mass(), 144.0, 1e-11);
  EXPECT_NEAR(distance(shape.centroid(), {10, 20, 30}), 0.0, 1e-12);
  EXPECT_NEAR(distance(shape.mesh().bounds().center(), {}), 0.0, 1e-12);
  // A box's moments: m(b² + c²)/12 and the other two likewise.
  EXPECT_NEAR(shape.inertia()(0, 0), 144.0 * (16 + 36) / 12, 1e-9);
  EXPECT_NEAR(shape.inertia()(1, 1), 144.0 * (4 + 36) / 12, 1e-9);
  EXPECT_NEAR(shape.inertia()(2, 2), 144.0 * (4 + 16) / 12, 1e-9);
  EXPECT_NEAR(shape.boundingRadius(), std::sqrt(1.0 + 4.0 + 9.0), 1e-12);
}

TEST(DemParticleShape, InverseInertiaOfATurnedGranulate) {
  Mesh grain = primitives::granulate(3, {1.0, 0.7, 0.5});
  grain.rotate(Vec3{1, 2, 3}, 0.8);  // products of inertia off the diagonal
  const ParticleShape shape(grain, 2.0);
  const Mat3 product = shape.inertia() * shape.inverseInertia();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(product(r, c), r == c ? 1.0 : 0.0, 1e-12);
  EXPECT_GT(std::fabs(shape.inertia()(0, 1)), 1e-3);
}

TEST(DemParticleShape, TheInertiaOfATinyParticleIsInvertedToo) {
  // A particle of radius 1e-22 has an inertia of about 1e-107, whose determinant (1e-321) was
  // subnormal: its inverse was garbage, and the first step ended "no longer finite" with a time
  // step that was the one suggested. The inverse is now taken scaled by a power of two.
  for (const double size : {1e-22, 1e-40, 1e25}) {
    Mesh grain = primitives::granulate(3, {1.0, 0.7, 0.5});
    grain.rotate(Vec3{1, 2, 3}, 0.8);
    grain.scale(size);
    const ParticleShape shape(grain, 2.0);
    const Mat3 product = shape.inertia() * shape.inverseInertia();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(product(r, c), r == c ? 1.0 : 0.0, 1e-12) << size;
  }
}

TEST(DemParticleShape, RejectsOpenMeshesAndBadDensities) {
  EXPECT_THROW(ParticleShape(primitives::quad(), 1.0), Error);
  EXPECT_THROW(ParticleShape(primitives::icosphere(1), 0.0), Error);
  EXPECT_THROW(ParticleShape(primitives::icosphere(1), -2.0), Error);
  EXPECT_THROW(ParticleShape(primitives::icosphere(1), std::numeric_limits<double>::quiet_NaN()),
               Error);
}

TEST(DemParticleShape, RejectsMeshesThatBoundNoSolid) {
  // An icosphere with a vertex pushed through it: closed, and crossing itself, its mass would
  // count the overlap twice.
  const Mesh sphere = primitives::icosphere(2);
  std::vector<Vec3> vertices(sphere.vertices().begin(), sphere.vertices().end());
  vertices[0] = vertices[0] * -1.3;
  const Mesh crossing(vertices, {sphere.triangles().begin(), sphere.triangles().end()});
  const auto messageOf = [](const Mesh& mesh) -> std::string {
    try {
      (void)ParticleShape(mesh, 1.0);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_NE(messageOf(crossing).find("crosses itself"), std::string::npos);
  // A ball with a smaller ball of the same orientation inside: its mass would be both volumes.
  const Mesh inner = primitives::icosphere(2, 0.5);
  vertices.assign(sphere.vertices().begin(), sphere.vertices().end());
  vertices.insert(vertices.end(), inner.vertices().begin(), inner.vertices().end());
  std::vector<TriangleIndices> triangles(sphere.triangles().begin(), sphere.triangles().end());
  const auto offset = static_cast<std::uint32_t>(sphere.vertexCount());
  for (const TriangleIndices& t : inner.triangles())
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  EXPECT_NE(messageOf(Mesh(vertices, triangles)).find("oriented against"), std::string::npos);
  // The inner ball turned inward is a cavity: a hollow ball, whose mass is the shell's.
  for (std::size_t k = sphere.triangleCount(); k < triangles.size(); ++k)
    std::swap(triangles[k][1], triangles[k][2]);
  const ParticleShape hollow(Mesh(vertices, triangles), 1.0);
  EXPECT_NEAR(hollow.volume(),
              ParticleShape(sphere, 1.0).volume() - ParticleShape(inner, 1.0).volume(), 1e-12);
}

TEST(DemParticleShape, SphereHasExactMassProperties) {
  const double r = 0.02, density = 2500.0;
  const ParticleShape shape = ParticleShape::sphere(r, density);
  const double mass = density * 4.0 / 3.0 * std::numbers::pi * r * r * r;
  EXPECT_TRUE(shape.isSphere());
  EXPECT_EQ(shape.kind(), ParticleKind::Sphere);
  EXPECT_NEAR(shape.mass() / mass, 1.0, 1e-15);
  EXPECT_EQ(shape.boundingRadius(), r);
  EXPECT_EQ(shape.centroid(), Vec3{});
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column)
      EXPECT_NEAR(shape.inertia()(row, column), row == column ? 0.4 * mass * r * r : 0.0,
                  1e-15 * mass * r * r);
  EXPECT_NEAR(shape.inverseInertia()(1, 1) * shape.inertia()(1, 1), 1.0, 1e-15);
  EXPECT_EQ(shape.mesh().triangleCount(), 320u);  // the display icosphere, 2 subdivisions
  EXPECT_EQ(ParticleShape::sphere(r, density, 1).mesh().triangleCount(), 80u);
  EXPECT_FALSE(ParticleShape(primitives::icosphere(1), 1.0).isSphere());
}

// isotropicInertia(): exactly where the inverse inertia is a multiple of the identity.
TEST(DemParticleShape, IsotropicInertiaIsAMultipleOfTheIdentity) {
  const auto multipleOfIdentity = [](const Mat3& m) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (m(r, c) != (r == c ? m(0, 0) : 0.0)) return false;
    return true;
  };
  const ParticleShape sphere = ParticleShape::sphere(0.02, 2500.0);
  EXPECT_TRUE(sphere.isotropicInertia());
  Mesh turned = primitives::granulate(3, {1.0, 0.7, 0.5});
  turned.rotate(Vec3{1, 2, 3}, 0.8);
  for (const ParticleShape& shape :
       {sphere, ParticleShape(primitives::box({2, 4, 6}), 3.0),
        ParticleShape(primitives::box({1, 1, 1}), 1.0), ParticleShape(turned, 2.0),
        ParticleShape(primitives::granulate(4), 1.0), ParticleShape(primitives::icosphere(2), 1.0)})
    EXPECT_EQ(shape.isotropicInertia(), multipleOfIdentity(shape.inverseInertia()));
  EXPECT_FALSE(ParticleShape(turned, 2.0).isotropicInertia());
}

TEST(DemParticleShape, SphereRejectsBadRadiiDensitiesAndSubdivisions) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ParticleShape::sphere(0.0, 1.0), Error);
  EXPECT_THROW(ParticleShape::sphere(-1.0, 1.0), Error);
  EXPECT_THROW(ParticleShape::sphere(nan, 1.0), Error);
  EXPECT_THROW(ParticleShape::sphere(1.0, 0.0), Error);
  EXPECT_THROW(ParticleShape::sphere(1.0, nan), Error);
  EXPECT_THROW(ParticleShape::sphere(1.0, 1.0, -1), Error);
  EXPECT_THROW(ParticleShape::sphere(1.0, 1.0, 7), Error);
}

}  // namespace
}  // namespace delta::dem
