// The guide's "Using Δ inside an MPI code" (docs/guide.md): a DEM code whose ranks each own the
// particles of a slab of the domain. Δ makes no MPI call and holds no global state; a rank gives
// it the particles it owns and the ghosts within reach, and computes the pairs it owns.
//
// The tests build this file without DELTA_GUIDE_WITH_MPI: main() then runs three ranks one
// after another in this process, and checks that their contacts together are exactly those of
// one rank that owns every particle. The MPI version (DELTA_GUIDE_WITH_MPI, below) is not
// compiled by the tests, since Δ does not depend on MPI; build it yourself with
//   mpicxx -DDELTA_GUIDE_WITH_MPI $(pkg-config --cflags delta-mpi) mpi_ranks.cpp
//     $(pkg-config --libs delta-mpi)        (one line; delta-mpi.pc is installed with Δ)
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "delta/delta.h"

#ifdef DELTA_GUIDE_WITH_MPI
#include <mpi.h>
#endif

namespace {

// [guide:begin records]
/// A particle as the ranks exchange it: plain data, so MPI sends it as bytes.
struct ParticleRecord {
  std::uint64_t id = 0;     // global; the owner rule compares ids
  std::uint32_t shape = 0;  // an index into the shapes every rank builds alike
  delta::Vec3 position;     // of the centre of mass
  delta::Quaternion orientation;
};
static_assert(std::is_trivially_copyable_v<ParticleRecord>);

/// A pair's contact points, found by the rank that owns the pair.
struct PairContacts {
  std::uint64_t first = 0, second = 0;  // particle ids, first < second
  std::vector<delta::ContactPoint> points;
};
// [guide:end records]

// [guide:begin rank]
/// Δ's part of a rank's step: the contacts of the pairs this rank owns (those whose smaller id
/// is one of its particles) that touch. `ghosts` must hold every particle of the other ranks whose
/// centre lies within 2·rMax + 2ε of this rank's subdomain (rMax the largest bounding radius).
std::vector<PairContacts> ownedPairContacts(std::span<const delta::dem::ParticleShape> shapes,
                                            std::span<const ParticleRecord> owned,
                                            std::span<const ParticleRecord> ghosts, double epsilon,
                                            double h) {
  std::vector<ParticleRecord> local(owned.begin(), owned.end());
  local.insert(local.end(), ghosts.begin(), ghosts.end());
  std::vector<delta::Sphere> spheres;
  std::vector<delta::QueryMesh> placed;  // copies share their shape's prepared mesh
  for (const ParticleRecord& particle : local) {
    const delta::dem::ParticleShape& shape = shapes[particle.shape];
    spheres.push_back({particle.position, shape.boundingRadius()});
    placed.push_back(shape.queryMesh());
    placed.back().setPose({particle.orientation, particle.position});
  }
  const std::vector<delta::dem::CandidatePair> near = delta::dem::nearbyPairs(spheres, 2 * epsilon);
  std::vector<PairContacts> found(near.size());
  // In parallel over the pairs; each Δ call inside runs serially on its thread.
  delta::parallelFor(0, near.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      std::uint32_t i = near[k].first, j = near[k].second;
      if (local[j].id < local[i].id) std::swap(i, j);  // i: the smaller id
      if (i >= owned.size()) continue;                 // a ghost's pair: its owner computes it
      found[k] = {local[i].id, local[j].id,
                  delta::dem::pairContacts(placed[i], placed[j], epsilon, h).points};
    }
  });
  std::erase_if(found, [](const PairContacts& pair) { return pair.points.empty(); });
  return found;
}
// [guide:end rank]

/// Three granulate shapes of radius about 1, density 1: every rank makes the same ones (the
/// same seed gives the same mesh on every machine).
std::vector<delta::dem::ParticleShape> makeShapes() {
  std::vector<delta::dem::ParticleShape> shapes;
  for (std::uint64_t seed = 1; seed <= 3; ++seed)
    shapes.emplace_back(delta::primitives::granulate(seed, {1.0, 0.9, 0.8}), 1.0);
  return shapes;
}

/// 24 particles on a 6 × 2 × 2 lattice 1.9 apart along x, turned every way, their ids a
/// permutation of 0 … 23 (so that the smaller id of a pair is not always on the left).
std::vector<ParticleRecord> lattice() {
  std::vector<ParticleRecord> particles;
  for (std::uint32_t k = 0; k < 24; ++k)
    particles.push_back(
        {.id = (7u * k) % 24u,
         .shape = k % 3u,
         .position = {1.9 * (k % 6u), 1.95 * (k / 6u % 2u), 1.95 * (k / 12u)},
         .orientation = delta::Quaternion::fromAxisAngle({1.0, 0.5 * k, 2.0}, 0.7 * k)});
  return particles;
}

constexpr double kEpsilon = 0.05, kFilter = 0.25;

}  // namespace

#ifdef DELTA_GUIDE_WITH_MPI
// [guide:begin mpi]
/// Sends each neighbour the owned particles within `reach` of the face they share and returns
/// what the neighbours send: this rank's ghosts. Slabs along x, rank order, each at least
/// `reach` wide (so ghosts come from the two neighbours only).
std::vector<ParticleRecord> exchangeGhosts(std::span<const ParticleRecord> owned, double lower,
                                           double upper, double reach, MPI_Comm comm) {
  int rank = 0, size = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::vector<ParticleRecord> ghosts;
  for (const int side : {-1, +1}) {  // send left and receive from the right, then the reverse
    const int to = rank + side, from = rank - side;
    const int destination = to >= 0 && to < size ? to : MPI_PROC_NULL;
    const int source = from >= 0 && from < size ? from : MPI_PROC_NULL;
    std::vector<ParticleRecord> send;
    for (const ParticleRecord& particle : owned)
      if (side < 0 ? particle.position.x < lower + reach : particle.position.x >= upper - reach)
        send.push_back(particle);
    int sendBytes = static_cast<int>(send.size() * sizeof(ParticleRecord)), receiveBytes = 0;
    MPI_Sendrecv(&sendBytes, 1, MPI_INT, destination, 0, &receiveBytes, 1, MPI_INT, source, 0, comm,
                 MPI_STATUS_IGNORE);
    std::vector<ParticleRecord> received(receiveBytes / sizeof(ParticleRecord));
    MPI_Sendrecv(send.data(), sendBytes, MPI_BYTE, destination, 1, received.data(), receiveBytes,
                 MPI_BYTE, source, 1, comm, MPI_STATUS_IGNORE);
    ghosts.insert(ghosts.end(), received.begin(), received.end());
  }
  return ghosts;
}

