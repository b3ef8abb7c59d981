#include "delta/ib/adaptive_grid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "delta/core/cancel.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/query/part_nesting.h"
#include "delta/query/self_intersections.h"

namespace delta::ib {
namespace {

constexpr int kMaxLevels = 20;
constexpr std::uint64_t kEmptyKey = ~std::uint64_t{0};
constexpr std::uint32_t kNotOld = Cell::kLeaf;
/// Relative rounding allowance of a bound on a distance's change: a little over the rounding of
/// the distance computation, so that a decision the bound calls certain is the one an exact
/// recomputation makes.
constexpr double kRoundingAllowance = 1e-12;
/// The same for the rounding that goes with the size of the coordinates rather than of the
/// distance: a pose's image of a point and a query's distance round by ulps of the coordinates
/// (a domain at 1e6 of side 2⁻¹⁰: the computed largest displacement fell an ulp of 1e6 short of
/// the exact one, and a moved grid kept a cell a new grid splits).
constexpr double kCoordinateRounding = 64.0 * std::numeric_limits<double>::epsilon();

/// A vertex's integer position, 21 bits per axis.
constexpr std::uint64_t packKey(std::uint32_t x, std::uint32_t y, std::uint32_t z) noexcept {
  return std::uint64_t{x} | (std::uint64_t{y} << 21) | (std::uint64_t{z} << 42);
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The box of the boundary where it is now.
Aabb currentBounds(const QueryMesh& boundary) {
  return movedBox(boundary.bounds(), boundary.pose());
}

/// Throws delta::Error where the distance queries of a move to `pose` would refuse a point
/// half-way through it: where the boundary there, or a point of `domain` carried into the
/// boundary's frame, lies beyond the coordinate range (mesh/coordinate_range.h). The points'
/// images lie in the hull of the corners' (the map is affine); the allowance covers the rounding
/// of carrying any of them, which is a few ulps of their size and the translation's.
void requireQueryableAt(const QueryMesh& boundary, const RigidTransform& pose, const Aabb& domain) {
  QueryMesh moved = boundary;
  moved.setPose(pose);
  checkCoordinateRange(currentBounds(moved), "AdaptiveGrid: the boundary moved to this pose");
  const RigidTransform& inverse = moved.inversePose();
  Aabb images;
  double largest = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p = domain.corner(corner);
    images.extend(inverse.apply(p));
    largest = std::max(largest, length(p));
  }
  const double allowance = 0x1p-40 * (largest + maxAbs(inverse.translation));
  if (!(magnitude(images) + allowance <= kLargestCoordinate))
    throw Error("AdaptiveGrid: this pose carries the domain " + toString(domain.lower) + " to " +
                toString(domain.upper) + " to " + toString(images.lower) + " to " +
                toString(images.upper) + " in the boundary's frame, beyond the coordinate range " +
                coordinateRangeText() + " the distance queries answer; the grid is unchanged");
}

/// The largest displacement of a point of `box` (prepared frame) between poses `from` and `to`.
/// The displacement (R₁ − R₀)p + t₁ − t₀ is affine in p, so its length is convex and largest at
/// a corner of the box.
double largestDisplacement(const Aabb& box, const RigidTransform& from, const RigidTransform& to) {
  double largest = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p = box.corner(corner);
    largest = std::max(largest, length(to.apply(p) - from.apply(p)));
  }
  return largest;
}

/// Cells or vertices a serial loop of a build goes through between two polls for cancellation
/// (core/cancel.h): some milliseconds of hashing and bookkeeping.
constexpr std::size_t kCellsBetweenPolls = std::size_t{1} << 14;

/// What a grid needs a cell, as measured (peak resident memory over cells, all levels counted:
/// 345 MB for 1.74 million cells, levels 8 around granulate:1): the cell, its share of the
/// vertices (their keys, distances, hash table) and of the query batches.
constexpr double kBytesPerCell = 200.0;

/// The boundary's area (a rigid motion keeps it).
double surfaceArea(const QueryMesh& boundary) {
  const TriangleSoA& triangles = boundary.triangles();
  double area = 0.0;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    area += 0.5 * length(triangles.triangle(t).areaVector());
  return area;
}

/// Refuses a build's next level before its cells are made when the grid it leads to would not
/// fit. `refined` cells of `level` (of `levels`) are to be split, `cells` are made so far. The
/// finest level's cells are estimated two ways and the smaller is taken (each errs on its own
/// side): extrapolated, 8·refined·4^(levels − 1 − level), since a surface's band of refined cells
/// quadruples each finer level once the cells are smaller than its features (fewer before); and
/// from the band itself, `finestBand` cells (the boundary's area over the finest cell's face,
/// times the band's width in cells; more where parts of the boundary lie closer than the band).
/// Throws delta::Error with the estimate and the limit: more cells in a level than 32-bit indices
/// hold, or more memory than core/memory.h allows.
void requireRoomToRefine(std::size_t refined, int level, int levels, std::size_t cells,
                         double finestBand) {
  if (refined == 0) return;
  const double next = 8.0 * static_cast<double>(refined);  // made now
  const double extrapolated = next * std::pow(4.0, levels - 1 - level);
  const double finest = std::max(next, std::min(extrapolated, finestBand));
  const double total = static_cast<double>(cells) + finest * 4.0 / 3.0;  // 1 + 1/4 + 1/16 ...
  const std::string estimate = "levels " + std::to_string(levels) + ": about " +
                               toString(std::round(finest)) + " cells at level " +
                               std::to_string(levels) + " (estimated from the " +
                               std::to_string(refined) + " cells refined at level " +
                               std::to_string(level) + " and the boundary's area)";
  if (finest >= static_cast<double>(Cell::kLeaf))
    throw Error("AdaptiveGrid: " + estimate + ", more than the " + std::to_string(Cell::kLeaf) +
                " a level's 32-bit indices hold; it would need about " +
                describeBytes(total * kBytesPerCell) + " of memory: use fewer levels");
  requireMemory(total * kBytesPerCell, "AdaptiveGrid: " + estimate);
}

/// Throws delta::Error naming the first option out of its range.
void check(const GridOptions& options, const QueryMesh& boundary) {
  if (options.levels < 1 || options.levels > kMaxLevels)
    throw Error("GridOptions: levels " + std::to_string(options.levels) + " must be 1 to " +
                std::to_string(kMaxLevels));
  if (!(std::isfinite(options.refineFactor) && options.refineFactor > 0.0))
    throw Error("GridOptions: refineFactor " + toString(options.refineFactor) +
                " must be finite and positive");
  if (!(std::isfinite(options.padding) && options.padding >= 0.0))
    throw Error("GridOptions: padding " + toString(options.padding) +
                " must be finite and not negative");
  if (options.exactBand && !(*options.exactBand >= 0.0))
    throw Error("GridOptions: exactBand " + toString(*options.exactBand) +
                " must not be negative or NaN (leave it unset for the default)");
  if (options.domain) {
    const Aabb& box = *options.domain;
    const Vec3 extent = box.extent();
    if (!isFinite(box.lower) || !isFinite(box.upper) || !(extent.x > 0.0) || !(extent.y > 0.0) ||
        !(extent.z > 0.0))
      throw Error("GridOptions: domain " + toString(box.lower) + " to " + toString(box.upper) +
                  " must be finite with lower < upper on every axis");
  }
  if (options.signedDistance && options.sign == contactdetection::Sign::pseudonormal &&
      !boundary.closed())
    throw Error("signed distances by pseudonormals need a closed boundary, and this one is not (" +
                describeDefects(boundary.topology()) +
                "); the winding-number sign takes it (GridOptions::sign = Sign::winding), and "
                "unsigned distances work (GridOptions::signedDistance = false)");
}

/// The domain of checked options: the one given, or the boundary's box made a cube and padded.
Aabb domainOf(const GridOptions& options, const QueryMesh& boundary) {
  // Its vertices are the distance queries' points: the domain must lie in their range (a huge
  // padding or domain was refused by the queries as "point 0 (…)", or overflowed to NaN).
  if (options.domain) {
    checkCoordinateRange(*options.domain, "GridOptions: the domain");
    return *options.domain;
  }
  const Aabb box = currentBounds(boundary);
  const Vec3 extent = box.extent();
  const double side = std::max({extent.x, extent.y, extent.z}) * (1.0 + 2.0 * options.padding);
  const Vec3 half = Vec3{side, side, side} * 0.5;
  const Aabb domain{box.center() - half, box.center() + half};
  const Vec3 size = domain.extent();
  if (!isFinite(domain.lower) || !isFinite(domain.upper) || !(size.x > 0.0) || !(size.y > 0.0) ||
      !(size.z > 0.0))
    throw Error("GridOptions: the default domain " + toString(domain.lower) + " to " +
                toString(domain.upper) +
                " around the boundary must be finite with a positive extent (do its vertices "
                "all coincide, or is padding " +
                toString(options.padding) + " too large?)");
  checkCoordinateRange(domain,
                       "GridOptions: the default domain (the boundary's box grown by padding = " +
                           toString(options.padding) + " of its size on each side)");
  return domain;
}

}  // namespace

