#include "delta/dem/mpi/distributed_world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta::dem {
namespace {

/// A particle on its way to another rank: as its owner, or as a ghost.
struct ParticleRecord {
  std::uint32_t id;
  Particle particle;
};
/// A friction spring going with the particle that owns its pair.
struct SpringRecord {
  std::uint64_t key;
  TangentialSpring spring;
  std::uint8_t withObstacle;
};
static_assert(std::is_trivially_copyable_v<ParticleRecord>);
static_assert(std::is_trivially_copyable_v<SpringRecord>);
static_assert(std::is_trivially_copyable_v<RankLoad>);
static_assert(std::is_trivially_copyable_v<Contact>);

void check(int code, const char* call) {
  if (code != MPI_SUCCESS) throw Error(std::string("dem: MPI call ") + call + " failed");
}

/// What a rank received in an exchange: the items by source rank, and how many each sent.
template <class T>
struct Received {
  std::vector<T> items;
  std::vector<int> counts;  ///< by source rank
};

/// Sends outgoing[r] to rank r, for every r, and returns what every rank sent this one: sizes
/// first, then the data between the ranks that have any. With `neighbours` (ranks, the same
/// relation on every rank: r is j's neighbour when j is r's), only they exchange anything, each
/// with each of its own: O(neighbours) messages instead of an MPI_Alltoall over all ranks;
/// outgoing[r] must then be empty for every other r. Collective over `communicator`.
template <class T>
Received<T> sendToRanks(MPI_Comm communicator, const std::vector<std::vector<T>>& outgoing,
                        const std::vector<int>* neighbours = nullptr) {
  static_assert(std::is_trivially_copyable_v<T>);
  const int ranks = static_cast<int>(outgoing.size());
  std::vector<int> sendCounts(outgoing.size()), receiveCounts(outgoing.size(), 0);
  for (int r = 0; r < ranks; ++r) {
    const std::size_t bytes = outgoing[r].size() * sizeof(T);
    if (bytes > static_cast<std::size_t>(std::numeric_limits<int>::max()))
      throw Error("dem: more than 2 GiB for one rank in one exchange");
    sendCounts[r] = static_cast<int>(outgoing[r].size());
  }
  if (neighbours) {
    std::vector<MPI_Request> requests;
    constexpr int kCountTag = 7000;
    for (const int r : *neighbours) {
      requests.emplace_back();
      check(MPI_Irecv(&receiveCounts[r], 1, MPI_INT, r, kCountTag, communicator, &requests.back()),
            "MPI_Irecv");
    }
    for (const int r : *neighbours) {
      requests.emplace_back();
      check(MPI_Isend(&sendCounts[r], 1, MPI_INT, r, kCountTag, communicator, &requests.back()),
            "MPI_Isend");
    }
    check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE),
          "MPI_Waitall");
  } else {
    check(
        MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, communicator),
        "MPI_Alltoall");
  }
  std::vector<std::size_t> offset(outgoing.size() + 1, 0);
  for (int r = 0; r < ranks; ++r)
    offset[r + 1] = offset[r] + static_cast<std::size_t>(receiveCounts[r]);
  std::vector<T> incoming(offset.back());
  std::vector<MPI_Request> requests;
  constexpr int kTag = 7001;
  for (int r = 0; r < ranks; ++r)
    if (receiveCounts[r] > 0) {
      requests.emplace_back();
      check(MPI_Irecv(incoming.data() + offset[r], receiveCounts[r] * static_cast<int>(sizeof(T)),
                      MPI_BYTE, r, kTag, communicator, &requests.back()),
            "MPI_Irecv");
    }
  for (int r = 0; r < ranks; ++r)
    if (sendCounts[r] > 0) {
      requests.emplace_back();
      check(MPI_Isend(outgoing[r].data(), sendCounts[r] * static_cast<int>(sizeof(T)), MPI_BYTE, r,
                      kTag, communicator, &requests.back()),
            "MPI_Isend");
    }
  check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE),
        "MPI_Waitall");
  return {std::move(incoming), std::move(receiveCounts)};
}

