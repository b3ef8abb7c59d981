#include "delta/cache/spatial_cache.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/mesh/coordinate_range.h"

namespace delta {
namespace detail {

/// One octree cell. Its children, once built, are 8 consecutive cells in a ChildBlock, published
/// through `children` (release) after they are completely built; readers load it with acquire.
struct CacheCell {
  Aabb box;
  double lowerBound = 0.0;
  double upperBound = 0.0;
  const std::uint32_t* candidates = nullptr;
  std::uint32_t candidateCount = 0;
  int depth = 0;
  std::atomic<CacheCell*> children{nullptr};

  std::span<const std::uint32_t> candidateSpan() const noexcept {
    return {candidates, candidateCount};
  }
};

/// The 8 children of a cell and their candidate lists, one after the other in one array.
struct ChildBlock {
  std::array<CacheCell, 8> cells;
  std::vector<std::uint32_t> candidates;
};

struct SpatialCacheState {
  static constexpr std::size_t kStripes = 64;

  const TriangleSoA* triangles = nullptr;
  CacheOptions options;
  std::vector<Aabb> boxes;  ///< of every triangle, by id
  double scale = 0.0;       ///< the root side: rounding slacks are relative to it
  CacheCell root;
  std::vector<std::uint32_t> rootCandidates;
  std::atomic<bool> refinementAllowed{true};
  std::atomic<std::size_t> cellCount{1};
  std::atomic<std::size_t> memoryBytes{0};
  /// Taken only to refine: stripe of the cell, then (briefly) blocksMutex to own the block.
  std::array<std::mutex, kStripes> stripes;
  std::mutex blocksMutex;
  std::vector<std::unique_ptr<ChildBlock>> blocks;  ///< never moves a published cell
};

namespace {

/// Relative size of the rounding slack in the bounds and in the nearest search: far above the
/// few ulps of closestPointOnTriangle (a few ε·(size + distance)) and of box distances, far
/// below any distance that matters.
constexpr double kSlack = 1e-12;

bool meetsCriterion(const SpatialCacheState& state, const CacheCell& cell) noexcept {
  return cell.candidateCount > state.options.maxCandidates && cell.depth < state.options.maxDepth &&
         cell.lowerBound == 0.0;
}

/// The child of a cell with centre `mid` that holds `p`: bit a set when p is on the upper side
/// of `mid` along axis a (a point on the dividing plane goes up; boxes are closed, so it is in
/// that child too).
std::size_t childIndex(const Vec3& p, const Vec3& mid) noexcept {
  return (p.x >= mid.x ? 1u : 0u) | (p.y >= mid.y ? 2u : 0u) | (p.z >= mid.z ? 4u : 0u);
}

/// The squared gap between the intervals [lower, upper] and [otherLower, otherUpper] (0 where
/// they overlap): one axis of a box–box or point–box distance (aabb.h).
inline double gapSquared(double lower, double upper, double otherLower,
                         double otherUpper) noexcept {
  const double gap = std::max(0.0, std::max(otherLower - upper, lower - otherUpper));
  return gap * gap;
}

struct BoxEntry {
  double boxDistanceSquared;  ///< from the query point to the triangle's box
  std::uint32_t id;
};

/// The squared radius within which a triangle's box must lie to win against (or tie with) the
/// best squared distance found: the distance enlarged by a rounding slack, since the kernel's
/// distance may fall a few ulps below the box's.
double pruneRadiusSquared(const SpatialCacheState& state, double bestSquared) noexcept {
  const double radius = std::sqrt(bestSquared) * (1.0 + kSlack) + kSlack * state.scale;
  return radius * radius;
}

CachedNearest evaluate(const SpatialCacheState& state, const Vec3& p, std::uint32_t id) noexcept {
  CachedNearest result;
  result.triangle = id;
  result.closest = kernels::closestPointOnTriangle(p, state.triangles->triangle(id));
  result.distanceSquared = result.closest.distanceSquared;
  return result;
}

/// Finishes a nearest search that starts from `best`: visits `entries` (other triangles, with
/// their box distances from `p`) nearest box first and calls the kernel while a box is within
/// the prune radius. Ties go to the smallest id, so the answer does not depend on the order.
void improve(const SpatialCacheState& state, const Vec3& p, std::span<BoxEntry> entries,
             CachedNearest& best) {
  std::sort(entries.begin(), entries.end(), [](const BoxEntry& a, const BoxEntry& b) {
    return a.boxDistanceSquared < b.boxDistanceSquared;
  });
  double prune = pruneRadiusSquared(state, best.distanceSquared);
  for (const BoxEntry& entry : entries) {
    if (entry.boxDistanceSquared > prune) break;
    const CachedNearest next = evaluate(state, p, entry.id);
    if (next.distanceSquared < best.distanceSquared ||
        (next.distanceSquared == best.distanceSquared && entry.id < best.triangle)) {
      best = next;
      prune = pruneRadiusSquared(state, best.distanceSquared);
    }
  }
}

/// The exact nearest of `candidates` (non-empty) to `p`: the triangle with the nearest box
/// first, then every other whose box is within the prune radius, nearest first.
CachedNearest nearestAmong(const SpatialCacheState& state, const Vec3& p,
                           std::span<const std::uint32_t> candidates) {
  assert(!candidates.empty());  // every cell lists at least the nearest triangle of its centre
  constexpr std::size_t kStackEntries = 64;
  std::array<BoxEntry, kStackEntries> onStack;
  std::unique_ptr<BoxEntry[]> onHeap;
  BoxEntry* entries = onStack.data();
  if (candidates.size() > kStackEntries) {
    onHeap.reset(new BoxEntry[candidates.size()]);
    entries = onHeap.get();
  }
  std::size_t first = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    entries[i] = {distanceSquared(p, state.boxes[candidates[i]]), candidates[i]};
    if (entries[i].boxDistanceSquared < entries[first].boxDistanceSquared) first = i;
  }
  CachedNearest best = evaluate(state, p, entries[first].id);
  const double prune = pruneRadiusSquared(state, best.distanceSquared);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (i != first && entries[i].boxDistanceSquared <= prune) entries[kept++] = entries[i];
  improve(state, p, std::span<BoxEntry>(entries, kept), best);
  return best;
}

/// Sets the bounds of `cell` (its box set) from the distance of its centre to the mesh.
void setBounds(const SpatialCacheState& state, CacheCell& cell, double centreDistance) noexcept {
  const Vec3 centre = cell.box.center();
  const double halfDiagonal = length(max(centre - cell.box.lower, cell.box.upper - centre));
  const double slack = kSlack * (state.scale + centreDistance);
  cell.lowerBound = std::max(0.0, centreDistance - halfDiagonal - slack);
  cell.upperBound = centreDistance + halfDiagonal + slack;
}

/// The 8 children of `parent`, from its candidates only, in three passes over them (rather than
/// two for each child): the per-axis gaps of a triangle's box to the two halves of the parent
/// give its distances to all 8 children. Pass 1 finds, for each child's centre, the triangle with
/// the nearest box; pass 2 collects the boxes within reach of that triangle's distance and ends
/// each centre's exact nearest search (the nearest triangle of a child's centre is a candidate of
/// the parent, the centre being in the parent); pass 3 keeps, for each child, the boxes within
/// its upper bound.
std::unique_ptr<ChildBlock> buildChildren(const SpatialCacheState& state, const CacheCell& parent) {
  auto block = std::make_unique<ChildBlock>();
  const std::span<const std::uint32_t> from = parent.candidateSpan();
  const Vec3 lower = parent.box.lower, mid = parent.box.center(), upper = parent.box.upper;
  // Per axis and half (0 lower, 1 upper): the child's interval and its centre coordinate.
  std::array<std::array<double, 2>, 3> halfLower{}, halfUpper{}, halfCentre{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    halfLower[axis] = {lower[axis], mid[axis]};
    halfUpper[axis] = {mid[axis], upper[axis]};
  }
  std::array<Vec3, 8> centres;
  for (std::size_t k = 0; k < 8; ++k) {
    CacheCell& child = block->cells[k];
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::size_t half = (k >> axis) & 1u;
      child.box.lower[axis] = halfLower[axis][half];
      child.box.upper[axis] = halfUpper[axis][half];
    }
    child.depth = parent.depth + 1;
    centres[k] = child.box.center();
    for (std::size_t axis = 0; axis < 3; ++axis)
      halfCentre[axis][(k >> axis) & 1u] = centres[k][axis];
  }
  // gaps[axis][half]: squared gaps of one triangle box to the halves' intervals (or centres).
  using Gaps = std::array<std::array<double, 2>, 3>;
  const auto centreGaps = [&](const Aabb& box) {
    Gaps gaps;
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (std::size_t half = 0; half < 2; ++half)
        gaps[axis][half] = gapSquared(halfCentre[axis][half], halfCentre[axis][half],
                                      box.lower[axis], box.upper[axis]);
    return gaps;
  };
  const auto sum = [](const Gaps& gaps, std::size_t k) {
    return gaps[0][k & 1u] + gaps[1][(k >> 1) & 1u] + gaps[2][(k >> 2) & 1u];
  };

