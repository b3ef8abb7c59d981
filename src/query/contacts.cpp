#include "delta/query/contacts.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/kernels/pair_results.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/query/part_nesting.h"

#include "detail/dual_traversal.h"
#include "detail/placement.h"
#include "detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

/// Triangles of the second mesh handed to the kernels at once, and pruned as one box.
constexpr std::size_t kBlock = 64;
/// First leaves whose candidate pairs go to the kernels in one batch (QueryMesh contacts).
constexpr std::size_t kGroupsPerBatch = 16;
/// Triangle ids are 32-bit (ContactPoint).
constexpr std::size_t kMaxTriangles = std::size_t{1} << 32;
/// Tasks (one triangle against one block, at most kBlock kernel pairs, a few µs) per parallel
/// chunk: enough to amortise the chunk's scratch and scheduling, few enough to balance.
constexpr std::size_t kTaskGrain = 2;
/// The id of an empty slot of the moved second leaves (a last leaf holds fewer than eight).
constexpr std::uint32_t kNoPartner = std::numeric_limits<std::uint32_t>::max();

/// The boxes of consecutive blocks of kBlock triangles.
std::vector<Aabb> blockBoxes(const TriangleSoA& mesh) {
  std::vector<Aabb> boxes((mesh.size() + kBlock - 1) / kBlock);
  for (std::size_t i = 0; i < mesh.size(); ++i)
    boxes[i / kBlock].extend(mesh.triangle(i).bounds());
  return boxes;
}

Aabb meshBox(const std::vector<Aabb>& blocks) {
  Aabb box;
  for (const Aabb& block : blocks)
    box.extend(block);
  return box;
}

/// The contact direction where the closest points coincide, from the faces (see contacts.h).
Vec3 faceDirection(const Triangle& first, const Triangle& second) noexcept {
  const Vec3 n1 = normalized(first.areaVector());
  const Vec3 n2 = normalized(second.areaVector());
  for (const Vec3& candidate : {n2 - n1, n2, -n1}) {
    const Vec3 unit = normalized(candidate);
    if (lengthSquared(unit) > 0.5) return unit;
  }
  return {0, 0, 1};
}

/// The contact of the pair `k` of `results`, triangles `first` (id i) and `second` (id j). The
/// kernels take the squared distance in a frame near the pair, P and Q rounded to the world's
/// coordinates: at an offset far beyond the pair's size P − Q is mostly that rounding (at 1e8 a
/// distance of 0.37 came out 6e-8 short). The distance is the kernel's, and where the rounding
/// of P − Q may exceed 2⁻³⁰ of it the direction is that of the pair's closest points found again
/// near P (the brute force on the triangles less P; exact translations where the coordinates
/// exceed the pair's size).
ContactPoint contactPoint(const Triangle& first, const Triangle& second,
                          const kernels::PairResults& results, std::size_t k, std::size_t i,
                          std::size_t j) {
  const Vec3 p = results.p(k), q = results.q(k);
  const double squared = results.distanceSquared(k);
  ContactPoint contact;
  contact.x = (p + q) * 0.5;
  // A square below 2⁻⁹⁶⁰ may have underflowed: a distance below 2⁻⁴⁸⁰, which P and Q give
  // where they are that small, and which bounds it where they are not.
  contact.distance = squared >= detail::kUnderflowingSquare ? std::sqrt(squared)
                                                            : std::min(distance(p, q), 0x1p-480);
  Vec3 along = p - q;
  // (An intersecting pair has P = Q and takes its direction from the faces.)
  const bool rounded =
      !results.intersect(k) && std::max(maxAbs(p), maxAbs(q)) * 0x1p-50 > 0x1p-30 * length(along);
  if (rounded) {
    const kernels::TriangleDistanceResult local = kernels::triangleDistanceBruteForce(
        {first.a - p, first.b - p, first.c - p}, {second.a - p, second.b - p, second.c - p});
    along = local.p - local.q;
  }
  contact.direction = normalized(along);
  if (!(lengthSquared(contact.direction) > 0.5)) contact.direction = faceDirection(first, second);
  contact.normal = rounded ? contact.direction * (0.5 * contact.distance) : p - contact.x;
  contact.overlap = results.intersect(k);
  contact.converged = results.converged(k);
  contact.first = static_cast<std::uint32_t>(i);
  contact.second = static_cast<std::uint32_t>(j);
  return contact;
}

/// A table over a tree's leaves is used where it is small beside the pairs (a sort otherwise):
/// a particle against a large obstacle pays for the pairs it has, not for the obstacle's size.
bool tableFits(std::size_t leaves, std::size_t pairs) noexcept {
  return leaves <= 16 * pairs + 1024;
}

