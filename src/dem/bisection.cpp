#include "delta/dem/bisection.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>
#include <optional>
#include <string>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta::dem {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// Bins of a histogram round: 8 bits of the 64-bit key a round, so 8 rounds at most.
constexpr std::size_t kBins = 256;
/// The most values one collective call carries (8 MiB).
constexpr std::size_t kValuesPerCall = std::size_t{1} << 20;
/// The values a node adds to a call of bounding boxes: max x, y, z and −min x, y, z.
constexpr std::size_t kBoxValues = 6;

Aabb allSpace() {
  return {{-kInfinity, -kInfinity, -kInfinity}, {kInfinity, kInfinity, kInfinity}};
}

/// −0 made +0, so that equal coordinates have equal bits (and equal keys).
double canonical(double coordinate) {
  return coordinate == 0.0 ? 0.0 : coordinate;
}

/// A finite, canonical double as an unsigned integer in the same order: the sign bit set for
/// positive values, every bit flipped for negative ones.
std::uint64_t orderedKey(double coordinate) {
  constexpr std::uint64_t kSign = std::uint64_t{1} << 63;
  const auto bits = std::bit_cast<std::uint64_t>(coordinate);
  return (bits & kSign) != 0 ? ~bits : bits | kSign;
}

/// A cut above `below` and at or below `above` (below < above): midway, or `above` where they
/// are adjacent doubles and the midpoint rounds down to `below`.
double cutBetween(double below, double above) {
  const double middle = std::midpoint(below, above);
  return middle > below ? middle : above;
}

/// The points the lower side of a node of `points` points and `parts` parts gets:
/// points·⌊parts/2⌋/parts rounded to the nearest integer, halves down (less than `points` when
/// there are any), computed without overflow.
std::uint64_t lowerTarget(std::uint64_t points, int parts) {
  const auto whole = static_cast<std::uint64_t>(parts), half = whole / 2;
  const std::uint64_t quotient = points / whole, remainder = points % whole;
  return quotient * half + (2 * remainder * half + whole - 1) / (2 * whole);
}

/// Whether the box, faces included, lies within `reach` of x: each axis's gap compared with
/// reach first, then the sum of the squared gaps in units of reach, which neither overflows nor
/// underflows to a wrong answer; it grows with each gap, so a box never comes nearer than a box
/// that holds it.
bool withinReach(const Vec3& x, const Aabb& box, double reach) {
  Vec3 gap;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    gap[axis] = std::max({box.lower[axis] - x[axis], x[axis] - box.upper[axis], 0.0});
    if (gap[axis] > reach) return false;
  }
  if (reach == 0.0 || reach == kInfinity) return true;
  return lengthSquared(gap / reach) <= 1.0;
}

}  // namespace
}  // namespace delta::dem

namespace delta::detail {

// The builder is the Bisection's friend (bisection.h) and uses the helpers above.
using namespace dem;

/// Builds a Bisection's tree level by level, so that each level's nodes share their collective
/// calls (see the header for the calls).
class BisectionBuilder {
 public:
  /// `weights` empty: every point weighs 1.
  BisectionBuilder(std::span<const Vec3> points, std::span<const std::uint32_t> weights, int parts,
                   const BisectionReduction& reduction)
      : parts_(parts), reduction_(reduction) {
    if (!weights.empty() && weights.size() != points.size())
      badWeight_ = std::min(weights.size(), points.size());
    points_.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec3& p = points[i];
      if (!badPoint_ && !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
        badPoint_ = i;
      const std::uint32_t weight = i < weights.size() ? weights[i] : 1;
      if (!badWeight_ && weight == 0) badWeight_ = i;
      points_.push_back({{canonical(p.x), canonical(p.y), canonical(p.z)}, weight});
    }
    if (badWeight_ && weights.size() != points.size())
      weightMessage_ = std::to_string(weights.size()) + " weights for " +
                       std::to_string(points.size()) + " points";
    else if (badWeight_)
      weightMessage_ = "the weight of point " + std::to_string(*badWeight_) + " is 0";
  }

  void build(Bisection& bisection);

 private:
  using Node = Bisection::Node;

