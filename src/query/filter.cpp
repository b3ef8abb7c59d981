#include "delta/query/filter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <unordered_map>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/mesh/coordinate_range.h"

namespace delta::contactdetection {
namespace {

/// Integer cell coordinates of a uniform grid, packed into one key.
struct CellKey {
  std::int64_t i, j, k;
  friend bool operator==(const CellKey&, const CellKey&) = default;
};

struct CellHash {
  std::size_t operator()(const CellKey& c) const noexcept {
    // Large odd multipliers (from a 64-bit multiplicative hash) spread neighbouring cells.
    return static_cast<std::size_t>(static_cast<std::uint64_t>(c.i) * 0x9E3779B97F4A7C15ull ^
                                    static_cast<std::uint64_t>(c.j) * 0xC2B2AE3D27D4EB4Full ^
                                    static_cast<std::uint64_t>(c.k) * 0x165667B19E3779F9ull);
  }
};

/// A grid over the points' box with cells wider than `h` by more than the rounding of the cell
/// computation (so two points closer than h fall in neighbouring cells), and at most 2⁴⁰ cells
/// across, so the integer cell coordinates stay exact whatever the ratio of coordinates to h.
///
/// The rounding: an offset p − lower (at most the box's extent E) and its quotient by the cell
/// each round by half an ulp, together at most ε·E along an axis, so two points' cell
/// coordinates, as lengths, differ from their offsets' difference by at most 2ε·E; and a
/// squared distance below h² as computed may belong to points up to h·(1 + 2ε) apart. A cell
/// of h·(1 + 2⁻³⁰) + 2⁻⁵⁰·E exceeds both together. (With a fixed relative slack alone, 10⁻⁹ of
/// h, points 10⁻¹⁰ apart in a box 2 across fell two cells apart, and both were kept.)
class Grid {
 public:
  Grid(const Aabb& box, double h)
      : origin_(box.lower),
        cell_(std::max(h * (1.0 + 0x1p-30) + maxAbs(box.extent()) * 0x1p-50,
                       maxAbs(box.extent()) * 0x1p-40)) {}

  CellKey cellOf(const Vec3& p) const noexcept {
    return {index(p.x - origin_.x), index(p.y - origin_.y), index(p.z - origin_.z)};
  }

 private:
  std::int64_t index(double offset) const noexcept {
    return static_cast<std::int64_t>(std::floor(offset / cell_));
  }

  Vec3 origin_;
  double cell_;
};

/// filter() of a few contacts (a DEM pair's), on the stack: every kept point is tested, not only
/// those of the neighbouring cells, which holds every point closer than h, so the same points
/// are kept.
std::vector<ContactPoint> filterFew(std::span<const ContactPoint> contacts, double h) {
  constexpr std::size_t kFew = 64;
  std::size_t order[kFew];
  const std::size_t count = contacts.size();
  // Insertion sort by |normal|, equal keys in index order (as the stable sort below).
  for (std::size_t i = 0; i < count; ++i) {
    const double key = lengthSquared(contacts[i].normal);
    std::size_t j = i;
    for (; j > 0 && key < lengthSquared(contacts[order[j - 1]].normal); --j)
      order[j] = order[j - 1];
    order[j] = i;
  }
  bool keep[kFew] = {};
  std::size_t kept[kFew], keptCount = 0;
  const double hSquared = h * h;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t candidate = order[k];
    bool crowded = false;
    for (std::size_t other = 0; other < keptCount && !crowded; ++other)
      crowded = distanceSquared(contacts[kept[other]].x, contacts[candidate].x) < hSquared;
    if (crowded) continue;
    keep[candidate] = true;
    kept[keptCount++] = candidate;
  }
  std::vector<ContactPoint> result;
  result.reserve(keptCount);
  for (std::size_t i = 0; i < count; ++i)
    if (keep[i]) result.push_back(contacts[i]);
  return result;
}

}  // namespace

std::vector<ContactPoint> filter(std::span<const ContactPoint> contacts, double h) {
  if (!std::isfinite(h) || !(h > 0.0))
    throw Error("filter: h = " + toString(h) + " must be finite and positive");
  // h² and every squared distance must be normal doubles where they are compared: below 2⁻⁴⁸¹ h²
  // came out subnormal or 0 (coincident points both kept for h = 1e-170), above 2²⁰⁰ squares of
  // differences could overflow (points 2e155 apart not closer than h = 1e300).
  if (!(h >= 0x1p-481 && h <= kLargestCoordinate))
    throw Error("filter: h = " + toString(h) + " must lie between 2^-481 (" + toString(0x1p-481) +
                ") and the coordinate range " + toString(kLargestCoordinate));
  for (std::size_t i = 0; i < contacts.size(); ++i)
    if (const Vec3& n = contacts[i].normal; !inCoordinateRange(contacts[i].x) ||
                                            !std::isfinite(n.x) || !std::isfinite(n.y) ||
                                            !std::isfinite(n.z))
      throw Error("filter: contact point " + std::to_string(i) + " at " + toString(contacts[i].x) +
                  " with normal " + toString(contacts[i].normal) +
                  " is not finite or lies beyond the coordinate range (" +
                  toString(kLargestCoordinate) + ")");
  if (contacts.size() <= 64) return filterFew(contacts, h);
  std::vector<std::size_t> order(contacts.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return lengthSquared(contacts[a].normal) < lengthSquared(contacts[b].normal);
  });

  Aabb box;
  for (const ContactPoint& contact : contacts)
    box.extend(contact.x);
  const Grid grid(box, h);
  std::unordered_map<CellKey, std::vector<std::size_t>, CellHash> kept;
  std::vector<bool> keep(contacts.size(), false);
  const double hSquared = h * h;
  for (std::size_t candidate : order) {
    const Vec3& x = contacts[candidate].x;
    const CellKey cell = grid.cellOf(x);
    bool crowded = false;
    for (std::int64_t di = -1; di <= 1 && !crowded; ++di)
      for (std::int64_t dj = -1; dj <= 1 && !crowded; ++dj)
        for (std::int64_t dk = -1; dk <= 1 && !crowded; ++dk) {
          const auto found = kept.find({cell.i + di, cell.j + dj, cell.k + dk});
          if (found == kept.end()) continue;
          for (std::size_t other : found->second)
            if (distanceSquared(contacts[other].x, x) < hSquared) {
              crowded = true;
              break;
            }
        }
    if (crowded) continue;
    keep[candidate] = true;
    kept[cell].push_back(candidate);
  }

  std::vector<ContactPoint> result;
  for (std::size_t i = 0; i < contacts.size(); ++i)
    if (keep[i]) result.push_back(contacts[i]);
  return result;
}

}  // namespace delta::contactdetection
