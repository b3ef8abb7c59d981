// The point queries' kernels of one instruction set: the nearest-triangle descent, its node
// bounds (node_bounds.h) and exact lanes (exact_lanes.h), compiled once per ISA
// (src/CMakeLists.txt, delta_isa) with that ISA's flags, DELTA_ISA (the namespace of everything
// here) and DELTA_ISA_LANES (its batch kernels' W, whose leaf bounds the descent calls). The
// descent is the same source on every ISA, and so are its answers: the bounds only decide what
// the exact kernel skips, and the exact lanes give the scalar kernel's bits.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "delta/kernels/detail/batch_kernels.h"
#include "delta/kernels/point_triangle.h"

#include "query/detail/exact_lanes.h"
#include "query/detail/grid_sieve.h"
#include "query/detail/node_bounds.h"
#include "query/detail/point_kernels.h"
#include "query/detail/query_mesh_data.h"

namespace delta::detail::DELTA_ISA {
namespace {

#if defined(DELTA_NODE_BOUNDS_AVX512)
using Bounds = Avx512Bounds;
#elif defined(DELTA_NODE_BOUNDS_AVX2)
using Bounds = Avx2Bounds;  // Zen 2, ARCHER2's (GCC 12 leaves the plain loops scalar there)
#elif defined(DELTA_NODE_BOUNDS_NEON)
using Bounds = NeonBounds;  // AArch64's NEON and SVE tables
#else
using Bounds = PlainBounds;
#endif

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// A node waiting on the stack: its box's distance and, in one word, its level (high half) and
/// index. (Two 32-bit fields stored apart and loaded as one 64-bit pair stalled every pop on
/// store forwarding: an eighth of an ε-limited query.)
struct Pending {
  double bound;
  std::uint64_t node;

