#include "delta/query/point_distance.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "delta/core/cancel.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/query/part_nesting.h"
#include "delta/query/self_intersections.h"

#include "detail/morton.h"
#include "detail/point_kernels.h"
#include "detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

/// Points per parallel chunk: a few hundred tree descents amortise the scheduling.
constexpr std::size_t kGrain = 256;
/// Batches from this size are answered in Morton order of their points.
constexpr std::size_t kCoherentFrom = 4 * kGrain;
/// A distance bound's square is searched with this growth (a few ulps of rounding allowed for).
constexpr double kBoundGrowth = 1.0 + 1e-12;

/// Checks the query and returns it as it runs: a winding sign on a mesh that bounds a solid
/// (closed, not crossing itself, its parts nested) is its pseudonormal sign, exactly (off the
/// surface the winding number is 0 or 1 there, and the pseudonormal decides its side exactly
/// where the solid angles of a point within rounding of a face would not).
PointQuery validate(const QueryMesh& mesh, const PointQuery& query) {
  if (std::isnan(query.epsilon) || !(query.epsilon > 0.0))
    throw Error("point distances: epsilon = " + toString(query.epsilon) + " must be positive");
  if (!(query.windingTolerance >= 0.0 && query.windingTolerance < 0.5))
    throw Error("point distances: windingTolerance = " + toString(query.windingTolerance) +
                " must be in [0, 0.5)");
  if (!query.signedDistance) return query;
  if (query.sign == Sign::winding) {
    if (boundsSolid(mesh)) {
      mesh.data().pseudonormals();  // made here, where it may throw
      PointQuery pseudonormal = query;
      pseudonormal.sign = Sign::pseudonormal;
      return pseudonormal;
    }
    mesh.data().windingTree();  // made here, where it may throw
    return query;
  }
  if (!mesh.closed())
    throw Error(
        "signed distance by pseudonormals needs a closed, consistently oriented mesh; "
        "this one has " +
        describeDefects(mesh.topology()) +
        "; the winding-number sign takes any mesh (C++ Sign::winding, Python "
        "sign=\"winding\", CLI --sign winding)");
  const SelfIntersections& crossings = selfIntersections(mesh);
  if (crossings.any())
    throw Error("signed distance by pseudonormals: the mesh crosses itself (" +
                std::to_string(crossings.count) + " pairs of triangles intersect, such as " +
                std::to_string(crossings.pairs.front().first) + " and " +
                std::to_string(crossings.pairs.front().second) +
                "), where pseudonormal signs are wrong; the winding-number sign is defined there "
                "(C++ Sign::winding, Python sign=\"winding\", CLI --sign winding)");
  const PartNesting& nesting = partNesting(mesh);
  if (!nesting.nested())
    throw Error("signed distance by pseudonormals: " + describePartNesting(nesting) +
                ", where pseudonormal signs are wrong; the winding-number sign is defined there "
                "(C++ Sign::winding, Python sign=\"winding\", CLI --sign winding)");
  mesh.data().pseudonormals();  // made here, where it may throw
  return query;
}

/// The squared limit a search for points closer than `epsilon` runs with: ε², or, where ε² may
/// have lost precision to underflow (or be 0: ε below about 1e-162), kUnderflowingSquare, a
/// superset whose answers `beyond` then cuts at ε by their distances at scale.
double searchLimit(double epsilon) noexcept {
  const double squared = epsilon * epsilon;
  return squared < detail::kUnderflowingSquare ? detail::kUnderflowingSquare : squared;
}

/// Whether a search's answer lies at ε or beyond, though its square was within the limit: only
/// where the limit was not ε² (searchLimit).
bool beyond(double distance, double epsilon) noexcept {
  return epsilon * epsilon < detail::kUnderflowingSquare && !(distance < epsilon);
}