  /// A node of the level being built.
  struct LevelNode {
    int node = 0;  ///< in Bisection::nodes_
    int firstPart = 0;
    int partCount = 0;
    std::size_t begin = 0, end = 0;  ///< its points on this process: points_[begin, end)
    std::uint64_t count = 0;         ///< its points over all processes
    Aabb region;                     ///< known once its parent's cut is
    Aabb box;                        ///< the bounding box of its points over all processes
  };

  /// How a node of the level is cut: the axis, which of its points go to the lower side (those
  /// whose key on the axis is below `threshold`; `lowerCount` of them over all processes), and
  /// the cut where it is known before the children's boxes are.
  struct Decision {
    std::size_t slot = 0;  ///< in the level
    int axis = 0;
    std::uint64_t lowerCount = 0;
    std::uint64_t threshold = 0;
    bool cutKnown = false;
    double cut = 0.0;
  };

  /// The histogram search of one node's boundary: the interval of keys [low, high] holds the
  /// target-th and (target+1)-th smallest keys, and `below` of the node's keys lie under it.
  struct Search {
    Decision* decision = nullptr;
    std::uint64_t target = 0;
    std::uint64_t low = 0, high = 0;
    std::uint64_t below = 0;
    bool done = false;
  };

  /// A cut of the level above, between the nodes lowerSlot and lowerSlot + 1 of this level.
  struct Split {
    int node = 0;
    int axis = 0;
    Aabb region;
    std::size_t lowerSlot = 0;
    bool cutKnown = false;
    double cut = 0.0;
  };

  void sum(std::span<std::uint64_t> values) const {
    if (reduction_.sum) reduction_.sum(values);
  }
  void maximum(std::span<double> values) const {
    if (reduction_.maximum) reduction_.maximum(values);
  }

  /// The first collective call: the root's box, whether any process has a non-finite point and
  /// the extremes of `parts`; throws on every process together.
  void reduceRoot(LevelNode& root);
  /// The bounding boxes of the level's nodes over all processes.
  void reduceBoxes(std::span<LevelNode> level);
  /// The cuts of the level above that waited for this level's boxes, and this level's regions.
  void settleCuts(std::span<const Split> splits, std::span<LevelNode> level,
                  std::vector<Node>& nodes) const;
  /// Cuts the level's inner nodes: their children, in order, and their splits.
  std::vector<Split> cutLevel(std::span<const LevelNode> level, std::vector<Node>& nodes,
                              std::vector<LevelNode>& next);
  /// Runs the searches in batches of at most kValuesPerCall / kBins nodes a call.
  void search(std::span<Search> searches, std::span<const LevelNode> level);
  /// One histogram round for the searches not yet done.
  void searchRound(std::span<Search*> searches, std::span<const LevelNode> level);
  /// The cut of a node whose lower side gets none of its points.
  double cutBelowAll(const LevelNode& node, int axis) const;

