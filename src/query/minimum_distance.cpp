#include "delta/query/minimum_distance.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <queue>
#include <span>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/parallel.h"
#include "delta/kernels/pair_results.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/mesh/mesh.h"

#include "detail/dual_traversal.h"
#include "detail/morton.h"
#include "detail/placement.h"
#include "detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

// Branch and bound over boxes. The second mesh is sorted along a Morton curve of its triangles'
// centroids and cut into blocks of kBlock triangles, each with its box (and superblocks of kSuper
// blocks, so that far ones cost one box test); the first mesh likewise into groups of kGroup
// triangles, searched nearest first. Each group lists the blocks by ascending box distance; each of
// its triangles visits them in that order (so its first block is a good first guess) and runs the
// kernels on a block only where the block's box is not further than the best distance known:
// the triangle's own best or the best any triangle has found so far (shared by all threads).
//
// Why the answer is the all-pairs one, for any thread count: the bound only ever holds the
// squared distance of a pair actually computed, so it never falls below the minimum d*², and a
// block is skipped only where its box is further than the bound (plus rounding slack): never
// the block of a pair at distance d*. Every pair attaining d*² is thus computed by its first
// triangle, whose best keeps the smallest second id among equal distances (blocks come out of
// id order, so ties compare ids), and the serial reduction keeps the smallest first id. A stale
// bound only prunes less. Every pair is computed in the same block whatever the thread count.
// The brute force and the penalty compute each pair alone (lane by lane), so their bits are
// those of any all-pairs loop; the hybrid's last bits can depend on the rest of the batch (its
// second stage runs a lone pair on the scalar kernels, several on the SIMD ones), which can
// only change which of two pairs equal to rounding is named.

/// Triangles of the second mesh handed to the kernels at once, and pruned as one box.
constexpr std::size_t kBlock = 64;
/// Blocks per superblock: the box tests of a group against far superblocks skip their blocks.
constexpr std::size_t kSuper = 16;
/// Triangles of the first mesh sharing one sorted list of blocks (and one parallel chunk).
constexpr std::size_t kGroup = 32;
/// Relative slack on distances compared with box gaps: the kernels' distances and the boxes'
/// gaps are both rounded (the kernels' by at most ~10⁻¹² of the pair's size plus a few ulps of
/// the coordinates), so a gap is widened to a bound by far more than either.
constexpr double kSlack = 1e-9;

struct Closest {
  double distanceSquared = std::numeric_limits<double>::infinity();
  std::uint32_t second = 0;
  Vec3 p, q;
  bool intersect = false;
};

/// The squared box gap up to which a block may still hold a pair whose computed squared
/// distance is at most `bound`: the distance widened relatively by kSlack and absolutely by
/// `slack` (kSlack times the largest coordinate, the scale of the kernels' rounding).
double pruneLimit(double bound, double slack) noexcept {
  if (!(bound < std::numeric_limits<double>::infinity())) return bound;
  const double widened = std::sqrt(bound) * (1.0 + kSlack) + slack;
  return widened * widened;
}

/// Lowers `bound` to `value` if that is smaller (a lock-free atomic minimum).
void lowerTo(std::atomic<double>& bound, double value) noexcept {
  double current = bound.load(std::memory_order_relaxed);
  while (value < current &&
         !bound.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
  }
}

/// The triangle ids of `mesh` in Morton order of their centroids (detail/morton.h): consecutive
/// runs are spatially compact.
std::vector<std::uint32_t> mortonOrder(const TriangleSoA& mesh) {
  return detail::mortonOrder(mesh.size(),
                             [&mesh](std::size_t i) { return mesh.triangle(i).centroid(); });
}

/// The second mesh cut into spatially compact blocks: its triangles in Morton order, flattened
/// again, with the original id of each, the box of each block of kBlock and of each run of
/// kSuper blocks.
struct Blocks {
  TriangleSoA triangles;
  std::vector<std::uint32_t> ids;
  std::vector<Aabb> boxes;
  std::vector<Aabb> superBoxes;