/// Whether a point (world frame) and, carried into the mesh's prepared frame, `local` lie in
/// the coordinate range (coordinate_range.h): false for a non-finite one too.
bool inRange(const Vec3& point, const Vec3& local) noexcept {
  return inCoordinateRange(point) && inCoordinateRange(local);
}

/// Throws for point `index`, which is not inRange: a non-finite coordinate, or one beyond the
/// range where it is or where the mesh's pose carries it.
[[noreturn]] void throwBadPoint(const QueryMesh& mesh, std::size_t index, const Vec3& point) {
  const std::string what = "point distances: point " + std::to_string(index);
  if (!isFinite(point))
    throw Error(what + " (" + toString(point) + ") has a non-finite coordinate");
  checkPointRange(point, what);
  checkPointRange(mesh.inversePose().apply(point),
                  what + " " + toString(point) + ", carried into the moved mesh's frame at");
  throw Error(what + " is out of range");  // not reached: one of the checks throws
}

/// The point carried into the mesh's prepared frame.
Vec3 localPoint(const QueryMesh& mesh, const Vec3& point) noexcept {
  return mesh.moved() ? mesh.inversePose().apply(point) : point;
}

/// Throws for the first point (in index order) with a non-finite coordinate or one out of the
/// coordinate range (where it is, or in the mesh's frame).
template <typename PointAt>
void validatePoints(const QueryMesh& mesh, std::size_t count, const PointAt& pointAt) {
  for (std::size_t i = 0; i < count; ++i)
    if (!inRange(pointAt(i), localPoint(mesh, pointAt(i)))) throwBadPoint(mesh, i, pointAt(i));
}

/// The triangle (tree order) that answered the previous point of a run, whose exact distance to
/// the next point is a first bound for its search: consecutive points along a Morton curve lie
/// close together, and so do their nearest triangles. Its kernel runs only where the triangle
/// inequality (its distance from the previous point plus the step) says it could tighten the
/// bound: the points of an ε-limited batch that the grid left in doubt lie sparse, and there the
/// kernel cost 7% of the batch for nothing.
struct Hint {
  std::uint32_t sorted = kNoTriangle;
  Vec3 point;             ///< the previous point (mesh frame)
  double distance = 0.0;  ///< its distance to that triangle
};