/// Every rank's `mine` gathered on `root`, by rank; empty elsewhere.
template <class T>
std::vector<T> gather(MPI_Comm communicator, int root, const std::vector<T>& mine) {
  static_assert(std::is_trivially_copyable_v<T>);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(communicator, &rank);
  MPI_Comm_size(communicator, &ranks);
  const int bytes = static_cast<int>(mine.size() * sizeof(T));
  std::vector<int> counts(rank == root ? ranks : 0), displacements(counts.size() + 1, 0);
  check(MPI_Gather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, root, communicator),
        "MPI_Gather");
  for (std::size_t r = 0; r < counts.size(); ++r)
    displacements[r + 1] = displacements[r] + counts[r];
  std::vector<T> all(rank == root ? static_cast<std::size_t>(displacements.back()) / sizeof(T) : 0);
  check(MPI_Gatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), displacements.data(),
                    MPI_BYTE, root, communicator),
        "MPI_Gatherv");
  return all;
}

/// Moves the elements of `values` to the order `order` gives (order[k]: the old index of the
/// new k-th).
template <class T>
void permute(std::vector<T>& values, const std::vector<std::size_t>& order) {
  std::vector<T> moved;
  moved.reserve(values.size());
  for (const std::size_t old : order)
    moved.push_back(std::move(values[old]));
  values = std::move(moved);
}

using SpringList = std::vector<std::pair<std::uint64_t, TangentialSpring>>;

/// The distance between two boxes (faces at ±infinity allowed): 0 where they touch or overlap.
double boxDistance(const Aabb& a, const Aabb& b) {
  double squared = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double gap =
        std::max({a.lower[axis] - b.upper[axis], b.lower[axis] - a.upper[axis], 0.0});
    squared += gap * gap;
  }
  return std::sqrt(squared);
}

/// The springs whose pair's first id is leaving (`leaving`: (id, new owner), by id), removed
/// from `springs` and added to what goes to the new owner.
void takeSprings(SpringList& springs, const std::vector<std::pair<std::uint32_t, int>>& leaving,
                 bool withObstacle, std::vector<std::vector<SpringRecord>>& outgoing) {
  std::size_t kept = 0;
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const auto id = static_cast<std::uint32_t>(springs[s].first >> 32);
    const auto found =
        std::lower_bound(leaving.begin(), leaving.end(), std::pair<std::uint32_t, int>{id, -1});
    if (found != leaving.end() && found->first == id)
      outgoing[found->second].push_back(
          {springs[s].first, springs[s].second, static_cast<std::uint8_t>(withObstacle)});
    else
      springs[kept++] = springs[s];
  }
  springs.resize(kept);
}

}  // namespace

/// The World's hooks between the phases of a step.
class DistributedWorld::Exchange final : public World::Exchange {
 public:
  explicit Exchange(DistributedWorld& owner) : owner_(owner) {}

  void refreshGhosts(World& /*part*/) override {
    owner_.migrate();
    owner_.rebalanceIfNeeded();
    owner_.receiveGhosts();
  }

  std::vector<World::GhostForce> swapGhostForces(std::vector<World::GhostForce> found) override {
    std::vector<std::vector<World::GhostForce>> outgoing(static_cast<std::size_t>(owner_.size_));
    for (const World::GhostForce& force : found) {
      const auto owner = std::lower_bound(owner_.ghostOwners_.begin(), owner_.ghostOwners_.end(),
                                          std::pair<std::uint32_t, int>{force.particle, -1});
      outgoing[static_cast<std::size_t>(owner->second)].push_back(force);
    }
    return sendToRanks(owner_.communicator_, outgoing, &owner_.neighbours_).items;
  }

  std::uint64_t firstNonFinite(std::uint64_t local) override {
    std::uint64_t first = local;
    check(MPI_Allreduce(&local, &first, 1, MPI_UINT64_T, MPI_MIN, owner_.communicator_),
          "MPI_Allreduce");
    return first;
  }

 private:
  DistributedWorld& owner_;
};

namespace {

/// 0² + 1² + … + (n − 1)², modulo 2⁶⁴: n(n − 1)(2n − 1)/6 with the divisions made exactly
/// before the products wrap.
std::uint64_t sumOfSquaresBelow(std::uint64_t n) {
  if (n == 0) return 0;
  std::uint64_t a = n, b = n - 1, c = 2 * n - 1;
  (a % 2 == 0 ? a : b) /= 2;
  if (a % 3 == 0)
    a /= 3;
  else if (b % 3 == 0)
    b /= 3;
  else
    c /= 3;
  return a * b * c;
}

void checkOptions(const DecompositionOptions& options, const World& world) {
  const double tolerance = options.rebalanceTolerance;
  if (std::isnan(tolerance) || tolerance < 0.0)
    throw Error("dem: DecompositionOptions::rebalanceTolerance = " + toString(tolerance) +
                " must be >= 0 (or infinity)");
  if (world.shapes().empty()) throw Error("dem: DistributedWorld: the World has no shapes");
}

}  // namespace