  /// Calls `visit(block, gap²)` for every block whose squared gap to `box` is at most `limit`
  /// (for every block when it is +∞), skipping the superblocks further than that.
  template <class Visit>
  void near(const Aabb& box, double limit, const Visit& visit) const {
    for (std::size_t s = 0; s < superBoxes.size(); ++s) {
      if (distanceSquared(box, superBoxes[s]) > limit) continue;
      const std::size_t end = std::min((s + 1) * kSuper, boxes.size());
      for (std::size_t b = s * kSuper; b < end; ++b) {
        const double gap = distanceSquared(box, boxes[b]);
        if (gap <= limit) visit(b, gap);
      }
    }
  }
};

Blocks blocksOf(const TriangleSoA& mesh) {
  Blocks blocks;
  blocks.ids = mortonOrder(mesh);
  std::vector<Vec3> vertices(3 * mesh.size());
  std::vector<TriangleIndices> triangles(mesh.size());
  blocks.boxes.resize((mesh.size() + kBlock - 1) / kBlock);
  for (std::size_t k = 0; k < mesh.size(); ++k) {
    const Triangle t = mesh.triangle(blocks.ids[k]);
    vertices[3 * k] = t.a;
    vertices[3 * k + 1] = t.b;
    vertices[3 * k + 2] = t.c;
    const auto first = static_cast<std::uint32_t>(3 * k);
    triangles[k] = {first, first + 1, first + 2};
    blocks.boxes[k / kBlock].extend(t.bounds());
  }
  blocks.superBoxes.resize((blocks.boxes.size() + kSuper - 1) / kSuper);
  for (std::size_t b = 0; b < blocks.boxes.size(); ++b)
    blocks.superBoxes[b / kSuper].extend(blocks.boxes[b]);
  blocks.triangles = TriangleSoA(Mesh(std::move(vertices), std::move(triangles)));
  return blocks;
}

/// The largest absolute coordinate of both meshes: the scale of the kernels' rounding.
double magnitude(const std::vector<Aabb>& boxes) noexcept {
  double largest = 0.0;
  for (const Aabb& box : boxes)
    largest = std::max({largest, maxAbs(box.lower), maxAbs(box.upper)});
  return largest;
}

/// A block (or a group) and its box gap, ordered by gap, then index.
struct Candidate {
  double gapSquared;
  std::uint32_t index;
  friend bool operator<(const Candidate& a, const Candidate& b) noexcept {
    return a.gapSquared < b.gapSquared || (a.gapSquared == b.gapSquared && a.index < b.index);
  }
};

/// Everything the search of one group reads, shared by all threads.
struct Search {
  const TriangleSoA& first;
  const Blocks& blocks;
  const std::vector<std::uint32_t>& firstOrder;  ///< groups are runs of kGroup of these
  kernels::Solver solver;
  double slack;
  std::atomic<double>& bestSoFar;  ///< the least squared distance any triangle has found
};

/// Finds the closest triangle of the second mesh to each triangle of group `group`, or proves
/// it further than the best known distance (then leaves its distance infinite).
void searchGroup(const Search& search, std::size_t group, std::vector<Candidate>& candidates,
                 kernels::PairResults& results, std::vector<Closest>& closest) {
  const std::size_t begin = group * kGroup;
  const std::size_t end = std::min(begin + kGroup, search.firstOrder.size());
  std::array<Triangle, kGroup> triangles;
  std::array<Aabb, kGroup> boxes;
  Aabb groupBox;
  for (std::size_t k = begin; k < end; ++k) {
    triangles[k - begin] = search.first.triangle(search.firstOrder[k]);
    boxes[k - begin] = triangles[k - begin].bounds();
    groupBox.extend(boxes[k - begin]);
  }
  const double groupLimit =
      pruneLimit(search.bestSoFar.load(std::memory_order_relaxed), search.slack);
  candidates.clear();
  search.blocks.near(groupBox, groupLimit, [&](std::size_t block, double gap) {
    candidates.push_back({gap, static_cast<std::uint32_t>(block)});
  });
  std::sort(candidates.begin(), candidates.end());

  const TriangleSoA& second = search.blocks.triangles;
  for (std::size_t k = begin; k < end; ++k) {
    Closest best;
    double bound = std::numeric_limits<double>::infinity();
    double limit = bound;
    for (const Candidate& candidate : candidates) {
      const double now =
          std::min(best.distanceSquared, search.bestSoFar.load(std::memory_order_relaxed));
      if (now != bound) {
        bound = now;
        limit = pruneLimit(bound, search.slack);
      }
      // Candidates ascend and a triangle's box lies inside its group's: none further can pass.
      if (candidate.gapSquared > limit) break;
      if (distanceSquared(boxes[k - begin], search.blocks.boxes[candidate.index]) > limit) continue;
      const std::size_t from = candidate.index * kBlock;
      const std::size_t to = std::min(from + kBlock, second.size());
      kernels::distances(search.solver, triangles[k - begin], second, from, to, results);
      for (std::size_t j = 0; j < results.size(); ++j) {
        const double d2 = results.distanceSquared(j);
        const std::uint32_t id = search.blocks.ids[from + j];
        if (d2 < best.distanceSquared || (d2 == best.distanceSquared && id < best.second)) {
          best.distanceSquared = d2;
          best.second = id;
          best.p = results.p(j);
          best.q = results.q(j);
          best.intersect = results.intersect(j);
        }
      }
    }
    lowerTo(search.bestSoFar, best.distanceSquared);
    closest[search.firstOrder[k]] = best;
  }
}

}  // namespace