/// One point's answer. A moved mesh is searched in the frame it was prepared in: the point goes
/// in by the inverse pose, the closest point comes out by the pose (distances are unchanged).
/// The search starts from the smallest of ε, the upper bound given and the distance to the
/// hint's triangle, each grown a little so that a triangle exactly at it is found; a given bound
/// that was too small finds nothing and the search runs again with ε (the hint's cannot be too
/// small: it is the distance to a triangle). So the answer is the same whatever the bounds.
/// `screened`: the caller has already asked the distance-bound grid (answerAll's sieve).
/// `near`: null, or leaves that hold every triangle within ε of the point (a cluster's), searched
/// instead of the tree.
PointDistance answer(const QueryMesh& mesh, const Vec3& worldPoint, const PointQuery& query,
                     double upperBound = std::numeric_limits<double>::infinity(),
                     Hint* hint = nullptr, bool screened = false,
                     const detail::LeafCandidates* near = nullptr) {
  const detail::QueryMeshData& data = mesh.data();
  const Vec3 point = mesh.moved() ? mesh.inversePose().apply(worldPoint) : worldPoint;
  const double limit = searchLimit(query.epsilon);
  // The seed's early "no contact" (for an unlimited search there is nothing to reject).
  if (!screened && std::isfinite(limit) && data.boundGrid.lowerBoundSquared(point) > limit)
    return {};
  const auto grown = [](double distanceSquared) {
    return std::nextafter(distanceSquared * kBoundGrowth, std::numeric_limits<double>::infinity());
  };
  // Never beyond the limit: a bound just below ε grown past ε² found a triangle at exactly ε.
  double first = limit;
  if (upperBound < query.epsilon) first = std::min(limit, grown(upperBound * upperBound));
  const double reach = hint ? hint->distance + length(point - hint->point) : 0.0;
  if (hint && hint->sorted != kNoTriangle && reach * reach < first)
    first = std::min(
        first,
        grown(kernels::closestPointOnTriangle(point, data.triangle(hint->sorted)).distanceSquared));
  const auto search = [&](double limitSquared) {
    return near ? detail::nearestAmong(data, point, limitSquared, *near)
                : detail::nearestTriangle(data, point, limitSquared);
  };
  detail::Nearest nearest = search(first);
  if (!nearest.found() && first < limit) nearest = search(limit);
  PointDistance result;
  if (!nearest.found()) {
    if (std::isinf(query.epsilon))
      throw Error("point distances: the distance from " + toString(point) +
                  " to the mesh overflows a double");
    return result;
  }
  if (nearest.distanceSquared < detail::kUnderflowingSquare)
    nearest = detail::resolveUnderflow(data, point, nearest);
  const double distance = detail::distanceOf(data, point, nearest);
  if (hint) *hint = {nearest.sorted, point, distance};
  if (beyond(distance, query.epsilon)) return result;
  result.distance = distance;
  result.closest =
      mesh.moved() ? mesh.pose().apply(nearest.closest.closest) : nearest.closest.closest;
  result.triangle = nearest.triangle;
  if (query.signedDistance) {
    if (query.sign == Sign::pseudonormal) {
      result.inside = detail::insideAt(data, point, nearest);
    } else {
      // Within rounding of a closed mesh's surface the solid angles of the nearest faces lose
      // their sign, and a distance may round to 0 off it: decided exactly there (the winding
      // number is an integer off the surface).
      const std::optional<bool> exact =
          data.closed ? detail::insideNearSurface(data, point, nearest, result.distance)
                      : std::nullopt;
      if (exact) {
        result.inside = *exact;
      } else if (result.distance > 0.0) {  // on the surface: neither inside nor ambiguous
        const detail::WindingSign sign = detail::windingSign(data, point, query.windingTolerance);
        result.inside = sign.inside;
        result.ambiguous = sign.ambiguous;
      }
    }
  }
  return result;
}

/// Points per block of the grid's sieve.
constexpr std::size_t kSieveBlock = 16 * kGrain;
/// Points the sieve carries into the mesh's frame at a time (a moved mesh's, or points that are
/// not one array of Vec3).
constexpr std::size_t kCarried = 256;

/// A point a block of the sieve keeps: as given (world frame), its index, and its order's key
/// (the Morton code of its grid cell, or of its place in the mesh's box: Survivors).
struct Kept {
  Vec3 point;
  std::uint32_t index;
  std::uint64_t code;
};

/// The buffers of an ε-limited batch's sieve and search, which the calling thread keeps from one
/// batch to the next. Freed after each batch, the allocator gave them back to the system, and
/// the fresh pages of the next batch cost a tenth of it to fault in and clear (10⁶ points around
/// armadillo, an eighth of them in doubt, ask for 15 MB: 52 against 47 ms on one thread). Every
/// element a batch reads it has written first.
struct BatchScratch {
  std::vector<std::vector<Kept>> kept;  ///< per sieve block
  std::vector<std::uint32_t> indices, order, cells;
  std::vector<Vec3> points;
  std::vector<std::uint64_t> keys, buffer;
  std::vector<PointDistance> found;

  std::size_t bytes() const noexcept {
    std::size_t total =
        kept.capacity() * sizeof(std::vector<Kept>) +
        (indices.capacity() + order.capacity() + cells.capacity()) * sizeof(std::uint32_t) +
        points.capacity() * sizeof(Vec3) +
        (keys.capacity() + buffer.capacity()) * sizeof(std::uint64_t) +
        found.capacity() * sizeof(PointDistance);
    for (const std::vector<Kept>& block : kept)
      total += block.capacity() * sizeof(Kept);
    return total;
  }
};

