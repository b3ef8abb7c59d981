#include "delta/dem/broad_phase.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/mesh/coordinate_range.h"

namespace delta::dem {
namespace {

/// Spheres per parallel chunk: a few µs of work each.
constexpr std::size_t kSphereGrain = 256;
/// At most this many cells along an axis of the spheres' box: larger cells when the spheres are
/// tiny and far apart keep the integer cell coordinates and their hashes far from overflow.
constexpr double kMostCellsPerAxis = 0x1p30;

struct Cell {
  std::int64_t x, y, z;
  friend constexpr bool operator==(const Cell&, const Cell&) = default;
};

/// A bucket of a table of `mask + 1` buckets (a power of two), by the primes of Teschner et al.,
/// "Optimized spatial hashing for collision detection of deformable objects" (VMV 2003).
std::uint64_t hashOf(const Cell& cell) noexcept {
  return (static_cast<std::uint64_t>(cell.x) * 73856093u) ^
         (static_cast<std::uint64_t>(cell.y) * 19349663u) ^
         (static_cast<std::uint64_t>(cell.z) * 83492791u);
}

std::size_t bucketOf(const Cell& cell, std::uint64_t mask) noexcept {
  return static_cast<std::size_t>(hashOf(cell) & mask);
}

/// Cells a little larger than the reach they must hold: two centres closer than the reach then
/// map to neighbouring cells although (c − lower) / edge rounds (by at most 2⁻²¹ of a cell, a
/// cell being at least 2⁻³⁰ of the extent). Without it two spheres 4.5e-14 inside each other's
/// reach, 1022 from the box's corner, fell two cells apart.
constexpr double kCellSlack = 1.0 + 0x1p-18;

/// The least non-zero radius or margin: reaches of at least 2⁻⁴⁸¹ have normal squares. Below it
/// reach² underflowed (two coincident spheres of radius 1e-170 were no pair); above the
/// coordinate range squared distances could overflow (radius 1e200, centres 1e170 apart).
constexpr double kSmallestLength = 0x1p-481;

/// Whether `length` is 0 or within [kSmallestLength, kLargestCoordinate].
bool inLengthRange(double length) noexcept {
  return length == 0.0 || (length >= kSmallestLength && length <= kLargestCoordinate);
}

void validate(std::span<const Sphere> spheres, double margin) {
  if (!inLengthRange(margin))
    throw Error("nearbyPairs: margin = " + toString(margin) +
                " must be 0 or between 2^-481 and the coordinate range " +
                toString(kLargestCoordinate));
  if (spheres.size() >= (std::size_t{1} << 32))
    throw Error("nearbyPairs: " + std::to_string(spheres.size()) +
                " spheres are more than 32-bit ids can name");
  for (std::size_t i = 0; i < spheres.size(); ++i)
    if (!inCoordinateRange(spheres[i].center) || !inLengthRange(spheres[i].radius))
      throw Error("nearbyPairs: sphere " + std::to_string(i) + " has centre " +
                  toString(spheres[i].center) + " and radius " + toString(spheres[i].radius) +
                  " (the centre must lie within the coordinate range, ±" +
                  toString(kLargestCoordinate) + ", and the radius be 0 or between 2^-481 and it)");
}

/// nearbyPairs on a dense grid of (last.x + 1)·(last.y + 1)·(last.z + 1) cells: the spheres
/// sorted by cell (x fastest; within a cell by index), so the three cells of a row around a
/// sphere's are one run; nine runs a sphere, no hashing.
std::vector<CandidatePair> pairsOnGrid(std::span<const Sphere> spheres, double margin,
                                       const std::vector<Cell>& cells, const Cell& last) {
  const std::size_t count = spheres.size();
  const auto nx = static_cast<std::size_t>(last.x) + 1, ny = static_cast<std::size_t>(last.y) + 1,
             nz = static_cast<std::size_t>(last.z) + 1;
  const auto indexOf = [&](std::size_t x, std::size_t y, std::size_t z) {
    return (z * ny + y) * nx + x;
  };
  std::vector<std::uint32_t> cellStart(nx * ny * nz + 1, 0);
  for (const Cell& cell : cells)
    ++cellStart[indexOf(static_cast<std::size_t>(cell.x), static_cast<std::size_t>(cell.y),
                        static_cast<std::size_t>(cell.z)) +
                1];
  for (std::size_t c = 1; c < cellStart.size(); ++c)
    cellStart[c] += cellStart[c - 1];
  std::vector<std::uint32_t> members(count);
  {
    std::vector<std::uint32_t> fill(cellStart.begin(), cellStart.end() - 1);
    for (std::size_t i = 0; i < count; ++i)
      members[fill[indexOf(
          static_cast<std::size_t>(cells[i].x), static_cast<std::size_t>(cells[i].y),
          static_cast<std::size_t>(cells[i].z))]++] = static_cast<std::uint32_t>(i);
  }
  std::vector<std::vector<CandidatePair>> perChunk((count + kSphereGrain - 1) / kSphereGrain);
  parallelFor(0, count, kSphereGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<CandidatePair>& found = perChunk[begin / kSphereGrain];
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t before = found.size();
      const Sphere& one = spheres[i];
      const auto x = static_cast<std::size_t>(cells[i].x), y = static_cast<std::size_t>(cells[i].y),
                 z = static_cast<std::size_t>(cells[i].z);
      const std::size_t fromX = x == 0 ? 0 : x - 1, toX = std::min(x + 1, nx - 1);
      for (std::size_t cz = z == 0 ? 0 : z - 1; cz <= std::min(z + 1, nz - 1); ++cz)
        for (std::size_t cy = y == 0 ? 0 : y - 1; cy <= std::min(y + 1, ny - 1); ++cy) {
          const std::uint32_t runEnd = cellStart[indexOf(toX, cy, cz) + 1];
          for (std::uint32_t k = cellStart[indexOf(fromX, cy, cz)]; k < runEnd; ++k) {
            const std::uint32_t j = members[k];
            if (j <= i) continue;
            const double reach = one.radius + spheres[j].radius + margin;
            if (distanceSquared(one.center, spheres[j].center) < reach * reach)
              found.push_back({static_cast<std::uint32_t>(i), j});
          }
        }
      std::sort(found.begin() + static_cast<std::ptrdiff_t>(before), found.end(),
                [](const CandidatePair& a, const CandidatePair& b) { return a.second < b.second; });
    }
  });
  return detail::joined<CandidatePair>(perChunk);
}

