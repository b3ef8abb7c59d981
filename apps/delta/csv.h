#pragma once

// The rows of the commands' CSV files: numbers in the shortest form that reads back to the same
// double, rows formatted on all threads and written in order.

#include <algorithm>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "delta/core/parallel.h"

namespace delta::cli {

/// Appends `value` in the shortest decimal form that reads back to exactly it (std::to_chars;
/// "0.1", not %.17g's "0.10000000000000001": as exact, shorter, and several times faster to
/// write). "inf", "-inf" and "nan" for the values that are no number.
inline void appendNumber(std::string& text, double value) {
  char digits[32];  // the longest shortest form, "-2.2250738585072014e-308", is 24 characters
  const std::to_chars_result result = std::to_chars(digits, digits + sizeof digits, value);
  text.append(digits, result.ptr);
}

inline void appendNumber(std::string& text, std::uint64_t value) {
  char digits[24];
  const std::to_chars_result result = std::to_chars(digits, digits + sizeof digits, value);
  text.append(digits, result.ptr);
}

/// Rows formatted this many at a time by one thread.
inline constexpr std::size_t kCsvRowsPerChunk = 1024;
/// Chunks formatted before their text is written (some 6 MB of rows in memory at once).
inline constexpr std::size_t kCsvChunksAtOnce = 64;

/// Appends rows 0 … count − 1 to `file` in order: `row(text, i)` appends row i to `text`. The
/// rows are formatted on Δ's threads a chunk each, kCsvChunksAtOnce chunks at a time, and each
/// batch of chunks is written before the next is formatted. `file` has write(std::string_view).
template <typename File, typename Row>
void writeRows(File& file, std::size_t count, const Row& row) {
  std::vector<std::string> chunks(kCsvChunksAtOnce);
  for (std::size_t first = 0; first < count; first += kCsvRowsPerChunk * kCsvChunksAtOnce) {
    const std::size_t last = std::min(count, first + kCsvRowsPerChunk * kCsvChunksAtOnce);
    const std::size_t used = (last - first + kCsvRowsPerChunk - 1) / kCsvRowsPerChunk;
    parallelFor(0, used, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t c = begin; c < end; ++c) {
        std::string& text = chunks[c];
        text.clear();
        const std::size_t from = first + c * kCsvRowsPerChunk;
        for (std::size_t i = from; i < std::min(last, from + kCsvRowsPerChunk); ++i)
          row(text, i);
      }
    });
    for (std::size_t c = 0; c < used; ++c)
      file.write(chunks[c]);
  }
}

}  // namespace delta::cli