/// At most this much of a thread's BatchScratch stays after a batch (about 130 bytes a point in
/// doubt: enough for some 4·10⁶ points with an eighth of them in doubt); a larger one is freed.
constexpr std::size_t kKeptScratchBytes = std::size_t{64} << 20;

/// The first `n` elements of `buffer`, which grows to hold them: their values are the last
/// batch's until written.
template <typename T>
std::span<T> firstOf(std::vector<T>& buffer, std::size_t n) {
  if (buffer.size() < n) {
    buffer.clear();  // nothing to copy when it grows
    buffer.resize(n);
  }
  return {buffer.data(), n};
}

/// The calling thread's BatchScratch for the length of a batch, or buffers of the batch's own
/// where the thread's are in use (a batch started from inside another one's cancellation
/// poll); at the end, the thread's are freed if they exceed kKeptScratchBytes.
class ScratchLease {
 public:
  ScratchLease() : shared_(!busy()) { busy() = true; }
  ~ScratchLease() {
    if (!shared_) return;
    if (threadScratch().bytes() > kKeptScratchBytes) threadScratch() = {};
    busy() = false;
  }
  ScratchLease(const ScratchLease&) = delete;
  ScratchLease& operator=(const ScratchLease&) = delete;

  BatchScratch& get() noexcept { return shared_ ? threadScratch() : own_; }

 private:
  static BatchScratch& threadScratch() {
    thread_local BatchScratch scratch;
    return scratch;
  }
  static bool& busy() {
    thread_local bool inUse = false;
    return inUse;
  }

  bool shared_;
  BatchScratch own_;
};

/// The points of a batch that the distance-bound grid leaves in doubt (not beyond ε), gathered
/// (as given, in the world frame) in input order with their indices, the order in which to
/// search them (along a Morton curve of the grid's cells, or where the grid has more than 1024
/// cells along an axis, of the mesh's box), and where each block's begin: views of a
/// BatchScratch.
struct Survivors {
  std::span<const std::uint32_t> indices;
  std::span<const Vec3> points;
  std::span<const std::uint32_t> order;
  /// Per position in `order`, the Morton code of its point's cell; empty where the order is not
  /// by cells.
  std::span<const std::uint32_t> cells;
  /// The survivors of sieve block b are [firstOfBlock[b], firstOfBlock[b + 1]).
  std::vector<std::size_t> firstOfBlock;
};

