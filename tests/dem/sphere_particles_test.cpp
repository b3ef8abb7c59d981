// Sphere particles in a World: the same broad phase, contact law and integrator as triangulated
// particles, with the analytic narrow phase (narrow_phase.h).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "delta/dem/broad_phase.h"
#include "delta/dem/scenarios.h"
#include "delta/dem/world.h"
#include "delta/mesh/primitives.h"

#include "centimetre_parameters.h"

namespace delta::dem {
namespace {

constexpr double kRadius = 0.01;
constexpr double kDensity = 2500.0;
constexpr double kGravity = 9.81;

std::string scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

/// twoParticles() with exact spheres: head-on at 1 m/s, starting r/10 outside the shells.
double measuredRestitution(double restitution) {
  const ParticleShape sphere = ParticleShape::sphere(kRadius, kDensity);
  World world(test::centimetreParameters(0.5 * sphere.mass(), 1.0, restitution, 0.0, {}));
  world.addShape(sphere);
  const double centres = 2.0 * kRadius + 2.0 * world.parameters().epsilon + 0.1 * kRadius;
  ParticleState left, right;
  left.position = {-0.5 * centres, 0, 0};
  left.velocity = {0.5, 0, 0};
  right.position = {0.5 * centres, 0, 0};
  right.velocity = {-0.5, 0, 0};
  world.addParticle(0, left);
  world.addParticle(0, right);
  RestitutionMeter meter(world);
  for (int step = 0; step < 200 && !meter.separated(); ++step) {
    world.step();
    meter.observe(world);
  }
  EXPECT_TRUE(meter.separated());
  return meter.restitution();
}

TEST(DemSpheres, HeadOnRestitutionMatchesTheCoefficient) {
  // Measured: 0.4994, 0.9004, 1.0006 (the icospheres of twoParticles(): 0.4979, 0.9003, 0.99994).
  for (double e : {0.5, 0.9, 1.0}) {
    const double measured = measuredRestitution(e);
    EXPECT_NEAR(measured / e, 1.0, 0.02) << "e " << e;
    RecordProperty("restitution_" + scientific(e), scientific(measured));
  }
}

TEST(DemSpheres, SphereOnAFloorComesToRest) {
  const ParticleShape shape = ParticleShape::sphere(kRadius, kDensity);
  World world(test::centimetreParameters(shape.mass(), std::sqrt(2 * kGravity * 0.02), 0.5, 0.5,
                                         {0, 0, -kGravity}));
  world.addShape(shape);
  world.addObstacle(primitives::quad(0.1, 0.1));
  ParticleState state;
  // Off the floor's diagonal by 0.3 r: the triangle it is not over reports a point on the
  // diagonal, which must not push it sideways.
  state.position = {0.002, -0.001, kRadius + 0.2 * kRadius};
  world.addParticle(0, state);
  const double dt = world.parameters().timeStep;
  world.run(static_cast<std::size_t>(2.0 / dt));
  const Vec3 settled = world.particles()[0].position;
  const double start = world.time();
  world.run(static_cast<std::size_t>(0.1 / dt));
  const double drift =
      distance(world.particles()[0].position, settled) / (2.0 * kRadius) / (world.time() - start);
  EXPECT_LT(drift, 1e-6);
  EXPECT_EQ(world.statistics().contactPoints, 1u);
  EXPECT_NEAR(world.particles()[0].position.x, state.position.x, 1e-12);
  EXPECT_NEAR(world.particles()[0].position.y, state.position.y, 1e-12);
  // Resting in the shell: k·δ = m·g.
  const double depth = shape.mass() * kGravity / world.parameters().stiffness;
  EXPECT_NEAR(world.particles()[0].position.z, kRadius + 2.0 * world.parameters().epsilon - depth,
              1e-9 * kRadius);
  RecordProperty("drift_per_second", scientific(drift));
}

TEST(DemSpheres, ClosedSystemConservesMomentaToRoundOff) {
  // Five spheres of two sizes and a granulate (the mixed sphere–mesh path) flying at each other
  // off-centre and spinning, with friction: no gravity, no walls.
  const ParticleShape small = ParticleShape::sphere(0.8 * kRadius, kDensity);
  World world(test::centimetreParameters(small.mass(), 1.0, 0.7, 0.5, {}));
  world.addShape(small);
  world.addShape(ParticleShape::sphere(kRadius, kDensity));
  world.addShape(primitives::granulate(3, {kRadius, 0.8 * kRadius, 0.6 * kRadius}), kDensity);
  test::addConvergingParticles(world, 5, std::array<std::uint32_t, 6>{0, 1, 2, 1, 0, 1});
  const Vec3 linear = world.linearMomentum(), angular = world.angularMomentum();
  double linearScale = 0.0, angularScale = 0.0;
  for (const Particle& particle : world.particles()) {
    const double mass = world.shapes()[particle.shape].mass();
    linearScale += mass * length(particle.velocity);
    angularScale += length(cross(particle.position, particle.velocity * mass)) +
                    length(particle.angularMomentum);
  }
  std::size_t stepsInContact = 0, mixedContacts = 0;
  double linearError = 0.0, angularError = 0.0;
  for (int step = 0; step < 1500; ++step) {
    world.step();
    stepsInContact += world.statistics().pairsInContact > 0 ? 1 : 0;
    for (const Contact& contact : world.contacts())
      mixedContacts += contact.first == 2 || contact.second == 2 ? 1 : 0;
    linearError = std::fmax(linearError, length(world.linearMomentum() - linear) / linearScale);
    angularError =
        std::fmax(angularError, length(world.angularMomentum() - angular) / angularScale);
  }
  EXPECT_GT(stepsInContact, 100u);
  EXPECT_GT(mixedContacts, 0u);
  EXPECT_LT(linearError, 1e-13);
  EXPECT_LT(angularError, 1e-13);
  RecordProperty("linear_momentum_error", scientific(linearError));
  RecordProperty("angular_momentum_error", scientific(angularError));
}

/// The spheres' turns, taken eight to a batch in vector lanes (and the whole batch by the plain
/// formula where one of them is at rest or spins past its small-angle series), give each sphere
/// the orientation it gets alone in a World (where it takes the plain formula), bit for bit.
TEST(DemSpheres, TurnsInBatchesMatchEachSphereAlone) {
  const ParticleShape sphere = ParticleShape::sphere(kRadius, kDensity);
  const Parameters parameters = test::centimetreParameters(sphere.mass(), 1.0, 0.5, 0.0, {});
  std::mt19937_64 random(11);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
  // 21 spheres far apart: two batches of eight and five alone. Sphere 12 is at rest and sphere
  // 13 turns by more than 2⁻⁶ rad a half step (the series' reach), so the second batch takes the
  // plain formula.
  const double fast = 0.1 / parameters.timeStep;
  std::vector<ParticleState> states(21);
  for (std::size_t i = 0; i < states.size(); ++i) {
    ParticleState& state = states[i];
    state.position = {10.0 * kRadius * static_cast<double>(i), 0.0, 0.0};
    state.orientation = Quaternion::fromAxisAngle({uniform(), uniform(), 1.0}, 6.0 * uniform());
    const double rate = std::pow(10.0, 4.0 * uniform());  // 0.01 to 100 rad/s
    state.angularVelocity = Vec3{uniform(), uniform(), uniform()} * rate;
  }
  states[12].angularVelocity = {};
  states[13].angularVelocity = {fast, -fast, 0.5 * fast};
  World together(parameters);
  together.addShape(sphere);
  for (const ParticleState& state : states)
    together.addParticle(0, state);
  together.run(5);
  const auto bits = [](const Quaternion& q) {
    return std::array<std::uint64_t, 4>{
        std::bit_cast<std::uint64_t>(q.w), std::bit_cast<std::uint64_t>(q.x),
        std::bit_cast<std::uint64_t>(q.y), std::bit_cast<std::uint64_t>(q.z)};
  };
  for (std::size_t i = 0; i < states.size(); ++i) {
    World alone(parameters);
    alone.addShape(sphere);
    alone.addParticle(0, states[i]);
    alone.run(5);
    EXPECT_EQ(bits(together.particles()[i].orientation), bits(alone.particles()[0].orientation))
        << "sphere " << i;
  }
  // They did turn: at ω ≥ 0.01 rad/s, by more than rounding in five steps.
  EXPECT_NE(bits(together.particles()[0].orientation), bits(states[0].orientation));
}

/// The highest the particle's centre rises after its first bounce on a floor, dropped from
/// `height` (gap between its lowest point and the floor) onto a floor.
double bounceHeight(const ParticleShape& shape, double stiffnessMass, double restitution) {
  const double height = 0.02;
  const double speed = std::sqrt(2.0 * kGravity * height);
  World world(
      test::centimetreParameters(stiffnessMass, speed, restitution, 0.0, {0, 0, -kGravity}));
  world.addShape(shape);
  world.addObstacle(primitives::quad(0.1, 0.1));
  ParticleState state;
  state.position = {0.001, 0.002, kRadius + height};
  world.addParticle(0, state);
  bool touched = false, rising = false;
  double highest = 0.0;
  for (int step = 0; step < 200000; ++step) {
    world.step();
    const Particle& particle = world.particles()[0];
    touched = touched || world.statistics().contactPoints > 0;
    if (touched && world.statistics().contactPoints == 0 && particle.velocity.z > 0.0)
      rising = true;
    if (rising) highest = std::max(highest, particle.position.z);
    if (rising && particle.velocity.z < 0.0) break;
  }
  return highest - kRadius;
}

TEST(DemSpheres, SphereAndIcosphereBounceAlike) {
  // The same stiffness (set for the sphere's mass) and restitution; the icosphere of 1280
  // triangles has its vertices on the sphere. Measured: within 0.1% at e = 0.5 and 0.9.
  const ParticleShape sphere = ParticleShape::sphere(kRadius, kDensity);
  const ParticleShape icosphere(primitives::icosphere(3, kRadius), kDensity);
  for (double e : {0.5, 0.9}) {
    const double sphereHeight = bounceHeight(sphere, sphere.mass(), e);
    const double icosphereHeight = bounceHeight(icosphere, sphere.mass(), e);
    EXPECT_GT(sphereHeight, 0.5 * e * e * 0.02);
    EXPECT_NEAR(icosphereHeight / sphereHeight, 1.0, 0.03) << "e " << e;
    RecordProperty("bounce_height_" + scientific(e), scientific(sphereHeight));
    RecordProperty("bounce_ratio_" + scientific(e), scientific(icosphereHeight / sphereHeight));
  }
}

TEST(DemSpheres, HopperBuildsSpheresWhereTheGranulatesWere) {
  const Scenario granulates = hopper(1000, 1);
  Scenario spheres = hopper(1000, 1, ParticleKind::Sphere);
  const World& world = spheres.world;
  ASSERT_EQ(world.particles().size(), 1000u);
  ASSERT_EQ(world.shapes().size(), 1u);
  EXPECT_TRUE(world.shapes()[0].isSphere());
  double meanMass = 0.0;
  for (const Particle& particle : granulates.world.particles())
    meanMass += granulates.world.shapes()[particle.shape].mass() / 1000.0;
  EXPECT_NEAR(world.shapes()[0].mass() / meanMass, 1.0, 0.05);  // the pool's mean volume
  EXPECT_EQ(world.parameters().epsilon, granulates.world.parameters().epsilon);
  EXPECT_EQ(world.parameters().filterDistance, granulates.world.parameters().filterDistance);
  EXPECT_EQ(world.parameters().friction, granulates.world.parameters().friction);
  EXPECT_EQ(world.parameters().restitution, granulates.world.parameters().restitution);
  ASSERT_EQ(world.obstacles().size(), granulates.world.obstacles().size());
  std::vector<Sphere> balls;
  for (std::size_t i = 0; i < 1000; ++i) {
    EXPECT_EQ(world.particles()[i].position, granulates.world.particles()[i].position);
    balls.push_back({world.particles()[i].position, world.shapes()[0].boundingRadius()});
  }
  EXPECT_TRUE(nearbyPairs(balls, 2.0 * world.parameters().epsilon).empty());
  // A smaller hopper (a 5 × 5 lattice, wider than the outlet): its outer spheres land on the
  // funnel's wall, never through the shell. The free fall is taken in steps 20 times longer (exact
  // for velocity Verlet without contacts) up to the last one that finds none, to keep the test
  // short; then 4000 steps of the scenario's.
  Scenario small = hopper(125, 1, ParticleKind::Sphere);
  const double dt = small.world.parameters().timeStep;
  for (;;) {
    World trial = small.world;
    trial.setTimeStep(20.0 * dt);
    trial.step();
    if (trial.statistics().rawContactPoints > 0) break;
    trial.setTimeStep(dt);
    small.world = std::move(trial);
  }
  std::size_t obstacleContacts = 0, particleContacts = 0;
  double deepest = 0.0;
  for (int step = 0; step < 4000; ++step) {
    small.world.step();
    for (const Contact& contact : small.world.contacts())
      (contact.withObstacle ? obstacleContacts : particleContacts) += 1;
    deepest = std::max(deepest, small.world.statistics().deepestRatio);
  }
  EXPECT_GT(obstacleContacts, 0u);
  EXPECT_LT(deepest, 1.0);
  for (const Particle& particle : small.world.particles())
    EXPECT_GT(particle.position.z, 0.0);
  RecordProperty("deepest_ratio", scientific(deepest));
  RecordProperty("particle_contacts", std::to_string(particleContacts));
}

}  // namespace
}  // namespace delta::dem