/// Sorts `pairs` by first leaf, then second, and puts in `groups` where each first leaf's run
/// starts (and the end): a counting sort where the table fits (measured: std::sort took a sixth
/// of a contact query on refined_elephant). `start` and `grouped` are scratch.
void groupByFirst(std::vector<detail::LeafPair>& pairs, std::size_t leaves,
                  std::vector<std::size_t>& groups, std::vector<std::size_t>& start,
                  std::vector<detail::LeafPair>& grouped) {
  const auto bySecond = [](const detail::LeafPair& x, const detail::LeafPair& y) {
    return x.second < y.second;
  };
  groups.clear();
  if (!tableFits(leaves, pairs.size())) {
    std::sort(pairs.begin(), pairs.end(), [](const detail::LeafPair& x, const detail::LeafPair& y) {
      return x.first != y.first ? x.first < y.first : x.second < y.second;
    });
    for (std::size_t p = 0; p < pairs.size(); ++p)
      if (p == 0 || pairs[p].first != pairs[p - 1].first) groups.push_back(p);
  } else {
    start.assign(leaves + 1, 0);
    for (const detail::LeafPair& pair : pairs)
      ++start[pair.first + 1];
    for (std::size_t leaf = 0; leaf < leaves; ++leaf)
      start[leaf + 1] += start[leaf];
    grouped.resize(pairs.size());
    for (const detail::LeafPair& pair : pairs)  // start[leaf] ends at its run's end
      grouped[start[pair.first]++] = pair;
    pairs.swap(grouped);
    std::size_t from = 0;
    for (std::size_t leaf = 0; leaf < leaves; ++leaf) {
      const std::size_t to = start[leaf];
      if (to > from) {
        groups.push_back(from);
        std::sort(pairs.begin() + static_cast<std::ptrdiff_t>(from),
                  pairs.begin() + static_cast<std::ptrdiff_t>(to), bySecond);
      }
      from = to;
    }
  }
  groups.push_back(pairs.size());
}

/// The distinct second leaves of `pairs` (ascending) and each pair's rank among them.
struct SecondLeaves {
  std::vector<std::uint32_t> leaves;
  std::vector<std::uint32_t> rankOfPair;
  std::vector<std::uint32_t> rank;  ///< scratch: per leaf of the second tree
};

void secondLeavesOf(const std::vector<detail::LeafPair>& pairs, std::size_t leaves,
                    SecondLeaves& result) {
  result.leaves.clear();
  result.rankOfPair.resize(pairs.size());
  if (tableFits(leaves, pairs.size())) {
    std::vector<std::uint32_t>& rank = result.rank;
    rank.assign(leaves, kNoPartner);
    for (const detail::LeafPair& pair : pairs)
      rank[pair.second] = 0;
    for (std::uint32_t leaf = 0; leaf < leaves; ++leaf)
      if (rank[leaf] == 0) {
        rank[leaf] = static_cast<std::uint32_t>(result.leaves.size());
        result.leaves.push_back(leaf);
      }
    for (std::size_t p = 0; p < pairs.size(); ++p)
      result.rankOfPair[p] = rank[pairs[p].second];
    return;
  }
  for (const detail::LeafPair& pair : pairs)
    result.leaves.push_back(pair.second);
  std::sort(result.leaves.begin(), result.leaves.end());
  result.leaves.erase(std::unique(result.leaves.begin(), result.leaves.end()), result.leaves.end());
  for (std::size_t p = 0; p < pairs.size(); ++p)
    result.rankOfPair[p] = static_cast<std::uint32_t>(
        std::lower_bound(result.leaves.begin(), result.leaves.end(), pairs[p].second) -
        result.leaves.begin());
}

/// What a QueryMesh contact query keeps between its phases, per calling thread, with its
/// capacity kept from one query to the next: a DEM step makes hundreds of small queries, and
/// allocating these each time took a tenth of one.
struct MeshPairScratch {
  std::vector<detail::LeafPair> pairs, grouped;
  std::vector<std::size_t> groups, start;
  SecondLeaves named;
  std::vector<Triangle> partnerTriangles;
  std::vector<Aabb> partnerBoxes;
  std::vector<detail::MovedOctet> partnerOctets;
  std::vector<detail::SeparatingPlane> partnerPlanes;
  std::vector<std::uint32_t> partnerIds;
  std::vector<std::uint32_t> partnerIndices;      ///< the second mesh's sorted triangle index
  std::vector<std::vector<ContactPoint>> perRun;  ///< inner vectors emptied, not freed

  /// This thread's (a query never nests in a thread).
  static MeshPairScratch& ofThread() {
    thread_local MeshPairScratch scratch;
    return scratch;
  }
};

/// What a run of kGroupsPerBatch first leaves builds for the kernels, per thread that runs one.
struct RunScratch {
  kernels::PairResults results{kBlock};
  std::vector<Triangle> firsts, seconds;
  std::vector<std::uint32_t> firstIds, secondIds;
  TriangleSoA firstBatch, secondBatch;
  std::vector<std::uint32_t> partners;  ///< slots of a group's second triangles near its leaf
  // A first leaf's triangles and planes, each made on first use (not zeroed per leaf: that was
  // 3% of a query).
  Triangle leafTriangles[detail::kFanout];
  detail::SeparatingPlane leafPlanes[detail::kFanout];

  static RunScratch& ofThread() {
    thread_local RunScratch scratch;
    return scratch;
  }
};

/// One unit of parallel work: a triangle of the first mesh against a block of the second.
struct Task {
  std::uint32_t triangle;
  std::uint32_t block;
};

/// The (triangle, block) pairs whose boxes come within `reach` of each other, in (triangle,
/// block) order: blocks of the first mesh against blocks of the second, then each triangle of
/// a first block against the second blocks that block reaches. Listing the work first lets the
/// parallel loop hand out only pairs that reach the kernels, in even pieces.
std::vector<Task> tasksWithin(const TriangleSoA& first, const std::vector<Aabb>& firstBlocks,
                              const std::vector<Aabb>& secondBlocks, double reach) {
  std::vector<Task> tasks;
  std::vector<std::uint32_t> near;
  for (std::size_t a = 0; a < firstBlocks.size(); ++a) {
    near.clear();
    for (std::size_t b = 0; b < secondBlocks.size(); ++b)
      if (!apart(firstBlocks[a], secondBlocks[b], reach))
        near.push_back(static_cast<std::uint32_t>(b));
    if (near.empty()) continue;
    const std::size_t end = std::min((a + 1) * kBlock, first.size());
    for (std::size_t i = a * kBlock; i < end; ++i) {
      const Aabb box = first.triangle(i).bounds();
      for (std::uint32_t b : near)
        if (!apart(box, secondBlocks[b], reach))
          tasks.push_back({static_cast<std::uint32_t>(i), b});
    }
  }
  return tasks;
}