AdaptiveGrid::AdaptiveGrid(const QueryMesh& boundary, const GridOptions& options)
    : boundary_(boundary), options_(options) {
  check(options_, boundary_);
  domain_ = domainOf(options_, boundary_);
  options_.domain = domain_;
  resolution_ = std::uint32_t{1} << options_.levels;
  exactBand_ = options_.exactBand ? *options_.exactBand : cellDiagonal(options_.levels);
  // A winding sign of a boundary that bounds no solid (open, crossing itself, its parts not nested)
  // may change away from it as it moves.
  if (options_.signedDistance && options_.sign == contactdetection::Sign::winding &&
      !boundsSolid(boundary_))
    exactBand_ = std::numeric_limits<double>::infinity();
  rebuildTable(1024);
  poses_.push_back(boundary_.pose());
  refine();
}

namespace {

/// Poses that place every point alike: equal components (a zero's sign aside).
bool samePose(const RigidTransform& a, const RigidTransform& b) noexcept {
  return a.rotation.w == b.rotation.w && a.rotation.x == b.rotation.x &&
         a.rotation.y == b.rotation.y && a.rotation.z == b.rotation.z &&
         a.translation == b.translation;
}

}  // namespace

const GridStatistics& AdaptiveGrid::moveBoundary(const RigidTransform& motion) {
  QueryMesh moved = boundary_;
  moved.transform(motion);
  return moveBoundaryTo(moved.pose());
}