/// The seed's early "no contact" for a whole batch: streams through the points once, in
/// parallel blocks, in the vector lanes of the point tables (detail::sieveByGrid), and keeps those
/// the grid does not put beyond √limit, each block in a buffer of its own while its points are
/// still in the cache (a second pass over the input, as this was, read a tenth of the points back
/// from memory: a fifth of an ε-limited batch). The blocks' buffers are then laid end to end, so
/// the survivors and their keys are in input order whatever the thread count. `contiguous`: the
/// points as one array (pointAt(i) is contiguous[i]), or null. Also the batch's validation:
/// throws for the first point with a non-finite coordinate or one out of range.
template <typename PointAt>
Survivors sieve(const QueryMesh& mesh, std::size_t count, const PointAt& pointAt,
                const Vec3* contiguous, double limit, BatchScratch& scratch) {
  const detail::GridView grid = mesh.data().boundGrid.view();
  const Aabb& box = mesh.data().bounds;
  const auto local = [&mesh, &pointAt](std::size_t i) {
    return mesh.moved() ? mesh.inversePose().apply(pointAt(i)) : pointAt(i);
  };
  // The survivors of a cell, searched one after another, share its leaves (searchInOrder).
  const bool byCells = std::max({grid.lastCell[0], grid.lastCell[1], grid.lastCell[2]}) < 1024;
  const auto codeOf = [&](const Vec3& inMeshFrame) {
    if (!byCells) return detail::mortonCode(inMeshFrame, box);
    const std::array<std::uint32_t, 3> cell = grid.cellOf(inMeshFrame);
    return detail::mortonOfCell(cell[0], cell[1], cell[2]);
  };
  const std::size_t blocks = (count + kSieveBlock - 1) / kSieveBlock;
  if (scratch.kept.size() < blocks) scratch.kept.resize(blocks);
  std::vector<std::vector<Kept>>& kept = scratch.kept;
  std::vector<std::size_t> firstBad(blocks, count);
  parallelFor(0, blocks, 1, [&](std::size_t firstBlock, std::size_t endBlock) {
    std::array<std::uint32_t, kSieveBlock> inDoubt;  // offsets in the block
    std::array<Vec3, kCarried> carried;
    for (std::size_t block = firstBlock; block < endBlock; ++block) {
      const std::size_t begin = block * kSieveBlock;
      const std::size_t end = std::min(count, begin + kSieveBlock);
      std::size_t doubtful = 0;
      bool fine = true;
      if (contiguous != nullptr && !mesh.moved()) {
        doubtful =
            detail::sieveByGrid(grid, contiguous + begin, end - begin, limit, inDoubt.data(), fine);
      } else {
        for (std::size_t at = begin; at < end; at += kCarried) {
          const std::size_t n = std::min(kCarried, end - at);
          for (std::size_t j = 0; j < n; ++j) {
            const Vec3 point = pointAt(at + j);
            fine = fine && inCoordinateRange(point);  // the grid's sieve checks the carried one
            carried[j] = mesh.moved() ? mesh.inversePose().apply(point) : point;
          }
          std::uint32_t* const more = inDoubt.data() + doubtful;
          const std::size_t added = detail::sieveByGrid(grid, carried.data(), n, limit, more, fine);
          for (std::size_t k = 0; k < added; ++k)
            more[k] += static_cast<std::uint32_t>(at - begin);
          doubtful += added;
        }
      }
      if (!fine)
        for (std::size_t i = begin; i < end && firstBad[block] == count; ++i)
          if (!inRange(pointAt(i), local(i))) firstBad[block] = i;
      std::vector<Kept>& mine = kept[block];
      mine.resize(doubtful);
      for (std::size_t k = 0; k < doubtful; ++k) {
        const std::size_t i = begin + inDoubt[k];
        // The survivor lies within ε of the mesh's box.
        mine[k] = {pointAt(i), static_cast<std::uint32_t>(i), codeOf(local(i))};
      }
    }
  });
  for (std::size_t block = 0; block < blocks; ++block)
    if (firstBad[block] != count) throwBadPoint(mesh, firstBad[block], pointAt(firstBad[block]));
  Survivors survivors;
  survivors.firstOfBlock.assign(blocks + 1, 0);
  for (std::size_t block = 0; block < blocks; ++block)
    survivors.firstOfBlock[block + 1] = survivors.firstOfBlock[block] + kept[block].size();
  const std::size_t total = survivors.firstOfBlock[blocks];
  const std::span<std::uint32_t> indices = firstOf(scratch.indices, total);
  const std::span<Vec3> points = firstOf(scratch.points, total);
  const std::span<std::uint64_t> keys = firstOf(scratch.keys, total);
  parallelFor(0, blocks, 1, [&](std::size_t firstBlock, std::size_t endBlock) {
    for (std::size_t block = firstBlock; block < endBlock; ++block)
      for (std::size_t at = survivors.firstOfBlock[block]; const Kept& k : kept[block]) {
        indices[at] = k.index;
        points[at] = k.point;
        keys[at] = k.code << 32 | at;
        ++at;
      }
  });
  // A cell's Morton code has three bits for each bit of the largest cell index: a sort of that
  // many bits takes fewer passes than one of all 30.
  const std::uint32_t mostCells = std::max({grid.lastCell[0], grid.lastCell[1], grid.lastCell[2]});
  const int codeBits = byCells ? 3 * std::max(static_cast<int>(std::bit_width(mostCells)), 1) : 30;
  const std::span<std::uint32_t> order = firstOf(scratch.order, total);
  const std::span<std::uint32_t> cells =
      byCells ? firstOf(scratch.cells, total) : std::span<std::uint32_t>{};
  detail::sortKeys(keys, firstOf(scratch.buffer, total), codeBits, order, cells);
  survivors.indices = indices;
  survivors.points = points;
  survivors.order = order;
  survivors.cells = cells;
  return survivors;
}