  int parts_;
  const BisectionReduction& reduction_;
  /// A point of this process and its weight (the counts below are sums of weights).
  struct WeightedPoint {
    Vec3 point;
    std::uint64_t weight = 1;
  };
  std::vector<WeightedPoint> points_;  ///< this process's, canonical, reordered node by node
  std::optional<std::size_t> badPoint_;
  std::optional<std::size_t> badWeight_;
  std::string weightMessage_;
  Aabb domain_;  ///< the bounding box of all points, or [−1, 1]³ without any
};

void BisectionBuilder::build(Bisection& bisection) {
  std::vector<Node>& nodes = bisection.nodes_;
  nodes.assign(1, {});
  bisection.regions_.assign(static_cast<std::size_t>(parts_), allSpace());
  std::vector<LevelNode> level(1);
  level[0].partCount = parts_;
  level[0].end = points_.size();
  level[0].region = allSpace();
  reduceRoot(level[0]);
  domain_ = level[0].box.empty() ? Aabb{{-1, -1, -1}, {1, 1, 1}} : level[0].box;
  if (parts_ > 1) {
    level[0].count = 0;
    for (const WeightedPoint& p : points_)
      level[0].count += p.weight;
    sum({&level[0].count, 1});
  }
  std::vector<Split> splits;
  for (;;) {
    settleCuts(splits, level, nodes);
    for (const LevelNode& leaf : level)
      if (leaf.partCount == 1) {
        nodes[static_cast<std::size_t>(leaf.node)] = {0.0, Node::kLeaf, leaf.firstPart};
        bisection.regions_[static_cast<std::size_t>(leaf.firstPart)] = leaf.region;
      }
    std::vector<LevelNode> next;
    splits = cutLevel(level, nodes, next);
    if (next.empty()) break;
    level = std::move(next);
    reduceBoxes(level);
  }
}

void BisectionBuilder::reduceRoot(LevelNode& root) {
  Aabb box;  // of finite points only: an empty box where there is a bad one
  if (!badPoint_)
    for (const WeightedPoint& p : points_)
      box.extend(p.point);
  const double bad = badPoint_ || badWeight_ ? 1.0 : 0.0, parts = parts_;
  std::vector<double> values = {bad,         parts,        -parts,       box.upper.x, box.upper.y,
                                box.upper.z, -box.lower.x, -box.lower.y, -box.lower.z};
  maximum(values);
  if (badPoint_) {
    const Vec3& p = points_[*badPoint_].point;
    throw Error("Bisection: point " + std::to_string(*badPoint_) +
                " is not finite: " + toString(p));
  }
  if (badWeight_) throw Error("Bisection: " + weightMessage_);
  if (values[0] > 0.0)
    throw Error("Bisection: a point of another process is not finite, or its weight is 0");
  if (values[1] != parts || -values[2] != parts)
    throw Error("Bisection: the processes disagree on the number of parts (" +
                std::to_string(parts_) + " here, from " + toString(-values[2]) + " to " +
                toString(values[1]) + ")");
  root.box = {{-values[6], -values[7], -values[8]}, {values[3], values[4], values[5]}};
}

void BisectionBuilder::reduceBoxes(std::span<LevelNode> level) {
  constexpr std::size_t kNodesPerCall = kValuesPerCall / kBoxValues;
  std::vector<double> values;
  for (std::size_t first = 0; first < level.size(); first += kNodesPerCall) {
    const std::span<LevelNode> batch =
        level.subspan(first, std::min(kNodesPerCall, level.size() - first));
    values.clear();
    for (const LevelNode& node : batch) {
      Aabb box;
      for (std::size_t i = node.begin; i < node.end; ++i)
        box.extend(points_[i].point);
      values.insert(values.end(), {box.upper.x, box.upper.y, box.upper.z, -box.lower.x,
                                   -box.lower.y, -box.lower.z});
    }
    maximum(values);
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const double* v = &values[kBoxValues * i];
      batch[i].box = {{-v[3], -v[4], -v[5]}, {v[0], v[1], v[2]}};
    }
  }
}

void BisectionBuilder::settleCuts(std::span<const Split> splits, std::span<LevelNode> level,
                                  std::vector<Node>& nodes) const {
  for (const Split& split : splits) {
    LevelNode& lower = level[split.lowerSlot];
    LevelNode& upper = level[split.lowerSlot + 1];
    const auto axis = static_cast<std::size_t>(split.axis);
    // Below: the largest coordinate of the lower side; above: the smallest of the upper side.
    const double cut =
        split.cutKnown ? split.cut : cutBetween(lower.box.upper[axis], upper.box.lower[axis]);
    nodes[static_cast<std::size_t>(split.node)].cut = cut;
    lower.region = upper.region = split.region;
    lower.region.upper[axis] = cut;
    upper.region.lower[axis] = cut;
  }
}

double BisectionBuilder::cutBelowAll(const LevelNode& node, int axis) const {
  const auto a = static_cast<std::size_t>(axis);
  const double lowest = node.box.lower[a];
  const double lowerFace = std::max(node.region.lower[a], domain_.lower[a]);
  return lowerFace < lowest ? std::midpoint(lowerFace, lowest) : lowest;
}