MinimumDistance minimumDistance(const TriangleSoA& first, const TriangleSoA& second,
                                kernels::Solver solver) {
  if (first.size() == 0 || second.size() == 0)
    throw Error("minimumDistance: a mesh has no triangles");
  checkMeshScale(first, "minimumDistance: the first mesh");
  checkMeshScale(second, "minimumDistance: the second mesh");
  const Blocks blocks = blocksOf(second);
  const std::vector<std::uint32_t> firstOrder = mortonOrder(first);
  const std::size_t groups = (first.size() + kGroup - 1) / kGroup;

  std::vector<Aabb> groupBoxes(groups);
  for (std::size_t k = 0; k < first.size(); ++k)
    groupBoxes[k / kGroup].extend(first.triangle(firstOrder[k]).bounds());
  const double slack = kSlack * std::max(magnitude(groupBoxes), magnitude(blocks.boxes));

  // Groups nearest the second mesh (its superblocks) first, so the shared bound falls early.
  std::vector<Candidate> groupOrder(groups);
  parallelFor(0, groups, kGroup, [&](std::size_t begin, std::size_t end) {
    for (std::size_t g = begin; g < end; ++g) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const Aabb& box : blocks.superBoxes)
        nearest = std::min(nearest, distanceSquared(groupBoxes[g], box));
      groupOrder[g] = {nearest, static_cast<std::uint32_t>(g)};
    }
  });
  std::sort(groupOrder.begin(), groupOrder.end());

  std::atomic<double> bestSoFar{std::numeric_limits<double>::infinity()};
  const Search search{first, blocks, firstOrder, solver, slack, bestSoFar};
  std::vector<Closest> closest(first.size());
  parallelFor(0, groups, 1, [&](std::size_t begin, std::size_t end) {
    std::vector<Candidate> candidates;
    candidates.reserve(blocks.boxes.size());
    kernels::PairResults results(kBlock);
    for (std::size_t g = begin; g < end; ++g)
      searchGroup(search, groupOrder[g].index, candidates, results, closest);
  });

  std::size_t bestFirst = 0;  // serial reduction in id order: the same answer for any threads
  for (std::size_t i = 1; i < closest.size(); ++i)
    if (closest[i].distanceSquared < closest[bestFirst].distanceSquared) bestFirst = i;
  const Closest& best = closest[bestFirst];
  return {std::sqrt(best.distanceSquared),
          static_cast<std::uint32_t>(bestFirst),
          best.second,
          best.p,
          best.q,
          best.intersect};
}

namespace {

/// The leaves of a prepared mesh as one search meets them: each leaf's triangles (moved by
/// `motion` when there is one), their boxes (grown by the mesh's slack, so that rounding never
/// drops a tie), their separating planes and ids, made on the leaf's first use.
class LeafCache {
 public:
  struct Leaf {
    const Triangle* triangles;
    const Aabb* boxes;
    const detail::SeparatingPlane* planes;
    const std::uint32_t* ids;
    const detail::MovedOctet* octet;  ///< the boxes again, side by side
    std::size_t count;
  };