/// The contacts of one task's pairs, in id order.
void contactsOf(const Task& task, const TriangleSoA& first, const TriangleSoA& second,
                double epsilon, kernels::Solver solver, kernels::PairResults& results,
                std::vector<ContactPoint>& out) {
  const Triangle one = first.triangle(task.triangle);
  const double reach = 2.0 * epsilon;
  const std::size_t begin = std::size_t{task.block} * kBlock;
  const std::size_t end = std::min(begin + kBlock, second.size());
  kernels::distances(solver, one, second, begin, end, results);
  for (std::size_t k = 0; k < results.size(); ++k)
    if (results.distanceSquared(k) < reach * reach)
      out.push_back(
          contactPoint(one, second.triangle(begin + k), results, k, task.triangle, begin + k));
}

}  // namespace

namespace {

/// The least ε a contact query takes, 2⁻⁴⁸¹ (about 1.6e-145): below it (2ε)² would lie below
/// kUnderflowingSquare, where a kernel's squared distance has lost precision to underflow or
/// is 0, and a pair closer than 2ε could not be told from one farther (a pair at distance 0 was
/// missed). Geometry that small is scaled up by a power of two, which is exact.
constexpr double kSmallestEpsilon = 0x1p-481;
static_assert(4.0 * kSmallestEpsilon * kSmallestEpsilon == detail::kUnderflowingSquare);

void checkEpsilon(double epsilon) {
  if (!std::isfinite(epsilon) || !(epsilon > 0.0))
    throw Error("contacts: epsilon = " + toString(epsilon) + " must be finite and positive");
  if (epsilon < kSmallestEpsilon)
    throw Error("contacts: epsilon = " + toString(epsilon) + " is below 2^-481 (" +
                toString(kSmallestEpsilon) +
                "), where squared distances underflow and a pair closer than 2 epsilon cannot be "
                "told from one farther; scale both meshes and epsilon up by a power of two "
                "(exact)");
}

}  // namespace

std::vector<ContactPoint> contacts(const TriangleSoA& first, const TriangleSoA& second,
                                   double epsilon, kernels::Solver solver) {
  checkEpsilon(epsilon);
  if (first.size() == 0 || second.size() == 0) throw Error("contacts: a mesh has no triangles");
  if (first.size() >= kMaxTriangles || second.size() >= kMaxTriangles)
    throw Error("contacts: a mesh has more triangles than 32-bit ids can name");
  checkMeshScale(first, "contacts: the first mesh");
  checkMeshScale(second, "contacts: the second mesh");
  const std::vector<Aabb> firstBlocks = blockBoxes(first), secondBlocks = blockBoxes(second);
  const Aabb firstBox = meshBox(firstBlocks), secondBox = meshBox(secondBlocks);
  // Boxes are compared with a slack far above the rounding of a kernel's distance (a few ulps of
  // the coordinates), so pruning never drops a pair the kernel would find closer than 2ε.
  const double slack =
      0x1p-36 * std::max({maxAbs(firstBox.lower), maxAbs(firstBox.upper), maxAbs(secondBox.lower),
                          maxAbs(secondBox.upper), firstBox.diagonal(), secondBox.diagonal()});
  const double reach = 2.0 * epsilon + slack;
  if (apart(firstBox, secondBox, reach)) return {};
  const std::vector<Task> tasks = tasksWithin(first, firstBlocks, secondBlocks, reach);

  // Chunks of kTaskGrain tasks each write their own slot; concatenated in order, the contacts
  // come sorted by (first, second) whatever thread ran which chunk.
  std::vector<std::vector<ContactPoint>> perChunk((tasks.size() + kTaskGrain - 1) / kTaskGrain);
  parallelFor(0, tasks.size(), kTaskGrain, [&](std::size_t begin, std::size_t end) {
    kernels::PairResults results(kBlock);
    std::vector<ContactPoint> out;  // filled locally: neighbouring slots share cache lines
    for (std::size_t t = begin; t < end; ++t)
      contactsOf(tasks[t], first, second, epsilon, solver, results, out);
    perChunk[begin / kTaskGrain] = std::move(out);
  });
  return detail::joined<ContactPoint>(perChunk);
}