const GridStatistics& AdaptiveGrid::moveBoundaryTo(const RigidTransform& pose) {
  const CancelScope uninterruptible({});  // a move stopped half-way would leave no valid grid
  requireQueryableAt(boundary_, pose, domain_);  // before anything changes
  const QueryMesh before = boundary_;
  boundary_.setPose(pose);
  if (samePose(boundary_.pose(), before.pose())) {
    // Nothing moved: every distance and cell stands (a refine would ask the band again and get
    // the same answers).
    boundary_ = before;
    statistics_ = {};
    return statistics_;
  }
  poses_.push_back(boundary_.pose());
  try {
    refine();
  } catch (...) {
    // Not a refused point (checked above): memory ran out half-way, and the cells and vertices
    // are neither before nor after the move. The grid is made anew where the boundary was, so
    // that it stays usable, and the error passed on.
    *this = AdaptiveGrid(before, options_);
    throw;
  }
  return statistics_;
}

std::span<const Cell> AdaptiveGrid::cells(int level) const {
  if (level < 0 || level > options_.levels)
    throw Error("AdaptiveGrid::cells: level " + std::to_string(level) + " is not 0 to " +
                std::to_string(options_.levels));
  return levels_[level];
}

std::vector<std::size_t> AdaptiveGrid::leavesPerLevel() const {
  std::vector<std::size_t> leaves;
  for (const std::vector<Cell>& level : levels_)
    leaves.push_back(static_cast<std::size_t>(
        std::count_if(level.begin(), level.end(), [](const Cell& cell) { return cell.leaf(); })));
  return leaves;
}

