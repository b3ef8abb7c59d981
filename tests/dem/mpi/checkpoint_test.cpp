// Checkpoints of a distributed run under mpirun (1, 2 and 4 ranks): a checkpoint gathered from
// P ranks (DistributedWorld::gatherWorld) restarts on Q ranks — all of them, half of them, one
// process — and ends bit for bit where an uninterrupted World of one process does; a checkpoint
// of a World of one process restarts on P ranks alike.
#include "delta/dem/checkpoint.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "delta/dem/mpi/distributed_world.h"
#include "delta/dem/scenarios.h"

namespace delta::dem {
namespace {

constexpr std::size_t kBefore = 1500;  ///< steps before the checkpoint: contacts, springs
constexpr std::size_t kAfter = 150;

int rankIn(MPI_Comm communicator) {
  int rank = 0;
  MPI_Comm_rank(communicator, &rank);
  return rank;
}

int sizeOf(MPI_Comm communicator) {
  int size = 1;
  MPI_Comm_size(communicator, &size);
  return size;
}

/// Rank 0's bytes on every rank.
std::string broadcast(std::string bytes) {
  unsigned long long size = bytes.size();
  MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  bytes.resize(static_cast<std::size_t>(size));
  MPI_Bcast(bytes.data(), static_cast<int>(size), MPI_CHAR, 0, MPI_COMM_WORLD);
  return bytes;
}

bool sameParticles(const std::vector<Particle>& a, std::span<const Particle> b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Particle)) == 0);
}

/// Every rank: the state of kBefore + kAfter uninterrupted steps of one process.
World uninterrupted() {
  Scenario scenario = settle(27, 3);
  scenario.world.run(kBefore + kAfter);
  return std::move(scenario.world);
}

/// Restarts `bytes` on the ranks of `communicator` (a DistributedWorld, or World::step on one
/// process when `alone`), runs kAfter steps and checks the end on its rank 0.
void restartAndCompare(const std::string& bytes, MPI_Comm communicator, const World& expected,
                       const char* what) {
  SCOPED_TRACE(what);
  World loaded = readCheckpoint(bytes, what).world;
  DistributedWorld world(communicator, loaded);
  world.run(kAfter);
  const std::optional<World> end = world.gatherWorld();
  if (rankIn(communicator) != 0) return;
  ASSERT_TRUE(end);
  EXPECT_EQ(end->stepCount(), expected.stepCount());
  EXPECT_TRUE(sameParticles(std::vector<Particle>(end->particles().begin(), end->particles().end()),
                            expected.particles()));
  EXPECT_EQ(end->stateDigest(), expected.stateDigest());
}

TEST(DistributedCheckpoint, WrittenOnPRanksRestartsOnAnyCountBitForBit) {
  const World expected = uninterrupted();
  Scenario scenario = settle(27, 3);
  std::string bytes;
  {
    DistributedWorld world(MPI_COMM_WORLD, scenario.world);
    world.run(kBefore);
    const std::optional<World> whole = world.gatherWorld();
    if (rankIn(MPI_COMM_WORLD) == 0) {
      ASSERT_TRUE(whole);
      EXPECT_GT(whole->contacts().size(), 0u);
      bytes = checkpointBytes(*whole);
    }
  }
  bytes = broadcast(bytes);

  // On one process: World::step.
  if (rankIn(MPI_COMM_WORLD) == 0) {
    World alone = readCheckpoint(bytes, "on one process").world;
    alone.run(kAfter);
    EXPECT_TRUE(
        sameParticles(std::vector<Particle>(alone.particles().begin(), alone.particles().end()),
                      expected.particles()));
    EXPECT_EQ(alone.stateDigest(), expected.stateDigest());
  }
  // On every rank, and on the first half of them (a different count where there are 2 or 4).
  restartAndCompare(bytes, MPI_COMM_WORLD, expected, "on every rank");
  const int half = std::max(1, sizeOf(MPI_COMM_WORLD) / 2);
  MPI_Comm halfRanks = MPI_COMM_NULL;
  const bool inHalf = rankIn(MPI_COMM_WORLD) < half;
  MPI_Comm_split(MPI_COMM_WORLD, inHalf ? 0 : MPI_UNDEFINED, 0, &halfRanks);
  if (inHalf) {
    restartAndCompare(bytes, halfRanks, expected, "on half of the ranks");
    MPI_Comm_free(&halfRanks);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

TEST(DistributedCheckpoint, AOneProcessCheckpointRestartsOnEveryRank) {
  const World expected = uninterrupted();
  Scenario scenario = settle(27, 3);
  scenario.world.run(kBefore);
  restartAndCompare(checkpointBytes(scenario.world), MPI_COMM_WORLD, expected, "from one process");
}

}  // namespace
}  // namespace delta::dem