  std::array<double, 8> nearestBox;
  nearestBox.fill(std::numeric_limits<double>::infinity());
  std::array<std::uint32_t, 8> first{};
  for (const std::uint32_t id : from) {
    const Gaps gaps = centreGaps(state.boxes[id]);
    for (std::size_t k = 0; k < 8; ++k) {
      const double d = sum(gaps, k);
      if (d < nearestBox[k]) nearestBox[k] = d, first[k] = id;
    }
  }
  std::array<CachedNearest, 8> best;
  std::array<double, 8> prune;
  for (std::size_t k = 0; k < 8; ++k) {
    best[k] = evaluate(state, centres[k], first[k]);
    prune[k] = pruneRadiusSquared(state, best[k].distanceSquared);
  }
  std::array<std::vector<BoxEntry>, 8> entries;
  for (const std::uint32_t id : from) {
    const Gaps gaps = centreGaps(state.boxes[id]);
    for (std::size_t k = 0; k < 8; ++k) {
      const double d = sum(gaps, k);
      if (d <= prune[k] && id != first[k]) entries[k].push_back({d, id});
    }
  }
  std::array<double, 8> reachSquared;
  for (std::size_t k = 0; k < 8; ++k) {
    improve(state, centres[k], entries[k], best[k]);
    setBounds(state, block->cells[k], std::sqrt(best[k].distanceSquared));
    reachSquared[k] = block->cells[k].upperBound * block->cells[k].upperBound;
  }