  LeafCache(const detail::QueryMeshData& mesh, const detail::MatrixMotion* motion)
      : mesh_(mesh), motion_(motion), table_(kFirstCapacity, kEmpty) {}

  Leaf leaf(std::uint32_t index) {
    const std::size_t begin = std::size_t{index} * detail::kFanout;
    const std::size_t count = std::min(begin + detail::kFanout, mesh_.size()) - begin;
    std::uint64_t& entry = find(index);
    if (entry == kEmpty) {
      entry = std::uint64_t{index} << 32 | triangles_.size();
      if (2 * ++used_ > table_.size()) grow();
      for (std::size_t k = begin; k < begin + count; ++k) {
        const Triangle t = motion_ ? motion_->apply(mesh_.triangle(k)) : mesh_.triangle(k);
        triangles_.push_back(t);
        boxes_.push_back(t.bounds().grown(mesh_.slack));
        planes_.push_back(detail::separatingPlane(t));
        ids_.push_back(mesh_.order[k]);
      }
      octets_.push_back(
          detail::boxesOf(&triangles_[triangles_.size() - count], count, mesh_.slack));
      // Every leaf takes kFanout entries, a short last leaf too: a leaf's entries start at
      // kFanout × its octet's index (a last leaf met first shifted every later leaf's octet).
      const std::size_t padded = octets_.size() * detail::kFanout;
      triangles_.resize(padded);
      boxes_.resize(padded);
      planes_.resize(padded);
      ids_.resize(padded);
    }
    const std::size_t at = find(index) & 0xffffffffu;
    return {&triangles_[at],
            &boxes_[at],
            &planes_[at],
            &ids_[at],
            &octets_[at / detail::kFanout],
            count};
  }

 private:
  static constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();
  static constexpr std::size_t kFirstCapacity = 64;

  /// The table's entry for leaf `index`: (index, where its entries start), or an empty one where
  /// it goes. Open addressing, linear probing, at most half full.
  std::uint64_t& find(std::uint32_t index) noexcept {
    const std::size_t mask = table_.size() - 1;
    for (std::size_t at = (index * std::size_t{0x9e3779b1}) & mask;; at = (at + 1) & mask)
      if (table_[at] == kEmpty || table_[at] >> 32 == index) return table_[at];
  }
  void grow() {
    std::vector<std::uint64_t> old(2 * table_.size(), kEmpty);
    old.swap(table_);
    for (const std::uint64_t entry : old)
      if (entry != kEmpty) find(static_cast<std::uint32_t>(entry >> 32)) = entry;
  }

  const detail::QueryMeshData& mesh_;
  const detail::MatrixMotion* motion_;
  /// The leaves met so far and where their entries start: a hash table, so that a search pays
  /// for the leaves it meets, not for the tree's size (a particle against a large obstacle).
  std::vector<std::uint64_t> table_;
  std::size_t used_ = 0;
  std::vector<Triangle> triangles_;
  std::vector<Aabb> boxes_;
  std::vector<detail::SeparatingPlane> planes_;
  std::vector<std::uint32_t> ids_;
  std::vector<detail::MovedOctet> octets_;
};

}  // namespace

namespace {

/// minimumDistance(QueryMesh, QueryMesh)'s search: best first over pairs of nodes of the two
/// prepared trees, the pair with the nearest boxes opened next (the second tree's boxes moved
/// into the first's prepared frame), until the nearest remaining boxes are farther than the best
/// pair found (strictly: equal boxes may still hold a tie with smaller ids).
class PreparedPairSearch {
 public:
  PreparedPairSearch(const detail::QueryMeshData& a, const detail::QueryMeshData& b,
                     const detail::MovedTree& secondTree, const detail::MatrixMotion* motion,
                     kernels::Solver solver)
      : a_(a),
        b_(b),
        secondTree_(secondTree),
        solver_(solver),
        firstLeaves_(a, nullptr),
        secondLeaves_(b, motion),
        slabMargin_(a.slack + b.slack) {}