std::size_t AdaptiveGrid::leafCount() const {
  std::size_t count = 0;
  for (std::size_t leaves : leavesPerLevel())
    count += leaves;
  return count;
}

Vec3 AdaptiveGrid::position(std::uint32_t v) const noexcept {
  return positionOfKey(keys_[v]);
}

Vec3 AdaptiveGrid::positionOfKey(std::uint64_t key) const noexcept {
  const double scale = 1.0 / resolution_;
  const Vec3& lower = domain_.lower;
  const Vec3 extent = domain_.extent();
  constexpr std::uint64_t mask = (std::uint64_t{1} << 21) - 1;
  return {lower.x + extent.x * (double(key & mask) * scale),
          lower.y + extent.y * (double((key >> 21) & mask) * scale),
          lower.z + extent.z * (double((key >> 42) & mask) * scale)};
}

std::vector<Vec3> AdaptiveGrid::positions() const {
  std::vector<Vec3> all(keys_.size());
  for (std::uint32_t v = 0; v < all.size(); ++v)
    all[v] = position(v);
  return all;
}

std::vector<double> AdaptiveGrid::errorBounds() const {
  std::vector<double> bounds(epoch_.size());
  for (std::size_t v = 0; v < bounds.size(); ++v)
    bounds[v] = slackOfEpoch_[epoch_[v]];
  return bounds;
}

double AdaptiveGrid::cellDiagonal(int level) const noexcept {
  return std::ldexp(length(domain_.extent()), -level);
}

void AdaptiveGrid::refine() {
  const auto start = std::chrono::steady_clock::now();
  statistics_ = {};
  const std::uint32_t now = static_cast<std::uint32_t>(poses_.size() - 1);
  updateSlacks(now);

  std::vector<std::vector<Cell>> old = std::move(levels_);
  std::size_t oldCells = 0;
  for (const std::vector<Cell>& level : old)
    oldCells += level.size();
  levels_.assign(options_.levels + 1, {});
  std::vector<std::uint32_t> fromOld, nextFromOld;  // each new cell's index in `old`, if any

  if (old.empty()) {
    Cell root;
    for (std::uint32_t c = 0; c < 8; ++c)
      root.corners[c] = vertexAt(c & 1 ? resolution_ : 0, c & 2 ? resolution_ : 0,
                                 c & 4 ? resolution_ : 0, nullptr);
    levels_[0].push_back(root);
    fromOld.push_back(kNotOld);
  } else {
    levels_[0].push_back(old[0][0]);
    fromOld.push_back(0);
  }

  std::vector<std::uint8_t> decision;  // per cell: 0 keep a leaf, 1 refine
  double finestBand = -1.0;            // a build's estimate of its finest cells, once needed
  std::size_t carried = 0;
  for (int level = 0;; ++level) {
    query();  // the new vertices of this level
    if (level == options_.levels) {
      for (Cell& cell : levels_[level])
        cell.firstChild = Cell::kLeaf;
      break;
    }
    decideRefinement(level, now, decision);
    if (old.empty()) {  // a build; a move, never stopped half-way, keeps about its cell count
      if (finestBand < 0.0) finestBand = finestCellsEstimate();
      std::size_t cellsSoFar = 0;
      for (int coarser = 0; coarser <= level; ++coarser)
        cellsSoFar += levels_[coarser].size();
      requireRoomToRefine(static_cast<std::size_t>(std::count(decision.begin(), decision.end(), 1)),
                          level, options_.levels, cellsSoFar, finestBand);
    }
    nextFromOld.clear();
    carried += makeNextLevel(level, decision, old, fromOld, nextFromOld);
    std::swap(fromOld, nextFromOld);
  }
  if (old.empty()) {
    statistics_.cellsCreated += 1;  // the root
  } else {
    statistics_.cellsRemoved = oldCells - 1 - carried;
  }

  compact();
  refreshBand(now);
  forgetUnusedPoses();
  statistics_.seconds = secondsSince(start);
}

