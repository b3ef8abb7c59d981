#include "vertex_join.h"

#include <bit>
#include <limits>

#include "delta/core/error.h"

namespace delta::detail {
namespace {

constexpr std::uint32_t kEmptySlot = std::numeric_limits<std::uint32_t>::max();

/// splitmix64's finaliser: spreads every input bit over the whole word.
constexpr std::uint64_t mix(std::uint64_t h) noexcept {
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

std::uint64_t bits(double coordinate) noexcept {
  return std::bit_cast<std::uint64_t>(coordinate + 0.0);  // -0.0 + 0.0 is +0.0
}

std::uint64_t hashPosition(const Vec3& p) noexcept {
  return mix(mix(mix(bits(p.x)) ^ bits(p.y)) ^ bits(p.z));
}

/// Open addressing with linear probing, kept at most half full: a probe ends after a couple of
/// slots on average. Slots hold indices into the distinct positions.
class PositionTable {
 public:
  explicit PositionTable(std::size_t expected)
      : slots_(std::bit_ceil(2 * expected + 2), kEmptySlot) {}

  /// The index of `p` among `distinct`, adding it there if it is new.
  std::uint32_t find(const Vec3& p, std::vector<Vec3>& distinct) {
    std::size_t slot = slotOf(p, distinct);
    if (slots_[slot] != kEmptySlot) return slots_[slot];
    if (distinct.size() == kEmptySlot) throw Error("more than 2^32 - 1 distinct vertex positions");
    const auto index = static_cast<std::uint32_t>(distinct.size());
    distinct.push_back(p);
    slots_[slot] = index;
    if (2 * distinct.size() > slots_.size()) grow(distinct);
    return index;
  }

 private:
  /// The slot that holds `p`, or the empty slot where it belongs.
  std::size_t slotOf(const Vec3& p, const std::vector<Vec3>& distinct) const noexcept {
    const std::size_t mask = slots_.size() - 1;
    std::size_t slot = static_cast<std::size_t>(hashPosition(p)) & mask;
    while (slots_[slot] != kEmptySlot && !(distinct[slots_[slot]] == p))
      slot = (slot + 1) & mask;
    return slot;
  }

  void grow(const std::vector<Vec3>& distinct) {
    slots_.assign(2 * slots_.size(), kEmptySlot);
    for (std::size_t i = 0; i < distinct.size(); ++i)
      slots_[slotOf(distinct[i], distinct)] = static_cast<std::uint32_t>(i);
  }

  std::vector<std::uint32_t> slots_;
};

}  // namespace

JoinedVertices joinIdenticalVertices(std::span<const Vec3> vertices) {
  JoinedVertices joined;
  joined.newIndex.reserve(vertices.size());
  // Sized for a sixth of the input distinct (a closed triangle soup), grown by doubling.
  PositionTable table(vertices.size() / 6);
  for (const Vec3& p : vertices)
    joined.newIndex.push_back(table.find(p, joined.vertices));
  return joined;
}

}  // namespace delta::detail
