#pragma once

#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "delta/dem/bisection.h"
#include "delta/dem/world.h"

/// @file
/// The DEM case study on many processes: a World split over the ranks of an MPI communicator by
/// recursive coordinate bisection of the particle centres. Part of the optional library
/// delta::mpi (built where CMake finds MPI; link it and MPI::MPI_CXX).

namespace delta::dem {

/// How a DistributedWorld splits the particles and when it splits them again.
///
/// Threading: a value type; no shared state.
struct DecompositionOptions {
  /// The particles are split again (a new bisection of their centres, and every particle sent
  /// to its new owner) when the most particles a rank owns exceed the mean by more than this
  /// fraction, and exceed the best possible, ⌈N / P⌉. Finite and ≥ 0, or infinity (never after
  /// the start).
  double rebalanceTolerance = 0.1;
};

/// A DEM simulation split over the ranks of an MPI communicator (domain decomposition).
///
/// Space is cut into one region per rank by recursive coordinate bisection of the particle
/// centres (Bisection), and each rank owns and integrates the particles whose centres lie in its
/// region. Before every force evaluation a rank hands the particles that left its region to
/// their new owners (with the friction springs of the pairs they evaluate) and receives ghost
/// copies of every particle within reach of its region: the particle's bounding radius, plus
/// the largest bounding radius, plus 2ε. A pair of particles is evaluated by the rank owning its
/// lower id (the same rule as World's), once; the forces on a ghost go back to its owner. All of
/// this passes between neighbouring ranks only (neighbours()). The particles are split again
/// when the counts drift apart (DecompositionOptions).
///
/// The obstacles, shapes and parameters are the same on every rank; each rank places only its
/// own particles and ghosts, so its meshes' spatial caches follow its region.
///
/// Results do not depend on the number of ranks: every rank sums the forces on a particle in the
/// order of the pairs' ids, as a World of one process does, so positions, velocities and angular
/// momenta are bit for bit those of World::step for any number of ranks (and threads); only
/// sums over ranks (energies, momenta, counts) may differ by round-off.
///
/// Every member function not marked "local" is collective: all ranks call it, in the same
/// order. An error found on one rank (a particle no longer finite) is thrown on every rank.
///
/// Threading: MPI must be initialised with at least MPI_THREAD_FUNNELED; one thread a rank
/// calls the DistributedWorld (step() runs in parallel itself, as World::step does). Local
/// const functions may be called concurrently between steps.
class DistributedWorld {
 public:
  /// Splits `whole` over the ranks of `communicator` (duplicated; the caller keeps its own):
  /// every rank passes the same World (same parameters, shapes, obstacles and particles, e.g.
  /// a scenario each rank builds, or one loaded from a checkpoint) and keeps only its part. A
  /// World that was stepped keeps its last forces and friction springs: the next step goes on
  /// bit for bit as whole.step() would. Particle ids are their indices in
  /// `whole`. Throws delta::Error (on every rank) for a World with no shapes, or options out of
  /// range. Memory: every rank holds `whole` while this runs; for a simulation too large for
  /// one node, use the next constructor.
  DistributedWorld(MPI_Comm communicator, const World& whole,
                   const DecompositionOptions& options = {});
  /// Splits a simulation whose particles the ranks made between them: every rank passes a World
  /// with the same parameters, shapes and obstacles and the particles it made (any of them, any
  /// number, none included), not yet stepped, and their ids: over all ranks, 0 … N − 1, each
  /// once. The particles go to their owners before the first step. Throws delta::Error on every
  /// rank, before stepping, for a World that was stepped or has no shapes, an id count that is
  /// not the World's particle count, or ids that are not 0 … N − 1 over the ranks (each below N
  /// and their sum and sum of squares those of 0 … N − 1), and options out of range.
  DistributedWorld(MPI_Comm communicator, const World& share, std::span<const std::uint32_t> ids,
                   const DecompositionOptions& options = {});
  ~DistributedWorld();
  DistributedWorld(const DistributedWorld&) = delete;
  DistributedWorld& operator=(const DistributedWorld&) = delete;

