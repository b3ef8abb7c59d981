#include "dual_traversal.h"

#include <algorithm>
#include <bit>
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

/// apart(a, b, gap) without a branch: the descents below test eight children at once, whose
/// outcomes a branch per test would mispredict.
[[gnu::always_inline]] inline bool near(const Aabb& a, const Aabb& b, double gap) noexcept {
  return static_cast<bool>(static_cast<int>(a.lower.x - b.upper.x < gap) &
                           static_cast<int>(b.lower.x - a.upper.x < gap) &
                           static_cast<int>(a.lower.y - b.upper.y < gap) &
                           static_cast<int>(b.lower.y - a.upper.y < gap) &
                           static_cast<int>(a.lower.z - b.upper.z < gap) &
                           static_cast<int>(b.lower.z - a.upper.z < gap));
}

}  // namespace

MatrixMotion matrixMotion(const RigidTransform& motion) {
  const Quaternion& q = motion.rotation;
  return {Quaternion::fromComponents(q.w, q.x, q.y, q.z).matrix(), motion.translation};
}

/// Each body's move is bounded by its box centre's move plus ‖R − R₀‖ times its radius about that
/// centre (|(R − R₀)·(p − c)| ≤ ‖R − R₀‖·|p − c|). ‖R − R₀‖ = ‖Rᵀ − R₀ᵀ‖ = ‖R₀ᵀR − I‖ = 2 sin(θ/2)
/// = √(3 − tr R₀ᵀR) for rotations, the same in both frames; the trace, ⟨R₀, R⟩ summed entry by
/// entry, cancels for small turns, so its rounding (a few ulps of 3) is added under the root. (The
/// box's farthest corner is no less than the centre's move, so it can beat the ball by less
/// than ‖R − R₀‖ times the radius, 2⁻²⁰ of it for a pure translation, and bounds a turn up to √3
/// times worse: not computed.)
double relativeMove(const QueryMeshData& first, const QueryMeshData& second,
                    const MatrixMotion& now, const Mat3& rotation,
                    const Vec3& translation) noexcept {
  double trace = 0.0;
  for (std::size_t k = 0; k < 9; ++k)
    trace += rotation.entries[k] * now.rotation.entries[k];
  const double turnNorm = std::sqrt(std::max(0.0, 3.0 - trace) + 0x1p-40);
  // The second's centre in the first's frame, now and then.
  const Vec3 centreB = second.bounds.center();
  const double secondMoved =
      length(now.apply(centreB) - (rotation * centreB + translation)) + turnNorm * second.radius;
  // The first's centre in the second's frame, now and then: Rᵀ·(c − t).
  const Vec3 centreA = first.bounds.center();
  const double firstMoved = length(now.rotation.transposed() * (centreA - now.translation) -
                                   rotation.transposed() * (centreA - translation)) +
                            turnNorm * first.radius;
  return std::min(secondMoved, firstMoved);
}

double placedMagnitude(const Aabb& first, const Aabb& second,
                       const RigidTransform& secondToFirst) noexcept {
  double magnitude = std::max(maxAbs(first.lower), maxAbs(first.upper));
  for (int corner = 0; corner < 8; ++corner)
    magnitude = std::max(magnitude, maxAbs(secondToFirst.apply(second.corner(corner))));
  return magnitude;
}

MovedOctet boxesOf(const Triangle* triangles, std::size_t count, double slack) noexcept {
  MovedOctet octet;
  for (std::size_t i = 0; i < kFanout; ++i) {
    const Aabb box = i < count ? triangles[i].bounds().grown(slack) : Aabb{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      octet.lower[axis][i] = box.lower[axis];
      octet.upper[axis][i] = box.upper[axis];
    }
  }
  return octet;
}