std::vector<BisectionBuilder::Split> BisectionBuilder::cutLevel(std::span<const LevelNode> level,
                                                                std::vector<Node>& nodes,
                                                                std::vector<LevelNode>& next) {
  // First how each inner node is cut (the searches of the whole level share their calls), then
  // its points partitioned and its children made, in the level's order.
  std::vector<Decision> decisions;
  for (std::size_t slot = 0; slot < level.size(); ++slot)
    if (level[slot].partCount > 1) decisions.push_back({.slot = slot});
  std::vector<Search> searches;
  for (Decision& decision : decisions) {
    const LevelNode& node = level[decision.slot];
    if (node.count == 0) {
      const Aabb room = intersection(node.region, domain_);
      decision.axis = longestAxis(room);
      const auto axis = static_cast<std::size_t>(decision.axis);
      decision.cutKnown = true;
      decision.cut = std::midpoint(room.lower[axis], room.upper[axis]);
      continue;
    }
    decision.axis = longestAxis(node.box);
    const std::uint64_t target = lowerTarget(node.count, node.partCount);
    if (target == 0) continue;  // settled below: nothing to the lower side
    const auto axis = static_cast<std::size_t>(decision.axis);
    searches.push_back({.decision = &decision,
                        .target = target,
                        .low = orderedKey(node.box.lower[axis]),
                        .high = orderedKey(node.box.upper[axis])});
  }
  search(searches, level);

  std::vector<Split> splits;
  for (Decision& decision : decisions) {
    const LevelNode& node = level[decision.slot];
    if (node.count > 0 && decision.lowerCount == 0) {
      decision.cutKnown = true;
      decision.cut = cutBelowAll(node, decision.axis);
    }
    const auto axis = static_cast<std::size_t>(decision.axis);
    std::size_t middle = node.begin;
    if (decision.lowerCount > 0)
      middle = static_cast<std::size_t>(
          std::partition(points_.begin() + static_cast<std::ptrdiff_t>(node.begin),
                         points_.begin() + static_cast<std::ptrdiff_t>(node.end),
                         [&](const WeightedPoint& p) {
                           return orderedKey(p.point[axis]) < decision.threshold;
                         }) -
          points_.begin());
    const int child = static_cast<int>(nodes.size());
    nodes.resize(nodes.size() + 2);
    nodes[static_cast<std::size_t>(node.node)] = {decision.cut, decision.axis, child};
    const int lowerParts = node.partCount / 2;
    splits.push_back({.node = node.node,
                      .axis = decision.axis,
                      .region = node.region,
                      .lowerSlot = next.size(),
                      .cutKnown = decision.cutKnown,
                      .cut = decision.cut});
    next.push_back({.node = child,
                    .firstPart = node.firstPart,
                    .partCount = lowerParts,
                    .begin = node.begin,
                    .end = middle,
                    .count = decision.lowerCount,
                    .region = {},  // both settled after the next level's box reduction
                    .box = {}});
    next.push_back({.node = child + 1,
                    .firstPart = node.firstPart + lowerParts,
                    .partCount = node.partCount - lowerParts,
                    .begin = middle,
                    .end = node.end,
                    .count = node.count - decision.lowerCount,
                    .region = {},
                    .box = {}});
  }
  return splits;
}

void BisectionBuilder::search(std::span<Search> searches, std::span<const LevelNode> level) {
  constexpr std::size_t kNodesPerCall = kValuesPerCall / kBins;
  std::vector<Search*> open;
  for (std::size_t first = 0; first < searches.size(); first += kNodesPerCall) {
    const std::span<Search> batch =
        searches.subspan(first, std::min(kNodesPerCall, searches.size() - first));
    for (;;) {
      open.clear();
      for (Search& s : batch)
        if (!s.done) open.push_back(&s);
      if (open.empty()) break;
      searchRound(open, level);
    }
  }
}