  /// Advances by one time step (World::step on every rank's part, with the exchanges between
  /// its phases). Throws delta::Error, on every rank, when a particle stops being finite.
  void step();
  /// step() `steps` times.
  void run(std::size_t steps);

  // Local reading.

  int rank() const noexcept { return rank_; }
  int size() const noexcept { return size_; }
  /// The particles this rank owns, by ascending id.
  std::span<const Particle> particles() const noexcept { return part_.particles(); }
  /// Their ids (indices in the World the run started from).
  std::span<const std::uint32_t> ids() const noexcept { return {part_.ids_.data(), part_.owned_}; }
  /// The contact points of the pairs this rank evaluated in the last step; `first` and `second`
  /// are particle ids. Over all ranks, each contact point once.
  std::span<const Contact> contacts() const noexcept { return part_.contacts(); }
  /// This rank's part: its parameters, shapes and obstacles are the whole simulation's.
  const World& part() const noexcept { return part_; }
  const Bisection& decomposition() const noexcept { return decomposition_; }
  /// The ranks whose regions lie within 2·(rMax + ε) of this one's (rMax the largest bounding
  /// radius), ascending: the only ones a step exchanges particles, ghosts and forces with (a
  /// new bisection, or a particle that moved further than that in a step, exchanges with all).
  std::span<const int> neighbours() const noexcept { return neighbours_; }
  /// How many times the particles were split again after the start.
  std::size_t rebalances() const noexcept { return rebalances_; }
  RankLoad load() const noexcept { return load_; }
  double time() const noexcept { return part_.time(); }
  std::size_t stepCount() const noexcept { return part_.stepCount(); }

  // Collective.

  /// All particles' count.
  std::size_t particleCount() const noexcept { return particleCount_; }
  /// Summed over the ranks.
  Energies energies() const;
  Vec3 linearMomentum() const;
  Vec3 angularMomentum() const;
  /// The last step's statistics over all ranks: counts summed, deepestRatio and seconds the
  /// largest of any rank.
  StepStatistics statistics() const;
  /// Every particle, by id, on rank `root`; empty on the others.
  std::vector<Particle> gatherParticles(int root = 0) const;
  /// Every contact point of the last step, sorted as World::contacts() sorts them, on `root`.
  std::vector<Contact> gatherContacts(int root = 0) const;
  /// The whole simulation as one World, on rank `root` (std::nullopt on the others): every
  /// particle by id (its index there) with the forces of the last step, the friction springs
  /// of every pair, the last step's contacts (sorted as World's), the time and the step count.
  /// Stepping it goes on bit for bit as this DistributedWorld would, and so does a
  /// DistributedWorld made from it on any number of ranks: checkpoints (dem/checkpoint.h) of a
  /// distributed run are those of this World, and restart on any rank count.
  std::optional<World> gatherWorld(int root = 0) const;
  /// Every rank's load, by rank, on `root`; empty on the others.
  std::vector<RankLoad> gatherLoads(int root = 0) const;

 private:
  class Exchange;

  /// Hands every owned particle whose centre is outside this rank's region to its owner: to the
  /// neighbours only, unless `everywhere` (after a new bisection) or a particle jumped further.
  void migrate(bool everywhere = false);
  /// Splits the particles again if the counts drifted apart (every rank decides alike).
  void rebalanceIfNeeded();
  void rebalance();
  void receiveGhosts();
  /// The first split, from the particles each rank holds (the constructors' common end).
  void start();

  MPI_Comm communicator_ = MPI_COMM_NULL;
  int rank_ = 0;
  int size_ = 1;
  World part_;
  DecompositionOptions options_;
  Bisection decomposition_;
  std::size_t particleCount_ = 0;
  std::size_t rebalances_ = 0;
  double largestRadius_ = 0.0;
  std::vector<std::pair<std::uint32_t, int>> ghostOwners_;  ///< (id, rank), by id
  /// The ranks whose regions lie within 2·(rMax + ε) of this one's, ascending: the ones its
  /// steps exchange with (the same relation on every rank).
  std::vector<int> neighbours_;
  RankLoad load_;
};

}  // namespace delta::dem
