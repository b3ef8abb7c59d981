#include "delta/dem/world.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <thread>
#include <vector>

#include "delta/core/error.h"
#include "delta/dem/scenarios.h"
#include "delta/mesh/primitives.h"

#include "centimetre_parameters.h"

namespace delta::dem {
namespace {

constexpr double kRadius = 0.01;
constexpr double kDensity = 2500.0;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Six granulates flying at each other off-centre and spinning: no gravity, no walls, friction.
World closedSystem() {
  std::vector<ParticleShape> shapes;
  for (std::uint64_t seed = 1; seed <= 3; ++seed)
    shapes.emplace_back(primitives::granulate(seed, {kRadius, 0.8 * kRadius, 0.6 * kRadius}),
                        kDensity);
  World world(test::centimetreParameters(shapes[0].mass(), 1.0, 0.7, 0.5, {}));
  for (const ParticleShape& shape : shapes)
    world.addShape(shape);
  test::addConvergingParticles(world, 11, std::array<std::uint32_t, 6>{0, 1, 2, 0, 1, 2});
  return world;
}

TEST(DemWorld, RejectsBadInput) {
  Parameters good;
  good.timeStep = 1e-4;
  good.epsilon = 1e-3;
  good.filterDistance = 1e-3;
  good.stiffness = 1e3;
  EXPECT_NO_THROW(World{good});
  const auto rejects = [&good](auto change) {
    Parameters bad = good;
    change(bad);
    EXPECT_THROW(World{bad}, Error);
  };
  rejects([](Parameters& p) { p.timeStep = 0.0; });
  rejects([](Parameters& p) { p.timeStep = -1e-4; });
  rejects([](Parameters& p) { p.timeStep = kNaN; });
  rejects([](Parameters& p) { p.epsilon = 0.0; });
  rejects([](Parameters& p) { p.epsilon = kNaN; });
  // Beyond what the contact queries take: refused here, not by a step half-way (1e308 made the
  // broad phase's margin +inf; below 2^-481 the contacts refuse ε).
  rejects([](Parameters& p) { p.epsilon = 1e308; });
  rejects([](Parameters& p) { p.epsilon = 1e-200; });
  rejects([](Parameters& p) { p.filterDistance = 1e300; });
  good.epsilon = 0x1p-481;
  EXPECT_NO_THROW(World{good});
  good.epsilon = 1e-3;
  rejects([](Parameters& p) { p.filterDistance = -1.0; });
  rejects([](Parameters& p) { p.stiffness = 0.0; });
  rejects([](Parameters& p) { p.restitution = 1.5; });
  rejects([](Parameters& p) { p.restitution = -0.5; });
  rejects([](Parameters& p) { p.restitution = kNaN; });
  rejects([](Parameters& p) { p.friction = -0.1; });
  rejects([](Parameters& p) { p.gravity = {0, 0, kNaN}; });

  World world(good);
  EXPECT_THROW(world.addShape(primitives::quad(), kDensity), Error);  // open
  EXPECT_THROW(world.addShape(primitives::icosphere(1), 0.0), Error);
  EXPECT_THROW(world.addShape(primitives::icosphere(1), -1.0), Error);
  EXPECT_THROW(world.addParticle(0, {}), Error);  // no such shape
  world.addShape(primitives::icosphere(1), kDensity);
  ParticleState state;
  state.position = {kNaN, 0, 0};
  EXPECT_THROW(world.addParticle(0, state), Error);
  state.position = {};
  state.orientation = {0, 0, 0, 0};
  EXPECT_THROW(world.addParticle(0, state), Error);
  EXPECT_THROW(world.setVelocity(0, {1, 0, 0}), Error);  // no such particle
  EXPECT_THROW(world.setTimeStep(0.0), Error);
  ObstacleMotion motion;
  motion.velocity = {kNaN, 0, 0};
  EXPECT_THROW(world.addObstacle(primitives::quad(), motion), Error);
}

TEST(DemWorld, FreeFallIsExactForVelocityVerlet) {
  World world(test::centimetreParameters(1.0, 1.0, 0.5, 0.0, {0, 0, -9.81}));
  world.addShape(primitives::icosphere(1, kRadius), kDensity);
  ParticleState state;
  state.position = {1, 2, 3};
  state.velocity = {0.5, 0, 2};
  world.addParticle(0, state);
  world.run(1000);
  const double t = world.time();
  const Vec3 expected = state.position + state.velocity * t + Vec3{0, 0, -9.81} * (0.5 * t * t);
  EXPECT_NEAR(distance(world.particles()[0].position, expected), 0.0, 1e-12);
  EXPECT_NEAR(world.particles()[0].velocity.z, 2.0 - 9.81 * t, 1e-12);
  EXPECT_NEAR(world.energies().total(), World(world).energies().total(), 0.0);
}

TEST(DemWorld, TorqueFreeRotationKeepsAngularMomentum) {
  World world(test::centimetreParameters(1.0, 1.0, 0.5, 0.0, {}));
  world.addShape(primitives::granulate(5, {kRadius, 0.7 * kRadius, 0.4 * kRadius}), kDensity);
  ParticleState state;
  state.angularVelocity = {30, 20, 10};  // no principal axis: the body tumbles
  world.addParticle(0, state);
  const Vec3 momentum = world.angularMomentum();
  const double energy = world.energies().rotational;
  world.setTimeStep(1e-5);
  world.run(2000);
  EXPECT_EQ(world.angularMomentum(), momentum);
  EXPECT_NEAR(world.energies().rotational / energy - 1.0, 0.0, 1e-3);
  // The angular velocity moved (tumbling) while L stood still.
  EXPECT_GT(distance(world.particles()[0].angularVelocity, state.angularVelocity), 1.0);
}

TEST(DemWorld, ATumblingBodyKeepsItsEnergy) {
  // The turn of a step uses ω at the half-turned body: turning at the start's ω gained energy at
  // first order (1.4·10⁻³ here), the midpoint rule keeps it to round-off and O(dt²) wobble.
  World world(test::centimetreParameters(1.0, 1.0, 0.5, 0.0, {}));
  world.addShape(primitives::granulate(5, {kRadius, 0.8 * kRadius, 0.6 * kRadius}), kDensity);
  ParticleState state;
  state.angularVelocity = {30, 5, 40};
  world.addParticle(0, state);
  world.setTimeStep(2.95e-5);  // the settle scenario's
  const double energy = world.energies().rotational;
  world.run(20000);
  EXPECT_NEAR(world.energies().rotational / energy - 1.0, 0.0, 1e-7);
}

TEST(DemWorld, ClosedSystemConservesMomentaToRoundOff) {
  World world = closedSystem();
  const Vec3 linear = world.linearMomentum(), angular = world.angularMomentum();
  double linearScale = 0.0, angularScale = 0.0;
  for (const Particle& particle : world.particles()) {
    const double mass = world.shapes()[particle.shape].mass();
    linearScale += mass * length(particle.velocity);
    angularScale += length(cross(particle.position, particle.velocity * mass)) +
                    length(particle.angularMomentum);
  }
  std::size_t stepsInContact = 0;
  double linearError = 0.0, angularError = 0.0;
  for (int step = 0; step < 1500; ++step) {
    world.step();
    stepsInContact += world.statistics().pairsInContact > 0 ? 1 : 0;
    linearError = std::fmax(linearError, length(world.linearMomentum() - linear) / linearScale);
    angularError =
        std::fmax(angularError, length(world.angularMomentum() - angular) / angularScale);
  }
  EXPECT_GT(stepsInContact, 100u);
  // Round-off only, growing as a random walk over the steps. Measured after 1500 steps: ~1e-16
  // (linear) and ~2e-14 (angular), relative to Σ m|v| and Σ (|x × mv| + |L|).
  EXPECT_LT(linearError, 1e-13);
  EXPECT_LT(angularError, 1e-13);
  RecordProperty("linear_momentum_error", std::to_string(linearError));
  RecordProperty("angular_momentum_error", std::to_string(angularError));
}

TEST(DemWorld, ParticleOnAFloorComesToRest) {
  const ParticleShape shape(primitives::granulate(7, {kRadius, 0.8 * kRadius, 0.6 * kRadius}),
                            kDensity);
  World world(test::centimetreParameters(shape.mass(), std::sqrt(2 * 9.81 * 0.02), 0.5, 0.5,
                                         {0, 0, -9.81}));
  world.addShape(shape);
  world.addObstacle(primitives::quad(0.1, 0.1));
  ParticleState state;
  state.position = {0, 0, shape.boundingRadius() + 0.2 * kRadius};
  state.orientation = Quaternion::fromAxisAngle({1, 2, 3}, 0.7);
  world.addParticle(0, state);
  const double dt = world.parameters().timeStep;
  world.run(static_cast<std::size_t>(2.0 / dt));  // it lands, rocks and settles on a face
  const Vec3 settled = world.particles()[0].position;
  const double start = world.time();
  world.run(static_cast<std::size_t>(0.1 / dt));
  const double size = 2.0 * shape.boundingRadius();
  const double drift =
      distance(world.particles()[0].position, settled) / size / (world.time() - start);
  // Measured: about 1e-8 of its size per second after 2 s (tenfold less every ~0.15 s).
  EXPECT_LT(drift, 1e-6);
  EXPECT_GE(world.statistics().contactPoints, 3u);  // on a face, not balanced on an edge
  EXPECT_LT(world.particles()[0].position.z, shape.boundingRadius());
}

TEST(DemWorld, ObstaclesMoveAsPrescribed) {
  World world(test::centimetreParameters(1.0, 1.0, 0.5, 0.0, {}));
  ObstacleMotion motion;
  motion.velocity = {0, 0, 0.1};
  motion.angularVelocity = {0, 0, 2.0};
  motion.pivot = {1, 0, 0};
  world.addObstacle(primitives::quad(), motion);
  world.run(100);
  const double t = world.time();
  const Obstacle& obstacle = world.obstacles()[0];
  EXPECT_NEAR(distance(obstacle.pose.apply(motion.pivot), motion.pivot + motion.velocity * t), 0.0,
              1e-12);
  const Vec3 corner = obstacle.pose.apply({0, 0, 0});  // was 1 from the pivot along −x
  EXPECT_NEAR(corner.x, 1.0 - std::cos(2.0 * t), 1e-9);
  EXPECT_NEAR(corner.y, -std::sin(2.0 * t), 1e-9);
}

TEST(DemWorld, SameResultsForOneAndTwoThreads) {
  const auto runWith = [](int threads) {
    const int before = omp_get_max_threads();
    omp_set_num_threads(threads);
    World world = closedSystem();
    world.run(600);
    Scenario settling = settle(12, 3);
    settling.world.run(1500);
    // Spheres: their pairs' law in batches of 64 pairs a chunk, a cache each on the walls.
    Scenario spheres = settle(300, 4, ParticleKind::Sphere);
    spheres.world.run(10000);
    omp_set_num_threads(before);
    std::vector<Particle> state(world.particles().begin(), world.particles().end());
    state.insert(state.end(), settling.world.particles().begin(), settling.world.particles().end());
    state.insert(state.end(), spheres.world.particles().begin(), spheres.world.particles().end());
    EXPECT_GT(settling.world.statistics().pairsInContact, 0u);
    EXPECT_GT(spheres.world.statistics().pairsInContact, 100u);
    return state;
  };
  const std::vector<Particle> one = runWith(1), two = runWith(2);
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(std::memcmp(&one[i].position, &two[i].position, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&one[i].velocity, &two[i].velocity, sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(&one[i].angularMomentum, &two[i].angularMomentum, sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(&one[i].orientation, &two[i].orientation, sizeof(Quaternion)), 0);
  }
}

TEST(DemWorld, ContactsAskedFromManyThreadsAreMadeOnce) {
  // The records wait for the first contacts() after a step; readers on several threads at
  // once (const calls between steps) all get the same records, and so do copies of the World
  // made meanwhile (a copy read them without the records' lock: a race ThreadSanitizer found).
  Scenario settling = settle(30, 5, ParticleKind::Sphere);
  settling.world.run(3000);
  ASSERT_GT(settling.world.statistics().contactPoints, 0u);
  const World copy = settling.world;  // its records made on their own
  std::vector<std::vector<Contact>> seen(6);
  std::vector<std::thread> readers;
  for (std::size_t k = 0; k < seen.size(); ++k)
    readers.emplace_back([&, k] {
      std::vector<Contact>& records = seen[k];
      if (k % 2 == 0) {
        const std::span<const Contact> contacts = settling.world.contacts();
        records.assign(contacts.begin(), contacts.end());
      } else {
        const World mine = settling.world;
        const std::span<const Contact> contacts = mine.contacts();
        records.assign(contacts.begin(), contacts.end());
      }
    });
  for (std::thread& reader : readers)
    reader.join();
  const std::span<const Contact> expected = copy.contacts();
  ASSERT_EQ(expected.size(), settling.world.statistics().contactPoints);
  for (const std::vector<Contact>& records : seen) {
    ASSERT_EQ(records.size(), expected.size());
    EXPECT_EQ(std::memcmp(records.data(), expected.data(), expected.size() * sizeof(Contact)), 0);
  }
}

}  // namespace
}  // namespace delta::dem