namespace {

/// Phase 2 of contacts(QueryMesh, QueryMesh): every second leaf the leaf pairs name, carried into
/// the first's frame once (a leaf meets several first leaves): its triangles, their boxes (also
/// side by side) and planes, and ids, at 8·(its rank among them), in `scratch`'s partner arrays.
void placePartnerLeaves(const detail::QueryMeshData& b, const detail::MatrixMotion* motion,
                        MeshPairScratch& scratch) {
  const std::vector<std::uint32_t>& secondLeaves = scratch.named.leaves;
  const std::size_t slots = secondLeaves.size() * detail::kFanout;
  std::vector<Triangle>& partnerTriangles = scratch.partnerTriangles;
  std::vector<Aabb>& partnerBoxes = scratch.partnerBoxes;
  std::vector<detail::MovedOctet>& partnerOctets = scratch.partnerOctets;
  std::vector<detail::SeparatingPlane>& partnerPlanes = scratch.partnerPlanes;
  std::vector<std::uint32_t>& partnerIds = scratch.partnerIds;
  std::vector<std::uint32_t>& partnerIndices = scratch.partnerIndices;
  // Every slot is written below (an empty one past a last leaf's end as such).
  partnerTriangles.resize(slots);
  partnerBoxes.resize(slots);
  partnerOctets.resize(secondLeaves.size());
  partnerPlanes.resize(slots);
  partnerIds.resize(slots);
  partnerIndices.resize(slots);
  parallelFor(0, secondLeaves.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t j = begin; j < end; ++j) {
      const std::size_t from = std::size_t{secondLeaves[j]} * detail::kFanout;
      const std::size_t to = std::min(from + detail::kFanout, b.size());
      for (std::size_t k = from; k < to; ++k) {
        const std::size_t slot = j * detail::kFanout + (k - from);
        const Triangle other = motion ? motion->apply(b.triangle(k)) : b.triangle(k);
        partnerTriangles[slot] = other;
        partnerBoxes[slot] = other.bounds();
        partnerPlanes[slot] = detail::separatingPlane(other);
        partnerIds[slot] = b.order[k];
        partnerIndices[slot] = static_cast<std::uint32_t>(k);
      }
      for (std::size_t slot = j * detail::kFanout + (to - from);  // past a last leaf's end: empty
           slot < (j + 1) * detail::kFanout; ++slot) {
        partnerTriangles[slot] = Triangle{};
        partnerBoxes[slot] = Aabb{};
        partnerPlanes[slot] = detail::SeparatingPlane{};
        partnerIds[slot] = kNoPartner;
        partnerIndices[slot] = kNoPartner;
      }
      detail::MovedOctet& octet = partnerOctets[j];  // the same boxes, eight side by side
      for (std::size_t i = 0; i < detail::kFanout; ++i) {
        const Aabb& box = partnerBoxes[j * detail::kFanout + i];  // empty past a last leaf's end
        for (std::size_t axis = 0; axis < 3; ++axis) {
          octet.lower[axis][i] = box.lower[axis];
          octet.upper[axis][i] = box.upper[axis];
        }
      }
    }
  });
}

using CandidatePair = ContactCache::KeptPair;

/// The triangle pairs gathered in `work` (firsts[k] against seconds[k]) through the kernels in
/// one batch; returns their answers, pair by pair.
const kernels::PairResults& runKernels(RunScratch& work, kernels::Solver solver) {
  work.firstBatch.assign(work.firsts);
  work.secondBatch.assign(work.seconds);
  kernels::PairResults& results = work.results;
  results.reserve(work.firsts.size());  // the kernels fill at most the capacity
  kernels::distances(solver, work.firstBatch, work.secondBatch, results);
  return results;
}

/// The gathered pairs [begin, end) of `work` that the kernels found within `reach`, appended to
/// `out` as contacts.
void appendWithin(const RunScratch& work, std::size_t begin, std::size_t end, double reach,
                  std::vector<ContactPoint>& out) {
  const kernels::PairResults& results = work.results;
  for (std::size_t k = begin; k < end; ++k)
    if (results.distanceSquared(k) < reach * reach)
      out.push_back(contactPoint(work.firsts[k], work.seconds[k], results, k, work.firstIds[k],
                                 work.secondIds[k]));
}

/// The triangle pairs gathered in `work` (firsts[k] against seconds[k], ids firstIds[k] and
/// secondIds[k]) through the kernels in one batch; those within `reach` appended to `out`.
/// Returns the kernels' answers, pair by pair.
const kernels::PairResults& batchedContacts(RunScratch& work, double reach, kernels::Solver solver,
                                            std::vector<ContactPoint>& out) {
  const kernels::PairResults& results = runKernels(work, solver);
  appendWithin(work, 0, results.size(), reach, out);
  return results;
}