int main(int argc, char** argv) try {
  // Only the main thread calls MPI; Δ's threads never do.
  int provided = 0, rank = 0, size = 1;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  if (provided < MPI_THREAD_FUNNELED) MPI_Abort(MPI_COMM_WORLD, 1);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  const std::vector<delta::dem::ParticleShape> shapes = makeShapes();  // alike on every rank
  double rMax = 0.0;
  for (const delta::dem::ParticleShape& shape : shapes)
    rMax = std::max(rMax, shape.boundingRadius());
  const double reach = 2 * rMax + 2 * kEpsilon;
  const double width = 6 * 1.9 / size;  // this rank's slab [lower, upper) of the lattice's x
  const double lower = rank == 0 ? -1e300 : rank * width - 0.95;
  const double upper = rank == size - 1 ? 1e300 : (rank + 1) * width - 0.95;
  if (size > 1 && width < reach) MPI_Abort(MPI_COMM_WORLD, 1);  // slabs narrower than the reach

  std::vector<ParticleRecord> owned;  // a real code creates or reads only its own
  for (const ParticleRecord& particle : lattice())
    if (particle.position.x >= lower && particle.position.x < upper) owned.push_back(particle);

  const std::vector<ParticleRecord> ghosts =
      exchangeGhosts(owned, lower, upper, reach, MPI_COMM_WORLD);
  const std::vector<PairContacts> pairs =
      ownedPairContacts(shapes, owned, ghosts, kEpsilon, kFilter);
  // Forces: dem::pairForces per pair; the force on a ghost goes back to its owner.

  unsigned long long mine = 0, total = 0;
  for (const PairContacts& pair : pairs)
    mine += pair.points.size();
  MPI_Reduce(&mine, &total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
  if (rank == 0) std::printf("%llu contact points on %d ranks\n", total, size);
  MPI_Finalize();
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "mpi_ranks: %s\n", error.what());
  MPI_Abort(MPI_COMM_WORLD, 1);
  return 1;
}
// [guide:end mpi]
#else
int main() try {
  const std::vector<delta::dem::ParticleShape> shapes = makeShapes();
  const std::vector<ParticleRecord> particles = lattice();
  double rMax = 0.0;
  for (const delta::dem::ParticleShape& shape : shapes)
    rMax = std::max(rMax, shape.boundingRadius());
  const double reach = 2 * rMax + 2 * kEpsilon;

  // One rank that owns everything: the reference.
  std::vector<PairContacts> reference = ownedPairContacts(shapes, particles, {}, kEpsilon, kFilter);

  // Three ranks, slabs of x with faces at 3.3 and 6.6, each with its ghosts.
  const double faces[] = {-1e300, 3.3, 6.6, 1e300};
  std::vector<PairContacts> together;
  std::size_t crossing = 0;  // pairs computed with a ghost
  for (int rank = 0; rank < 3; ++rank) {
    const double lower = faces[rank], upper = faces[rank + 1];
    std::vector<ParticleRecord> owned, ghosts;
    for (const ParticleRecord& particle : particles) {
      const double x = particle.position.x;
      if (x >= lower && x < upper)
        owned.push_back(particle);
      else if (x >= lower - reach && x < upper + reach)
        ghosts.push_back(particle);
    }
    for (PairContacts& pair : ownedPairContacts(shapes, owned, ghosts, kEpsilon, kFilter)) {
      crossing += std::none_of(owned.begin(), owned.end(), [&](const ParticleRecord& particle) {
        return particle.id == pair.second;
      });
      together.push_back(std::move(pair));
    }
  }

  // The same pairs, each computed once, with the same points to the bit.
  const auto byIds = [](const PairContacts& a, const PairContacts& b) {
    return std::pair(a.first, a.second) < std::pair(b.first, b.second);
  };
  std::sort(reference.begin(), reference.end(), byIds);
  std::sort(together.begin(), together.end(), byIds);
  std::size_t points = 0;
  bool same = reference.size() == together.size();
  for (std::size_t k = 0; same && k < reference.size(); ++k) {
    const PairContacts &one = reference[k], &other = together[k];
    same = one.first == other.first && one.second == other.second &&
           one.points.size() == other.points.size();
    for (std::size_t i = 0; same && i < one.points.size(); ++i) {
      const delta::ContactPoint &p = one.points[i], &q = other.points[i];
      same = p.x == q.x && p.normal == q.normal && p.direction == q.direction &&
             p.distance == q.distance && p.overlap == q.overlap && p.first == q.first &&
             p.second == q.second;
    }
    points += one.points.size();
  }
  std::printf("%zu pairs in contact, %zu contact points; %zu pairs across a rank's face\n",
              reference.size(), points, crossing);
  if (!same || points == 0 || crossing == 0) {
    std::fprintf(stderr, "the ranks' contacts are not those of one rank\n");
    return 1;
  }
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "mpi_ranks: %s\n", error.what());
  return 1;
}
#endif