/// Whether the spheres in `cells` share their cells with more than 128 others on average (the
/// sum of the squared counts of a hash of the cells, which collisions only raise): then each
/// sphere's neighbourhood costs hundreds of tests.
bool crowded(const std::vector<Cell>& cells) {
  const std::uint64_t mask = std::bit_ceil(2 * cells.size()) - 1;
  std::vector<std::uint32_t> counts(mask + 1, 0);
  double sharing = 0.0;
  for (const Cell& cell : cells)
    sharing += 2.0 * counts[bucketOf(cell, mask)]++ + 1.0;  // (c + 1)² − c²
  return sharing > 128.0 * static_cast<double>(cells.size());
}

/// A cell of one level of levelledPairs' grids.
struct LevelCell {
  Cell cell;
  std::uint32_t level;
  friend constexpr bool operator==(const LevelCell&, const LevelCell&) = default;
};

std::size_t bucketOf(const LevelCell& key, std::uint64_t mask) noexcept {
  return static_cast<std::size_t>((hashOf(key.cell) ^ (key.level * 2654435761u)) & mask);
}

/// The spheres by the bucket of their key (`keys[i]` sphere i's), by a counting sort: bucket b's
/// run is members[start[b], start[b + 1]), in index order within it.
struct Buckets {
  std::vector<std::size_t> start;
  std::vector<std::uint32_t> members;
};

