#include "point_source.h"

#include <charconv>
#include <random>
#include <string_view>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/io/points.h"

namespace delta::cli {
namespace {

std::uint64_t number(std::string_view text, const std::string& source) {
  std::uint64_t value = 0;
  const auto [end, status] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || status != std::errc() || end != text.data() + text.size())
    throw Error("points '" + source + "': '" + printable(text) + "' is not a non-negative integer");
  return value;
}

}  // namespace

std::vector<Vec3> loadPointSource(const std::string& source, const Aabb& box) {
  constexpr std::string_view kUniform = "builtin:uniform:";
  const std::string_view text = source;
  if (!text.starts_with("builtin:")) return io::loadPoints(source);
  if (!text.starts_with(kUniform))
    throw Error("points '" + source + "': the built-in point set is builtin:uniform:N[:SEED]");
  const std::string_view rest = text.substr(kUniform.size());
  const std::size_t colon = rest.find(':');
  const std::uint64_t count = number(rest.substr(0, colon), source);
  const std::uint64_t seed =
      colon == std::string_view::npos ? 1 : number(rest.substr(colon + 1), source);
  if (count == 0 || count > (std::uint64_t{1} << 32))
    throw Error("points '" + source + "': N must be between 1 and 2^32 (4294967296)");
  // Checked before they are allocated (`delta distance` checks what its output needs itself).
  requireMemory(static_cast<double>(count) * sizeof(Vec3),
                "points '" + source + "': " + std::to_string(count) + " points");
  std::mt19937_64 random(seed);
  const auto unit = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  const Vec3 lower = box.lower - box.extent() * 0.1, size = box.extent() * 1.2;
  std::vector<Vec3> points(count);
  for (Vec3& p : points)
    p = {lower.x + size.x * unit(), lower.y + size.y * unit(), lower.z + size.z * unit()};
  return points;
}

}  // namespace delta::cli