  /// The nearest pair, in the first mesh's prepared frame.
  MinimumDistance run() {
    push(static_cast<std::uint32_t>(a_.levels.size() - 1), 0,
         static_cast<std::uint32_t>(secondTree_.levelCount() - 1), 0);
    while (!open_.empty()) {
      const Entry entry = open_.top();
      open_.pop();
      if (entry.bound > bestSquared_) break;
      // Boxes of curved patches facing each other across a small gap overlap; their slabs often
      // do not (a third of refined_elephant's pairs end here, and the query takes 0.65 of the
      // time).
      const double gap = detail::slabGap(
          a_.slabs[entry.firstLevel][entry.firstNode], a_.levels[entry.firstLevel][entry.firstNode],
          secondTree_.moved(b_.slabs[entry.secondLevel][entry.secondNode]),
          secondTree_.box(entry.secondLevel, entry.secondNode), slabMargin_);
      if (gap > 0.0 && gap * gap > bestSquared_) continue;
      if (entry.firstLevel > 0 && (entry.secondLevel == 0 || entry.firstLevel >= entry.secondLevel))
        openFirst(entry);
      else if (entry.secondLevel > 0)
        openSecond(entry);
      else
        crossLeaves(entry);
    }
    best_.distance = std::sqrt(bestSquared_);
    return best_;
  }

 private:
  struct Entry {
    double bound;
    std::uint32_t firstLevel, firstNode, secondLevel, secondNode;
    bool operator>(const Entry& other) const noexcept { return bound > other.bound; }
  };

  /// Queues a pair of nodes unless farther than the best found so far (the best only falls: it
  /// could never be opened).
  void push(std::uint32_t la, std::uint32_t na, std::uint32_t lb, std::uint32_t nb) {
    const double bound = distanceSquared(a_.levels[la][na], secondTree_.box(lb, nb));
    if (!(bound > bestSquared_)) open_.push({bound, la, na, lb, nb});
  }

  // A node opens into its eight children at once: their boxes from the trees' octets (the
  // second's moved eight at a time), each pair queued unless farther than the best. (Opening the
  // nearest child next without the queue measured slower: it runs ahead of pairs nearer still.)

  /// The first node's children against the second node.
  void openFirst(const Entry& entry) {
    double bounds[detail::kFanout];
    const std::uint32_t level = entry.firstLevel - 1;
    // The octets lie less the origin of A's single-precision copy: the box too.
    const Aabb box = secondTree_.box(entry.secondLevel, entry.secondNode);
    detail::distancesSquared(a_.childOctets[level][entry.firstNode],
                             {box.lower - a_.lanes.origin, box.upper - a_.lanes.origin}, bounds);
    const std::size_t begin = std::size_t{entry.firstNode} * detail::kFanout;
    const std::size_t count = std::min(detail::kFanout, a_.levels[level].size() - begin);
    for (std::size_t c = 0; c < count; ++c)
      if (!(bounds[c] > bestSquared_))
        open_.push({bounds[c], level, static_cast<std::uint32_t>(begin + c), entry.secondLevel,
                    entry.secondNode});
  }

  /// The first node against the second node's children.
  void openSecond(const Entry& entry) {
    double bounds[detail::kFanout];
    const std::uint32_t level = entry.secondLevel - 1;
    detail::distancesSquared(
        secondTree_.moved(b_.childOctets[level][entry.secondNode], b_.lanes.origin),
        a_.levels[entry.firstLevel][entry.firstNode], bounds);
    const std::size_t begin = std::size_t{entry.secondNode} * detail::kFanout;
    const std::size_t count = std::min(detail::kFanout, secondTree_.nodeCount(level) - begin);
    for (std::size_t c = 0; c < count; ++c)
      if (!(bounds[c] > bestSquared_))
        open_.push({bounds[c], entry.firstLevel, entry.firstNode, level,
                    static_cast<std::uint32_t>(begin + c)});
  }