FloatOctet movedLeafBoxes(const FloatTriangles& lanes, std::size_t leaf, std::size_t count,
                          const MatrixMotion* motion, const Vec3& reference) noexcept {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  // Moved, less the reference: R·(f + origin) + t − reference = R·f + c, f a corner of the copy.
  const Mat3 rotation = motion ? motion->rotation : Mat3::identity();
  const Vec3 translation = motion ? motion->translation : Vec3{};
  const Vec3 c = rotation * lanes.origin + translation - reference;
  // Every rounding, generously: the copy's (δ, at most √3·δ through R), single precision's in
  // R·f + c and in the bounds (a few 2⁻²⁴ of |R·f| + |c| ≤ √3·largest + |c|), double's in c and
  // in the corners the queries move (2⁻⁵³ of their terms).
  constexpr double kRootThree = 1.7320508075688772;
  const double largest = 0x1p22 * lanes.rounding;  // ≥ every |coordinate| of the copy
  const double terms =
      kRootThree * (largest + maxAbs(lanes.origin)) + maxAbs(translation) + maxAbs(reference);
  double slack[3];
  for (std::size_t k = 0; k < 3; ++k)
    slack[k] = kRootThree * lanes.rounding + 0x1p-19 * (kRootThree * largest + std::abs(c[k])) +
               0x1p-48 * terms + 0x1p-140;
  // Single precision holds it all while it stays below 2¹¹⁰ (its limit is 2¹²⁸); beyond, boxes
  // without bounds.
  const bool bounded =
      largest < 0x1p100 && std::max({maxAbs(c), slack[0], slack[1], slack[2]}) < 0x1p110;
  FloatOctet boxes;
  for (std::size_t axis = 0; axis < 3; ++axis)
    for (std::size_t i = 0; i < kFanout; ++i) {
      const bool unbounded = i < count && !bounded;
      boxes.lower[axis][i] = unbounded ? -kInfinity : kInfinity;
      boxes.upper[axis][i] = unbounded ? kInfinity : -kInfinity;
    }
  if (!bounded) return boxes;
  float r[3][3], offset[3], widen[3];
  for (int row = 0; row < 3; ++row) {
    const auto k = static_cast<std::size_t>(row);
    for (int column = 0; column < 3; ++column)
      r[k][static_cast<std::size_t>(column)] = static_cast<float>(rotation(row, column));
    offset[k] = static_cast<float>(c[k]);
    widen[k] = static_cast<float>(slack[k]);
  }
  const float* block = lanes.coordinates.data() + leaf * 9 * kFanout;
  for (std::size_t row = 0; row < 3; ++row) {
    float low[kFanout], high[kFanout];
    for (std::size_t i = 0; i < kFanout; ++i) {
      low[i] = kInfinity;
      high[i] = -kInfinity;
    }
    for (std::size_t corner = 0; corner < 3; ++corner) {
      const float* f = block + 3 * corner * kFanout;
#pragma GCC unroll 1  // vectorised whole (see lanesMeeting)
      for (std::size_t i = 0; i < kFanout; ++i) {
        const float moved = r[row][0] * f[i] + r[row][1] * f[kFanout + i] +
                            r[row][2] * f[2 * kFanout + i] + offset[row];
        low[i] = std::min(low[i], moved);  // NaN (padding) leaves the lane empty
        high[i] = std::max(high[i], moved);
      }
    }
    for (std::size_t i = 0; i < kFanout; ++i) {
      boxes.lower[row][i] = low[i] - widen[row];
      boxes.upper[row][i] = high[i] + widen[row];
    }
  }
  return boxes;
}

std::uint32_t lanesMeeting(const FloatOctet& boxes, const float lower[3],
                           const float upper[3]) noexcept {
  // Without branches, so that it vectorises (a branch a lane would be a coin toss). An empty
  // lane (+∞, −∞) is tested as such: against a box without bounds (−∞, +∞: a mesh beyond single
  // precision's range) the two closed comparisons alone hold for it, and the overlap query then
  // placed triangles past the leaf's last, reading outside the mesh.
  std::int32_t meets[kFanout];
  for (std::size_t i = 0; i < kFanout; ++i)
    meets[i] = 1;
  for (std::size_t axis = 0; axis < 3; ++axis)
#pragma GCC unroll 1  // left whole, GCC vectorises the loop; unrolled first, it did not
    for (std::size_t i = 0; i < kFanout; ++i)
      meets[i] &= static_cast<std::int32_t>(lower[axis] <= boxes.upper[axis][i]) &
                  static_cast<std::int32_t>(boxes.lower[axis][i] <= upper[axis]) &
                  static_cast<std::int32_t>(boxes.lower[axis][i] <= boxes.upper[axis][i]);
  std::uint32_t mask = 0;
  for (std::size_t i = 0; i < kFanout; ++i)
    mask |= static_cast<std::uint32_t>(meets[i]) << i;
  return mask;
}