/// Phase 3: the contacts of run `run` (first leaves run·kGroupsPerBatch onward): per group, the
/// partner leaves' eight triangle boxes at once against the first leaf's box, then each leaf
/// triangle's box and the separating planes (a leaf triangle's made on its first use), all
/// within `pruneReach`; the pairs left through the kernels in one batch, those within `reach`
/// into `out` (unsorted: the caller sorts), and every pair left into `candidates` when given.
void contactsOfRun(std::size_t run, const detail::QueryMeshData& a, const MeshPairScratch& scratch,
                   double reach, double pruneReach, kernels::Solver solver, RunScratch& work,
                   std::vector<ContactPoint>& out, std::vector<CandidatePair>* candidates) {
  const std::vector<detail::LeafPair>& pairs = scratch.pairs;
  const std::vector<std::size_t>& groups = scratch.groups;
  const std::size_t groupCount = groups.size() - 1;
  std::vector<Triangle>&firsts = work.firsts, &seconds = work.seconds;
  std::vector<std::uint32_t>&firstIds = work.firstIds, &secondIds = work.secondIds;
  std::vector<std::uint32_t>& partners = work.partners;
  Triangle(&leafTriangles)[detail::kFanout] = work.leafTriangles;
  detail::SeparatingPlane(&leafPlanes)[detail::kFanout] = work.leafPlanes;
  out.clear();
  firsts.clear();
  seconds.clear();
  firstIds.clear();
  secondIds.clear();
  for (std::size_t g = run * kGroupsPerBatch; g < std::min(groupCount, (run + 1) * kGroupsPerBatch);
       ++g) {
    const std::uint32_t firstLeaf = pairs[groups[g]].first;
    const std::size_t firstBegin = std::size_t{firstLeaf} * detail::kFanout;
    const Aabb firstLeafBox = a.levels[0][firstLeaf];
    partners.clear();
    for (std::size_t p = groups[g]; p < groups[g + 1]; ++p) {  // most leaf neighbours are not
      const std::size_t j = scratch.named.rankOfPair[p];
      for (unsigned rest = detail::notApartMask(scratch.partnerOctets[j], firstLeafBox, pruneReach);
           rest != 0; rest &= rest - 1)
        partners.push_back(static_cast<std::uint32_t>(j * detail::kFanout) +
                           static_cast<std::uint32_t>(std::countr_zero(rest)));
    }
    // Per partner the leaf's eight triangle boxes at once (grown by the slack, so no pair is
    // lost), then the planes, a leaf triangle's made on its first use. The contacts are sorted
    // at the end: the batch's order does not matter.
    if (partners.empty()) continue;
    const std::size_t count = std::min(detail::kFanout, a.size() - firstBegin);
    for (std::size_t i = 0; i < count; ++i)
      leafTriangles[i] = a.triangle(firstBegin + i);
    const detail::MovedOctet leafBoxes = detail::boxesOf(leafTriangles, count, a.slack);
    unsigned made = 0;
    for (const std::uint32_t slot : partners) {
      for (unsigned rest = detail::notApartMask(leafBoxes, scratch.partnerBoxes[slot], pruneReach);
           rest != 0; rest &= rest - 1) {
        const auto i = static_cast<std::size_t>(std::countr_zero(rest));
        if (!(made & 1u << i)) {
          made |= 1u << i;
          leafPlanes[i] = detail::separatingPlane(leafTriangles[i]);
        }
        const Triangle& one = leafTriangles[i];
        const Triangle& other = scratch.partnerTriangles[slot];
        const detail::SeparatingPlane& otherPlane = scratch.partnerPlanes[slot];
        // Both tests, then one branch (each alone is a coin toss to the predictor).
        if (static_cast<int>(
                detail::separated(leafPlanes[i], other, otherPlane.magnitude, pruneReach)) |
            static_cast<int>(
                detail::separated(otherPlane, one, leafPlanes[i].magnitude, pruneReach)))
          continue;
        if (candidates)
          candidates->push_back(
              {static_cast<std::uint32_t>(firstBegin + i), scratch.partnerIndices[slot], 0.0});
        firsts.push_back(one);
        seconds.push_back(other);
        firstIds.push_back(a.order[firstBegin + i]);
        secondIds.push_back(scratch.partnerIds[slot]);
      }
    }
  }
  if (firsts.empty()) return;
  const kernels::PairResults& results = batchedContacts(work, reach, solver, out);
  if (candidates)  // the run's pairs are its last ones, in the batch's order
    for (std::size_t k = 0; k < results.size(); ++k)
      (*candidates)[candidates->size() - results.size() + k].distance = results.distance(k);
}

/// Contacts sorted by (first, second) id.
void sortByIds(std::vector<ContactPoint>& found) {
  std::sort(found.begin(), found.end(), [](const ContactPoint& x, const ContactPoint& y) {
    return x.first != y.first ? x.first < y.first : x.second < y.second;
  });
}

/// Phase 4: every run's contacts in one list, sorted by (first, second) id.
std::vector<ContactPoint> joinedAndSorted(std::span<const std::vector<ContactPoint>> perRun) {
  std::vector<ContactPoint> found = detail::joined(perRun);
  sortByIds(found);
  return found;
}

/// Phase 5, for two closed meshes: a contact whose triangles do not cross is marked overlapping
/// where its x lies inside both (each mesh's nearest-triangle sign, or its winding number where
/// it bounds no solid: it crosses itself, or its parts do not nest, part_nesting.h); `toFirst`
/// and `toSecond` carry x into each mesh's prepared frame.
template <class ToFirst, class ToSecond>
void markInsideBoth(const QueryMesh& first, const QueryMesh& second, double epsilon,
                    std::span<ContactPoint> found, const ToFirst& toFirst,
                    const ToSecond& toSecond) {
  const detail::QueryMeshData &a = first.data(), &b = second.data();
  // x lies within ε of both surfaces, so the nearest-triangle searches stop within 2ε.
  const double limit = 4.0 * epsilon * epsilon;
  // A closed mesh that bounds no solid is signed by its winding number (pseudonormals are wrong
  // near the crossings, a misoriented part and a pinched vertex). Made here, where they may throw,
  // not in the parallel loop.
  const bool aCrosses = !boundsSolid(first), bCrosses = !boundsSolid(second);
  aCrosses ? (void)a.windingTree() : (void)a.pseudonormals();
  bCrosses ? (void)b.windingTree() : (void)b.pseudonormals();
  const auto inside = [limit, &a, aCrosses, bCrosses](const detail::QueryMeshData& mesh,
                                                      const Vec3& x) {
    const detail::Nearest nearest = detail::nearestTriangle(mesh, x, limit);
    if (!nearest.found()) return false;
    if (!(&mesh == &a ? aCrosses : bCrosses)) return detail::insideAt(mesh, x, nearest);
    const double distance = detail::distanceOf(mesh, x, nearest);
    if (const std::optional<bool> exact = detail::insideNearSurface(mesh, x, nearest, distance))
      return *exact;
    return distance > 0.0 && detail::windingSign(mesh, x, 0.0).inside;
  };
  // Each point once: contacts at one point share the answer (the pairs of two faces lying on
  // one another, each sliver of a fan against a face resting on its centre, take the same
  // closest point, and a search from a fan's centre ties with every sliver: a box resting on
  // the cap of a CAD cylinder of 2,000 segments put 3,850 of its 6,020 contacts there).
  std::vector<std::uint32_t> order;
  for (std::size_t i = 0; i < found.size(); ++i)
    if (!found[i].overlap) order.push_back(static_cast<std::uint32_t>(i));
  // By the coordinates' bits: a total order whatever they hold, equal bits one point.
  const auto bits = [&found](std::uint32_t i) {
    const Vec3& x = found[i].x;
    return std::tuple{std::bit_cast<std::uint64_t>(x.x), std::bit_cast<std::uint64_t>(x.y),
                      std::bit_cast<std::uint64_t>(x.z)};
  };
  std::sort(order.begin(), order.end(), [&bits](std::uint32_t i, std::uint32_t j) {
    return std::pair{bits(i), i} < std::pair{bits(j), j};
  });
  std::vector<std::size_t> starts;  // of the runs of one point in `order`
  for (std::size_t k = 0; k < order.size(); ++k)
    if (k == 0 || bits(order[k]) != bits(order[k - 1])) starts.push_back(k);
  starts.push_back(order.size());
  parallelFor(0, starts.size() - 1, kBlock, [&](std::size_t begin, std::size_t end) {
    for (std::size_t run = begin; run < end; ++run) {
      const Vec3& x = found[order[starts[run]]].x;
      const bool both = inside(a, toFirst(x)) && inside(b, toSecond(x));
      for (std::size_t k = starts[run]; k < starts[run + 1]; ++k)
        found[order[k]].overlap = both;
    }
  });
}

