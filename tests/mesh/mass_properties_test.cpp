#include "delta/mesh/mass_properties.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/rotation.h"
#include "delta/mesh/primitives.h"

#include "mesh/test_meshes.h"

namespace delta {
namespace {

constexpr double kPi = std::numbers::pi;

/// The analytic inertia tensor of a solid a×b×c box of mass m, about its centre.
Mat3 boxInertia(const Vec3& size, double mass) {
  const double a2 = size.x * size.x;
  const double b2 = size.y * size.y;
  const double c2 = size.z * size.z;
  return Mat3::diagonal({b2 + c2, a2 + c2, a2 + b2}) * (mass / 12.0);
}

void expectNear(const Mat3& actual, const Mat3& expected, double tolerance) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(actual(r, c), expected(r, c), tolerance) << "entry (" << r << ", " << c << ")";
}

void expectNear(const Vec3& actual, const Vec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

Mesh reversed(const Mesh& mesh) {
  std::vector<TriangleIndices> triangles(mesh.triangles().begin(), mesh.triangles().end());
  for (TriangleIndices& t : triangles)
    std::swap(t[1], t[2]);
  return Mesh({mesh.vertices().begin(), mesh.vertices().end()}, std::move(triangles));
}

TEST(MassProperties, UnitBox) {
  const MassProperties unit = massProperties(primitives::box());
  EXPECT_NEAR(unit.volume, 1.0, 1e-15);
  EXPECT_NEAR(unit.mass, 1.0, 1e-15);
  expectNear(unit.centroid, {0, 0, 0}, 1e-15);
  expectNear(unit.inertia, Mat3::identity() * (1.0 / 6.0), 1e-15);
}

TEST(MassProperties, OneByTwoByThreeBoxWithDensity) {
  const Vec3 size{1, 2, 3};
  const MassProperties p = massProperties(primitives::box(size, {0.5, 1, 1.5}), 2.5);
  EXPECT_NEAR(p.volume, 6.0, 1e-12);
  EXPECT_NEAR(p.mass, 15.0, 1e-12);
  expectNear(p.centroid, {0.5, 1, 1.5}, 1e-12);
  expectNear(p.inertia, boxInertia(size, 15.0), 1e-12);  // diag(16.25, 12.5, 6.25)
  EXPECT_NEAR(signedVolume(primitives::box(size)), 6.0, 1e-12);
}

TEST(MassProperties, BoxFarFromTheOriginKeepsItsDigits) {
  const Vec3 size{1, 2, 3};
  const Vec3 far{1e6, 1e6, 1e6};
  const MassProperties p = massProperties(primitives::box(size, far));
  EXPECT_NEAR(p.volume, 6.0, 1e-12);
  expectNear(p.centroid, far, 1e-9);
  expectNear(p.inertia, boxInertia(size, 6.0), 1e-12);
  EXPECT_NEAR(signedVolume(primitives::box(size, far)), 6.0, 1e-12);
}

/// `a` and `b` as one mesh (b's vertices after a's).
Mesh joined(const Mesh& a, const Mesh& b) {
  std::vector<Vec3> vertices(a.vertices().begin(), a.vertices().end());
  vertices.insert(vertices.end(), b.vertices().begin(), b.vertices().end());
  std::vector<TriangleIndices> triangles(a.triangles().begin(), a.triangles().end());
  const auto offset = static_cast<std::uint32_t>(a.vertexCount());
  for (TriangleIndices t : b.triangles())
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return Mesh(std::move(vertices), std::move(triangles));
}

TEST(MassProperties, PartsFarApartKeepTheirDigits) {
  // Two 1×2×3 boxes d apart along x: summed about one point, each triangle's term was of d²
  // into a volume of 6 (d = 10¹²: signedVolume −67,108,860), and massProperties refused the
  // mesh as enclosing no volume (its threshold was relative to the whole box).
  for (const double d : {1e4, 1e6, 1e8, 1e10, 1e12}) {
    const Mesh two = joined(primitives::box({1, 2, 3}, {-d / 2, 0, 0}),
                            primitives::box({1, 2, 3}, {d / 2, 0, 0}));
    EXPECT_NEAR(signedVolume(two), 12.0, 12.0 * 1e-14) << d;
    const MassProperties p = massProperties(two);
    EXPECT_NEAR(p.volume, 12.0, 12.0 * 1e-14) << d;
    expectNear(p.centroid, {0, 0, 0}, 1e-15 * d);
    // Each box's own tensor plus 2·6·(d/2)² about y and z.
    const Mat3 expected = boxInertia({1, 2, 3}, 12.0) + Mat3::diagonal({0, 3 * d * d, 3 * d * d});
    EXPECT_NEAR(p.inertia(0, 0), expected(0, 0), 1e-12 * expected(0, 0)) << d;
    EXPECT_NEAR(p.inertia(1, 1), expected(1, 1), 1e-12 * expected(1, 1)) << d;
    EXPECT_NEAR(p.inertia(2, 2), expected(2, 2), 1e-12 * expected(2, 2)) << d;
  }
  // A unit tetrahedron beside one that rounding at 10⁵⁵ collapsed to a point: 0 for 1/6.
  const Mesh tetra = test::unitTetrahedron();
  const Mesh point(std::vector<Vec3>(4, Vec3{1e55, 1e55, 0}),
                   {tetra.triangles().begin(), tetra.triangles().end()});
  const Mesh collapsed = joined(tetra, point);
  EXPECT_NEAR(signedVolume(collapsed), 1.0 / 6.0, 1e-16);
}

TEST(MassProperties, VerticesNoTriangleUsesAreLeftOutOfTheScale) {
  // A Mesh keeps unused vertices; one far away set the scale, and the tetrahedron's terms
  // vanished (signedVolume 0 at 10⁷⁰; massProperties refused it as flat from 10¹⁰ on).
  const Mesh tetra = test::unitTetrahedron();
  for (const double far : {1e10, 1e70, 1e110, 1e300}) {
    const Mesh withFar = test::withUnusedVertex(tetra, {far, 0, 0});
    EXPECT_EQ(signedVolume(withFar), signedVolume(tetra)) << far;
    const MassProperties p = massProperties(withFar), q = massProperties(tetra);
    EXPECT_EQ(p.volume, q.volume) << far;
    expectNear(p.centroid, q.centroid, 1e-16);
  }
}

TEST(MassProperties, RotatedBoxTurnsTheTensor) {
  const Vec3 size{1, 2, 3};
  const Quaternion q = Quaternion::fromAxisAngle({1, 2, -0.5}, 0.7);
  const Mat3 r = q.matrix();
  const Mat3 expected = r * boxInertia(size, 6.0) * r.transposed();

  Mesh turned = primitives::box(size);
  turned.rotate(q);
  const MassProperties p = massProperties(turned);
  EXPECT_NEAR(p.volume, 6.0, 1e-13);
  expectNear(p.centroid, {0, 0, 0}, 1e-14);
  expectNear(p.inertia, expected, 1e-13);

  // Turned about its centre far from the origin: vertices rounded to ~1e-10 there, so the
  // tensor is right to about that relative error.
  const Vec3 far{1e6, -2e6, 3e6};
  Mesh turnedFar = primitives::box(size, far);
  turnedFar.rotate(q, far);
  const MassProperties pf = massProperties(turnedFar);
  EXPECT_NEAR(pf.volume, 6.0, 1e-9);
  expectNear(pf.centroid, far, 1e-9);
  expectNear(pf.inertia, expected, 1e-8);
}

TEST(MassProperties, IcosphereIsBetweenItsInscribedAndCircumscribedBalls) {
  // The polyhedron lies inside the ball of radius r (its vertices are on it) and contains the
  // ball of radius ρ, its smallest face-plane distance. Volume and every moment ∫(y²+z²)dV
  // grow with the region, so each lies between the two balls' values: 4/3πρ³ ≤ V ≤ 4/3πr³ and
  // 8/15πρ⁵ ≤ I ≤ 8/15πr⁵ (a ball's moment is 2/5·m·r²).
  const double r = 1.5;
  const Vec3 center{3, -2, 1};
  const Mesh sphere = primitives::icosphere(5, r, center);
  double inscribed = r;
  for (std::size_t t = 0; t < sphere.triangleCount(); ++t) {
    const Triangle face = sphere.triangle(t);
    inscribed = std::min(inscribed, dot(face.a - center, normalized(face.areaVector())));
  }
  ASSERT_GT(inscribed, 0.999 * r);
  const MassProperties p = massProperties(sphere);
  const auto ballVolume = [](double radius) { return 4.0 / 3.0 * kPi * std::pow(radius, 3); };
  const auto ballMoment = [](double radius) { return 8.0 / 15.0 * kPi * std::pow(radius, 5); };
  EXPECT_GE(p.volume, ballVolume(inscribed));
  EXPECT_LE(p.volume, ballVolume(r));
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GE(p.inertia(axis, axis), ballMoment(inscribed));
    EXPECT_LE(p.inertia(axis, axis), ballMoment(r));
  }
  // Central symmetry puts the centroid at the centre; icosahedral symmetry makes the tensor
  // isotropic: equal moments and no products of inertia, to rounding.
  expectNear(p.centroid, center, 1e-13);
  const double moment = p.inertia(0, 0);
  EXPECT_NEAR(p.inertia(1, 1), moment, 1e-12 * moment);
  EXPECT_NEAR(p.inertia(2, 2), moment, 1e-12 * moment);
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column)
      if (row != column) {
        EXPECT_NEAR(p.inertia(row, column), 0.0, 1e-12 * moment);
      }
}

