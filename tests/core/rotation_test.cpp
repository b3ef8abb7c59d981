#include "delta/core/rotation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "delta/core/error.h"

namespace delta {
namespace {

constexpr double kPi = std::numbers::pi;

void expectNear(const Vec3& actual, const Vec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

TEST(Rotation, AxisAngleTurnsRightHanded) {
  const Quaternion q = Quaternion::fromAxisAngle({0, 0, 2}, kPi / 2);
  expectNear(q.rotate({1, 0, 0}), {0, 1, 0}, 1e-15);
  expectNear(q.matrix() * Vec3{0, 1, 0}, {-1, 0, 0}, 1e-15);
}

TEST(Rotation, MatrixRoundTripsThroughQuaternion) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 axis{uniform(random), uniform(random), uniform(random) + 1e-3};
    const double angle = 4 * kPi * uniform(random);  // every branch of Shepperd's method
    const Quaternion q = Quaternion::fromAxisAngle(axis, angle);
    const Quaternion back = Quaternion::fromMatrix(q.matrix());
    const Vec3 p{uniform(random), uniform(random), uniform(random)};
    expectNear(back.rotate(p), q.rotate(p), 1e-14);
  }
}

TEST(Rotation, LongChainsStayOrthonormal) {
  // A DEM particle turned by a small rotation every step, a million times.
  const Quaternion step = Quaternion::fromAxisAngle({0.3, -1.0, 0.7}, 1e-3);
  Quaternion q;
  for (int i = 0; i < 1'000'000; ++i)
    q = step * q;
  EXPECT_LE(orthonormalityError(q.matrix()), 1e-14);
  EXPECT_NEAR(q.matrix().determinant(), 1.0, 1e-14);
  // and it is the rotation by 1000 radians about that axis
  const Quaternion direct = Quaternion::fromAxisAngle({0.3, -1.0, 0.7}, 1000.0);
  expectNear(q.rotate({1, 2, 3}), direct.rotate({1, 2, 3}), 1e-9);
}

TEST(Rotation, RejectsWhatIsNotARotation) {
  EXPECT_THROW(Quaternion::fromAxisAngle({0, 0, 0}, 1.0), Error);
  EXPECT_THROW(Quaternion::fromAxisAngle({1, 0, 0}, NAN), Error);
  EXPECT_THROW(Quaternion::fromAxisAngle({INFINITY, 0, 0}, 1.0), Error);
  EXPECT_THROW(Quaternion::fromComponents(0, 0, 0, 0), Error);
  EXPECT_THROW(Quaternion::fromMatrix(Mat3::diagonal({1, 1, -1})), Error);  // a reflection
  EXPECT_THROW(Quaternion::fromMatrix(Mat3::diagonal({1, 2, 1})), Error);   // a stretch
  Mat3 nan = Mat3::identity();
  nan(1, 2) = NAN;
  EXPECT_THROW(Quaternion::fromMatrix(nan), Error);
}

TEST(Rotation, AnAxisOfAnyFiniteLengthKeepsItsDirection) {
  // An axis whose squared length overflowed became no rotation at all, silently (1e200 × (1, 1,
  // 1) turned nothing), and one whose square underflowed was refused as zero.
  const Quaternion unit = Quaternion::fromAxisAngle({1, 1, 1}, 0.7);
  for (const double scale : {1e200, 1e300, 1.7e308, 1e-170, 1e-300, 5e-324 * 4}) {
    const Quaternion q = Quaternion::fromAxisAngle(Vec3{1, 1, 1} * scale, 0.7);
    EXPECT_NEAR(q.w, unit.w, 1e-15) << scale;
    EXPECT_NEAR(q.x, unit.x, 1e-15) << scale;
    EXPECT_NEAR(q.y, unit.y, 1e-15) << scale;
    EXPECT_NEAR(q.z, unit.z, 1e-15) << scale;
  }
  // Components of any size make the unit quaternion of their direction.
  const Quaternion big = Quaternion::fromComponents(0, 1e300, 1e300, 0);
  EXPECT_NEAR(big.x, std::sqrt(0.5), 4e-16);
  EXPECT_NEAR(big.y, std::sqrt(0.5), 4e-16);
  const Quaternion tiny = Quaternion::fromComponents(1e-320, 0, 0, 0);
  EXPECT_EQ(tiny.w, 1.0);
  // Ordinary sizes are not rescaled: the same bits as the plain formula.
  const Vec3 axis{0.3, -1.0, 0.7};
  const double s = std::sin(0.35) / length(axis);
  const Quaternion plain =
      detail::normalizedOrIdentity(std::cos(0.35), axis.x * s, axis.y * s, axis.z * s);
  const Quaternion q = Quaternion::fromAxisAngle(axis, 0.7);
  EXPECT_EQ(q.w, plain.w);
  EXPECT_EQ(q.x, plain.x);
  EXPECT_EQ(q.y, plain.y);
  EXPECT_EQ(q.z, plain.z);
  // The messages say what is wrong.
  try {
    (void)Quaternion::fromAxisAngle({1, 0, 0}, INFINITY);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("angle inf (radians) is not finite"), std::string::npos)
        << e.what();
  }
}

TEST(Rotation, NearlyOrthonormalMatrixIsProjected) {
  Mat3 m = Quaternion::fromAxisAngle({1, 1, 0}, 0.4).matrix();
  m(0, 1) += 1e-8;  // as read from a file with 8 digits
  EXPECT_LE(orthonormalityError(Quaternion::fromMatrix(m).matrix()), 1e-14);
}

TEST(RigidTransform, ComposesAndInverts) {
  const RigidTransform a{Quaternion::fromAxisAngle({0, 1, 0}, 0.7), {1, 2, 3}};
  const RigidTransform b =
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, 0, 0}, -1.1), {5, -1, 2});
  const Vec3 p{0.25, -4, 9};
  expectNear((a * b).apply(p), a.apply(b.apply(p)), 1e-13);
  expectNear((a * b).inverse().apply((a * b).apply(p)), p, 1e-13);
  expectNear(b.apply({5, -1, 2}), {5, -1, 2}, 1e-15);  // the pivot stays put
}

TEST(Mat3, MultipleOfIdentityOnlyExactly) {
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    m(i, i) = 2.5;
  EXPECT_TRUE(isMultipleOfIdentity(m));
  m(1, 0) = -0.0;  // a negative zero is zero
  EXPECT_TRUE(isMultipleOfIdentity(m));
  m(2, 1) = 1e-300;
  EXPECT_FALSE(isMultipleOfIdentity(m));
  m(2, 1) = 0.0;
  m(2, 2) = std::nextafter(2.5, 3.0);
  EXPECT_FALSE(isMultipleOfIdentity(m));
  m(2, 2) = std::nan("");
  EXPECT_FALSE(isMultipleOfIdentity(m));
  EXPECT_TRUE(isMultipleOfIdentity(Mat3{}));  // zero: 0·I
}

}  // namespace
}  // namespace delta