/// Phase 5 on contacts in the first mesh's prepared frame.
void markOverlaps(const QueryMesh& first, const QueryMesh& second,
                  const RigidTransform& secondToFirst, double epsilon,
                  std::vector<ContactPoint>& found) {
  const bool moved = first.moved() || second.moved();
  const detail::MatrixMotion firstToSecond = detail::matrixMotion(secondToFirst.inverse());
  markInsideBoth(
      first, second, epsilon, found, [](const Vec3& x) { return x; },
      [&](const Vec3& x) { return moved ? firstToSecond.apply(x) : x; });
}

/// Phases 1–4 of contacts(QueryMesh, QueryMesh): the contacts closer than `reach` of the pairs
/// within `pruneReach` (≥ reach), sorted by ids, in the first mesh's prepared frame; every pair
/// within `pruneReach` into `candidates` when given (then the runs go serially: a cache is
/// made inside a caller's parallel loop over its pairs).
std::vector<ContactPoint> descendedContacts(const detail::QueryMeshData& a,
                                            const detail::QueryMeshData& b,
                                            const detail::MatrixMotion* motion, double reach,
                                            double pruneReach, kernels::Solver solver,
                                            std::vector<CandidatePair>* candidates) {
  // Both trees are descended together down to pairs of leaves within reach (boxes grown by the
  // slack, so no pair the kernel would find is dropped); then each triangle of the first leaf
  // against the second leaf's eight. Moved meshes meet in the first one's prepared frame: the
  // second's boxes and, leaf by leaf, its triangles are carried there; nothing is rebuilt.
  const detail::MovedTree secondTree(b.levels, motion);
  MeshPairScratch& scratch = MeshPairScratch::ofThread();

  // 1. The leaf pairs within reach, grouped by the first leaf: each of its triangles then meets
  // the triangles of all its second leaves in one kernel batch (the batched solvers want long
  // batches, not eight pairs a call).
  detail::leafPairsWithin(a, b, secondTree, pruneReach, scratch.pairs);
  groupByFirst(scratch.pairs, a.levels[0].size(), scratch.groups, scratch.start, scratch.grouped);
  secondLeavesOf(scratch.pairs, b.levels[0].size(), scratch.named);
  // 2. The second leaves they name, in the first's frame.
  placePartnerLeaves(b, motion, scratch);

  // 3. The candidate pairs of a run of kGroupsPerBatch first leaves go to the kernels in one
  // batch of pairs: a first leaf has a few (nearly parallel surfaces: two), which would leave
  // most of a batch's lanes idle and pay a call each. A pair's answer does not depend on its
  // batch (kernels/hybrid.h), so neither on the runs nor on the thread count.
  const std::size_t runs = (scratch.groups.size() - 1 + kGroupsPerBatch - 1) / kGroupsPerBatch;
  std::vector<std::vector<ContactPoint>>& perRun = scratch.perRun;
  if (perRun.size() < runs) perRun.resize(runs);
  if (candidates) {
    candidates->clear();
    RunScratch& work = RunScratch::ofThread();
    for (std::size_t run = 0; run < runs; ++run)
      contactsOfRun(run, a, scratch, reach, pruneReach, solver, work, perRun[run], candidates);
  } else {
    parallelFor(0, runs, 1, [&](std::size_t firstRun, std::size_t endRun) {
      RunScratch& work = RunScratch::ofThread();
      for (std::size_t run = firstRun; run < endRun; ++run)
        contactsOfRun(run, a, scratch, reach, pruneReach, solver, work, perRun[run], nullptr);
    });
  }
  // 4. Sorted by ids.
  return joinedAndSorted(std::span<const std::vector<ContactPoint>>(perRun.data(), runs));
}

/// The kept triangle pairs (sorted indices) whose distance when kept is below `nearer` (2ε plus
/// the move since and the rounding allowance), placed as a descent would place them, appended to
/// the pairs gathered in `work`.
void gatherKept(const detail::QueryMeshData& a, const detail::QueryMeshData& b,
                const detail::MatrixMotion* motion, const std::vector<ContactCache::KeptPair>& kept,
                double nearer, RunScratch& work) {
  // Sorted by distance: those that may be within 2ε now, rounding allowed for, come first (a
  // scan reads only them: a binary search's scattered reads missed the cache).
  for (std::size_t k = 0; k < kept.size() && kept[k].distance < nearer; ++k) {
    work.firsts.push_back(a.triangle(kept[k].first));
    const Triangle other = b.triangle(kept[k].second);
    work.seconds.push_back(motion ? motion->apply(other) : other);  // as placePartnerLeaves does
    work.firstIds.push_back(a.order[kept[k].first]);
    work.secondIds.push_back(b.order[kept[k].second]);
  }
}