DistributedWorld::DistributedWorld(MPI_Comm communicator, const World& whole,
                                   const DecompositionOptions& options)
    : part_(whole), options_(options), particleCount_(whole.particles().size()) {
  checkOptions(options, whole);
  check(MPI_Comm_dup(communicator, &communicator_), "MPI_Comm_dup");
  MPI_Comm_rank(communicator_, &rank_);
  MPI_Comm_size(communicator_, &size_);
  // Each rank starts with every size_-th particle (and the springs of its pairs), then the
  // first bisection sends each to its owner: the same path a later rebalance takes.
  World& part = part_;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < whole.particles().size(); ++i)
    if (i % static_cast<std::size_t>(size_) == static_cast<std::size_t>(rank_)) {
      part.particles_[kept] = part.particles_[i];
      part.ids_[kept] = part.ids_[i];
      ++kept;
    }
  part.particles_.resize(kept);
  part.ids_.resize(kept);
  part.owned_ = kept;
  const auto notMine = [&](const std::pair<std::uint64_t, TangentialSpring>& spring) {
    return (spring.first >> 32) % static_cast<std::uint64_t>(size_) !=
           static_cast<std::uint64_t>(rank_);
  };
  std::erase_if(part.particleSprings_, notMine);
  std::erase_if(part.obstacleSprings_, notMine);
  start();
  // A stepped World's particles carry the forces of its last evaluation (each one's own, whole):
  // the next step's first half kick uses them, as World::step would, instead of evaluating again.
  part_.forcesCurrent_ = whole.forcesCurrent_;
}

DistributedWorld::DistributedWorld(MPI_Comm communicator, const World& share,
                                   std::span<const std::uint32_t> ids,
                                   const DecompositionOptions& options)
    : part_(share), options_(options) {
  checkOptions(options, share);
  if (share.stepCount() != 0)
    throw Error("dem: DistributedWorld: a rank's share was stepped (" +
                std::to_string(share.stepCount()) + " steps); pass it before the first step");
  if (ids.size() != share.particles().size())
    throw Error("dem: DistributedWorld: " + std::to_string(ids.size()) + " ids for " +
                std::to_string(share.particles().size()) + " particles");
  check(MPI_Comm_dup(communicator, &communicator_), "MPI_Comm_dup");
  MPI_Comm_rank(communicator_, &rank_);
  MPI_Comm_size(communicator_, &size_);
  // Over the ranks the ids must be 0 … N − 1: each below N, and their sum and the sum of their
  // squares (modulo 2⁶⁴) those of 0 … N − 1. Checked together, so every rank throws alike.
  std::uint64_t sums[3] = {ids.size(), 0, 0}, largest = 0;
  for (const std::uint32_t id : ids) {
    sums[1] += id;
    sums[2] += std::uint64_t{id} * id;
    largest = std::max<std::uint64_t>(largest, std::uint64_t{id} + 1);
  }
  check(MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_UINT64_T, MPI_SUM, communicator_),
        "MPI_Allreduce");
  check(MPI_Allreduce(MPI_IN_PLACE, &largest, 1, MPI_UINT64_T, MPI_MAX, communicator_),
        "MPI_Allreduce");
  const std::uint64_t n = sums[0];
  if (largest > n || (n > 0 && (sums[1] != n * (n - 1) / 2 || sums[2] != sumOfSquaresBelow(n)))) {
    MPI_Comm_free(&communicator_);
    throw Error("dem: DistributedWorld: the ranks' particle ids are not 0 ... " +
                std::to_string(n) + " - 1, each once");
  }
  particleCount_ = n;
  for (std::size_t i = 0; i < ids.size(); ++i)
    part_.ids_[i] = ids[i];
  part_.particleSprings_.clear();
  part_.obstacleSprings_.clear();
  start();
}

void DistributedWorld::start() {
  for (const ParticleShape& shape : part_.shapes())
    largestRadius_ = std::max(largestRadius_, shape.boundingRadius());
  part_.records_.contacts.clear();
  part_.records_.pending = false;
  part_.forcesCurrent_ = false;  // the first step evaluates with the ghosts
  try {
    rebalance();
  } catch (...) {  // thrown on every rank (a point not finite): the destructor will not run
    MPI_Comm_free(&communicator_);
    throw;
  }
  rebalances_ = 0;
}

DistributedWorld::~DistributedWorld() {
  if (communicator_ != MPI_COMM_NULL) MPI_Comm_free(&communicator_);
}

