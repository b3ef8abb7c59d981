#include "dual_traversal.h"

#include <algorithm>
#include <cmath>

namespace delta::detail {
namespace {

double largestExtent(const Aabb& box) noexcept {
  const Vec3 extent = box.extent();
  return std::max({extent.x, extent.y, extent.z});
}

struct NodePair {
  std::uint32_t firstLevel, first, secondLevel, second;
};

}  // namespace

MatrixMotion matrixMotion(const RigidTransform& motion) {
  const Quaternion& q = motion.rotation;
  return {Quaternion::fromComponents(q.w, q.x, q.y, q.z).matrix(), motion.translation};
}

MovedTree::MovedTree(const std::vector<std::vector<Aabb>>& levels,
                     const MatrixMotion* motion) noexcept
    : levels_(levels), motion_(motion) {
  if (!motion) return;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      magnitude_(r, c) = std::abs(motion->rotation(r, c));
}

std::vector<LeafPair> leafPairsWithin(const std::vector<std::vector<Aabb>>& firstLevels,
                                      const MovedTree& second, double reach) {
  std::vector<LeafPair> pairs;
  std::vector<NodePair> stack;
  stack.push_back({static_cast<std::uint32_t>(firstLevels.size() - 1), 0,
                   static_cast<std::uint32_t>(second.levelCount() - 1), 0});
  while (!stack.empty()) {
    const NodePair pair = stack.back();
    stack.pop_back();
    const Aabb& a = firstLevels[pair.firstLevel][pair.first];
    const Aabb b = second.box(pair.secondLevel, pair.second);
    if (apart(a, b, reach)) continue;
    if (pair.firstLevel == 0 && pair.secondLevel == 0) {
      pairs.push_back({pair.first, pair.second});
      continue;
    }
    const bool splitFirst =
        pair.secondLevel == 0 || (pair.firstLevel > 0 && largestExtent(a) >= largestExtent(b));
    if (splitFirst) {
      const std::uint32_t level = pair.firstLevel - 1;
      const std::size_t begin = std::size_t{pair.first} * kFanout;
      const std::size_t end = std::min(begin + kFanout, firstLevels[level].size());
      for (std::size_t c = begin; c < end; ++c)
        stack.push_back({level, static_cast<std::uint32_t>(c), pair.secondLevel, pair.second});
    } else {
      const std::uint32_t level = pair.secondLevel - 1;
      const std::size_t begin = std::size_t{pair.second} * kFanout;
      const std::size_t end = std::min(begin + kFanout, second.nodeCount(level));
      for (std::size_t c = begin; c < end; ++c)
        stack.push_back({pair.firstLevel, pair.first, level, static_cast<std::uint32_t>(c)});
    }
  }
  return pairs;
}

}  // namespace delta::detail