/// Runs of at least this many points of one cell share its leaves (gatherNear): for fewer, the
/// gathering costs more than the searches from the root it saves.
constexpr std::size_t kClusterFrom = 2;

/// Into `near`, the leaves that hold every triangle within ε of any of `points` (world frame):
/// those whose bound from the centre of the points' box (mesh frame) is within ε + r, r half
/// its diagonal, grown by far more than the rounding. False where there are too many.
bool gatherNear(const QueryMesh& mesh, std::span<const Vec3> points, double epsilon,
                detail::LeafCandidates& near) {
  Aabb box;
  for (const Vec3& point : points)
    box.extend(localPoint(mesh, point));
  const double radius = (epsilon + 0.5 * box.diagonal()) * (1.0 + 0x1p-20);
  return near.collect(mesh.data(), box.center(), radius * radius);
}

/// Answers the points `pointAt(k)` (world frame), k in `order`, into out[k], with the upper
/// bounds `boundOf(k)`. Along a Morton curve, consecutive points descend to the same nodes and
/// triangles, which the previous descents left in the cache: scattered input (a user's points
/// in any order) runs as fast as sorted input. `cells`: empty, or per position in `order` the
/// cell of a grid of its point, where the points of a cell, consecutive in the order, are
/// searched among the leaves near them all (gatherNear) instead of from the root: an ε-limited
/// batch's survivors, a few a cell, whose descents from the root passed the same nodes. Each
/// answer is that point's alone, so neither the order nor the sharing changes a result.
template <typename PointAt, typename BoundOf>
void searchInOrder(const QueryMesh& mesh, std::span<const std::uint32_t> order,
                   const PointAt& pointAt, const BoundOf& boundOf, const PointQuery& query,
                   bool screened, std::span<PointDistance> out,
                   std::span<const std::uint32_t> cells = {}) {
  const std::size_t count = order.size();
  // Each run of kGrain points is gathered before and its answers scattered after the searches:
  // the scattered reads and writes then overlap in tight loops instead of each stalling a search.
  cancellableParallelFor(0, count, kGrain, [&](std::size_t begin, std::size_t end) {
    std::array<Vec3, kGrain> points;
    std::array<PointDistance, kGrain> answers;
    Hint hint;
    detail::LeafCandidates near;
    for (std::size_t run = begin; run < end; run += kGrain) {
      const std::size_t runEnd = std::min(run + kGrain, end);
      for (std::size_t k = run; k < runEnd; ++k)
        points[k - run] = pointAt(order[k]);
      for (std::size_t k = run; k < runEnd;) {
        std::size_t clusterEnd = k + 1;
        if (!cells.empty())
          while (clusterEnd < runEnd && cells[clusterEnd] == cells[k])
            ++clusterEnd;
        const detail::LeafCandidates* shared =
            clusterEnd - k >= kClusterFrom &&
                    gatherNear(mesh, std::span(points).subspan(k - run, clusterEnd - k),
                               query.epsilon, near)
                ? &near
                : nullptr;
        // Among a cell's few leaves the previous answer's triangle (Hint) saves less than its
        // exact kernel costs (W2 2-3% faster without).
        for (; k < clusterEnd; ++k)
          answers[k - run] = answer(mesh, points[k - run], query, boundOf(order[k]),
                                    shared ? nullptr : &hint, screened, shared);
      }
      for (std::size_t k = run; k < runEnd; ++k)
        out[order[k]] = answers[k - run];
    }
  });
}