  std::array<std::vector<std::uint32_t>, 8> lists;
  for (const std::uint32_t id : from) {
    const Aabb& box = state.boxes[id];
    Gaps gaps;
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (std::size_t half = 0; half < 2; ++half)
        gaps[axis][half] = gapSquared(halfLower[axis][half], halfUpper[axis][half], box.lower[axis],
                                      box.upper[axis]);
    for (std::size_t k = 0; k < 8; ++k)
      if (sum(gaps, k) <= reachSquared[k]) lists[k].push_back(id);
  }
  std::size_t total = 0;
  for (const auto& list : lists)
    total += list.size();
  block->candidates.reserve(total);
  for (std::size_t k = 0; k < 8; ++k) {
    block->cells[k].candidateCount = static_cast<std::uint32_t>(lists[k].size());
    block->candidates.insert(block->candidates.end(), lists[k].begin(), lists[k].end());
  }
  std::size_t offset = 0;
  for (CacheCell& child : block->cells) {
    child.candidates = block->candidates.data() + offset;
    offset += child.candidateCount;
  }
  return block;
}

/// The children of `cell`, built now unless another thread built them first.
CacheCell* refine(SpatialCacheState& state, CacheCell& cell) {
  const auto address = reinterpret_cast<std::uintptr_t>(&cell);
  std::mutex& stripe = state.stripes[((address >> 4) ^ (address >> 12)) % state.stripes.size()];
  const std::lock_guard<std::mutex> lock(stripe);
  if (CacheCell* built = cell.children.load(std::memory_order_acquire)) return built;
  std::unique_ptr<ChildBlock> block = buildChildren(state, cell);
  CacheCell* children = block->cells.data();
  const std::size_t bytes = sizeof(ChildBlock) + sizeof(std::unique_ptr<ChildBlock>) +
                            block->candidates.capacity() * sizeof(std::uint32_t);
  {
    const std::lock_guard<std::mutex> own(state.blocksMutex);
    state.blocks.push_back(std::move(block));
  }
  state.cellCount.fetch_add(8, std::memory_order_relaxed);
  state.memoryBytes.fetch_add(bytes, std::memory_order_relaxed);
  cell.children.store(children, std::memory_order_release);
  return children;
}

/// The walk from the root towards `p`'s leaf, refining on the way where allowed; stops early at
/// the first cell for which `stop(cell)` holds.
template <typename Stop>
const CacheCell& descend(SpatialCacheState& state, const Vec3& p, const Stop& stop) {
  CacheCell* cell = &state.root;
  while (!stop(*cell)) {
    CacheCell* children = cell->children.load(std::memory_order_acquire);
    if (children == nullptr) {
      if (!state.refinementAllowed.load(std::memory_order_relaxed) || !meetsCriterion(state, *cell))
        break;
      children = refine(state, *cell);
    }
    cell = &children[childIndex(p, cell->box.center())];
  }
  return *cell;
}

void requireContained(const SpatialCacheState& state, const Vec3& p, const char* caller) {
  if (!state.root.box.contains(p))
    throw Error(std::string(caller) + ": the point " + toString(p) +
                " is outside the cache's root cube, from " + toString(state.root.box.lower) +
                " to " + toString(state.root.box.upper));
}

void validate(const TriangleSoA& triangles, const CacheOptions& options) {
  if (triangles.size() == 0) throw Error("SpatialCache: the mesh has no triangles");
  checkMeshScale(triangles, "SpatialCache: the mesh");
  if (triangles.size() > std::numeric_limits<std::uint32_t>::max())
    throw Error("SpatialCache: " + std::to_string(triangles.size()) +
                " triangles, more than 32-bit ids can name");
  if (options.maxCandidates == 0)
    throw Error("SpatialCache: CacheOptions::maxCandidates is 0; it must be at least 1");
  if (options.maxDepth < 0 || options.maxDepth > 20)
    throw Error("SpatialCache: CacheOptions::maxDepth is " + std::to_string(options.maxDepth) +
                "; it must be in 0–20");
  if (!(options.margin >= 0.0) || !std::isfinite(options.margin))
    throw Error("SpatialCache: CacheOptions::margin is " + toString(options.margin) +
                "; it must be finite and at least 0");
}

}  // namespace