void AdaptiveGrid::updateSlacks(std::uint32_t now) {
  // How far each remembered distance may be off now (0 for this pose).
  const double roundingScale = kRoundingAllowance * length(domain_.extent());
  const double fixedMagnitude =
      std::max(magnitude(domain_), magnitude(movedBox(boundary_.bounds(), poses_[now])));
  slackOfEpoch_.resize(poses_.size());
  for (std::uint32_t epoch = 0; epoch < now; ++epoch) {
    const double largest =
        std::max(fixedMagnitude, magnitude(movedBox(boundary_.bounds(), poses_[epoch])));
    slackOfEpoch_[epoch] = largestDisplacement(boundary_.bounds(), poses_[epoch], poses_[now]) *
                               (1.0 + kRoundingAllowance) +
                           roundingScale + kCoordinateRounding * largest;
  }
  slackOfEpoch_[now] = 0.0;
}

void AdaptiveGrid::decideRefinement(int level, std::uint32_t now,
                                    std::vector<std::uint8_t>& decision) {
  // Refine where the smallest corner distance is below the threshold: certain from the bounds of
  // remembered distances, or else (2: in doubt) from fresh ones.
  const std::vector<Cell>& cells = levels_[level];
  const double threshold = options_.refineFactor * cellDiagonal(level);
  decision.assign(cells.size(), 0);
  ++pass_;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i % kCellsBetweenPolls == 0) pollCancellation();
    double lowest = std::numeric_limits<double>::infinity();
    double highest = std::numeric_limits<double>::infinity();
    for (std::uint32_t v : cells[i].corners) {
      const double d = std::abs(distance_[v]), slack = slackOfEpoch_[epoch_[v]];
      lowest = std::min(lowest, d - slack);
      highest = std::min(highest, d + slack);
    }
    if (highest < threshold) {
      decision[i] = 1;
    } else if (lowest < threshold) {
      decision[i] = 2;
      for (std::uint32_t v : cells[i].corners)
        if (epoch_[v] != now) queue(v, std::abs(distance_[v]) + slackOfEpoch_[epoch_[v]]);
    }
  }
  query();
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (decision[i] != 2) continue;
    double lowest = std::numeric_limits<double>::infinity();
    for (std::uint32_t v : cells[i].corners)
      lowest = std::min(lowest, std::abs(distance_[v]));
    decision[i] = lowest < threshold ? 1 : 0;
  }
}

double AdaptiveGrid::finestCellsEstimate() const {
  // (4√3·F + 3)·A/h² finest cells, h the side of a finest cell: the band refined at level L − 1
  // is about 2·(F·√3·2h + 1.5h) wide, each of its cells split in 8 (measured on granulate:1
  // with F = 1: 9.86·A/h², where this gives 9.93).
  const Vec3 cell = domain_.extent() / double(std::uint64_t{1} << options_.levels);
  const double side = std::cbrt(cell.x * cell.y * cell.z);
  return std::min(
      (4.0 * std::sqrt(3.0) * options_.refineFactor + 3.0) * surfaceArea(boundary_) / (side * side),
      std::pow(8.0, options_.levels));
}