TEST(MassProperties, RejectsInsideOutOpenMisorientedAndFlatMeshes) {
  const Mesh inverted = reversed(primitives::box({1, 2, 3}));
  EXPECT_NEAR(signedVolume(inverted), -6.0, 1e-12);
  EXPECT_THROW(massProperties(inverted), Error);
  EXPECT_THROW(massProperties(reversed(primitives::icosphere(2))), Error);

  const Mesh box = primitives::box();
  std::vector<TriangleIndices> open(box.triangles().begin(), box.triangles().end() - 1);
  EXPECT_THROW(massProperties(Mesh({box.vertices().begin(), box.vertices().end()}, open)), Error);
  EXPECT_THROW(massProperties(primitives::quad()), Error);

  std::vector<TriangleIndices> oneFlipped(box.triangles().begin(), box.triangles().end());
  std::swap(oneFlipped[0][1], oneFlipped[0][2]);
  EXPECT_THROW(massProperties(Mesh({box.vertices().begin(), box.vertices().end()}, oneFlipped)),
               Error);

  // Two faces of one triangle back to back: closed and consistently oriented, but flat.
  const Mesh sheet({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 1}});
  EXPECT_THROW(massProperties(sheet), Error);
}

TEST(MassProperties, RejectsBadDensity) {
  const Mesh box = primitives::box();
  for (double density : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity()})
    EXPECT_THROW(massProperties(box, density), Error) << density;
}

}  // namespace
}  // namespace delta
