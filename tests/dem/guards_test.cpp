// World's guard against bodies passing through each other in one step (world.h, "No
// pass-through"; src/dem/guards.cpp), and the overlap the CLI's start warning reads.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/dem/particle_shape.h"
#include "delta/dem/world.h"
#include "delta/mesh/primitives.h"

#include "centimetre_parameters.h"

namespace delta::dem {
namespace {

constexpr double kRadius = 0.01;
constexpr double kDensity = 2500.0;

/// A sphere of radius 1 cm at `position` moving at `velocity`, over a 1 m floor at z = 0.
World sphereOverFloor(const Vec3& position, const Vec3& velocity) {
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addObstacle(primitives::quad(1.0, 1.0));
  world.addParticle(0, {position, {}, velocity, {}});
  return world;
}

/// `particles` icospheres 5 cm apart along x, falling along x under a gravity of 1e71 m/s²,
/// stepped `steps` times by 1e-40 s: a step of 1e-5 s then carries them beyond the queries'
/// coordinate range (they pass through nothing: the pass-through guard lets them go).
World fallingBeyondTheRange(std::size_t particles, std::size_t steps) {
  Parameters parameters = test::centimetreParameters(0.01, 1.0, 1.0, 0.5, {1e71, 0, 0});
  parameters.timeStep = 1e-40;
  World world(parameters);
  world.addShape(primitives::icosphere(1, kRadius), kDensity);
  for (std::size_t i = 0; i < particles; ++i)
    world.addParticle(0, {{0.05 * static_cast<double>(i), 0, 0}, {}, {}, {}});
  world.run(steps);
  return world;
}

/// The error the next `steps` steps throw, or "" when they do not.
std::string stepError(World& world, std::size_t steps = 1) {
  try {
    world.run(steps);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST(DemGuards, AParticleTooFastForTheShellStopsTheRunBeforeMoving) {
  World world = sphereOverFloor({0, 0, 0.02}, {0, 0, -1000.0});
  const std::string message = stepError(world);
  ASSERT_FALSE(message.empty()) << "a 1000 m/s particle passed a 1 mm shell silently";
  EXPECT_NE(message.find("particle 0 (speed 1000"), std::string::npos) << message;
  EXPECT_NE(message.find("largest safe time step"), std::string::npos) << message;
  // Nothing moved: the check comes before the step changes anything.
  EXPECT_EQ(world.particles()[0].position, (Vec3{0, 0, 0.02}));
  EXPECT_EQ(world.particles()[0].velocity, (Vec3{0, 0, -1000.0}));
  EXPECT_EQ(world.stepCount(), 0u);
}

TEST(DemGuards, TheSafeTimeStepItNamesCatchesTheFloor) {
  World world = sphereOverFloor({0, 0, 0.02}, {0, 0, -1000.0});
  const std::string message = stepError(world);
  const std::size_t at = message.find("is about ");
  ASSERT_NE(at, std::string::npos) << message;
  const double safe = std::stod(message.substr(at + 9));
  ASSERT_GT(safe, 0.0);
  world.setTimeStep(0.99 * safe);
  // Above the floor until the shell catches it: no step may carry the sphere through unseen.
  bool caught = false;
  for (int step = 0; step < 100 && world.particles()[0].position.z > 0.0; ++step) {
    world.step();
    caught = caught || !world.contacts().empty();
    if (world.particles()[0].position.z < kRadius) {
      EXPECT_TRUE(caught) << "surface below the floor with no contact at step " << step;
    }
  }
  EXPECT_TRUE(caught);
}

TEST(DemGuards, TwoParticlesApproachingTooFastAreStoppedNamingTheFirst) {
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addParticle(0, {{-0.03, 0, 0}, {}, {500.0, 0, 0}, {}});
  world.addParticle(0, {{0.03, 0, 0}, {}, {-500.0, 0, 0}, {}});
  // Stopped in the first step that could carry them into each other, before they meet.
  const std::string message = stepError(world, 1000);
  EXPECT_NE(message.find("particle 0 (speed 500"), std::string::npos) << message;
  EXPECT_NE(message.find("within reach of particle 1"), std::string::npos) << message;
  EXPECT_LT(world.particles()[0].position.x, world.particles()[1].position.x);
}

TEST(DemGuards, SpeedsWhoseSquaresOverflowAreStoppedToo) {
  // |v|² overflows from 1.3e154 on: such a speed was taken for one that is not finite, its
  // particle left out of the guard, and it passed through the other unseen. The same for a
  // spin, and for a drift whose square overflows in the closest approach.
  for (const double speed : {1e160, 1e200, 1e300}) {
    World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
    world.addShape(primitives::icosphere(2, kRadius), kDensity);
    world.addParticle(0, {{-0.03, 0, 0}, {}, {speed, 0, 0}, {}});
    world.addParticle(0, {{0.03, 0, 0}, {}, {}, {}});
    const std::string message = stepError(world);
    EXPECT_NE(message.find("within reach of particle 1"), std::string::npos)
        << speed << ": " << message;
    EXPECT_NE(message.find("(speed " + toString(speed)), std::string::npos) << message;
    EXPECT_EQ(world.particles()[0].position, (Vec3{-0.03, 0, 0}));  // stopped before moving
  }
  World spinning = sphereOverFloor({0, 0, 0.012}, {});
  spinning.setAngularVelocity(0, {1e200, 0, 0});
  EXPECT_NE(stepError(spinning).find("within reach of obstacle 0"), std::string::npos);
  // Far from everything it flies on (nothing to pass through), within the coordinate range.
  World alone(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  alone.addShape(primitives::icosphere(2, kRadius), kDensity);
  alone.addParticle(0, {{0, 0, 0}, {}, {}, {}});
  alone.addParticle(0, {{0, 1.0, 0}, {}, {1e160, 0, 0}, {}});
  alone.setTimeStep(1e-110);
  EXPECT_EQ(stepError(alone), "");
  EXPECT_GT(alone.particles()[1].position.x, 1e49);
}

TEST(DemGuards, AStepThatWouldTakeTheTimePastADoubleIsRefused) {
  // A checkpoint holds the time, and its reader refuses one that is not finite: no step may end
  // there.
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addParticle(0, {{0, 0, 0}, {}, {}, {}});
  world.setTimeStep(1e308);
  EXPECT_EQ(stepError(world), "");
  EXPECT_NE(stepError(world).find("the time is no longer finite at step 2"), std::string::npos);
  EXPECT_EQ(world.stepCount(), 1u);
}

TEST(DemGuards, FastParticlesFarFromEverythingAreNotStopped) {
  // One particle crosses the box at 0.3 m a step beside a row it never comes near (a test of the
  // distributed DEM does this on purpose): nothing can pass through anything.
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addParticle(0, {{0, 0, 0}, {}, {}, {}});
  world.addParticle(0, {{0.05, 0, 0}, {}, {}, {}});
  world.addParticle(0, {{-1.0, 0.1, 0}, {}, {0.3 / world.parameters().timeStep, 0, 0}, {}});
  EXPECT_EQ(stepError(world, 5), "");
}

TEST(DemGuards, SpinCountsAtTheBoundingRadius) {
  // 2ε = 1 mm a step at r = 1 cm: a turn of 0.1 rad a step is too much.
  World world = sphereOverFloor({0, 0, 0.012}, {});  // 2 mm above the floor
  const double rate = 0.1 / world.parameters().timeStep;
  world.setAngularVelocity(0, {rate, 0, 0});
  EXPECT_NE(stepError(world).find("angular speed"), std::string::npos);
  world.setAngularVelocity(0, {0.01 * rate, 0, 0});  // 1 mm·0.1 a step: caught
  EXPECT_EQ(stepError(world), "");
}

TEST(DemGuards, AFastObstacleCountsToo) {
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addParticle(0, {{0, 0, 0.5}, {}, {}, {}});
  world.addParticle(0, {{0.5, 0, 0.5}, {}, {0.001, 0, 0}, {}});
  world.addObstacle(primitives::quad(1.0, 1.0), {{0, 0, 2000.0}, {}, {}});
  const std::string message = stepError(world, 1000);
  EXPECT_NE(message.find("within reach of obstacle 0"), std::string::npos) << message;
  EXPECT_NE(message.find("largest safe time step"), std::string::npos) << message;
  EXPECT_LT(world.obstacles()[0].pose.translation.z, 0.5);  // stopped before reaching them
}

TEST(DemGuards, SlowMotionIsNeverStopped) {
  World world = sphereOverFloor({0, 0, 0.05}, {0, 0, -1.0});
  EXPECT_NO_THROW(world.run(2000));  // falls, bounces (restitution 1), rises
  EXPECT_GT(world.particles()[0].velocity.z, 0.0);
}

TEST(DemGuards, ParticlesPlacedOverlappingShowOverlapAfterTheFirstStep) {
  // What `delta dem` warns of ("particles start overlapping").
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addParticle(0, {{0, 0, 0}, {}, {}, {}});
  world.addParticle(0, {{0.5 * kRadius, 0, 0}, {}, {}, {}});
  world.step();
  EXPECT_GT(world.statistics().overlappingContacts, 0u);
}

TEST(DemGuards, AStepThatFailsLeavesTheWorldAsItWasAndItMayGoOn) {
  // Two sphere particles 3ε apart along x (no contact), the second moving at the first. A time
  // step of 7e10 s brings them within 2ε (1.5ε of drift: the pass-through guard lets it go), and
  // the force of a stiffness of 1e300 then carries the velocities past a double in the step's
  // last half kick: the step fails after its force evaluation. It had left the particles moved,
  // with the step count and the time as before: a World that went on, or was saved, held half a
  // step.
  Parameters parameters = test::centimetreParameters(0.01, 1.0, 1.0, 0.5, {});
  parameters.stiffness = 1e300;
  const double epsilon = parameters.epsilon, bigStep = 7e10;
  World world(parameters);
  world.addShape(ParticleShape::sphere(kRadius, kDensity));
  world.addParticle(0, {{0, 0, 0}, {}, {}, {}});
  world.addParticle(0,
                    {{2 * kRadius + 3 * epsilon, 0, 0}, {}, {-1.5 * epsilon / bigStep, 0, 0}, {}});
  world.setTimeStep(1e-30);
  world.run(5);
  for (const bool recordsMade : {false, true}) {
    const std::size_t madeBefore = recordsMade ? world.contacts().size() : 0;
    const World before = world;
    world.setTimeStep(bigStep);
    const std::string message = stepError(world);
    EXPECT_NE(message.find("particle 0 is no longer finite at step " +
                           std::to_string(before.stepCount() + 1)),
              std::string::npos)
        << message;
    EXPECT_EQ(world.stateDigest(), before.stateDigest());
    EXPECT_EQ(world.stepCount(), before.stepCount());
    EXPECT_EQ(world.time(), before.time());
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(world.particles()[i].position, before.particles()[i].position);
      EXPECT_EQ(world.particles()[i].velocity, before.particles()[i].velocity);
    }
    EXPECT_EQ(world.energies().kinetic(), before.energies().kinetic());
    // The last evaluation's records: kept where they had been made; otherwise overwritten by
    // the failed step's, and contacts() says so rather than answer with them.
    if (recordsMade) {
      EXPECT_EQ(world.contacts().size(), madeBefore);
    } else {
      EXPECT_THROW(static_cast<void>(world.contacts()), Error);
      // And still after a second step that fails (its evaluation begins and fails again).
      EXPECT_NE(stepError(world).find("no longer finite"), std::string::npos);
      EXPECT_THROW(static_cast<void>(world.contacts()), Error);
      EXPECT_EQ(world.stateDigest(), before.stateDigest());
    }
    // It goes on with the smaller time step, bit for bit as the World that never tried.
    world.setTimeStep(1e-30);
    World untried = before;
    world.run(2);
    untried.run(2);
    EXPECT_EQ(world.stateDigest(), untried.stateDigest());
    EXPECT_EQ(world.contacts().size(), untried.contacts().size());
  }
}

/// Three icospheres resting in a row on the floor, touching one another (restitution 0.5: the
/// forces depend on the velocities), after 3 steps.
World restingRow() {
  World world(test::centimetreParameters(0.01, 1.0, 0.5, 0.5, {0, 0, -9.81}));
  world.addShape(primitives::icosphere(2, kRadius), kDensity);
  world.addObstacle(primitives::quad(1.0, 1.0));
  for (int i = 0; i < 3; ++i)
    world.addParticle(0, {{0.0203 * i, 0, kRadius + 0.0008}, {}, {}, {0, 0, 10.0 * i}});
  world.run(3);
  return world;
}

TEST(DemGuards, ASetterThatRefusesAValueChangesNothing) {
  // An audit's cases: setPose with a zero orientation moved the particle before refusing it,
  // and every refused setter still made the next step evaluate its forces anew (and drop the
  // neighbour list), which changes the run: 2e-5 m after 300 steps.
  const World start = restingRow();
  const std::vector<std::function<void(World&)>> refused = {
      [](World& w) {
        w.setPose(1, {0.5, 0.5, 0.5}, Quaternion{0, 0, 0, 0});
      },
      [](World& w) {
        w.setPose(1, {NAN, 0, 0}, {});
      },
      [](World& w) {
        w.setPose(1, {1e61, 0, 0}, {});
      },
      [](World& w) {
        w.setVelocity(1, {INFINITY, 0, 0});
      },
      [](World& w) {
        w.setAngularVelocity(1, {NAN, 0, 0});
      },
      [](World& w) {
        w.setVelocity(7, {0, 0, 0});
      }};
  for (std::size_t k = 0; k < refused.size(); ++k) {
    World world = start, untouched = start;
    EXPECT_THROW(refused[k](world), Error) << k;
    EXPECT_EQ(world.stateDigest(), untouched.stateDigest()) << k;
    world.run(100);
    untouched.run(100);
    EXPECT_EQ(world.stateDigest(), untouched.stateDigest()) << k;
  }
}

TEST(DemGuards, AStepRefusedAfterItsFirstEvaluationPutsTheForcesBack) {
  // A setter makes the next step evaluate the forces first; the pass-through guard then refused
  // it, and the particles kept that evaluation's forces and torques (an audit: 13 of 30
  // changed), so the World's digest and checkpoint were no longer those before the step.
  World world = restingRow();
  ASSERT_GE(world.contacts().size(), 3u);  // on the floor and against one another
  world.setVelocity(1, {0, 0, -500});      // valid, but too fast for the shell
  const World before = world;
  EXPECT_NE(stepError(world).find("particle 1 (speed 500"), std::string::npos);
  EXPECT_EQ(world.stateDigest(), before.stateDigest());
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(world.particles()[i].force, before.particles()[i].force) << i;
    EXPECT_EQ(world.particles()[i].torque, before.particles()[i].torque) << i;
  }
  world.setVelocity(1, {0, 0, 0});
  World untried = before;
  untried.setVelocity(1, {0, 0, 0});
  world.run(10);
  untried.run(10);
  EXPECT_EQ(world.stateDigest(), untried.stateDigest());
}

TEST(DemGuards, AStepThatFailsBeforeItsEvaluationKeepsTheContactRecords) {
  // A step that carries both particles beyond the queries' coordinate range is refused after
  // the drift, before its evaluation: the last evaluation's records stay.
  World world = fallingBeyondTheRange(2, 5);
  const World before = world;
  world.setTimeStep(1e-5);
  EXPECT_NE(stepError(world).find("particle 0's bounding sphere at step 6 reaches a coordinate"),
            std::string::npos);
  EXPECT_EQ(world.stateDigest(), before.stateDigest());
  World untried = before;
  EXPECT_EQ(world.contacts().size(), untried.contacts().size());
}

TEST(DemGuards, ABodyLeavingTheCoordinateRangeIsRefusedWithNothingNearIt) {
  // One particle flies beyond ±2^200 with nothing near it. No pair's query met it, and the
  // step went on; the World then held a position every query refuses.
  World world = fallingBeyondTheRange(1, 3);
  const World before = world;
  world.setTimeStep(1e-5);
  const std::string message = stepError(world);
  EXPECT_NE(message.find("particle 0's bounding sphere at step 4 reaches a coordinate"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("±2^200"), std::string::npos) << message;
  EXPECT_EQ(world.stateDigest(), before.stateDigest());
  EXPECT_EQ(world.stepCount(), 3u);
  // Within the range it goes on.
  world.setTimeStep(1e-40);
  EXPECT_EQ(stepError(world), "");
}

TEST(DemGuards, AMovingObstacleLeavingTheCoordinateRangeIsRefused) {
  // No particle (the pass-through guard would stop one near so fast a wall first).
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addObstacle(primitives::quad(1.0, 1.0),
                    {.velocity = {0, 0, -1e55}, .angularVelocity = {}, .pivot = {}});
  world.setTimeStep(1e-30);
  EXPECT_EQ(stepError(world), "");
  const World before = world;
  world.setTimeStep(1e6);
  const std::string message = stepError(world);
  EXPECT_NE(message.find("obstacle 0 at step 2 reaches a coordinate"), std::string::npos)
      << message;
  EXPECT_EQ(world.stateDigest(), before.stateDigest());
  EXPECT_EQ(world.obstacles()[0].pose.translation, before.obstacles()[0].pose.translation);
}

TEST(DemGuards, BodiesPlacedBeyondTheCoordinateRangeAreRefused) {
  World world(test::centimetreParameters(0.01, 1.0, 1.0, 0.0, {}));
  world.addShape(primitives::icosphere(1, kRadius), kDensity);
  for (const Vec3 position : {Vec3{1e61, 0, 0}, Vec3{0, -2e60, 0}, Vec3{0, 0, 2e60}}) {
    try {
      world.addParticle(0, {position, {}, {}, {}});
      ADD_FAILURE() << "a particle at " << toString(position) << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find("addParticle 0: its bounding sphere reaches"),
                std::string::npos)
          << error.what();
    }
  }
  EXPECT_EQ(world.particles().size(), 0u);
  world.addParticle(0, {{0, 0, 0}, {}, {}, {}});
  EXPECT_THROW(world.setPose(0, {0, 1e61, 0}, {}), Error);
  EXPECT_EQ(world.particles()[0].position, (Vec3{0, 0, 0}));
  Mesh far = primitives::quad(1.0, 1.0);
  far.translate({0, 0, 1e61});
  EXPECT_THROW(world.addObstacle(far), Error);
  EXPECT_EQ(world.obstacles().size(), 0u);
}

}  // namespace
}  // namespace delta::dem