std::size_t AdaptiveGrid::makeNextLevel(int level, const std::vector<std::uint8_t>& decision,
                                        const std::vector<std::vector<Cell>>& old,
                                        const std::vector<std::uint32_t>& fromOld,
                                        std::vector<std::uint32_t>& nextFromOld) {
  // The children of refined cells, carried over where they were refined before.
  std::vector<Cell>& cells = levels_[level];
  std::vector<Cell>& next = levels_[level + 1];
  std::size_t carried = 0;
  const std::uint32_t half = (resolution_ >> level) / 2;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i % kCellsBetweenPolls == 0) pollCancellation();
    Cell& cell = cells[i];
    if (decision[i] == 0) {
      cell.firstChild = Cell::kLeaf;
      continue;
    }
    const std::uint32_t before =
        fromOld[i] == kNotOld ? Cell::kLeaf : old[level][fromOld[i]].firstChild;
    cell.firstChild = static_cast<std::uint32_t>(next.size());
    if (before != Cell::kLeaf) {
      for (std::uint32_t c = 0; c < 8; ++c) {
        next.push_back(old[level + 1][before + c]);
        nextFromOld.push_back(before + c);
      }
      carried += 8;
      continue;
    }
    // New children share the 3 × 3 × 3 lattice of vertices of their parent.
    std::uint32_t lattice[27];
    for (std::uint32_t k = 0; k < 3; ++k)
      for (std::uint32_t j = 0; j < 3; ++j)
        for (std::uint32_t a = 0; a < 3; ++a) {
          const std::uint32_t at = a + 3 * j + 9 * k;
          const bool corner = a != 1 && j != 1 && k != 1;
          lattice[at] = corner ? cell.corners[a / 2 + 2 * (j / 2) + 4 * (k / 2)]
                               : vertexAt(cell.origin[0] + a * half, cell.origin[1] + j * half,
                                          cell.origin[2] + k * half, &cell);
        }
    for (std::uint32_t c = 0; c < 8; ++c) {
      Cell child;
      child.level = static_cast<std::uint8_t>(level + 1);
      const std::uint32_t cx = c & 1, cy = (c >> 1) & 1, cz = (c >> 2) & 1;
      child.origin = {cell.origin[0] + cx * half, cell.origin[1] + cy * half,
                      cell.origin[2] + cz * half};
      for (std::uint32_t corner = 0; corner < 8; ++corner)
        child.corners[corner] = lattice[(cx + (corner & 1)) + 3 * (cy + ((corner >> 1) & 1)) +
                                        9 * (cz + ((corner >> 2) & 1))];
      next.push_back(child);
      nextFromOld.push_back(kNotOld);
    }
    statistics_.cellsCreated += 8;
  }
  return carried;
}

void AdaptiveGrid::refreshBand(std::uint32_t now) {
  // The band: every vertex that may be within exactBand gets its exact distance.
  ++pass_;
  pollCancellation();
  for (std::uint32_t v = 0; v < keys_.size(); ++v)
    if (epoch_[v] != now && std::abs(distance_[v]) - slackOfEpoch_[epoch_[v]] <= exactBand_)
      queue(v, std::abs(distance_[v]) + slackOfEpoch_[epoch_[v]]);
  query();
}

void AdaptiveGrid::forgetUnusedPoses() {
  std::vector<std::uint32_t> renumbered(poses_.size(), 0);
  for (std::uint32_t epoch : epoch_)
    renumbered[epoch] = 1;
  std::uint32_t kept = 0;
  for (std::uint32_t epoch = 0; epoch < poses_.size(); ++epoch) {
    if (!renumbered[epoch]) continue;
    poses_[kept] = poses_[epoch];
    slackOfEpoch_[kept] = slackOfEpoch_[epoch];
    renumbered[epoch] = kept++;
  }
  if (kept == poses_.size()) return;
  poses_.resize(kept);
  slackOfEpoch_.resize(kept);
  for (std::uint32_t& epoch : epoch_)
    epoch = renumbered[epoch];
}

void AdaptiveGrid::queue(std::uint32_t v, double upperBound) {
  if (queuedAt_[v] == pass_) return;
  queuedAt_[v] = pass_;
  pending_.push_back(v);
  pendingBounds_.push_back(upperBound);
}

