#include "motion_options.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <system_error>

#include "delta/core/error.h"
#include "delta/core/format.h"

#include "commands.h"
#include "mesh_source.h"

namespace delta::cli {

std::vector<double> parseNumbers(const std::string& text, std::size_t count, const char* option) {
  std::vector<double> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    double value = 0.0;
    const char* begin = text.data() + start;
    const char* end = text.data() + comma;
    const auto [stop, status] = std::from_chars(begin, end, value);
    if (status != std::errc() || stop != end || !std::isfinite(value))
      throw Error(std::string(option) + " '" + text + "' must be " + std::to_string(count) +
                  " finite numbers separated by commas");
    values.push_back(value);
    start = comma + 1;
  }
  if (values.size() != count)
    throw Error(std::string(option) + " '" + text + "' must be " + std::to_string(count) +
                " numbers separated by commas");
  return values;
}

std::size_t parseStepCount(const std::string& text, const std::string& origin, std::size_t least) {
  std::size_t value = 0;
  const char* end = text.data() + text.size();
  const auto [stop, status] = std::from_chars(text.data(), end, value);
  if (text.empty() || status != std::errc() || stop != end || value < least || value > kMaxSteps)
    throw Error(origin + " '" + printable(text) + "' must be a whole number from " +
                std::to_string(least) + " to " + std::to_string(kMaxSteps));
  return value;
}

Vec3 parseVector(const std::string& text, const char* option) {
  const std::vector<double> v = parseNumbers(text, 3, option);
  return {v[0], v[1], v[2]};
}

Quaternion parseRotation(const std::string& text, const char* option) {
  const std::vector<double> r = parseNumbers(text, 4, option);
  if (r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0)
    throw Error(std::string(option) + " '" + text + "': the axis AX,AY,AZ must not be zero");
  // Degrees as radians: π/180 first, so that a finite angle stays finite.
  return Quaternion::fromAxisAngle({r[0], r[1], r[2]}, r[3] * (std::numbers::pi / 180.0));
}

void SecondMeshMotion::validate() const {
  if (!rotate.empty()) parseRotation(rotate, "--rotate-b");
  if (!translate.empty()) parseVector(translate, "--translate-b");
}

void SecondMeshMotion::apply(Mesh& b) const {
  if (!rotate.empty()) b.rotate(parseRotation(rotate, "--rotate-b"), b.bounds().center());
  if (!translate.empty()) b.translate(parseVector(translate, "--translate-b"));
}

void addMeshPair(CLI::App& command, std::string& meshA, std::string& meshB,
                 SecondMeshMotion& motion) {
  command.add_option("MESH_A", meshA, meshSourceHelp())->required();
  command.add_option("MESH_B", meshB, "The second mesh (same forms as MESH_A)")->required();
  command.add_option("--translate-b", motion.translate, "Move B by X,Y,Z (after rotating)");
  command.add_option("--rotate-b", motion.rotate,
                     "Turn B about the centre of its box: axis AX,AY,AZ and DEGREES");
}

}  // namespace delta::cli
