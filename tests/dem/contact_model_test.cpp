#include "delta/dem/contact_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "delta/core/error.h"

namespace delta::dem {
namespace {

/// The clamped oscillator δ'' = −δ − 2ζδ' (force δ + 2ζδ' ≥ 0) integrated by small RK4 steps
/// from δ = 0, δ' = 1 until the force vanishes: an independent reference for restitutionOf.
double restitutionByIntegration(double zeta) {
  double position = 0.0, velocity = 1.0;
  const double step = 1e-5;
  const auto acceleration = [zeta](double x, double v) { return -x - 2.0 * zeta * v; };
  for (int i = 0; i < 10'000'000; ++i) {
    const double k1x = velocity, k1v = acceleration(position, velocity);
    const double k2x = velocity + 0.5 * step * k1v,
                 k2v = acceleration(position + 0.5 * step * k1x, velocity + 0.5 * step * k1v);
    const double k3x = velocity + 0.5 * step * k2v,
                 k3v = acceleration(position + 0.5 * step * k2x, velocity + 0.5 * step * k2v);
    const double k4x = velocity + step * k3v,
                 k4v = acceleration(position + step * k3x, velocity + step * k3v);
    const double nextPosition = position + step / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
    const double nextVelocity = velocity + step / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (nextPosition + 2.0 * zeta * nextVelocity <= 0.0 && i > 0) {
      // The force's zero lies within this step: interpolate the velocity there.
      const double before = position + 2.0 * zeta * velocity;
      const double after = nextPosition + 2.0 * zeta * nextVelocity;
      const double fraction = before / (before - after);
      return -(velocity + fraction * (nextVelocity - velocity));
    }
    position = nextPosition;
    velocity = nextVelocity;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

ContactLaw law(double restitution, double friction = 0.0) {
  ContactLaw contactLaw;
  contactLaw.epsilon = 0.01;
  contactLaw.stiffness = 1000.0;
  contactLaw.dampingRatio = dampingRatio(restitution);
  contactLaw.friction = friction;
  contactLaw.tangentialStiffness = 2.0 / 7.0 * contactLaw.stiffness;
  return contactLaw;
}

/// A contact point at `x`, `distance` apart, the first body above (direction +z).
ContactPoint pointAt(const Vec3& x, double distance) {
  ContactPoint point;
  point.x = x;
  point.direction = {0, 0, 1};
  point.normal = point.direction * (0.5 * distance);
  point.distance = distance;
  return point;
}

TEST(DemContactModel, RestitutionOfMatchesTheClampedOscillator) {
  for (double zeta : {0.05, 0.2, 0.5, 0.9, 1.0, 1.5, 3.0})
    EXPECT_NEAR(restitutionOf(zeta), restitutionByIntegration(zeta), 1e-6) << "zeta " << zeta;
  EXPECT_EQ(restitutionOf(0.0), 1.0);
}

TEST(DemContactModel, DampingRatioInvertsRestitution) {
  for (double e : {0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99})
    EXPECT_NEAR(restitutionOf(dampingRatio(e)), e, 1e-12) << "e " << e;
  EXPECT_EQ(dampingRatio(1.0), 0.0);
  EXPECT_GT(dampingRatio(0.0), 10.0);
  // The clamped law needs less damping than the textbook exp(−πζ/√(1−ζ²)) for the same e.
  const double textbook = -std::log(0.5) / std::sqrt(M_PI * M_PI + std::log(0.5) * std::log(0.5));
  EXPECT_GT(dampingRatio(0.5), textbook * 1.1);
}

TEST(DemContactModel, DampingRatioRejectsRestitutionOutsideZeroToOne) {
  EXPECT_THROW(dampingRatio(-0.1), Error);
  EXPECT_THROW(dampingRatio(1.0001), Error);
  EXPECT_THROW(dampingRatio(std::numeric_limits<double>::quiet_NaN()), Error);
}

TEST(DemContactModel, OnePointAtRestIsALinearSpringOnTheDepth) {
  const ContactLaw contactLaw = law(0.5);
  const std::vector<ContactPoint> points = {pointAt({0, 0, 0}, 0.015)};
  const PairForces forces = pairForces(points, {}, {}, 1.0, {}, 1e-3, contactLaw);
  ASSERT_EQ(forces.points.size(), 1u);
  EXPECT_DOUBLE_EQ(forces.points[0].depth, 0.005);
  EXPECT_DOUBLE_EQ(forces.points[0].force.z, 1000.0 * 0.005);
  EXPECT_EQ(forces.points[0].force.x, 0.0);
  EXPECT_DOUBLE_EQ(forces.springEnergy, 0.5 * 1000.0 * 0.005 * 0.005);
}

/// Every field of two PairForces, bit for bit.
void expectSameForces(const PairForces& a, const PairForces& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(std::memcmp(&a.points[i].point.x, &b.points[i].point.x, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.points[i].force, &b.points[i].force, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.points[i].couple, &b.points[i].couple, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(a.points[i].depth, b.points[i].depth) << i;
    EXPECT_EQ(a.points[i].volume, b.points[i].volume) << i;
  }
  EXPECT_EQ(std::memcmp(&a.spring.displacement, &b.spring.displacement, sizeof(Vec3)), 0);
  EXPECT_EQ(a.spring.twist, b.spring.twist);
  EXPECT_EQ(a.normalForce, b.normalForce);
  EXPECT_EQ(a.deepest, b.deepest);
  EXPECT_EQ(a.springEnergy, b.springEnergy);
  EXPECT_EQ(a.sliding, b.sliding);
}

TEST(DemContactModel, AReusedResultGivesTheFreshResult) {
  // A World keeps one PairForces a pair slot from step to step: what an earlier pair left in it
  // (more points, a sliding spring, a twist) must not reach the next.
  const ContactLaw contactLaw = law(0.5, 0.3);
  BodyMotion sliding;
  sliding.velocity = {2.0, 0.0, -0.5};
  sliding.angularVelocity = {0.0, 0.0, 40.0};
  const TangentialSpring stretched{{0.01, 0.0, 0.0}, 0.2};
  const std::vector<ContactPoint> three = {pointAt({0, 0, 0}, 0.005), pointAt({1, 0, 0}, 0.015),
                                           pointAt({0, 1, 0}, 0.01)};
  const std::vector<ContactPoint> one = {pointAt({0.5, 0, 0}, 0.012)};
  PairForces reused;
  pairForces(three, sliding, {}, 1.0, stretched, 1e-3, contactLaw, reused);
  expectSameForces(reused, pairForces(three, sliding, {}, 1.0, stretched, 1e-3, contactLaw));
  ASSERT_TRUE(reused.sliding);
  pairForces(one, {}, {}, 1.0, {}, 1e-3, contactLaw, reused);
  expectSameForces(reused, pairForces(one, {}, {}, 1.0, {}, 1e-3, contactLaw));
  pairForces({}, {}, {}, 1.0, {}, 1e-3, contactLaw, reused);
  expectSameForces(reused, PairForces{});
}

TEST(DemContactModel, NeverAttractive) {
  const ContactLaw contactLaw = law(0.1);
  const std::vector<ContactPoint> points = {pointAt({0, 0, 0}, 0.019)};
  BodyMotion leaving;
  leaving.velocity = {0, 0, 50.0};  // the dashpot would pull far harder than the spring pushes
  const PairForces forces = pairForces(points, leaving, {}, 1.0, {}, 1e-3, contactLaw);
  EXPECT_EQ(forces.points[0].force.z, 0.0);
  BodyMotion approaching;
  approaching.velocity = {0, 0, -1.0};
  EXPECT_GT(pairForces(points, approaching, {}, 1.0, {}, 1e-3, contactLaw).points[0].force.z,
            1000.0 * 0.001);
}

TEST(DemContactModel, PointsShareTheDeepestSpringByDepth) {
  const ContactLaw contactLaw = law(0.5);
  // Depths 0.015 and 0.005: the pair's force is k·δ_max, split 3 : 1.
  const std::vector<ContactPoint> points = {pointAt({0, 0, 0}, 0.005), pointAt({1, 0, 0}, 0.015)};
  const PairForces forces = pairForces(points, {}, {}, 1.0, {}, 1e-3, contactLaw);
  EXPECT_DOUBLE_EQ(forces.points[0].force.z, 0.75 * 1000.0 * 0.015);
  EXPECT_DOUBLE_EQ(forces.points[1].force.z, 0.25 * 1000.0 * 0.015);
  EXPECT_DOUBLE_EQ(forces.normalForce, 1000.0 * 0.015);
}

TEST(DemContactModel, SeparatingPairsKeepTheirTotalWhereShallowPointsWouldPull) {
  // Depths 0.015 and 0.001 (2ε = 0.02), the bodies separating at 0.5: the shallow point's share
  // w·k·δ_max − (c/2)·v_n is negative. Cut at zero on its own, the pair's total was the deep
  // point's share, more than k·δ_max − c·v_n; now the deep point carries the whole of it.
  const ContactLaw contactLaw = law(0.5);
  const std::vector<ContactPoint> points = {pointAt({0, 0, 0}, 0.005), pointAt({1, 0, 0}, 0.019)};
  BodyMotion leaving;
  leaving.velocity = {0, 0, 0.5};
  const PairForces forces = pairForces(points, leaving, {}, 1.0, {}, 1e-6, contactLaw);
  const double damping = 2.0 * contactLaw.dampingRatio * std::sqrt(contactLaw.stiffness);
  const double total = contactLaw.stiffness * 0.015 - damping * 0.5;
  ASSERT_GT(total, 0.0);
  ASSERT_LT(1.0 / 16.0 * contactLaw.stiffness * 0.015 - damping / 2.0 * 0.5, 0.0);
  EXPECT_NEAR(forces.normalForce, total, 1e-12 * contactLaw.stiffness);
  EXPECT_NEAR(forces.points[0].force.z, total, 1e-12 * contactLaw.stiffness);
  EXPECT_EQ(forces.points[1].force.z, 0.0);
  // Approaching, no share is negative: the points' forces are their shares.
  BodyMotion approaching;
  approaching.velocity = {0, 0, -0.5};
  const PairForces pressed = pairForces(points, approaching, {}, 1.0, {}, 1e-6, contactLaw);
  EXPECT_NEAR(pressed.points[1].force.z,
              1.0 / 16.0 * contactLaw.stiffness * 0.015 + damping / 2.0 * 0.5,
              1e-12 * contactLaw.stiffness);
}

TEST(DemContactModel, OverlappingPointsTakeTheClearPointsDirection) {
  const ContactLaw contactLaw = law(0.5);
  ContactPoint crossing = pointAt({0, 0, 0}, 0.0);
  crossing.overlap = true;
  crossing.direction = {1, 0, 0};  // what the faces said: not to be trusted
  const std::vector<ContactPoint> points = {crossing, pointAt({0.1, 0, 0}, 0.01)};
  const PairForces forces = pairForces(points, {}, {}, 1.0, {}, 1e-3, contactLaw);
  EXPECT_DOUBLE_EQ(forces.points[0].depth, 0.02);  // 2ε: past the shell
  EXPECT_EQ(forces.points[0].point.direction, (Vec3{0, 0, 1}));
  EXPECT_EQ(forces.points[0].force.x, 0.0);
}

TEST(DemContactModel, FrictionSticksBelowAndSlidesAtTheCoulombLimit) {
  const ContactLaw contactLaw = law(1.0, 0.5);  // no damping: the spring alone
  const std::vector<ContactPoint> points = {pointAt({0, 0, 0}, 0.01)};
  const double normal = 1000.0 * 0.01;
  BodyMotion creeping;
  creeping.velocity = {1e-3, 0, 0};
  const PairForces stuck = pairForces(points, creeping, {}, 1.0, {}, 1e-3, contactLaw);
  EXPECT_FALSE(stuck.sliding);
  EXPECT_DOUBLE_EQ(stuck.spring.displacement.x, 1e-6);
  EXPECT_DOUBLE_EQ(stuck.points[0].force.x, -contactLaw.tangentialStiffness * 1e-6);
  BodyMotion sliding;
  sliding.velocity = {100.0, 0, 0};
  const PairForces slid = pairForces(points, sliding, {}, 1.0, {}, 1e-3, contactLaw);
  EXPECT_TRUE(slid.sliding);
  EXPECT_NEAR(slid.points[0].force.x, -0.5 * normal, 1e-12);
  EXPECT_NEAR(slid.spring.displacement.x, 0.5 * normal / contactLaw.tangentialStiffness, 1e-15);
}

TEST(DemContactModel, TwistIsResistedWithoutANetForce) {
  const ContactLaw contactLaw = law(1.0, 0.5);
  const std::vector<ContactPoint> points = {pointAt({1, 0, 0}, 0.01), pointAt({-1, 0, 0}, 0.01),
                                            pointAt({0, 1, 0}, 0.01)};
  BodyMotion spinning;
  spinning.centre = {0, 1.0 / 3.0, 0};
  spinning.angularVelocity = {0, 0, 1e-3};
  const PairForces forces = pairForces(points, spinning, {}, 1.0, {}, 1e-3, contactLaw);
  Vec3 sum, moment;
  for (const PointForce& point : forces.points) {
    sum += point.force;
    moment += cross(point.point.x - spinning.centre, point.force);
  }
  EXPECT_NEAR(sum.x, 0.0, 1e-15);
  EXPECT_NEAR(sum.y, 0.0, 1e-15);
  EXPECT_LT(moment.z, 0.0);  // against the spin
  EXPECT_NEAR(forces.spring.twist, 1e-6, 1e-18);
}

TEST(DemContactModel, SuggestedTimeStepResolvesAContactInThirtySteps) {
  EXPECT_DOUBLE_EQ(suggestedTimeStep(100.0, 2.0) * 30.0, contactDuration(100.0, 1.0));
  EXPECT_DOUBLE_EQ(stiffnessForImpact(2.0, 3.0, 0.5), 72.0);
}

}  // namespace
}  // namespace delta::dem
