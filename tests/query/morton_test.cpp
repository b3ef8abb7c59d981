#include "query/detail/morton.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace delta::detail {
namespace {

/// The order a stable sort by code gives (ties in index order), and the codes in that order.
struct Sorted {
  std::vector<std::uint32_t> order, codes;
};

Sorted byStableSort(const std::vector<std::uint64_t>& keys) {
  std::vector<std::uint64_t> sorted = keys;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](std::uint64_t a, std::uint64_t b) { return a >> 32 < b >> 32; });
  Sorted result;
  for (const std::uint64_t key : sorted) {
    result.order.push_back(static_cast<std::uint32_t>(key));
    result.codes.push_back(static_cast<std::uint32_t>(key >> 32));
  }
  return result;
}

TEST(Morton, SortKeysOrdersByCodeAndThenIndexForEveryCodeWidth) {
  // Widths that take one, two, three and four passes, digits of uneven sizes, few distinct codes
  // (ties) and many, and the sizes where a batch of the grid's survivors stops and starts.
  std::mt19937_64 random(7);
  for (const int codeBits : {1, 3, 9, 10, 11, 18, 21, 29, 30, 32}) {
    for (const std::size_t count : {0, 1, 2, 255, 1000, 4097}) {
      for (const bool fewCodes : {false, true}) {
        const std::uint64_t range =
            fewCodes ? 3 : (codeBits == 32 ? std::uint64_t{1} << 32 : std::uint64_t{1} << codeBits);
        std::vector<std::uint64_t> keys(count);
        for (std::size_t i = 0; i < count; ++i)
          keys[i] = (random() % std::min(range, std::uint64_t{1} << codeBits)) << 32 | i;
        const Sorted expected = byStableSort(keys);
        std::vector<std::uint64_t> work = keys, buffer(count, ~std::uint64_t{0});
        std::vector<std::uint32_t> order(count, 12345), codes(count, 12345);
        sortKeys(work, buffer, codeBits, order, codes);
        ASSERT_EQ(order, expected.order) << codeBits << " bits, " << count << " keys";
        ASSERT_EQ(codes, expected.codes) << codeBits << " bits, " << count << " keys";
        // Without codes, and through the vector call.
        work = keys;
        sortKeys(work, buffer, codeBits, order, {});
        ASSERT_EQ(order, expected.order) << codeBits << " bits, " << count << " keys";
        work = keys;
        ASSERT_EQ(orderOfKeys(work, codeBits), expected.order) << codeBits << " bits";
      }
    }
  }
}

}  // namespace
}  // namespace delta::detail