/// What the free functions need of a cache's insides.
struct SpatialCacheAccess {
  static SpatialCacheState& state(const SpatialCache& cache) noexcept { return *cache.state_; }
};

}  // namespace detail

using detail::CacheCell;
using detail::SpatialCacheState;

namespace {

SpatialCache::Leaf toLeaf(const CacheCell& cell) {
  return {cell.box, cell.lowerBound, cell.upperBound, cell.candidateSpan(), cell.depth};
}

}  // namespace

SpatialCache::SpatialCache(const TriangleSoA& triangles, const CacheOptions& options)
    : state_(std::make_unique<SpatialCacheState>()) {
  detail::validate(triangles, options);
  SpatialCacheState& state = *state_;
  state.triangles = &triangles;
  state.options = options;
  state.boxes.resize(triangles.size());
  Aabb meshBox;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    state.boxes[t] = triangles.triangle(t).bounds();
    meshBox.extend(state.boxes[t]);
  }
  const Vec3 extent = meshBox.extent();
  double largest = std::max({extent.x, extent.y, extent.z});
  if (largest == 0.0) largest = 1.0;
  const double half = 0.5 * largest * (1.0 + 2.0 * options.margin);
  const Vec3 centre = meshBox.center();
  state.root.box = {centre - Vec3{half, half, half}, centre + Vec3{half, half, half}};
  if (!isFinite(state.root.box.lower) || !isFinite(state.root.box.upper))
    throw Error("SpatialCache: the root cube around the mesh box from " + toString(meshBox.lower) +
                " to " + toString(meshBox.upper) + " with margin " + toString(options.margin) +
                " is not finite");
  state.scale = 2.0 * half;

  std::vector<std::uint32_t> all(triangles.size());
  for (std::size_t t = 0; t < all.size(); ++t)
    all[t] = static_cast<std::uint32_t>(t);
  detail::setBounds(
      state, state.root,
      std::sqrt(detail::nearestAmong(state, state.root.box.center(), all).distanceSquared));
  const double reachSquared = state.root.upperBound * state.root.upperBound;
  for (const std::uint32_t id : all)
    if (distanceSquared(state.root.box, state.boxes[id]) <= reachSquared)
      state.rootCandidates.push_back(id);
  state.rootCandidates.shrink_to_fit();
  state.root.candidateCount = static_cast<std::uint32_t>(state.rootCandidates.size());
  state.root.candidates = state.rootCandidates.data();
  state.memoryBytes.store(sizeof(SpatialCacheState) + state.boxes.capacity() * sizeof(Aabb) +
                          state.rootCandidates.capacity() * sizeof(std::uint32_t));
}

SpatialCache::~SpatialCache() = default;
SpatialCache::SpatialCache(SpatialCache&&) noexcept = default;
SpatialCache& SpatialCache::operator=(SpatialCache&&) noexcept = default;

