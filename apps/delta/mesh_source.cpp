#include "mesh_source.h"

#include <charconv>
#include <string_view>

#include "delta/core/error.h"
#include "delta/mesh/primitives.h"

namespace delta::cli {
namespace {

constexpr std::string_view kPrefix = "builtin:";

template <typename Integer>
Integer parameter(std::string_view text, Integer fallback, const std::string& source) {
  if (text.empty()) return fallback;
  Integer value{};
  const auto [end, status] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (status != std::errc() || end != text.data() + text.size())
    throw Error("mesh '" + source + "': parameter '" + std::string(text) +
                "' is not a non-negative integer");
  return value;
}

Mesh primitive(std::string_view name, std::string_view argument, const std::string& source) {
  if (name == "icosphere") return primitives::icosphere(parameter(argument, 2, source));
  if (name == "cylinder") return primitives::cylinder(1.0, 1.0, parameter(argument, 32, source));
  if (name == "granulate")
    return primitives::granulate(parameter<std::uint64_t>(argument, 1, source));
  if (!argument.empty())
    throw Error("mesh '" + source + "': builtin:" + std::string(name) + " takes no parameter");
  if (name == "box") return primitives::box();
  if (name == "quad") return primitives::quad();
  throw Error("mesh '" + source + "': unknown built-in primitive; " + meshSourceHelp());
}

}  // namespace

io::LoadedMesh loadMeshSource(const std::string& source) {
  if (!std::string_view(source).starts_with(kPrefix)) return io::loadWithStatistics(source);
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