  std::uint32_t level() const noexcept { return static_cast<std::uint32_t>(node >> 32); }
  std::uint32_t index() const noexcept { return static_cast<std::uint32_t>(node); }
};

std::uint64_t nodeKey(std::uint32_t level, std::uint32_t index) noexcept {
  return std::uint64_t{level} << 32 | index;
}

/// (distance², id) order: the smaller distance, or the same distance and the smaller id.
/// Before anything is found, only a distance strictly below the limit counts.
bool better(double distanceSquared, std::uint32_t id, const Nearest& best) noexcept {
  return distanceSquared < best.distanceSquared ||
         (distanceSquared == best.distanceSquared && best.found() && id < best.triangle);
}

/// What a descent reads besides the tree: the sorted triangles in single precision, and the
/// point less their origin.
struct Leaves {
  FloatLeavesView triangles;
  double point[3];
};

/// Triangles held back from the exact kernel: at most this many wait at once.
constexpr std::size_t kDeferred = 32;

/// A search's state. The exact kernel, which decides every answer, runs only on triangles whose
/// lower bound is not above the least upper bound seen (`prune`): the vector bounds give both
/// (kernels/detail/point_lanes.h), so a leaf's triangles tighten the pruning at once and their
/// kernels wait until the descent ends, when almost all of them have fallen behind. (Running the
/// kernel on each leaf's candidates as it came ran it 7 times a far point; most lost later.)
///
/// Why the answer is still the loop over all triangles: the winner's computed distance is at
/// most every computed distance, so at most every upper bound, so at most `prune` at any time;
/// its lower bound and its boxes' distances are at most that distance; so no box holding it is
/// skipped and it waits with the others, all of which the kernel decides in the end.
struct Search {
  Nearest best;  ///< the best the exact kernel has found (the limit before)
  double prune;  ///< min(best, the upper bounds of the triangles seen)
  double lower[kDeferred];
  std::uint32_t deferred[kDeferred];  ///< sorted triangle indices
  std::size_t count = 0;
  /// Whether to ask for a leaf's triangles and the exact kernels' vertices ahead: for a limited
  /// search, whose points (an ε-limited batch's, left in doubt by the grid) lie sparse and find
  /// them in memory (its hits −10%); an unlimited one's dense points find them in the cache, and
  /// the requests cost W1 1.5%.
  bool prefetch = false;
};

/// The exact kernel on sorted triangle `k`.
[[gnu::always_inline]] inline void exactly(const QueryMeshData& mesh, const Vec3& point,
                                           std::size_t k, Search& search) noexcept {
  const kernels::PointTriangleResult r = kernels::closestPointOnTriangle(point, mesh.triangle(k));
  if (better(r.distanceSquared, mesh.order[k], search.best)) {
    search.best.distanceSquared = r.distanceSquared;
    search.best.triangle = mesh.order[k];
    search.best.sorted = static_cast<std::uint32_t>(k);
    search.best.closest = r;
    search.prune = std::min(search.prune, r.distanceSquared);
  }
}

/// The squared distances of the waiting triangles [first, first + count) (at most eight) in one
/// eight-lane kernel; the best of them by (distance, id), whose closest point the scalar kernel
/// then gives (the same bits: exact_lanes.h). Where a lane is not finite (coordinates near
/// overflow) the scalar kernel answers them all instead.
void exactlyEight(const QueryMeshData& mesh, const Vec3& point, std::size_t first,
                  std::size_t count, Search& search) noexcept {
  double distances[kFanout];
  exactDistancesSquared8(mesh, point, search.deferred + first, count, distances);
  bool finite = true;
  for (std::size_t i = 0; i < count; ++i)
    finite = finite && std::isfinite(distances[i]);
  if (!finite) {
    for (std::size_t i = 0; i < count; ++i)
      exactly(mesh, point, search.deferred[first + i], search);
    return;
  }
  std::uint32_t winner = kNone;
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t k = search.deferred[first + i];
    if (better(distances[i], mesh.order[k], search.best)) {
      search.best.distanceSquared = distances[i];
      search.best.triangle = mesh.order[k];
      winner = k;
    }
  }
  if (winner == kNone) return;
  search.best.sorted = winner;
  search.best.closest = kernels::closestPointOnTriangle(point, mesh.triangle(winner));
  search.prune = std::min(search.prune, search.best.distanceSquared);
}

/// The kernel on the waiting triangles, nearest lower bound first, until the next is farther
/// than the best: one at a time, or, where the ISA has the eight-lane kernel and three or more
/// wait (most often the triangles around a vertex that a far point is nearest to, whose
/// distances tie but for rounding), eight at a time, as long as the first of the eight is not
/// farther than the best. The answer is the same: the best by (distance, id) of more triangles,
/// whose lower bounds are not above it. (For one or two the scalar kernel is as fast.)
[[gnu::noinline, gnu::flatten]] void settle(const QueryMeshData& mesh, const Vec3& point,
                                            Search& search) noexcept {
  std::size_t kept = 0;  // those still not beyond the pruning bound, in ascending order
  for (std::size_t c = 0; c < search.count; ++c) {
    const double lower = search.lower[c];
    if (!(lower <= search.prune)) continue;
    const std::uint32_t k = search.deferred[c];
    std::size_t at = kept++;
    for (; at > 0 && search.lower[at - 1] > lower; --at) {
      search.lower[at] = search.lower[at - 1];
      search.deferred[at] = search.deferred[at - 1];
    }
    search.lower[at] = lower;
    search.deferred[at] = k;
  }
  // The kernels' vertices asked for together (their corners were, when they were deferred).
  if (search.prefetch)
    for (std::size_t c = 0; c < kept; ++c)
      for (const std::uint32_t v : mesh.corners[search.deferred[c]])
        __builtin_prefetch(&mesh.vertices[v]);
  if (kExactLanes > 0 && kept > 2) {
    for (std::size_t c = 0; c < kept && !(search.lower[c] > search.best.distanceSquared);
         c += kFanout)
      exactlyEight(mesh, point, c, std::min(kFanout, kept - c), search);
  } else {
    for (std::size_t c = 0; c < kept && !(search.lower[c] > search.best.distanceSquared); ++c)
      exactly(mesh, point, search.deferred[c], search);
  }
  search.count = 0;
}

/// The triangles of leaf `leaf`: the vector bounds of the eight tighten the pruning with their
/// upper bounds, and those whose lower bound is not beyond it wait (Search).
template <typename Bounds>
[[gnu::always_inline]] inline void visitLeaf(const QueryMeshData& mesh, const Leaves& leaves,
                                             const Vec3& point, std::size_t leaf,
                                             Search& search) noexcept {
  double lower[kFanout], upper[kFanout];
  if (!pointBounds<DELTA_ISA_LANES>(leaves.triangles, leaf * kFanout, leaves.point, search.prune,
                                    lower, upper))
    return;
  const std::size_t count = std::min(kFanout, mesh.size() - leaf * kFanout);
  const unsigned present = (1u << count) - 1;  // not the padding
  for (unsigned rest = Bounds::candidates(lower, upper, present, search.prune); rest != 0;
       rest &= rest - 1) {
    const auto i = static_cast<std::size_t>(std::countr_zero(rest));
    if (search.count == kDeferred) settle(mesh, point, search);
    search.lower[search.count] = lower[i];
    search.deferred[search.count++] = static_cast<std::uint32_t>(leaf * kFanout + i);
    if (search.prefetch) __builtin_prefetch(&mesh.corners[leaf * kFanout + i]);  // for settle
  }
}

/// Asks for every cache line of `block` (a node's octet of boxes or cylinders): a child pushed now
/// is most often popped a few visits later (W1 −1.5% on Zen 5).
template <typename Block>
[[gnu::always_inline]] inline void prefetchBlock(const Block* block) noexcept {
  const char* bytes = reinterpret_cast<const char*>(block);
  for (std::size_t line = 0; line < sizeof(Block); line += 64)
    __builtin_prefetch(bytes + line);
}

/// Asks for every cache line of leaf `leaf`'s single-precision triangles (visitLeaf's).
[[gnu::always_inline]] inline void prefetchLeaf(const Leaves& leaves, std::size_t leaf) noexcept {
  const char* bytes = reinterpret_cast<const char*>(leaves.triangles.leaves + leaf * 72);
  for (std::size_t line = 0; line < 72 * sizeof(float); line += 64)
    __builtin_prefetch(bytes + line);
}

/// The descent, with the node bounds of `Bounds` (this ISA's).
template <typename Bounds>
[[gnu::always_inline]] inline Nearest descend(const QueryMeshData& mesh, const Leaves& leaves,
                                              const Vec3& point, double limitSquared) noexcept {
  Search search;
  search.best.distanceSquared = limitSquared;
  search.prune = limitSquared;
  search.prefetch = limitSquared < std::numeric_limits<double>::max();
  // Nearest-first, depth first: children are pushed farthest first, and every entry is checked
  // against the pruning bound again when it is popped. A node is skipped only when its box is
  // strictly farther than the bound, so ties still reach the smaller id.
  constexpr std::size_t kCapacity = 16 * kFanout;  // depth ≤ 11 for 2³² triangles
  Pending stack[kCapacity];
  std::size_t top = 0;
  const std::uint32_t rootLevel = static_cast<std::uint32_t>(mesh.levels.size() - 1);
  if (rootLevel == 0) {  // one leaf
    visitLeaf<Bounds>(mesh, leaves, point, 0, search);
    settle(mesh, point, search);
    return search.best;
  }
  stack[top++] = {distanceSquared(point, mesh.levels.back()[0]), nodeKey(rootLevel, 0)};
  const double shrink = cylinderShrink(mesh, point);
  const Vec3 local{leaves.point[0], leaves.point[1], leaves.point[2]};  // the octets' frame
  while (top > 0) {
    const Pending entry = stack[--top];
    if (entry.bound > admitting(search.prune)) continue;
    double bounds[kFanout];
    const std::uint32_t first = entry.index() * static_cast<std::uint32_t>(kFanout);
    if (entry.level() == 1) {
      // The children are leaves: visited here, nearest first, each checked against the bound as
      // it tightens (the order the stack gave them, without pushing and popping each).
      // Their triangles are asked for first (Search::prefetch): a leaf's bounds read 288 bytes.
      unsigned rest =
          Bounds::leaves(mesh.childOctets[0][entry.index()], mesh.leafCylinders[entry.index()],
                         local, shrink, admitting(search.prune), bounds);
      if (search.prefetch)
        for (unsigned more = rest; more != 0; more &= more - 1)
          prefetchLeaf(leaves, first + static_cast<std::uint32_t>(std::countr_zero(more)));
      while (rest != 0) {
        std::uint32_t nearest = static_cast<std::uint32_t>(std::countr_zero(rest));
        for (unsigned more = rest & (rest - 1); more != 0; more &= more - 1) {
          const auto i = static_cast<std::uint32_t>(std::countr_zero(more));
          if (bounds[i] < bounds[nearest]) nearest = i;
        }
        if (bounds[nearest] > admitting(search.prune)) break;
        visitLeaf<Bounds>(mesh, leaves, point, first + nearest, search);
        rest &= ~(1u << nearest);
      }
      continue;
    }
    // The children not beyond the bound (never the empty slots) go onto the stack in descending
    // order of distance, so the nearest is popped next. The mask is made without branches: a
    // branch per child mispredicted often enough to cost 4% of an ε-limited query.
    const unsigned near = Bounds::children(mesh.childOctets[entry.level() - 1][entry.index()],
                                           local, admitting(search.prune), bounds);
    const std::size_t base = top;
    for (unsigned rest = near; rest != 0; rest &= rest - 1) {
      const auto i = static_cast<std::uint32_t>(std::countr_zero(rest));
      std::size_t at = top++;
      for (; at > base && stack[at - 1].bound < bounds[i]; --at)
        stack[at] = stack[at - 1];
      stack[at] = {bounds[i], nodeKey(entry.level() - 1, first + i)};
      prefetchBlock(&mesh.childOctets[entry.level() - 2][first + i]);
      if (entry.level() == 2) prefetchBlock(&mesh.leafCylinders[first + i]);
    }
  }
  settle(mesh, point, search);
  return search.best;
}

/// PointKernels::collect with the node bounds of `Bounds`: a descent with a fixed bound.
template <typename Bounds>
[[gnu::always_inline]] inline std::size_t collectLeaves(const QueryMeshData& mesh,
                                                        const Vec3& center, double radiusSquared,
                                                        std::uint32_t* leaves) noexcept {
  const std::uint32_t rootLevel = static_cast<std::uint32_t>(mesh.levels.size() - 1);
  // One leaf: no level-1 node holds its box and cylinder to gather (the descent visits it
  // directly).
  if (rootLevel == 0) return kMostCandidates + 1;
  const double shrink = cylinderShrink(mesh, center);
  const Vec3 local = center - mesh.lanes.origin;   // the octets' frame
  constexpr std::size_t kCapacity = 16 * kFanout;  // depth ≤ 11 for 2³² triangles
  std::uint64_t stack[kCapacity];
  std::size_t top = 0, count = 0;
  stack[top++] = nodeKey(rootLevel, 0);
  while (top > 0) {
    const std::uint64_t node = stack[--top];
    const auto level = static_cast<std::uint32_t>(node >> 32);
    const auto index = static_cast<std::uint32_t>(node);
    const std::uint32_t first = index * static_cast<std::uint32_t>(kFanout);
    double bounds[kFanout];
    if (level == 1) {
      for (unsigned rest = Bounds::leaves(mesh.childOctets[0][index], mesh.leafCylinders[index],
                                          local, shrink, admitting(radiusSquared), bounds);
           rest != 0; rest &= rest - 1) {
        if (count == kMostCandidates) return kMostCandidates + 1;
        leaves[count++] = first + static_cast<std::uint32_t>(std::countr_zero(rest));
      }
      continue;
    }
    // Pushed in descending order of index, so the leaves come out ascending.
    const unsigned near = Bounds::children(mesh.childOctets[level - 1][index], local,
                                           admitting(radiusSquared), bounds);
    for (unsigned rest = near; rest != 0; rest &= ~(1u << (31 - std::countl_zero(rest))))
      stack[top++] =
          nodeKey(level - 1, first + static_cast<std::uint32_t>(31 - std::countl_zero(rest)));
  }
  return count;
}

/// PointKernels::among with the bounds of `Bounds`: the candidates' leaf bounds, then their
/// leaves nearest first, each checked against the pruning bound as it tightens (descend's
/// level-1 visits, over every candidate at once).
template <typename Bounds>
[[gnu::always_inline]] inline Nearest searchAmong(const QueryMeshData& mesh, const Leaves& leaves,
                                                  const Vec3& point, double limitSquared,
                                                  const CandidateView& candidates) noexcept {
  Search search;
  search.best.distanceSquared = limitSquared;
  search.prune = limitSquared;
  search.prefetch = true;  // a limited search
  const double shrink = cylinderShrink(mesh, point);
  const Vec3 local{leaves.point[0], leaves.point[1], leaves.point[2]};  // the octets' frame
  double bound[kMostCandidates];
  std::uint32_t leaf[kMostCandidates];
  std::size_t pending = 0;
  for (std::size_t octet = 0; octet < candidates.octets; ++octet) {
    double bounds[kFanout];
    for (unsigned rest = Bounds::leaves(candidates.boxes[octet], candidates.cylinders[octet], local,
                                        shrink, admitting(search.prune), bounds);
         rest != 0; rest &= rest - 1) {
      const auto i = static_cast<std::size_t>(std::countr_zero(rest));
      bound[pending] = bounds[i];
      leaf[pending] = candidates.leaves[octet * kFanout + i];
      prefetchLeaf(leaves, leaf[pending]);
      ++pending;
    }
  }
  while (pending > 0) {
    std::size_t nearest = 0;
    for (std::size_t k = 1; k < pending; ++k)
      if (bound[k] < bound[nearest]) nearest = k;
    if (bound[nearest] > admitting(search.prune)) break;
    visitLeaf<Bounds>(mesh, leaves, point, leaf[nearest], search);
    --pending;
    bound[nearest] = bound[pending];
    leaf[nearest] = leaf[pending];
  }
  settle(mesh, point, search);
  return search.best;
}

// The table's entries. No function this ISA's flags compiled may be left out of line for
// another object to share (ISA.NoSharedCodeBetweenInstructionSets checks every build): every
// entry inlines all it calls ([[gnu::flatten]]) but three functions kept out of line, each this
// ISA's own and flattened itself: settle (local; inlined into every call site of the loop it cost
// 2% of W1), exactDistancesSquared8 (in this ISA's namespace) and pointBounds<W> (a template over
// this ISA's lane count), which inlined cost 2.5%. The library's small helpers reached through an
// inlined call are always_inline (clang 14's flatten is not recursive, and with the sanitizers
// it left Vec3's operators out of line).

/// The descent, its limit capped at the largest finite double: an empty slot of a node (the
/// tree is not full) lies at +∞, and only a finite limit keeps it out. (An unlimited search
/// from a point whose every distance overflowed once walked into them, past the end of the
/// tree: the queries now refuse such points, coordinate_range.h, and this keeps the descent
/// inside the tree whatever it is given. A NaN limit finds nothing.)
[[gnu::flatten]] Nearest nearest(const QueryMeshData& mesh, const Vec3& point,
                                 double limitSquared) noexcept {
  const Vec3 local = point - mesh.lanes.origin;
  return descend<Bounds>(mesh, {mesh.lanes.view(), {local.x, local.y, local.z}}, point,
                         std::min(limitSquared, std::numeric_limits<double>::max()));
}

[[gnu::flatten]] unsigned children(const BoxOctet& boxes, const Vec3& point, double prune,
                                   double (&out)[kFanout]) noexcept {
  return Bounds::children(boxes, point, prune, out);
}

[[gnu::flatten]] unsigned leaves(const BoxOctet& boxes, const CylinderOctet& cylinders,
                                 const Vec3& point, double shrink, double prune,
                                 double (&out)[kFanout]) noexcept {
  return Bounds::leaves(boxes, cylinders, point, shrink, prune, out);
}

[[gnu::flatten]] std::size_t collect(const QueryMeshData& mesh, const Vec3& center,
                                     double radiusSquared, std::uint32_t* leaves) noexcept {
  return collectLeaves<Bounds>(mesh, center, radiusSquared, leaves);
}

[[gnu::flatten]] Nearest among(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                               const CandidateView& candidates) noexcept {
  const Vec3 local = point - mesh.lanes.origin;
  return searchAmong<Bounds>(mesh, {mesh.lanes.view(), {local.x, local.y, local.z}}, point,
                             limitSquared, candidates);
}

[[gnu::flatten]] std::size_t sieve(const GridView& grid, const Vec3* points, std::size_t count,
                                   double limit, std::uint32_t* kept, bool& inRange) noexcept {
  return sievePoints(grid, points, count, limit, kept, inRange);
}

}  // namespace

const PointKernels& pointKernels() noexcept {
  static constexpr PointKernels kernels{
      &nearest,  kExactLanes > 0 ? &exactDistancesSquared8 : nullptr,
      &children, &leaves,
      &sieve,    &collect,
      &among};
  return kernels;
}

}  // namespace delta::detail::DELTA_ISA