/// out[i] for i in [begin, end): found[k] where indices[k] is i (k in [first, last),
/// ascending), "not found" elsewhere, each written once, in order. (Non-temporal stores, which
/// spare the read of the output's lines, measured slower here on Zen 5.)
void writeMerged(std::span<PointDistance> out, std::size_t begin, std::size_t end,
                 std::span<const PointDistance> found, std::span<const std::uint32_t> indices,
                 std::size_t first, std::size_t last) noexcept {
  static constexpr PointDistance kNotFound{};
  std::size_t k = first;
  for (std::size_t i = begin; i < end; ++i) {
    const bool survivor = k < last && indices[k] == i;
    out[i] = survivor ? found[k] : kNotFound;
    k += survivor;
  }
}

/// `upperBounds` is empty or one bound per point; `contiguous` is the points as one array
/// (pointAt(i) is contiguous[i]) or null.
template <typename PointAt>
void answerAll(const QueryMesh& mesh, std::size_t count, const PointAt& pointAt,
               const Vec3* contiguous, const PointQuery& asked, std::span<PointDistance> out,
               std::span<const double> upperBounds = {}) {
  const PointQuery query = validate(mesh, asked);
  const auto boundOf = [upperBounds](std::size_t i) {
    return upperBounds.empty() ? std::numeric_limits<double>::infinity() : upperBounds[i];
  };
  const double limit = searchLimit(query.epsilon);
  if (count < kCoherentFrom || count > std::numeric_limits<std::uint32_t>::max()) {
    validatePoints(mesh, count, pointAt);
    cancellableParallelFor(0, count, kGrain, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        out[i] = answer(mesh, pointAt(i), query, boundOf(i));
    });
  } else if (std::isfinite(limit) && !mesh.data().boundGrid.empty()) {
    // The points the grid puts beyond ε are not searched (one cell read each, streaming through
    // the input); the others are, into a buffer of their own, which is then merged with the
    // rest in input order: the output is written once, in order (scattered into it, the answers
    // cost a tenth of the batch in cache misses).
    ScratchLease lease;
    const Survivors survivors = sieve(mesh, count, pointAt, contiguous, limit, lease.get());
    const std::span<PointDistance> found = firstOf(lease.get().found, survivors.indices.size());
    searchInOrder(
        mesh, survivors.order, [&survivors](std::size_t k) { return survivors.points[k]; },
        [&survivors, upperBounds](std::size_t k) {
          // Without bounds the index (a read at random) is not needed.
          return upperBounds.empty() ? std::numeric_limits<double>::infinity()
                                     : upperBounds[survivors.indices[k]];
        },
        query, true, found, survivors.cells);
    const std::size_t blocks = survivors.firstOfBlock.size() - 1;
    parallelFor(0, blocks, 1, [&](std::size_t firstBlock, std::size_t endBlock) {
      for (std::size_t block = firstBlock; block < endBlock; ++block)
        writeMerged(out, block * kSieveBlock, std::min(count, (block + 1) * kSieveBlock), found,
                    survivors.indices, survivors.firstOfBlock[block],
                    survivors.firstOfBlock[block + 1]);
    });
  } else {
    validatePoints(mesh, count, pointAt);
    searchInOrder(mesh, detail::mortonOrder(count, pointAt), pointAt, boundOf, query, false, out);
  }
}

}  // namespace

void distances(const QueryMesh& mesh, std::span<const Vec3> points, const PointQuery& query,
               std::span<PointDistance> out) {
  if (out.size() != points.size())
    throw Error("point distances: " + std::to_string(points.size()) + " points but room for " +
                std::to_string(out.size()) + " answers");
  answerAll(
      mesh, points.size(), [points](std::size_t i) { return points[i]; }, points.data(), query,
      out);
}