template <class Key>
Buckets byBucket(const std::vector<Key>& keys, std::uint64_t mask) {
  Buckets buckets{std::vector<std::size_t>(mask + 2, 0), std::vector<std::uint32_t>(keys.size())};
  for (const Key& key : keys)
    ++buckets.start[bucketOf(key, mask) + 1];
  for (std::size_t b = 1; b < buckets.start.size(); ++b)
    buckets.start[b] += buckets.start[b - 1];
  std::vector<std::size_t> fill(buckets.start.begin(), buckets.start.end() - 1);
  for (std::size_t i = 0; i < keys.size(); ++i)
    buckets.members[fill[bucketOf(keys[i], mask)]++] = static_cast<std::uint32_t>(i);
  return buckets;
}

/// nearbyPairs for spheres of very different sizes, on a hierarchy of grids (Ericson, Real-Time
/// Collision Detection 7.2.6): level l has cells of edge baseEdge·2^l, and a sphere lives on the
/// lowest level whose edge holds 2r + margin. For two spheres on levels a ≤ b, rᵢ + rⱼ + margin
/// ≤ edge_a / 2 + edge_b / 2 ≤ edge_b: the pair lies in neighbouring cells of level b, where the
/// sphere of level a looks for it. Each sphere looks on its own level (for larger indices) and on
/// every occupied level above (for all): O(n · levels) for any mix of sizes. The cells of all
/// levels are hashed into one table; the pairs, found from either end, are sorted at the end.
std::vector<CandidatePair> levelledPairs(std::span<const Sphere> spheres, double margin,
                                         const Aabb& box, double baseEdge) {
  const std::size_t count = spheres.size();
  std::vector<std::uint32_t> levels(count);
  std::uint32_t top = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double needed = (2.0 * spheres[i].radius + margin) * kCellSlack;
    std::uint32_t level = 0;
    while (std::ldexp(baseEdge, static_cast<int>(level)) < needed)
      ++level;
    levels[i] = level;
    top = std::max(top, level);
  }
  std::vector<bool> occupied(top + 1, false);
  for (const std::uint32_t level : levels)
    occupied[level] = true;
  const auto cellAt = [&](const Vec3& centre, std::uint32_t level) {
    const Vec3 offset = (centre - box.lower) / std::ldexp(baseEdge, static_cast<int>(level));
    return Cell{static_cast<std::int64_t>(offset.x), static_cast<std::int64_t>(offset.y),
                static_cast<std::int64_t>(offset.z)};
  };
  std::vector<LevelCell> keys(count);
  for (std::size_t i = 0; i < count; ++i)
    keys[i] = {cellAt(spheres[i].center, levels[i]), levels[i]};
  const std::uint64_t mask = std::bit_ceil(2 * count) - 1;
  const Buckets buckets = byBucket(keys, mask);
  std::vector<std::vector<CandidatePair>> perChunk((count + kSphereGrain - 1) / kSphereGrain);
  parallelFor(0, count, kSphereGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<CandidatePair>& found = perChunk[begin / kSphereGrain];
    for (std::size_t i = begin; i < end; ++i) {
      const Sphere& one = spheres[i];
      for (std::uint32_t level = levels[i]; level <= top; ++level) {
        if (!occupied[level]) continue;
        const Cell home = level == levels[i] ? keys[i].cell : cellAt(one.center, level);
        for (std::int64_t dx = -1; dx <= 1; ++dx)
          for (std::int64_t dy = -1; dy <= 1; ++dy)
            for (std::int64_t dz = -1; dz <= 1; ++dz) {
              const LevelCell neighbour{{home.x + dx, home.y + dy, home.z + dz}, level};
              const std::size_t bucket = bucketOf(neighbour, mask);
              for (std::size_t k = buckets.start[bucket]; k < buckets.start[bucket + 1]; ++k) {
                const std::uint32_t j = buckets.members[k];
                if (!(keys[j] == neighbour) || (level == levels[i] && j <= i)) continue;
                const double reach = one.radius + spheres[j].radius + margin;
                if (distanceSquared(one.center, spheres[j].center) < reach * reach)
                  found.push_back({static_cast<std::uint32_t>(std::min<std::size_t>(i, j)),
                                   static_cast<std::uint32_t>(std::max<std::size_t>(i, j))});
              }
            }
      }
    }
  });
  std::vector<CandidatePair> pairs = detail::joined<CandidatePair>(perChunk);
  std::sort(pairs.begin(), pairs.end(), [](const CandidatePair& a, const CandidatePair& b) {
    return a.first != b.first ? a.first < b.first : a.second < b.second;
  });
  return pairs;
}

}  // namespace