void BisectionBuilder::searchRound(std::span<Search*> searches, std::span<const LevelNode> level) {
  std::vector<std::uint64_t> counts(kBins * searches.size(), 0);
  std::vector<std::uint64_t> widths(searches.size());
  for (std::size_t i = 0; i < searches.size(); ++i) {
    const Search& s = *searches[i];
    // The keys of finite doubles span less than 2⁶⁴ − 1, so high − low + 1 does not overflow.
    const std::uint64_t span = s.high - s.low + 1;
    widths[i] = span / kBins + (span % kBins != 0 ? 1 : 0);
    const LevelNode& node = level[s.decision->slot];
    const auto axis = static_cast<std::size_t>(s.decision->axis);
    std::uint64_t* bins = &counts[kBins * i];
    for (std::size_t p = node.begin; p < node.end; ++p) {
      const std::uint64_t key = orderedKey(points_[p].point[axis]);
      if (key >= s.low && key <= s.high) bins[(key - s.low) / widths[i]] += points_[p].weight;
    }
  }
  sum(counts);
  for (std::size_t i = 0; i < searches.size(); ++i) {
    Search& s = *searches[i];
    const std::uint64_t* bins = &counts[kBins * i];
    std::uint64_t below = s.below;
    std::size_t bin = 0;
    while (below + bins[bin] <= s.target) {  // the bin that holds the (target+1)-th key
      below += bins[bin];
      ++bin;
      assert(bin < kBins && "the interval holds the (target+1)-th key");
    }
    const std::uint64_t binLow = s.low + bin * widths[i];
    Decision& decision = *s.decision;
    if (below == s.target) {  // the target-th key lies in an earlier bin: the boundary is here
      decision.lowerCount = s.target;
      decision.threshold = binLow;
      s.done = true;
    } else if (widths[i] == 1) {  // one value holds both: duplicates across the boundary
      const std::uint64_t through = below + bins[bin];
      decision.lowerCount = s.target - below <= through - s.target ? below : through;
      decision.threshold = decision.lowerCount == below ? binLow : binLow + 1;
      s.done = true;
    } else {
      s.low = binLow;
      s.high = std::min(binLow + (widths[i] - 1), s.high);
      s.below = below;
    }
  }
}

}  // namespace delta::detail

namespace delta::dem {

Bisection::Bisection() : nodes_(1), regions_(1, allSpace()) {}

Bisection::Bisection(std::span<const Vec3> points, int parts, const BisectionReduction& reduction) {
  if (parts < 1 || parts > kMaxParts)
    throw Error("Bisection: parts " + std::to_string(parts) + " is not in [1, " +
                std::to_string(kMaxParts) + "]");
  detail::BisectionBuilder(points, {}, parts, reduction).build(*this);
}

Bisection::Bisection(std::span<const Vec3> points, std::span<const std::uint32_t> weights,
                     int parts, const BisectionReduction& reduction) {
  if (parts < 1 || parts > kMaxParts)
    throw Error("Bisection: parts " + std::to_string(parts) + " is not in [1, " +
                std::to_string(kMaxParts) + "]");
  detail::BisectionBuilder(points, weights, parts, reduction).build(*this);
}

int Bisection::partOf(const Vec3& x) const noexcept {
  const Node* node = &nodes_[0];
  while (node->axis != Node::kLeaf) {
    const bool lower = x[static_cast<std::size_t>(node->axis)] < node->cut;
    node = &nodes_[static_cast<std::size_t>(node->child + (lower ? 0 : 1))];
  }
  return node->child;
}

void Bisection::partsWithin(const Vec3& x, double reach, std::vector<int>& out) const {
  if (!(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z)))
    throw Error("Bisection::partsWithin: the point " + toString(x) + " is not finite");
  if (!(reach >= 0.0))
    throw Error("Bisection::partsWithin: the reach " + toString(reach) +
                " is negative or not a number");
  out.clear();
  collectWithin(0, allSpace(), x, reach, out);
}

void Bisection::collectWithin(int node, const Aabb& region, const Vec3& x, double reach,
                              std::vector<int>& out) const {
  const Node& n = nodes_[static_cast<std::size_t>(node)];
  if (n.axis == Node::kLeaf) {
    out.push_back(n.child);
    return;
  }
  const auto axis = static_cast<std::size_t>(n.axis);
  Aabb lower = region, upper = region;
  lower.upper[axis] = n.cut;
  upper.lower[axis] = n.cut;
  if (withinReach(x, lower, reach)) collectWithin(n.child, lower, x, reach, out);
  if (withinReach(x, upper, reach)) collectWithin(n.child + 1, upper, x, reach, out);
}

Aabb Bisection::region(int part) const {
  if (part < 0 || part >= parts())
    throw Error("Bisection::region: part " + std::to_string(part) + " is not in [0, " +
                std::to_string(parts()) + ")");
  return regions_[static_cast<std::size_t>(part)];
}

}  // namespace delta::dem
