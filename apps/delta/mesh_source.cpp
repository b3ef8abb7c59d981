#include "mesh_source.h"

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/mesh/primitives.h"

namespace delta::cli {
namespace {

constexpr std::string_view kPrefix = "builtin:";

/// The parameter after "builtin:NAME:", `fallback` when there is none: a whole number in decimal
/// digits, at most `limit` (named `what` in the message, with the memory it would need at
/// `bytesEach` a unit).
std::uint64_t parameter(std::string_view text, std::uint64_t fallback, std::uint64_t limit,
                        const char* what, double bytesEach, const std::string& source) {
  if (text.empty()) return fallback;
  std::uint64_t value = 0;
  const auto [end, status] = std::from_chars(text.data(), text.data() + text.size(), value);
  const bool whole = end == text.data() + text.size();
  if (whole &&
      (status == std::errc::result_out_of_range || (status == std::errc() && value > limit)))
    throw Error("mesh '" + source + "': " + what + " " + std::string(text) +
                " is above the limit " + std::to_string(limit) +
                (bytesEach > 0.0 && status == std::errc()
                     ? "; it would need about " +
                           describeBytes(static_cast<double>(value) * bytesEach) + " of memory"
                     : std::string()));
  if (status != std::errc() || end != text.data() + text.size())
    throw Error("mesh '" + source + "': parameter '" + printable(text) +
                "' is not a non-negative integer");
  return value;
}

Mesh primitive(std::string_view name, std::string_view argument, const std::string& source) {
  if (name == "icosphere")
    return primitives::icosphere(static_cast<int>(parameter(
        argument, 2, primitives::kMaxIcosphereSubdivisions, "subdivision level", 0.0, source)));
  if (name == "cylinder")
    return primitives::cylinder(
        1.0, 1.0,
        static_cast<int>(parameter(argument, 32, primitives::kMaxCylinderSegments, "segments",
                                   primitives::kCylinderBytesPerSegment, source)));
  if (name == "granulate")
    return primitives::granulate(parameter(argument, 1, UINT64_MAX, "seed", 0.0, source));
  if (!argument.empty())
    throw Error("mesh '" + source + "': builtin:" + std::string(name) + " takes no parameter");
  if (name == "box") return primitives::box();
  if (name == "quad") return primitives::quad();
  throw Error("mesh '" + source + "': unknown built-in primitive; " + meshSourceHelp());
}

}  // namespace

io::LoadedMesh loadMeshSource(const std::string& source) {
  if (!std::string_view(source).starts_with(kPrefix)) {
    io::LoadedMesh loaded = io::loadWithStatistics(source);
    if (loaded.statistics.precision == io::CoordinatePrecision::single)
      std::fprintf(stderr,
                   "note: '%s' was read by assimp, which rounds coordinates to single precision "
                   "(Δ reads OFF, PLY, OBJ and STL exactly)\n",
                   source.c_str());
    return loaded;
  }
  const std::string_view spec = std::string_view(source).substr(kPrefix.size());
  const std::size_t colon = spec.find(':');
  const std::string_view name = spec.substr(0, colon);
  const std::string_view argument = colon == std::string_view::npos ? "" : spec.substr(colon + 1);
  Mesh mesh = primitive(name, argument, source);
  io::LoadStatistics statistics;
  statistics.meshes = 1;
  statistics.sourceVertices = mesh.vertexCount();
  return {std::move(mesh), statistics};
}

const char* meshSourceHelp() {
  return "a mesh file (any format assimp reads) or a built-in primitive: "
         "builtin:icosphere[:LEVEL], "
         "builtin:box, builtin:cylinder[:SEGMENTS], builtin:quad, builtin:granulate[:SEED]";
}

}  // namespace delta::cli