void clearGathered(RunScratch& work) noexcept {
  work.firsts.clear();
  work.seconds.clear();
  work.firstIds.clear();
  work.secondIds.clear();
}

/// Phases 5–6: overlaps marked (both meshes closed; unless `inside` leaves it to the caller),
/// then moved to where the first mesh is.
void finishContacts(const QueryMesh& first, const QueryMesh& second,
                    const RigidTransform& secondToFirst, double epsilon, InsideTest inside,
                    std::vector<ContactPoint>& found) {
  if (first.closed() && second.closed() && inside == InsideTest::now)
    markOverlaps(first, second, secondToFirst, epsilon, found);
  if (first.moved())
    for (ContactPoint& contact : found) {
      contact.x = first.pose().apply(contact.x);
      contact.normal = first.pose().rotation.rotate(contact.normal);
      contact.direction = first.pose().rotation.rotate(contact.direction);
    }
}

/// Where both QueryMesh contact queries start: ε and the pair checked, the second mesh placed
/// in the first's prepared frame (the motion only where either has moved).
struct PlacedPair {
  const detail::QueryMeshData& a;
  const detail::QueryMeshData& b;
  RigidTransform secondToFirst;
  detail::MatrixMotion motion;
  bool moved;
  double reach;  ///< 2ε

  const detail::MatrixMotion* placement() const noexcept { return moved ? &motion : nullptr; }
};

PlacedPair placedPair(const QueryMesh& first, const QueryMesh& second, double epsilon) {
  checkEpsilon(epsilon);
  const RigidTransform secondToFirst = detail::checkPlacedPair(first, second, "contacts");
  detail::requireTrianglesSpan(first, "contacts: the first mesh");
  detail::requireTrianglesSpan(second, "contacts: the second mesh");
  return {first.data(),
          second.data(),
          secondToFirst,
          detail::matrixMotion(secondToFirst),
          first.moved() || second.moved(),
          2.0 * epsilon};
}

/// The largest coordinate of the pair where the kernels meet it, or of the translation that
/// places the second there (the move's measure rounds with both: detail::relativeMove).
double magnitudeOf(const PlacedPair& pair) noexcept {
  return std::max(detail::placedMagnitude(pair.a.bounds, pair.b.bounds, pair.secondToFirst),
                  maxAbs(pair.motion.translation));
}

}  // namespace

std::vector<ContactPoint> contacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                                   kernels::Solver solver) {
  const PlacedPair pair = placedPair(first, second, epsilon);
  std::vector<ContactPoint> found =
      descendedContacts(pair.a, pair.b, pair.placement(), pair.reach, pair.reach, solver, nullptr);
  finishContacts(first, second, pair.secondToFirst, epsilon, InsideTest::now, found);
  return found;
}

}  // namespace delta::contactdetection

namespace delta::detail {

using contactdetection::CandidatePair;
using contactdetection::ContactCache;
using contactdetection::descendedContacts;
using contactdetection::gatherKept;
using contactdetection::magnitudeOf;
using contactdetection::PlacedPair;
using contactdetection::RunScratch;

/// What the cached queries read and write of a ContactCache (its friend).
struct CachedContacts {
  /// How far the second mesh has moved against the first since `cache` was made, +∞ where it was
  /// made for another ε or solver.
  static double moveSince(const ContactCache& cache, const PlacedPair& pair, const QueryMesh& first,
                          const QueryMesh& second, double epsilon, kernels::Solver solver) {
    return cache.epsilon_ == epsilon && cache.solver_ == solver
               ? cache.moveSince(first, second, pair.motion.rotation, pair.motion.translation)
               : std::numeric_limits<double>::infinity();
  }

  /// The contacts of a pair whose cache does not hold: phases 1–4, the cache made anew (from a
  /// descent to 2ε + skin) where it keeps pairs.
  static std::vector<ContactPoint> remade(const QueryMesh& first, const QueryMesh& second,
                                          double epsilon, const PlacedPair& pair,
                                          ContactCache& cache, kernels::Solver solver) {
    if (!cache.keeps()) {
      cache.madeWithoutKeeping();
      return descendedContacts(pair.a, pair.b, pair.placement(), pair.reach, pair.reach, solver,
                               nullptr);
    }
    // The kept pairs are those the kernels could find within 2ε until the second has moved by
    // the skin less what rounding can add: the kernels' error at both poses (10⁻¹² of a pair's
    // size: kernels/hybrid.h), the triangles' placement and the move's bound (a few ulps of the
    // coordinates each); allowed 2⁻³⁶ of the largest coordinate, as the flat query's prune is
    // (2ε itself has the prune's slack in the boxes and planes already).
    std::vector<CandidatePair> candidates;
    std::vector<ContactPoint> found =
        descendedContacts(pair.a, pair.b, pair.placement(), pair.reach, pair.reach + cache.skin(),
                          solver, &candidates);
    // By distance (then ids, for a fixed order): a call hands the kernels a prefix. The penalty
    // solver's distances are not bounds: its pairs all go, as if at distance 0.
    if (solver == kernels::Solver::Penalty)
      for (CandidatePair& candidate : candidates)
        candidate.distance = 0.0;
    std::sort(candidates.begin(), candidates.end(),
              [](const CandidatePair& x, const CandidatePair& y) {
                if (x.distance != y.distance) return x.distance < y.distance;
                return x.first != y.first ? x.first < y.first : x.second < y.second;
              });
    cache.pairs_ = std::move(candidates);
    cache.nearest_ = cache.pairs_.empty() ? std::numeric_limits<double>::infinity()
                                          : cache.pairs_.front().distance;
    cache.epsilon_ = epsilon;
    cache.solver_ = solver;
    cache.keep(first, second, pair.motion.rotation, pair.motion.translation,
               0x1p-36 * magnitudeOf(pair));
    return found;
  }