MovedTree::MovedTree(const std::vector<std::vector<Aabb>>& levels,
                     const MatrixMotion* motion) noexcept
    : levels_(levels), motion_(motion) {
  if (!motion) return;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      magnitude_(r, c) = std::abs(motion->rotation(r, c));
}

void leafPairsWithin(const QueryMeshData& firstMesh, const QueryMeshData& secondMesh,
                     const MovedTree& second, double reach, std::vector<LeafPair>& pairs) {
  // Pairs are tested when they are found, so that the box that stays (the second one, moved,
  // when the first node splits) is computed once for its eight partners, and only pairs within
  // reach are stacked; a stacked pair and a pair of leaves must also have their slabs within
  // reach (nearly parallel patches facing each other: boxes overlap, slabs need not).
  const std::vector<std::vector<Aabb>>& firstLevels = firstMesh.levels;
  const double margin = firstMesh.slack + secondMesh.slack;
  const auto slabsApart = [&](std::uint32_t firstLevel, std::uint32_t first, const Aabb& a,
                              std::uint32_t secondLevel, std::uint32_t secondNode, const Aabb& b) {
    return slabGap(firstMesh.slabs[firstLevel][first], a,
                   second.moved(secondMesh.slabs[secondLevel][secondNode]), b, margin) >= reach;
  };
  pairs.clear();
  thread_local std::vector<NodePair> stack;  // empty between calls (the loop below empties it)
  const auto firstRoot = static_cast<std::uint32_t>(firstLevels.size() - 1);
  const auto secondRoot = static_cast<std::uint32_t>(second.levelCount() - 1);
  if (!apart(firstLevels[firstRoot][0], second.box(secondRoot, 0), reach)) {
    if (firstRoot == 0 && secondRoot == 0) {
      pairs.push_back({0, 0});
      return;
    }
    stack.push_back({firstRoot, 0, secondRoot, 0});
  }
  while (!stack.empty()) {
    const NodePair pair = stack.back();
    stack.pop_back();
    const Aabb& a = firstLevels[pair.firstLevel][pair.first];
    const Aabb b = second.box(pair.secondLevel, pair.second);
    if (slabsApart(pair.firstLevel, pair.first, a, pair.secondLevel, pair.second, b)) continue;
    const bool splitFirst =
        pair.secondLevel == 0 || (pair.firstLevel > 0 && largestExtent(a) >= largestExtent(b));
    // The children within reach: a pair of leaves is a result at once, others go on the stack.
    if (splitFirst) {
      const std::uint32_t level = pair.firstLevel - 1;
      const std::size_t begin = std::size_t{pair.first} * kFanout;
      const std::size_t end = std::min(begin + kFanout, firstLevels[level].size());
      unsigned mask = 0;
      for (std::size_t c = begin; c < end; ++c)
        mask |= static_cast<unsigned>(near(firstLevels[level][c], b, reach)) << (c - begin);
      for (; mask != 0; mask &= mask - 1) {
        const auto c = static_cast<std::uint32_t>(begin) + std::countr_zero(mask);
        if (level == 0 && pair.secondLevel == 0) {
          if (!slabsApart(0, c, firstLevels[0][c], 0, pair.second, b))
            pairs.push_back({c, pair.second});
        } else {
          stack.push_back({level, c, pair.secondLevel, pair.second});
        }
      }
    } else {
      const std::uint32_t level = pair.secondLevel - 1;
      const std::size_t begin = std::size_t{pair.second} * kFanout;
      const std::size_t end = std::min(begin + kFanout, second.nodeCount(level));
      unsigned mask = 0;
      for (std::size_t c = begin; c < end; ++c)
        mask |= static_cast<unsigned>(near(a, second.box(level, c), reach)) << (c - begin);
      for (; mask != 0; mask &= mask - 1) {
        const auto c = static_cast<std::uint32_t>(begin) + std::countr_zero(mask);
        if (level == 0 && pair.firstLevel == 0) {
          if (!slabsApart(0, pair.first, a, 0, c, second.box(0, c)))
            pairs.push_back({pair.first, c});
        } else {
          stack.push_back({pair.firstLevel, pair.first, level, c});
        }
      }
    }
  }
}

}  // namespace delta::detail