void DistributedWorld::step() {
  Exchange exchange(*this);
  part_.advance(&exchange);
  const StepStatistics& statistics = part_.statistics();
  load_.particles = part_.owned_;
  load_.ghosts = part_.particles_.size() - part_.owned_;
  load_.neighbours = neighbours_.size();
  load_.contacts = statistics.contactPoints;
  ++load_.steps;
  load_.contactDetectionSeconds += statistics.contactDetectionSeconds;
  load_.communicationSeconds += statistics.communicationSeconds;
  load_.stepSeconds += statistics.totalSeconds;
}

void DistributedWorld::run(std::size_t steps) {
  for (std::size_t s = 0; s < steps; ++s)
    step();
}

void DistributedWorld::migrate(bool everywhere) {
  World& part = part_;
  part.particles_.resize(part.owned_);  // the ghosts are refreshed after
  part.ids_.resize(part.owned_);
  std::vector<std::vector<ParticleRecord>> outgoing(static_cast<std::size_t>(size_));
  std::vector<std::pair<std::uint32_t, int>> leaving;  // (id, new owner)
  std::size_t kept = 0;
  for (std::size_t i = 0; i < part.owned_; ++i) {
    const int owner = decomposition_.partOf(part.particles_[i].position);
    if (owner == rank_) {
      part.particles_[kept] = part.particles_[i];
      part.ids_[kept] = part.ids_[i];
      ++kept;
    } else {
      outgoing[static_cast<std::size_t>(owner)].push_back({part.ids_[i], part.particles_[i]});
      leaving.push_back({part.ids_[i], owner});
    }
  }
  std::sort(leaving.begin(), leaving.end());
  std::vector<std::vector<SpringRecord>> springsOut(static_cast<std::size_t>(size_));
  takeSprings(part.particleSprings_, leaving, false, springsOut);
  takeSprings(part.obstacleSprings_, leaving, true, springsOut);

  // A step moves a particle far less than the ghosts' reach, so into a neighbour's region; after
  // a new bisection, or a particle that jumped, every rank may send to any (all ranks agree).
  int far = everywhere ? 1 : 0;
  for (const auto& [id, owner] : leaving)
    far = far || !std::binary_search(neighbours_.begin(), neighbours_.end(), owner);
  if (!everywhere)
    check(MPI_Allreduce(MPI_IN_PLACE, &far, 1, MPI_INT, MPI_MAX, communicator_), "MPI_Allreduce");
  const std::vector<int>* to = far ? nullptr : &neighbours_;
  const std::vector<ParticleRecord> arrived = sendToRanks(communicator_, outgoing, to).items;
  const std::vector<SpringRecord> springsIn = sendToRanks(communicator_, springsOut, to).items;
  part.particles_.resize(kept);
  part.ids_.resize(kept);
  for (const ParticleRecord& record : arrived) {
    part.particles_.push_back(record.particle);
    part.ids_.push_back(record.id);
  }
  part.owned_ = part.particles_.size();
  if (!arrived.empty()) {  // keep the owned particles by id: output and gathers read them so
    std::vector<std::size_t> order(part.owned_);
    for (std::size_t i = 0; i < order.size(); ++i)
      order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return part.ids_[a] < part.ids_[b]; });
    permute(part.particles_, order);
    permute(part.ids_, order);
  }
  for (const SpringRecord& record : springsIn)
    (record.withObstacle ? part.obstacleSprings_ : part.particleSprings_)
        .push_back({record.key, record.spring});
  if (!springsIn.empty()) {
    const auto byKey = [](const auto& a, const auto& b) { return a.first < b.first; };
    std::sort(part.particleSprings_.begin(), part.particleSprings_.end(), byKey);
    std::sort(part.obstacleSprings_.begin(), part.obstacleSprings_.end(), byKey);
  }
}

void DistributedWorld::rebalanceIfNeeded() {
  if (std::isinf(options_.rebalanceTolerance) || size_ == 1) return;
  std::uint64_t mine = part_.owned_, most = 0;
  check(MPI_Allreduce(&mine, &most, 1, MPI_UINT64_T, MPI_MAX, communicator_), "MPI_Allreduce");
  const double mean = static_cast<double>(particleCount_) / static_cast<double>(size_);
  const auto best = static_cast<std::uint64_t>(std::ceil(mean));
  if (most > best && static_cast<double>(most) > (1.0 + options_.rebalanceTolerance) * mean) {
    rebalance();
  }
}