  /// Phases 1–4 of a pair through its cache: where the cache holds, its kept pairs that may be
  /// within 2ε now are appended to `work` (true: the kernels are the caller's); where it does
  /// not, it is made anew and the contacts are in `found` (false).
  static bool gatherOrRemake(const QueryMesh& first, const QueryMesh& second, double epsilon,
                             const PlacedPair& pair, ContactCache& cache, kernels::Solver solver,
                             RunScratch& work, std::vector<ContactPoint>& found) {
    const double move = moveSince(cache, pair, first, second, epsilon, solver);
    if (!cache.holds(move)) {
      found = remade(first, second, epsilon, pair, cache, solver);
      return false;
    }
    const double nearer = pair.reach + move + cache.allowance();
    if (cache.nearest_ < nearer)  // else every kept pair is still beyond 2ε: no contacts
      gatherKept(pair.a, pair.b, pair.placement(), cache.pairs_, nearer, work);
    cache.answered();
    return true;
  }
};

}  // namespace delta::detail

namespace delta::contactdetection {

std::vector<ContactPoint> contacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                                   ContactCache& cache, kernels::Solver solver, InsideTest inside) {
  const PlacedPair pair = placedPair(first, second, epsilon);
  std::vector<ContactPoint> found;
  RunScratch& work = RunScratch::ofThread();
  clearGathered(work);
  if (detail::CachedContacts::gatherOrRemake(first, second, epsilon, pair, cache, solver, work,
                                             found) &&
      !work.firsts.empty()) {
    batchedContacts(work, pair.reach, solver, found);
    sortByIds(found);
  }
  finishContacts(first, second, pair.secondToFirst, epsilon, inside, found);
  return found;
}

/// A pair added to a ContactBatch: what its finish needs, and where its kept triangle pairs lie
/// in the batch while `pending` (the kernels' answers awaited: run()).
struct ContactBatch::Entry {
  const QueryMesh* first;
  const QueryMesh* second;
  RigidTransform secondToFirst;
  double epsilon;
  InsideTest inside;
  bool pending;
  std::size_t begin, end;
};

struct ContactBatch::State {
  std::vector<Entry> entries;
  std::vector<std::vector<ContactPoint>> found;  ///< one a pair, kept from batch to batch
  RunScratch work;
};

ContactBatch::ContactBatch(kernels::Solver solver)
    : solver_(solver), state_(std::make_unique<State>()) {}

ContactBatch::~ContactBatch() = default;
ContactBatch::ContactBatch(ContactBatch&&) noexcept = default;
ContactBatch& ContactBatch::operator=(ContactBatch&&) noexcept = default;

std::size_t ContactBatch::size() const noexcept {
  return state_->entries.size();
}

void ContactBatch::clear() noexcept {
  state_->entries.clear();
  clearGathered(state_->work);
}

std::size_t ContactBatch::add(const QueryMesh& first, const QueryMesh& second, double epsilon,
                              ContactCache& cache, InsideTest inside) {
  State& state = *state_;
  const PlacedPair pair = placedPair(first, second, epsilon);
  const std::size_t index = state.entries.size();
  if (state.found.size() <= index) state.found.resize(index + 1);
  std::vector<ContactPoint>& found = state.found[index];
  found.clear();
  Entry entry{&first, &second, pair.secondToFirst, epsilon, inside, false, 0, 0};
  entry.begin = state.work.firsts.size();
  entry.pending = detail::CachedContacts::gatherOrRemake(first, second, epsilon, pair, cache,
                                                         solver_, state.work, found);
  entry.end = state.work.firsts.size();
  if (!entry.pending) finishContacts(first, second, pair.secondToFirst, epsilon, inside, found);
  state.entries.push_back(entry);
  return index;
}

void ContactBatch::run() {
  State& state = *state_;
  if (!state.work.firsts.empty()) runKernels(state.work, solver_);
  for (std::size_t index = 0; index < state.entries.size(); ++index) {
    Entry& entry = state.entries[index];
    if (!entry.pending) continue;
    entry.pending = false;
    std::vector<ContactPoint>& found = state.found[index];
    appendWithin(state.work, entry.begin, entry.end, 2.0 * entry.epsilon, found);
    sortByIds(found);
    finishContacts(*entry.first, *entry.second, entry.secondToFirst, entry.epsilon, entry.inside,
                   found);
  }
  clearGathered(state.work);
}

std::vector<ContactPoint>& ContactBatch::contacts(std::size_t index) {
  if (index >= state_->entries.size())
    throw Error("ContactBatch: contacts(" + std::to_string(index) + ") of a batch of " +
                std::to_string(state_->entries.size()) + " pairs");
  if (state_->entries[index].pending)
    throw Error("ContactBatch: contacts(" + std::to_string(index) + ") before run()");
  return state_->found[index];
}

void markInside(const QueryMesh& first, const QueryMesh& second, double epsilon,
                std::span<ContactPoint> contacts) {
  checkEpsilon(epsilon);
  if (contacts.empty() || !first.closed() || !second.closed()) return;
  markInsideBoth(
      first, second, epsilon, contacts,
      [&](const Vec3& x) { return first.moved() ? first.inversePose().apply(x) : x; },
      [&](const Vec3& x) { return second.moved() ? second.inversePose().apply(x) : x; });
}

}  // namespace delta::contactdetection
