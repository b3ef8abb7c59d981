#include "delta/dem/broad_phase.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"

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
std::size_t bucketOf(const Cell& cell, std::uint64_t mask) noexcept {
  const std::uint64_t hash = (static_cast<std::uint64_t>(cell.x) * 73856093u) ^
                             (static_cast<std::uint64_t>(cell.y) * 19349663u) ^
                             (static_cast<std::uint64_t>(cell.z) * 83492791u);
  return static_cast<std::size_t>(hash & mask);
}

void validate(std::span<const Sphere> spheres, double margin) {
  if (!std::isfinite(margin) || margin < 0.0)
    throw Error("nearbyPairs: margin = " + toString(margin) + " must be finite and non-negative");
  if (spheres.size() >= (std::size_t{1} << 32))
    throw Error("nearbyPairs: " + std::to_string(spheres.size()) +
                " spheres are more than 32-bit ids can name");
  for (std::size_t i = 0; i < spheres.size(); ++i)
    if (!isFinite(spheres[i].center) || !std::isfinite(spheres[i].radius) ||
        spheres[i].radius < 0.0)
      throw Error("nearbyPairs: sphere " + std::to_string(i) + " has centre " +
                  toString(spheres[i].center) + " and radius " + toString(spheres[i].radius) +
                  " (must be finite, radius non-negative)");
}

}  // namespace

std::vector<CandidatePair> nearbyPairs(std::span<const Sphere> spheres, double margin) {
  validate(spheres, margin);
  if (spheres.size() < 2) return {};
  Aabb box;
  double largestRadius = 0.0;
  for (const Sphere& sphere : spheres) {
    box.extend(sphere.center);
    largestRadius = std::max(largestRadius, sphere.radius);
  }
  const double extent = maxAbs(box.extent());
  const double edge = std::max(2.0 * largestRadius + margin, extent / kMostCellsPerAxis);
  if (!(edge > 0.0)) return {};  // every sphere a point at one place and no margin: no gap < 0

  const std::size_t count = spheres.size();
  std::vector<Cell> cells(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 offset = (spheres[i].center - box.lower) / edge;
    cells[i] = {static_cast<std::int64_t>(offset.x), static_cast<std::int64_t>(offset.y),
                static_cast<std::int64_t>(offset.z)};
  }
  // Counting sort of the spheres by bucket; within a bucket they stay in index order.
  const std::uint64_t mask = std::bit_ceil(2 * count) - 1;
  std::vector<std::size_t> bucketStart(mask + 2, 0);
  for (const Cell& cell : cells)
    ++bucketStart[bucketOf(cell, mask) + 1];
  for (std::size_t b = 1; b < bucketStart.size(); ++b)
    bucketStart[b] += bucketStart[b - 1];
  std::vector<std::uint32_t> members(count);
  {
    std::vector<std::size_t> fill(bucketStart.begin(), bucketStart.end() - 1);
    for (std::size_t i = 0; i < count; ++i)
      members[fill[bucketOf(cells[i], mask)]++] = static_cast<std::uint32_t>(i);
  }

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
            for (std::size_t k = bucketStart[bucket]; k < bucketStart[bucket + 1]; ++k) {
              const std::uint32_t j = members[k];
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
  std::vector<CandidatePair> pairs;
  for (const std::vector<CandidatePair>& some : perChunk)
    pairs.insert(pairs.end(), some.begin(), some.end());
  return pairs;
}

}  // namespace delta::dem