void DistributedWorld::rebalance() {
  std::vector<Vec3> centres;
  for (std::size_t i = 0; i < part_.owned_; ++i)
    centres.push_back(part_.particles_[i].position);
  BisectionReduction reduction;
  reduction.sum = [this](std::span<std::uint64_t> values) {
    check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_UINT64_T,
                        MPI_SUM, communicator_),
          "MPI_Allreduce");
  };
  reduction.maximum = [this](std::span<double> values) {
    check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE,
                        MPI_MAX, communicator_),
          "MPI_Allreduce");
  };
  decomposition_ = Bisection(centres, size_, reduction);
  // The ranks whose regions lie within the largest reach of a ghost of this one's (2·rMax + 2ε):
  // the only ones a step exchanges particles, ghosts and forces with.
  const double reach = 2.0 * (largestRadius_ + part_.contactLaw().epsilon);
  const Aabb mine = decomposition_.region(rank_);
  neighbours_.clear();
  for (int r = 0; r < size_; ++r)
    if (r != rank_ && boxDistance(mine, decomposition_.region(r)) <= reach)
      neighbours_.push_back(r);
  ++rebalances_;
  migrate(true);
}

void DistributedWorld::receiveGhosts() {
  World& part = part_;
  const double shell = 2.0 * part.contactLaw().epsilon + largestRadius_;
  std::vector<std::vector<ParticleRecord>> outgoing(static_cast<std::size_t>(size_));
  std::vector<int> near;
  for (std::size_t i = 0; i < part.owned_; ++i) {
    const Particle& particle = part.particles_[i];
    if (!isFinite(particle.position)) continue;  // the finiteness check reports it, on every rank
    const double reach = part.shapes_[particle.shape].boundingRadius() + shell;
    decomposition_.partsWithin(particle.position, reach, near);
    for (const int r : near)
      if (r != rank_) outgoing[static_cast<std::size_t>(r)].push_back({part.ids_[i], particle});
  }
  const Received<ParticleRecord> ghosts = sendToRanks(communicator_, outgoing, &neighbours_);
  ghostOwners_.clear();  // the forces on them go back to these ranks
  std::size_t next = 0;
  for (int r = 0; r < size_; ++r)
    for (int k = 0; k < ghosts.counts[static_cast<std::size_t>(r)]; ++k)
      ghostOwners_.push_back({ghosts.items[next++].id, r});
  std::sort(ghostOwners_.begin(), ghostOwners_.end());
  for (const ParticleRecord& record : ghosts.items) {
    part.particles_.push_back(record.particle);
    part.ids_.push_back(record.id);
  }
}

Energies DistributedWorld::energies() const {
  const Energies mine = part_.energies();
  double values[4] = {mine.translational, mine.rotational, mine.gravitational, mine.elastic};
  check(MPI_Allreduce(MPI_IN_PLACE, values, 4, MPI_DOUBLE, MPI_SUM, communicator_),
        "MPI_Allreduce");
  return {values[0], values[1], values[2], values[3]};
}

Vec3 DistributedWorld::linearMomentum() const {
  Vec3 sum = part_.linearMomentum();
  check(MPI_Allreduce(MPI_IN_PLACE, &sum.x, 3, MPI_DOUBLE, MPI_SUM, communicator_),
        "MPI_Allreduce");
  return sum;
}

Vec3 DistributedWorld::angularMomentum() const {
  Vec3 sum = part_.angularMomentum();
  check(MPI_Allreduce(MPI_IN_PLACE, &sum.x, 3, MPI_DOUBLE, MPI_SUM, communicator_),
        "MPI_Allreduce");
  return sum;
}