  /// Two leaves: each triangle of the first against those of the second's (at most) eight whose
  /// boxes (grown by the slack: rounding never drops a tie) are not farther than the best.
  void crossLeaves(const Entry& entry) {
    const LeafCache::Leaf other = secondLeaves_.leaf(entry.secondNode);
    const LeafCache::Leaf one = firstLeaves_.leaf(entry.firstNode);
    const Aabb secondBox = secondTree_.box(0, entry.secondNode);
    for (std::size_t i = 0; i < one.count; ++i) {
      if (distanceSquared(one.boxes[i], secondBox) > bestSquared_) continue;
      const double reach = std::sqrt(bestSquared_);  // +∞ before the first pair
      std::size_t kept = 0;
      double gaps[detail::kFanout];  // the second's eight boxes at once
      detail::distancesSquared(*other.octet, one.boxes[i], gaps);
      // Only the leaf's triangles: a short leaf's empty slots lie at +∞, which is not above the
      // best before the first pair (+∞), and their padding (zero triangles) would then be
      // measured as if they were triangles.
      const unsigned present = (1u << other.count) - 1;
      for (unsigned near = detail::notAboveMask(gaps, bestSquared_) & present; near != 0;
           near &= near - 1) {
        const auto k = static_cast<std::size_t>(std::countr_zero(near));
        if (!detail::separated(one.planes[i], other.triangles[k], other.planes[k].magnitude,
                               reach) &&
            !detail::separated(other.planes[k], one.triangles[i], one.planes[i].magnitude, reach)) {
          candidates_[kept] = other.triangles[k];
          ids_[kept++] = other.ids[k];
        }
      }
      if (kept == 0) continue;
      batch_.assign(std::span(candidates_, kept));
      kernels::distances(solver_, one.triangles[i], batch_, 0, kept, results_);
      for (std::size_t k = 0; k < results_.size(); ++k)
        offer(results_.distanceSquared(k), one.ids[i], ids_[k], k);
    }
  }

  /// The kernel's pair k (ids ia, ib at squared distance d) becomes the best if nearer, or as
  /// near with smaller ids.
  void offer(double d, std::uint32_t ia, std::uint32_t ib, std::size_t k) {
    const bool better =
        d < bestSquared_ || (d == bestSquared_ && found_ &&
                             (ia < best_.first || (ia == best_.first && ib < best_.second)));
    if (!better) return;
    bestSquared_ = d;
    found_ = true;
    best_ = {0.0, ia, ib, results_.p(k), results_.q(k), results_.intersect(k)};
  }

  const detail::QueryMeshData& a_;
  const detail::QueryMeshData& b_;
  const detail::MovedTree& secondTree_;
  const kernels::Solver solver_;
  // A leaf of either tree meets several of the other's: its triangles (the second's carried into
  // the first's frame), boxes and planes are made once, on its first meeting.
  LeafCache firstLeaves_, secondLeaves_;
  const double slabMargin_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open_;
  MinimumDistance best_;
  double bestSquared_ = std::numeric_limits<double>::infinity();
  bool found_ = false;
  kernels::PairResults results_{detail::kFanout};
  TriangleSoA batch_;
  Triangle candidates_[detail::kFanout];
  std::uint32_t ids_[detail::kFanout];
};

}  // namespace

MinimumDistance minimumDistance(const QueryMesh& first, const QueryMesh& second,
                                kernels::Solver solver) {
  // Moved meshes meet in the first one's prepared frame; the second's boxes and, leaf by leaf,
  // its triangles are carried there. Serial: the search is short and its answer must not depend
  // on threads.
  const RigidTransform secondToFirst = detail::checkPlacedPair(first, second, "minimumDistance");
  detail::requireTrianglesSpan(first, "minimumDistance: the first mesh");
  detail::requireTrianglesSpan(second, "minimumDistance: the second mesh");
  const detail::QueryMeshData &a = first.data(), &b = second.data();
  const bool moved = first.moved() || second.moved();
  const detail::MatrixMotion motion = detail::matrixMotion(secondToFirst);
  const detail::MovedTree secondTree(b.levels, moved ? &motion : nullptr);
  MinimumDistance best =
      PreparedPairSearch(a, b, secondTree, moved ? &motion : nullptr, solver).run();
  if (first.moved()) {
    best.p = first.pose().apply(best.p);
    best.q = first.pose().apply(best.q);
  }
  return best;
}

}  // namespace delta::contactdetection
