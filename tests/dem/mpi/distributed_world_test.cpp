// DistributedWorld under mpirun (1, 2 and 4 ranks): the same trajectories as World, bit for
// bit, with pairs split across ranks, migration, rebalancing and friction springs on the move;
// momentum conservation and restitution with the pair split; errors on every rank.
//
// Every rank also runs the one-process World, and rank 0 compares; checks that involve all
// ranks reduce first, so that no rank waits in a collective call another has skipped.
#include "delta/dem/mpi/distributed_world.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "delta/core/error.h"
#include "delta/dem/scenarios.h"
#include "delta/mesh/primitives.h"

#include "dem/centimetre_parameters.h"

namespace delta::dem {
namespace {

int rankOfThis() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int ranks() {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

std::uint64_t sumOverRanks(std::uint64_t value) {
  MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  return value;
}

bool sameBits(const Vec3& a, const Vec3& b) {
  return std::memcmp(&a, &b, sizeof(Vec3)) == 0;
}

bool sameState(const Particle& a, const Particle& b) {
  return a.shape == b.shape && sameBits(a.position, b.position) &&
         sameBits(a.velocity, b.velocity) && sameBits(a.angularMomentum, b.angularMomentum) &&
         sameBits(a.angularVelocity, b.angularVelocity) && sameBits(a.force, b.force) &&
         sameBits(a.torque, b.torque) &&
         std::memcmp(&a.orientation, &b.orientation, sizeof(Quaternion)) == 0;
}

/// 4 × 4 × 4 granulates (or spheres) of about a centimetre, 2.1 r apart, flying about at up to
/// 0.4 m/s and spinning, under gravity in an open box a little wider than them, with friction:
/// dozens of pairs in contact within a few hundred steps.
World crowdedBox(ParticleKind kind, std::uint64_t seed = 5, const Vec3& drift = {},
                 const std::function<bool(std::size_t)>& keep = {},
                 ContactModel model = ContactModel::point) {
  constexpr double r = 0.01, density = 2500.0;
  std::mt19937_64 random(seed);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
  std::vector<ParticleShape> shapes;
  if (kind == ParticleKind::Sphere) {
    shapes.push_back(ParticleShape::sphere(0.9 * r, density));
  } else {
    for (std::uint64_t s = 0; s < 4; ++s)
      shapes.emplace_back(
          primitives::granulate(seed * 10 + s, {r, r * (0.85 + 0.3 * uniform()), 0.8 * r}),
          density);
  }
  double heaviest = 0.0;
  for (const ParticleShape& shape : shapes)
    heaviest = std::max(heaviest, shape.mass());
  Parameters parameters = test::centimetreParameters(heaviest, 1.0, 0.5, 0.5, {0.0, 0.0, -9.81});
  parameters.contactModel = model;
  World world(parameters);
  for (const ParticleShape& shape : shapes)
    world.addShape(shape);
  constexpr int n = 4;
  constexpr double spacing = 2.1 * r;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        ParticleState state;
        state.position = Vec3{i - 1.5, j - 1.5, k + 0.6} * spacing;
        state.velocity = Vec3{uniform(), uniform(), uniform()} * 0.8 + drift;
        state.orientation = Quaternion::fromAxisAngle({uniform(), uniform(), 1.0}, 6.0 * uniform());
        state.angularVelocity = Vec3{uniform(), uniform(), uniform()} * 20.0;
        const std::size_t index = static_cast<std::size_t>((i * n + j) * n + k);
        if (!keep || keep(index))
          world.addParticle(static_cast<std::size_t>((i + j + k) % static_cast<int>(shapes.size())),
                            state);
      }
  if (model == ContactModel::volume)  // closed obstacles: the box's walls made solid
    for (const Mesh& wall : openBoxWalls(n * spacing + r, n * spacing + r, 10.0 * r, 0.0, r))
      world.addObstacle(wall);
  else
    world.addObstacle(openBox(n * spacing + r, n * spacing + r, 10.0 * r));
  return world;
}

/// Runs `whole` for `steps` in one process and distributed, comparing every `every` steps on
/// rank 0: particles bit for bit, contacts point for point. Returns the distributed world's
/// rebalances (the same on every rank).
struct Comparison {
  std::size_t mismatchedParticles = 0;
  std::size_t mismatchedContacts = 0;
  std::size_t contacts = 0;             ///< summed over the checks
  std::size_t contactsAcrossRanks = 0;  ///< particle–particle, owners on two ranks
  std::size_t rebalances = 0;
  std::uint64_t ghosts = 0;  ///< summed over ranks and checks
};

Comparison compare(World serial, std::size_t steps, std::size_t every,
                   const DecompositionOptions& options = {}) {
  DistributedWorld distributed(MPI_COMM_WORLD, serial, options);
  Comparison result;
  for (std::size_t step = 1; step <= steps; ++step) {
    serial.step();
    distributed.step();
    result.contacts += serial.contacts().size();
    if (step % every != 0 && step != steps) continue;
    const std::vector<Particle> particles = distributed.gatherParticles();
    const std::vector<Contact> contacts = distributed.gatherContacts();
    result.ghosts += sumOverRanks(distributed.load().ghosts);
    if (distributed.rank() != 0) continue;
    EXPECT_EQ(particles.size(), serial.particles().size());
    for (std::size_t i = 0; i < std::min(particles.size(), serial.particles().size()); ++i)
      result.mismatchedParticles += sameState(particles[i], serial.particles()[i]) ? 0 : 1;
    const std::span<const Contact> expected = serial.contacts();
    if (contacts.size() != expected.size()) {
      result.mismatchedContacts += std::max(contacts.size(), expected.size());
      continue;
    }
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      const Contact& a = contacts[c];
      const Contact& b = expected[c];
      const bool same = a.first == b.first && a.second == b.second &&
                        a.withObstacle == b.withObstacle && sameBits(a.point.x, b.point.x) &&
                        sameBits(a.force, b.force);
      result.mismatchedContacts += same ? 0 : 1;
      if (!a.withObstacle && distributed.decomposition().partOf(particles[a.first].position) !=
                                 distributed.decomposition().partOf(particles[a.second].position))
        ++result.contactsAcrossRanks;
    }
  }
  result.rebalances = distributed.rebalances();
  return result;
}

TEST(DistributedWorld, GranulatesFollowTheOneProcessTrajectoriesBitForBit) {
  const Comparison result = compare(crowdedBox(ParticleKind::Mesh), 400, 5);
  if (rankOfThis() != 0) return;
  EXPECT_EQ(result.mismatchedParticles, 0u);
  EXPECT_EQ(result.mismatchedContacts, 0u);
  EXPECT_GT(result.contacts, 500u);  // the test tests something
  if (ranks() > 1) {
    EXPECT_GT(result.contactsAcrossRanks, 0u);
    EXPECT_GT(result.ghosts, 0u);
  }
}

TEST(DistributedWorld, TheVolumeLawFollowsTheOneProcessTrajectoriesBitForBit) {
  // Its forces come with couples (contact_model.h), which ghosts hand back to their owners.
  const Comparison result =
      compare(crowdedBox(ParticleKind::Mesh, 5, {}, {}, ContactModel::volume), 300, 5);
  if (rankOfThis() != 0) return;
  EXPECT_EQ(result.mismatchedParticles, 0u);
  EXPECT_EQ(result.mismatchedContacts, 0u);
  EXPECT_GT(result.contacts, 100u);
  if (ranks() > 1) {
    EXPECT_GT(result.contactsAcrossRanks, 0u);
  }
}

TEST(DistributedWorld, SpheresFollowTheOneProcessTrajectoriesBitForBit) {
  const Comparison result = compare(crowdedBox(ParticleKind::Sphere), 400, 5);
  if (rankOfThis() != 0) return;
  EXPECT_EQ(result.mismatchedParticles, 0u);
  EXPECT_EQ(result.mismatchedContacts, 0u);
  EXPECT_GT(result.contacts, 500u);
  if (ranks() > 1) {
    EXPECT_GT(result.contactsAcrossRanks, 0u);
  }
}

TEST(DistributedWorld, RebalancingEveryFewStepsChangesNothing) {
  // Tolerance 0: split again whenever a rank has more than its share, moving particles and
  // their friction springs between ranks many times.
  DecompositionOptions options;
  options.rebalanceTolerance = 0.0;
  // All drift toward +x, so that particles cross the cuts and pile up on one side.
  const Comparison result =
      compare(crowdedBox(ParticleKind::Mesh, 9, {1.5, 0.0, 0.0}), 300, 30, options);
  if (rankOfThis() != 0) return;
  EXPECT_EQ(result.mismatchedParticles, 0u);
  EXPECT_EQ(result.mismatchedContacts, 0u);
  if (ranks() > 1) {
    EXPECT_GT(result.rebalances, 0u);
  }
}

TEST(DistributedWorld, RanksThatMadeTheirOwnParticlesFollowTheOneProcessRun) {
  // Rank r makes the particles whose index is congruent to −r: none where it will own them.
  const auto size = static_cast<std::size_t>(ranks());
  const auto rank = static_cast<std::size_t>(rankOfThis());
  const auto mine = [&](std::size_t index) { return (index + rank) % size == 0; };
  const World share = crowdedBox(ParticleKind::Mesh, 5, {}, mine);
  std::vector<std::uint32_t> ids;
  for (std::uint32_t index = 0; index < 64; ++index)
    if (mine(index)) ids.push_back(index);
  World serial = crowdedBox(ParticleKind::Mesh);
  DistributedWorld distributed(MPI_COMM_WORLD, share, ids);
  EXPECT_EQ(distributed.particleCount(), 64u);
  std::size_t mismatched = 0;
  for (int step = 0; step < 150; ++step) {
    serial.step();
    distributed.step();
  }
  const std::vector<Particle> particles = distributed.gatherParticles();
  if (distributed.rank() != 0) return;
  ASSERT_EQ(particles.size(), 64u);
  for (std::size_t i = 0; i < particles.size(); ++i)
    mismatched += sameState(particles[i], serial.particles()[i]) ? 0 : 1;
  EXPECT_EQ(mismatched, 0u);
}

TEST(DistributedWorld, IdsThatAreNotZeroToNAreErrorsOnEveryRank) {
  const World share =
      crowdedBox(ParticleKind::Sphere, 5, {}, [](std::size_t index) { return index < 3; });
  const std::uint32_t rank = static_cast<std::uint32_t>(rankOfThis());
  const std::uint32_t size = static_cast<std::uint32_t>(ranks());
  const std::vector<std::vector<std::uint32_t>> bad = {
      {3 * rank, 3 * rank + 1, 3 * rank + 1},      // a repeated id
      {3 * rank, 3 * rank + 1, 3 * size},          // one past N
      {3 * rank + 1, 3 * rank + 1, 3 * rank + 1},  // the sum of 0 … N − 1, not of their squares
  };
  for (std::size_t b = 0; b < bad.size(); ++b) {
    int threw = 0;
    try {
      DistributedWorld distributed(MPI_COMM_WORLD, share, bad[b]);
    } catch (const Error&) {
      threw = 1;
    }
    MPI_Allreduce(MPI_IN_PLACE, &threw, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    EXPECT_EQ(threw, ranks()) << "case " << b;
  }
  // The right ids, a wrong count of them, a share that was stepped.
  const std::vector<std::uint32_t> good = {3 * rank, 3 * rank + 1, 3 * rank + 2};
  EXPECT_NO_THROW(DistributedWorld(MPI_COMM_WORLD, share, good));
  EXPECT_THROW(DistributedWorld(MPI_COMM_WORLD, share, std::span(good).first(2)), Error);
  World stepped = share;
  stepped.step();
  EXPECT_THROW(DistributedWorld(MPI_COMM_WORLD, stepped, good), Error);
}

TEST(DistributedWorld, HopperFollowsTheOneProcessRun) {
  Scenario scenario = hopper(200, 2);
  const Comparison result = compare(std::move(scenario.world), 300, 100);
  if (rankOfThis() != 0) return;
  EXPECT_EQ(result.mismatchedParticles, 0u);
  EXPECT_EQ(result.mismatchedContacts, 0u);
}

TEST(DistributedWorld, ALongRowExchangesWithItsNeighboursOnly) {
  // 40 spheres in a row along x, colliding in pairs, and one more beside the row (no contact)
  // flying along it across several ranks' regions in each step: the ranks, slabs along x,
  // exchange with the slabs beside them only, and with everyone when a particle jumps further.
  Parameters parameters = crowdedBox(ParticleKind::Sphere).parameters();
  parameters.gravity = {};
  World world(parameters);
  world.addShape(ParticleShape::sphere(0.009, 2500.0));
  for (int i = 0; i < 40; ++i)
    world.addParticle(0, {Vec3{0.0195 * i, 0.0, 0.0}, {}, Vec3{i % 2 ? -0.3 : 0.3, 0.0, 0.0}, {}});
  const double jump = 0.3 / world.parameters().timeStep;  // 0.3 m a step
  world.addParticle(0, {Vec3{0.0, 0.1, 0.0}, {}, Vec3{jump, 0.0, 0.0}, {}});
  DecompositionOptions options;
  options.rebalanceTolerance = std::numeric_limits<double>::infinity();
  const Comparison result = compare(world, 300, 10, options);
  DistributedWorld distributed(MPI_COMM_WORLD, world, options);
  std::uint64_t neighbours = distributed.neighbours().size();
  MPI_Allreduce(MPI_IN_PLACE, &neighbours, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
  if (rankOfThis() != 0) return;
  EXPECT_EQ(result.mismatchedParticles, 0u);
  EXPECT_EQ(result.mismatchedContacts, 0u);
  EXPECT_GT(result.contacts, 100u);
  EXPECT_EQ(result.rebalances, 0u);
  // Slabs of about 10 particles, 0.2 m wide against a reach of 0.02 m: two neighbours at most.
  EXPECT_LE(neighbours, std::min<std::uint64_t>(2, static_cast<std::uint64_t>(ranks() - 1)));
  if (ranks() > 1) {
    EXPECT_GT(result.contactsAcrossRanks, 0u);
  }
}

TEST(DistributedWorld, MomentumIsConservedWithPairsAcrossRanks) {
  const ParticleShape rock(primitives::granulate(3, {0.01, 0.008, 0.007}), 2500.0);
  const ParticleShape ball = ParticleShape::sphere(0.009, 2500.0);
  World world(test::centimetreParameters(rock.mass(), 1.0, 0.3, 0.4, {}));
  world.addShape(rock);
  world.addShape(ball);
  const std::uint32_t shapes[6] = {0, 1, 0, 1, 0, 0};
  test::addConvergingParticles(world, 11, shapes);
  DistributedWorld distributed(MPI_COMM_WORLD, world);
  const Vec3 linear = distributed.linearMomentum();
  const Vec3 angular = distributed.angularMomentum();
  double scale = 0.0, spinScale = 0.0;
  for (const Particle& particle : world.particles()) {
    scale += length(particle.velocity) * world.shapes()[particle.shape].mass();
    spinScale +=
        length(particle.angularMomentum) +
        length(cross(particle.position, particle.velocity)) * world.shapes()[particle.shape].mass();
  }
  std::size_t contacts = 0, across = 0;
  for (int step = 0; step < 600; ++step) {
    distributed.step();
    const std::vector<Contact> all = distributed.gatherContacts();
    const std::vector<Particle> particles = distributed.gatherParticles();
    for (const Contact& contact : all) {
      ++contacts;
      if (!contact.withObstacle &&
          distributed.decomposition().partOf(particles[contact.first].position) !=
              distributed.decomposition().partOf(particles[contact.second].position))
        ++across;
    }
  }
  const Vec3 linearAfter = distributed.linearMomentum();
  const Vec3 angularAfter = distributed.angularMomentum();
  if (distributed.rank() != 0) return;
  EXPECT_GT(contacts, 20u);
  if (ranks() > 1) {
    EXPECT_GT(across, 0u);
  }
  EXPECT_LE(length(linearAfter - linear), 1e-13 * scale);
  EXPECT_LE(length(angularAfter - angular), 1e-13 * spinScale);
}

TEST(DistributedWorld, TwoParticleRestitutionWithThePairSplit) {
  Scenario scenario = twoParticles(0.5);
  World serial = scenario.world;
  DistributedWorld distributed(MPI_COMM_WORLD, scenario.world);
  // With two or more ranks the particles are owned by two ranks all along.
  const std::uint64_t owning = sumOverRanks(distributed.particles().empty() ? 0 : 1);
  RestitutionMeter expected(serial);
  std::optional<RestitutionMeter> measured;
  if (distributed.rank() == 0)
    measured.emplace(distributed.gatherParticles());
  else
    distributed.gatherParticles();
  std::size_t touchingSteps = 0;
  for (std::size_t step = 0; step < scenario.steps; ++step) {
    serial.step();
    distributed.step();
    expected.observe(serial);
    const std::vector<Particle> particles = distributed.gatherParticles();
    const std::vector<Contact> contacts = distributed.gatherContacts();
    if (measured) measured->observe(particles, contacts);
    touchingSteps += contacts.empty() ? 0 : 1;
  }
  if (distributed.rank() != 0) return;
  EXPECT_EQ(owning, ranks() > 1 ? 2u : 1u);
  EXPECT_GT(touchingSteps, 10u);
  ASSERT_TRUE(measured->separated());
  EXPECT_EQ(measured->restitution(), expected.restitution());
  EXPECT_NEAR(measured->restitution(), 0.5, 0.02);
}

TEST(DistributedWorld, AParticleThatStopsBeingFiniteThrowsOnEveryRank) {
  // Eight spheres in a row, the last two placed interpenetrating, with a spring and a time step
  // far beyond any stable pair: the first step's overlap force overflows their velocities.
  Parameters parameters = crowdedBox(ParticleKind::Sphere).parameters();
  parameters.stiffness = 1e300;
  parameters.timeStep = 1e10;
  World world(parameters);
  world.addShape(ParticleShape::sphere(0.01, 2500.0));
  for (int i = 0; i < 8; ++i)
    world.addParticle(0, {Vec3{i < 7 ? 0.03 * i : 0.185, 0.0, 0.0}, {}, {}, {}});
  DistributedWorld distributed(MPI_COMM_WORLD, world);
  int threw = 0;
  try {
    distributed.run(3);
  } catch (const Error& error) {
    threw = std::strstr(error.what(), "particle 6 is no longer finite") != nullptr ? 1 : 0;
  }
  int serialThrew = 0;
  try {
    world.run(3);
  } catch (const Error& error) {
    serialThrew = std::strstr(error.what(), "particle 6 is no longer finite") != nullptr ? 1 : 0;
  }
  MPI_Allreduce(MPI_IN_PLACE, &threw, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(threw, ranks());
  EXPECT_EQ(serialThrew, 1);
}

TEST(DistributedWorld, BadOptionsAreErrors) {
  const World world = crowdedBox(ParticleKind::Sphere);
  for (const double tolerance : {-0.1, std::nan("")}) {
    DecompositionOptions options;
    options.rebalanceTolerance = tolerance;
    EXPECT_THROW(DistributedWorld(MPI_COMM_WORLD, world, options), Error);
  }
  const World noShapes(world.parameters());
  EXPECT_THROW(DistributedWorld(MPI_COMM_WORLD, noShapes), Error);
}

}  // namespace
}  // namespace delta::dem