StepStatistics DistributedWorld::statistics() const {
  // Counts are summed over the ranks; the deepest ratio and the seconds are the largest.
  constexpr std::size_t StepStatistics::*kSummed[] = {
      &StepStatistics::particlePairsTested, &StepStatistics::obstaclePairsTested,
      &StepStatistics::pairsInContact,      &StepStatistics::rawContactPoints,
      &StepStatistics::contactPoints,       &StepStatistics::overlappingContacts};
  constexpr double StepStatistics::*kLargest[] = {&StepStatistics::deepestRatio,
                                                  &StepStatistics::broadPhaseSeconds,
                                                  &StepStatistics::contactDetectionSeconds,
                                                  &StepStatistics::forceSeconds,
                                                  &StepStatistics::integrationSeconds,
                                                  &StepStatistics::communicationSeconds,
                                                  &StepStatistics::totalSeconds};
  const StepStatistics& mine = part_.statistics();
  std::uint64_t sums[std::size(kSummed)];
  double largest[std::size(kLargest)];
  for (std::size_t k = 0; k < std::size(kSummed); ++k)
    sums[k] = mine.*kSummed[k];
  for (std::size_t k = 0; k < std::size(kLargest); ++k)
    largest[k] = mine.*kLargest[k];
  check(MPI_Allreduce(MPI_IN_PLACE, sums, static_cast<int>(std::size(sums)), MPI_UINT64_T, MPI_SUM,
                      communicator_),
        "MPI_Allreduce");
  check(MPI_Allreduce(MPI_IN_PLACE, largest, static_cast<int>(std::size(largest)), MPI_DOUBLE,
                      MPI_MAX, communicator_),
        "MPI_Allreduce");
  StepStatistics all;
  for (std::size_t k = 0; k < std::size(kSummed); ++k)
    all.*kSummed[k] = sums[k];
  for (std::size_t k = 0; k < std::size(kLargest); ++k)
    all.*kLargest[k] = largest[k];
  return all;
}

std::vector<Particle> DistributedWorld::gatherParticles(int root) const {
  std::vector<ParticleRecord> mine;
  for (std::size_t i = 0; i < part_.owned_; ++i)
    mine.push_back({part_.ids_[i], part_.particles_[i]});
  std::vector<ParticleRecord> all = gather(communicator_, root, mine);
  std::sort(all.begin(), all.end(),
            [](const ParticleRecord& a, const ParticleRecord& b) { return a.id < b.id; });
  std::vector<Particle> particles;
  particles.reserve(all.size());
  for (const ParticleRecord& record : all)
    particles.push_back(record.particle);
  return particles;
}

std::vector<Contact> DistributedWorld::gatherContacts(int root) const {
  const std::span<const Contact> local = part_.contacts();
  std::vector<Contact> all =
      gather(communicator_, root, std::vector<Contact>(local.begin(), local.end()));
  // World's order: particle pairs by ids, then particle–obstacle pairs; within a pair as found
  // (one rank found each pair, so a stable sort keeps that).
  std::stable_sort(all.begin(), all.end(), [](const Contact& a, const Contact& b) {
    return std::tuple(a.withObstacle, a.first, a.second) <
           std::tuple(b.withObstacle, b.first, b.second);
  });
  return all;
}

std::optional<World> DistributedWorld::gatherWorld(int root) const {
  std::vector<ParticleRecord> particles;
  for (std::size_t i = 0; i < part_.owned_; ++i)
    particles.push_back({part_.ids_[i], part_.particles_[i]});
  particles = gather(communicator_, root, particles);
  std::vector<SpringRecord> springs;
  for (const auto& [key, spring] : part_.particleSprings_)
    springs.push_back({key, spring, 0});
  for (const auto& [key, spring] : part_.obstacleSprings_)
    springs.push_back({key, spring, 1});
  springs = gather(communicator_, root, springs);
  std::vector<Contact> contacts = gatherContacts(root);
  double elastic = 0.0;
  check(MPI_Reduce(&part_.elasticEnergy_, &elastic, 1, MPI_DOUBLE, MPI_SUM, root, communicator_),
        "MPI_Reduce");
  if (rank_ != root) return std::nullopt;
  // The parameters, shapes, obstacles, time and step count are every rank's.
  World whole = part_;
  std::sort(particles.begin(), particles.end(),
            [](const ParticleRecord& a, const ParticleRecord& b) { return a.id < b.id; });
  whole.particles_.clear();
  whole.ids_.clear();
  for (const ParticleRecord& record : particles) {
    whole.particles_.push_back(record.particle);
    whole.ids_.push_back(record.id);
  }
  whole.owned_ = whole.particles_.size();
  std::sort(springs.begin(), springs.end(),
            [](const SpringRecord& a, const SpringRecord& b) { return a.key < b.key; });
  whole.particleSprings_.clear();
  whole.obstacleSprings_.clear();
  for (const SpringRecord& record : springs)
    (record.withObstacle ? whole.obstacleSprings_ : whole.particleSprings_)
        .push_back({record.key, record.spring});
  whole.records_.contacts = std::move(contacts);
  whole.records_.pending = false;
  whole.elasticEnergy_ = elastic;
  whole.placed_.clear();
  return whole;
}

std::vector<RankLoad> DistributedWorld::gatherLoads(int root) const {
  return gather(communicator_, root, std::vector<RankLoad>{load_});
}

}  // namespace delta::dem
