// A DEM checkpoint's header made to match its payload (size and CRC-32), as a file made by hand
// or by a program that is not Δ would have it: for the checkpoint fuzzer, so that it reaches the
// payload's parser, and for the tests that forge checkpoints to see what the reader refuses.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "delta/dem/checkpoint.h"

namespace delta::fuzz {

/// The header's size: "DELTADEM", u32 version, u64 payload bytes, u32 CRC-32 of the payload.
inline constexpr std::size_t kCheckpointHeaderBytes = 24;

/// The CRC-32 of `bytes` (zlib's polynomial, as the checkpoint's).
inline std::uint32_t crc32Of(std::string_view bytes) noexcept {
  std::uint32_t crc = 0xffffffffu;
  for (const char c : bytes) {
    crc ^= static_cast<unsigned char>(c);
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

/// `value`'s `width` low bytes, little-endian, over `bytes` from `at`.
inline void putLittleEndian(std::string& bytes, std::size_t at, std::uint64_t value, int width) {
  for (int b = 0; b < width; ++b)
    bytes[at + static_cast<std::size_t>(b)] = static_cast<char>((value >> (8 * b)) & 0xffu);
}

/// `bytes` with the header's payload size and CRC-32 made to match the bytes after it (its
/// version kept); where `bytes` do not start with a header, they are the payload of a header of
/// the current version made for them.
inline std::string withMatchingHeader(std::string_view bytes) {
  constexpr std::string_view kMagic = "DELTADEM";
  std::string file;
  if (bytes.size() >= kCheckpointHeaderBytes && bytes.substr(0, kMagic.size()) == kMagic) {
    file = bytes;
  } else {
    file = std::string(kMagic) + std::string(kCheckpointHeaderBytes - kMagic.size(), '\0');
    putLittleEndian(file, 8, dem::kCheckpointVersion, 4);
    file += bytes;
  }
  const std::string_view payload = std::string_view(file).substr(kCheckpointHeaderBytes);
  putLittleEndian(file, 12, payload.size(), 8);
  putLittleEndian(file, 20, crc32Of(payload), 4);
  return file;
}

}  // namespace delta::fuzz