void AdaptiveGrid::query() {
  if (pending_.empty()) return;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = pending_.size();
  batchPoints_.resize(n);
  batchAnswers_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    batchPoints_[i] = position(pending_[i]);
  contactdetection::PointQuery request;
  request.signedDistance = options_.signedDistance;
  request.sign = options_.sign;
  contactdetection::distances(boundary_, batchPoints_, pendingBounds_, request, batchAnswers_);
  const std::uint32_t now = static_cast<std::uint32_t>(poses_.size() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t v = pending_[i];
    distance_[v] =
        options_.signedDistance ? batchAnswers_[i].signedDistance() : batchAnswers_[i].distance;
    epoch_[v] = now;
  }
  pending_.clear();
  pendingBounds_.clear();
  statistics_.queries += n;
  statistics_.querySeconds += secondsSince(start);
}

std::size_t AdaptiveGrid::slotOf(std::uint64_t key) const noexcept {
  const std::size_t mask = tableKeys_.size() - 1;
  std::size_t slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
  while (tableKeys_[slot] != key && tableKeys_[slot] != kEmptyKey)
    slot = (slot + 1) & mask;
  return slot;
}

void AdaptiveGrid::rebuildTable(std::size_t capacity) {
  tableKeys_.assign(capacity, kEmptyKey);
  tableValues_.assign(capacity, 0);
  for (std::uint32_t v = 0; v < keys_.size(); ++v) {
    const std::size_t slot = slotOf(keys_[v]);
    tableKeys_[slot] = keys_[v];
    tableValues_[slot] = v;
  }
}

std::uint32_t AdaptiveGrid::vertexAt(std::uint32_t x, std::uint32_t y, std::uint32_t z,
                                     const Cell* parent) {
  const std::uint64_t key = packKey(x, y, z);
  std::size_t slot = slotOf(key);
  if (tableKeys_[slot] == key) return tableValues_[slot];
  const std::uint32_t v = static_cast<std::uint32_t>(keys_.size());
  // The distance is 1-Lipschitz: a parent's corner bounds it (what that corner knows, plus how
  // far it is).
  double bound = std::numeric_limits<double>::infinity();
  if (parent != nullptr) {
    const Vec3 p = positionOfKey(key);
    for (std::uint32_t c : parent->corners)
      bound = std::min(bound, std::abs(distance_[c]) + slackOfEpoch_[epoch_[c]] +
                                  length(p - positionOfKey(keys_[c])));
  }
  keys_.push_back(key);
  distance_.push_back(0.0);
  epoch_.push_back(0);
  queuedAt_.push_back(pass_);
  pending_.push_back(v);
  pendingBounds_.push_back(bound * (1.0 + kRoundingAllowance));
  tableKeys_[slot] = key;
  tableValues_[slot] = v;
  if (2 * keys_.size() > tableKeys_.size()) rebuildTable(2 * tableKeys_.size());
  return v;
}

void AdaptiveGrid::compact() {
  std::vector<std::uint32_t> remap(keys_.size(), 0);
  for (const std::vector<Cell>& level : levels_)
    for (const Cell& cell : level)
      for (std::uint32_t v : cell.corners)
        remap[v] = 1;
  std::uint32_t kept = 0;
  for (std::uint32_t v = 0; v < remap.size(); ++v) {
    if (!remap[v]) continue;
    keys_[kept] = keys_[v];
    distance_[kept] = distance_[v];
    epoch_[kept] = epoch_[v];
    queuedAt_[kept] = queuedAt_[v];
    remap[v] = kept++;
  }
  if (kept == keys_.size()) return;
  keys_.resize(kept);
  distance_.resize(kept);
  epoch_.resize(kept);
  queuedAt_.resize(kept);
  for (std::vector<Cell>& level : levels_)
    for (Cell& cell : level)
      for (std::uint32_t& v : cell.corners)
        v = remap[v];
  std::size_t capacity = 1024;
  while (capacity < 2 * kept)
    capacity *= 2;
  rebuildTable(capacity);
}

}  // namespace delta::ib