bool SpatialCache::contains(const Vec3& p) const noexcept {
  return state_->root.box.contains(p);
}

SpatialCache::Leaf SpatialCache::leafAt(const Vec3& p) const {
  detail::requireContained(*state_, p, "SpatialCache::leafAt");
  return toLeaf(detail::descend(*state_, p, [](const CacheCell&) { return false; }));
}

void SpatialCache::allowRefinement(bool allowed) noexcept {
  state_->refinementAllowed.store(allowed);
}

bool SpatialCache::refinementAllowed() const noexcept {
  return state_->refinementAllowed.load();
}

void SpatialCache::refineAll() {
  SpatialCacheState& state = *state_;
  std::vector<CacheCell*> level{&state.root}, next;
  while (!level.empty()) {
    parallelFor(0, level.size(), 4, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        if (level[i]->children.load(std::memory_order_acquire) == nullptr &&
            detail::meetsCriterion(state, *level[i]))
          detail::refine(state, *level[i]);
    });
    next.clear();
    for (CacheCell* cell : level)
      if (CacheCell* children = cell->children.load(std::memory_order_acquire))
        for (std::size_t k = 0; k < 8; ++k)
          next.push_back(children + k);
    level.swap(next);
  }
}

std::size_t SpatialCache::cellCount() const noexcept {
  return state_->cellCount.load(std::memory_order_relaxed);
}

std::size_t SpatialCache::memoryBytes() const noexcept {
  return state_->memoryBytes.load(std::memory_order_relaxed);
}

const CacheOptions& SpatialCache::options() const noexcept {
  return state_->options;
}

const TriangleSoA& SpatialCache::triangles() const noexcept {
  return *state_->triangles;
}

const Aabb& SpatialCache::bounds() const noexcept {
  return state_->root.box;
}

SpatialCache::Statistics SpatialCache::statistics() const {
  Statistics statistics;
  std::size_t candidateSum = 0;
  std::vector<const CacheCell*> stack{&state_->root};
  while (!stack.empty()) {
    const CacheCell* cell = stack.back();
    stack.pop_back();
    ++statistics.cells;
    if (const CacheCell* children = cell->children.load(std::memory_order_acquire)) {
      for (std::size_t k = 0; k < 8; ++k)
        stack.push_back(children + k);
      continue;
    }
    ++statistics.leaves;
    statistics.depth = std::max(statistics.depth, cell->depth);
    statistics.maxCandidates =
        std::max<std::size_t>(statistics.maxCandidates, cell->candidateCount);
    candidateSum += cell->candidateCount;
    if (cell->candidateCount > state_->options.maxCandidates) ++statistics.leavesOverCriterion;
  }
  statistics.meanCandidates =
      static_cast<double>(candidateSum) / static_cast<double>(statistics.leaves);
  return statistics;
}

SpatialCache buildCache(const TriangleSoA& triangles, const CacheOptions& options) {
  SpatialCache cache(triangles, options);
  cache.refineAll();
  return cache;
}

CachedNearest nearestTriangle(const SpatialCache& cache, const Vec3& p) {
  SpatialCacheState& state = detail::SpatialCacheAccess::state(cache);
  detail::requireContained(state, p, "nearestTriangle");
  const CacheCell& leaf = detail::descend(state, p, [](const CacheCell&) { return false; });
  return detail::nearestAmong(state, p, leaf.candidateSpan());
}

bool beyond(const SpatialCache& cache, const Vec3& p, double epsilon) {
  SpatialCacheState& state = detail::SpatialCacheAccess::state(cache);
  detail::requireContained(state, p, "beyond");
  if (std::isnan(epsilon)) throw Error("beyond: epsilon is NaN");
  const auto farEnough = [epsilon](const CacheCell& cell) { return cell.lowerBound >= epsilon; };
  const CacheCell& cell = detail::descend(state, p, farEnough);
  if (farEnough(cell)) return true;
  // The nearest triangle is a candidate, so d(p) is at least the distance to the nearest
  // candidate box: if every box is ε away (plus a rounding slack), so is every triangle.
  const double reach = epsilon + detail::kSlack * state.scale;
  const double reachSquared = reach * reach;
  for (const std::uint32_t id : cell.candidateSpan())
    if (distanceSquared(p, state.boxes[id]) < reachSquared) return false;
  return true;
}

}  // namespace delta