std::vector<CandidatePair> nearbyPairs(std::span<const Sphere> spheres, double margin) {
  validate(spheres, margin);
  if (spheres.size() < 2) return {};
  Aabb box;
  double largestRadius = 0.0, smallestRadius = spheres[0].radius;
  for (const Sphere& sphere : spheres) {
    box.extend(sphere.center);
    largestRadius = std::max(largestRadius, sphere.radius);
    smallestRadius = std::min(smallestRadius, sphere.radius);
  }
  const double extent = maxAbs(box.extent());
  const double edge =
      std::max((2.0 * largestRadius + margin) * kCellSlack, extent / kMostCellsPerAxis);
  if (!(edge > 0.0)) return {};  // every sphere a point at one place and no margin: no gap < 0

  const std::size_t count = spheres.size();
  std::vector<Cell> cells(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 offset = (spheres[i].center - box.lower) / edge;
    cells[i] = {static_cast<std::int64_t>(offset.x), static_cast<std::int64_t>(offset.y),
                static_cast<std::int64_t>(offset.z)};
  }
  // Sizes more than a factor 2 apart whose cells, as large as the largest sphere, crowd the
  // small ones (one sphere of radius 5 among 64,000 of 0.01 took 4.6 s, against 0.04 s without
  // it): each size gets cells of its own. Where the large cells hold few spheres each (a
  // polydisperse pack) they are faster (the levels' hashed walk cost 7–15 times as much).
  const double smallestEdge = std::max(2.0 * smallestRadius + margin, extent / kMostCellsPerAxis);
  if (edge > 2.0 * smallestEdge && smallestEdge > 0.0 && crowded(cells))
    return levelledPairs(spheres, margin, box, smallestEdge);

  // Packed spheres (a DEM pile or flow): a dense grid of cells where it holds at most a few
  // cells a sphere, each row of three neighbouring cells one run of the sorted spheres.
  Cell last{0, 0, 0};
  for (const Cell& cell : cells)
    last = {std::max(last.x, cell.x), std::max(last.y, cell.y), std::max(last.z, cell.z)};
  const double gridCells = static_cast<double>(last.x + 1) * static_cast<double>(last.y + 1) *
                           static_cast<double>(last.z + 1);
  if (gridCells <= 8.0 * static_cast<double>(count) + 4096.0)
    return pairsOnGrid(spheres, margin, cells, last);
  const std::uint64_t mask = std::bit_ceil(2 * count) - 1;
  const Buckets buckets = byBucket(cells, mask);

  std::vector<std::vector<CandidatePair>> perChunk((count + kSphereGrain - 1) / kSphereGrain);
  parallelFor(0, count, kSphereGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<CandidatePair> found;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t before = found.size();
      const Sphere& one = spheres[i];
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
          for (std::int64_t dz = -1; dz <= 1; ++dz) {
            const Cell neighbour{cells[i].x + dx, cells[i].y + dy, cells[i].z + dz};
            const std::size_t bucket = bucketOf(neighbour, mask);
            for (std::size_t k = buckets.start[bucket]; k < buckets.start[bucket + 1]; ++k) {
              const std::uint32_t j = buckets.members[k];
              // A sphere lies in one cell, so it is met once even when two neighbouring cells
              // share a bucket.
              if (j <= i || !(cells[j] == neighbour)) continue;
              const double reach = one.radius + spheres[j].radius + margin;
              if (distanceSquared(one.center, spheres[j].center) < reach * reach)
                found.push_back({static_cast<std::uint32_t>(i), j});
            }
          }
      std::sort(found.begin() + static_cast<std::ptrdiff_t>(before), found.end(),
                [](const CandidatePair& a, const CandidatePair& b) { return a.second < b.second; });
    }
    perChunk[begin / kSphereGrain] = std::move(found);
  });
  return detail::joined<CandidatePair>(perChunk);
}

}  // namespace delta::dem