void distances(const QueryMesh& mesh, std::span<const Vec3> points,
               std::span<const double> upperBounds, const PointQuery& query,
               std::span<PointDistance> out) {
  if (out.size() != points.size() || upperBounds.size() != points.size())
    throw Error("point distances: " + std::to_string(points.size()) + " points but " +
                std::to_string(upperBounds.size()) + " bounds and room for " +
                std::to_string(out.size()) + " answers");
  for (std::size_t i = 0; i < upperBounds.size(); ++i)
    if (std::isnan(upperBounds[i]) || upperBounds[i] < 0.0)
      throw Error("point distances: the upper bound " + toString(upperBounds[i]) + " of point " +
                  std::to_string(i) + " is negative or NaN");
  answerAll(
      mesh, points.size(), [points](std::size_t i) { return points[i]; }, points.data(), query, out,
      upperBounds);
}

std::vector<PointDistance> distances(const QueryMesh& mesh, std::span<const Vec3> points,
                                     const PointQuery& query) {
  std::vector<PointDistance> out(points.size());
  distances(mesh, points, query, out);
  return out;
}

std::vector<PointDistance> distances(const QueryMesh& mesh, std::span<const double> x,
                                     std::span<const double> y, std::span<const double> z,
                                     const PointQuery& query) {
  if (y.size() != x.size() || z.size() != x.size())
    throw Error("point distances: coordinate arrays of different lengths (" +
                std::to_string(x.size()) + ", " + std::to_string(y.size()) + ", " +
                std::to_string(z.size()) + ")");
  std::vector<PointDistance> out(x.size());
  answerAll(
      mesh, x.size(),
      [x, y, z](std::size_t i) {
        return Vec3{x[i], y[i], z[i]};
      },
      nullptr, query, out);
  return out;
}

PointDistance distance(const QueryMesh& mesh, const Vec3& point, const PointQuery& asked) {
  const PointQuery query = validate(mesh, asked);
  validatePoints(mesh, 1, [&point](std::size_t) { return point; });
  return answer(mesh, point, query);
}

std::vector<ContactPoint> contacts(const QueryMesh& mesh, std::span<const Vec3> points,
                                   double epsilon) {
  if (!std::isfinite(epsilon) || !(epsilon > 0.0))
    throw Error("point contacts: epsilon = " + toString(epsilon) + " must be finite and positive");
  // A closed mesh that bounds no solid (it crosses itself, or its parts do not nest) has its
  // overlaps by winding number, where pseudonormal signs are wrong.
  const bool closed = mesh.closed();
  const Sign sign = closed && !boundsSolid(mesh) ? Sign::winding : Sign::pseudonormal;
  const std::vector<PointDistance> near =
      distances(mesh, points, {.epsilon = epsilon, .signedDistance = closed, .sign = sign});
  const detail::QueryMeshData& data = mesh.data();
  std::vector<ContactPoint> found;
  for (std::size_t i = 0; i < near.size(); ++i) {
    if (!near[i].found()) continue;
    ContactPoint contact;
    contact.x = (points[i] + near[i].closest) * 0.5;
    contact.normal = points[i] - contact.x;
    contact.distance = near[i].distance;
    contact.direction = normalized(points[i] - near[i].closest);
    if (!(lengthSquared(contact.direction) > 0.5))
      contact.direction = mesh.pose().rotation.rotate(
          normalized(mesh.triangles().triangle(near[i].triangle).areaVector() * data.orientation));
    if (!(lengthSquared(contact.direction) > 0.5)) contact.direction = {0, 0, 1};
    contact.overlap = near[i].inside;
    contact.first = static_cast<std::uint32_t>(i);
    contact.second = near[i].triangle;
    found.push_back(contact);
  }
  return found;
}

const char* signName(Sign sign) noexcept {
  return sign == Sign::winding ? "winding" : "pseudonormal";
}

std::optional<Sign> parseSign(std::string_view text) noexcept {
  for (const Sign sign : {Sign::pseudonormal, Sign::winding})
    if (text == signName(sign)) return sign;
  return std::nullopt;
}

}  // namespace delta::contactdetection
