#include "morton.h"

#include <algorithm>
#include <cassert>

#include "delta/core/parallel.h"

namespace delta::detail {
namespace {

/// The 10 low bits of `x` spread to every third bit of a 30-bit Morton code.
std::uint64_t spreadBits(std::uint64_t x) noexcept {
  x &= 0x3ff;
  x = (x | x << 16) & 0x30000ff;
  x = (x | x << 8) & 0x300f00f;
  x = (x | x << 4) & 0x30c30c3;
  x = (x | x << 2) & 0x9249249;
  return x;
}

}  // namespace

std::uint64_t mortonCode(const Vec3& point, const Aabb& box) noexcept {
  constexpr double kCells = 1023.0;  // 1024 cells an axis: finer buys no locality
  std::uint64_t code = 0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double extent = box.upper[axis] - box.lower[axis];
    double unit = extent > 0.0 ? (point[axis] - box.lower[axis]) / extent : 0.0;
    if (!(unit > 0.0)) unit = 0.0;  // NaN where coordinates near overflow made extent infinite
    const auto cell = static_cast<std::uint64_t>(std::min(unit, 1.0) * kCells);
    code |= spreadBits(cell) << axis;
  }
  return code;
}

std::uint64_t mortonOfCell(std::uint32_t x, std::uint32_t y, std::uint32_t z) noexcept {
  return spreadBits(x) | spreadBits(y) << 1 | spreadBits(z) << 2;
}

std::vector<std::uint32_t> orderOfKeys(std::vector<std::uint64_t>& keys, int codeBits) {
  std::vector<std::uint64_t> buffer(keys.size());
  std::vector<std::uint32_t> order(keys.size());
  sortKeys(keys, buffer, codeBits, order, {});
  return order;
}

void sortKeys(std::span<std::uint64_t> keys, std::span<std::uint64_t> buffer, int codeBits,
              std::span<std::uint32_t> order, std::span<std::uint32_t> codes) {
  // Passes of a radix sort over the code (bits 32 and up), least significant digit first:
  // stable, so equal codes keep their index order. The last pass writes the order and the codes
  // instead of the keys.
  assert(codeBits > 0 && codeBits <= 32);
  assert(buffer.size() == keys.size() && order.size() == keys.size());
  constexpr int kMostDigitBits = 10;
  const int passes = (codeBits + kMostDigitBits - 1) / kMostDigitBits;
  const int digitBits = (codeBits + passes - 1) / passes;
  const std::uint64_t mask = (std::uint64_t{1} << digitBits) - 1;
  std::span<std::uint64_t> from = keys, to = buffer;
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = 32 + pass * digitBits;
    std::size_t start[(std::size_t{1} << kMostDigitBits) + 1] = {};
    for (const std::uint64_t key : from)
      ++start[(key >> shift & mask) + 1];
    for (std::uint64_t d = 0; d < mask; ++d)
      start[d + 1] += start[d];
    if (pass + 1 < passes) {
      for (const std::uint64_t key : from)
        to[start[key >> shift & mask]++] = key;
      std::swap(from, to);
      continue;
    }
    for (const std::uint64_t key : from) {
      const std::size_t at = start[key >> shift & mask]++;
      order[at] = static_cast<std::uint32_t>(key);
      if (!codes.empty()) codes[at] = static_cast<std::uint32_t>(key >> 32);
    }
  }
}

std::vector<std::uint32_t> mortonOrder(std::size_t count, Vec3 (*pointAt)(const void*, std::size_t),
                                       const void* context) {
  // The box and the keys in parallel blocks (the radix sort after them is a third of the time).
  constexpr std::size_t kBlock = std::size_t{1} << 14;
  const std::size_t blocks = (count + kBlock - 1) / kBlock;
  std::vector<Aabb> blockBoxes(blocks);
  parallelFor(0, blocks, 1, [&](std::size_t firstBlock, std::size_t endBlock) {
    for (std::size_t block = firstBlock; block < endBlock; ++block)
      for (std::size_t i = block * kBlock; i < std::min(count, (block + 1) * kBlock); ++i)
        blockBoxes[block].extend(pointAt(context, i));
  });
  Aabb box;
  for (const Aabb& blockBox : blockBoxes)
    box.extend(blockBox);
  std::vector<std::uint64_t> keys(count);
  parallelFor(0, blocks, 1, [&](std::size_t firstBlock, std::size_t endBlock) {
    for (std::size_t i = firstBlock * kBlock; i < std::min(count, endBlock * kBlock); ++i)
      keys[i] = mortonCode(pointAt(context, i), box) << 32 | i;
  });
  return orderOfKeys(keys);
}

}  // namespace delta::detail
