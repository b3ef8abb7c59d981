#include "dem_settings.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string_view>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/dem/contact_model.h"
#include "delta/io/regular_file.h"

#include "motion_options.h"

namespace delta::cli {
namespace {

/// The keys a config file may set, in the order `readDemConfig` lists them in messages.
constexpr const char* kKeys[] = {"scenario",      "particles",       "seed",         "restitution",
                                 "friction",      "offset",          "steps",        "output_every",
                                 "particle_mesh", "particle_radius", "contact_model"};

std::string_view trimmed(std::string_view text) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!text.empty() && space(text.front()))
    text.remove_prefix(1);
  while (!text.empty() && space(text.back()))
    text.remove_suffix(1);
  return text;
}

/// A whole number in [low, high], written in decimal digits only (no sign: "-1" would wrap).
std::uint64_t wholeNumber(const std::string& text, const std::string& origin, std::uint64_t low,
                          std::uint64_t high) {
  const std::string range = high == UINT64_MAX
                                ? "at least " + std::to_string(low)
                                : "from " + std::to_string(low) + " to " + std::to_string(high);
  std::uint64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [stop, status] = std::from_chars(text.data(), end, value);
  if (text.empty() || status == std::errc::invalid_argument || stop != end)
    throw Error(origin + " '" + printable(text) + "' must be a whole number, " + range);
  if (status == std::errc::result_out_of_range || value < low || value > high)
    throw Error(origin + " '" + printable(text) + "' is out of range: must be " + range);
  return value;
}

/// A finite real number.
double realNumber(const std::string& text, const std::string& origin) {
  double value = 0.0;
  const char* begin = text.data() + (text.starts_with('+') ? 1 : 0);
  const char* end = text.data() + text.size();
  const auto [stop, status] = std::from_chars(begin, end, value);
  if (text.empty() || status != std::errc() || stop != end || !std::isfinite(value))
    throw Error(origin + " '" + printable(text) + "' must be a finite number");
  return value;
}

}  // namespace

bool isDemScenario(const std::string& name) {
  return std::find(std::begin(kDemScenarios), std::end(kDemScenarios), name) !=
         std::end(kDemScenarios);
}

void setDemSetting(DemSettings& settings, const std::string& key, const std::string& text,
                   const std::string& origin) {
  if (key == "scenario") {
    if (!isDemScenario(text))
      throw Error(origin + " '" + printable(text) +
                  "' is not a scenario (two-particles, settle, hopper)");
    settings.scenario = text;
  } else if (key == "particles") {
    settings.particles = wholeNumber(text, origin, 1, kMaxDemParticles);
  } else if (key == "seed") {
    settings.seed = wholeNumber(text, origin, 0, UINT64_MAX);
  } else if (key == "restitution") {
    const double e = realNumber(text, origin);
    if (e < 0.0 || e > 1.0) throw Error(origin + " '" + printable(text) + "' must lie in [0, 1]");
    settings.restitution = e;
  } else if (key == "friction") {
    const double mu = realNumber(text, origin);
    if (mu < 0.0) throw Error(origin + " '" + printable(text) + "' must not be negative");
    settings.friction = mu;
  } else if (key == "offset") {
    const double offset = realNumber(text, origin);
    if (offset < 0.0 || offset >= 1.0)
      throw Error(origin + " '" + printable(text) +
                  "' must lie in [0, 1) (a fraction of the sum of radii)");
    settings.offset = offset;
  } else if (key == "steps") {
    settings.steps = parseStepCount(text, origin, 1);
  } else if (key == "output_every") {
    settings.outputEvery = wholeNumber(text, origin, 1, UINT64_MAX);
  } else if (key == "particle_mesh") {
    if (text.empty()) throw Error(origin + " must name a mesh file or builtin:");
    settings.particleMesh = text;
  } else if (key == "contact_model") {
    if (!dem::parseContactModel(text))
      throw Error(origin + " '" + printable(text) + "' is neither point nor volume");
    settings.contactModel = text;
  } else if (key == "particle_radius") {
    const double radius = realNumber(text, origin);
    if (!(radius > 0.0)) throw Error(origin + " '" + printable(text) + "' must be positive");
    settings.particleRadius = radius;
  } else {
    std::string known;
    for (const char* name : kKeys)
      known += (known.empty() ? "" : ", ") + std::string(name);
    throw Error(origin + ": unknown key (keys: " + known + ")");
  }
  settings.origins[key] = origin;
}

DemSettings readDemConfig(const std::string& path) {
  if (std::filesystem::is_directory(path))
    throw Error("config '" + path + "' is a folder, not a file");
  // A config sets a dozen keys: 1 MiB is far more than one needs, and bounds what a wrong path
  // (a FIFO or /dev/zero are refused as not regular files) can make Δ read.
  constexpr std::uintmax_t kMaxConfigBytes = std::uintmax_t{1} << 20;
  std::string contents;
  try {
    contents = io::readSmallRegularFile(path, kMaxConfigBytes, "a DEM config");
  } catch (const Error& error) {
    throw Error("cannot read config '" + path + "': " + error.what());
  }
  // A UTF-8 byte-order mark (some editors write one) is not part of the first key.
  if (contents.starts_with("\xEF\xBB\xBF")) contents.erase(0, 3);
  std::istringstream file(contents);
  DemSettings settings;
  std::string line;
  for (std::size_t number = 1; std::getline(file, line); ++number) {
    const std::string where = path + ":" + std::to_string(number);
    std::string_view text = line;
    text = trimmed(text.substr(0, text.find('#')));
    if (text.empty()) continue;
    const std::size_t equals = text.find('=');
    if (equals == std::string_view::npos)
      throw Error(where + ": '" + printable(text) + "' is not 'key = value'");
    const std::string key(trimmed(text.substr(0, equals)));
    const std::string value(trimmed(text.substr(equals + 1)));
    if (key.empty()) throw Error(where + ": no key before '='");
    // The key as a message may quote it (a garbled file's bytes are not written raw).
    const std::string named = where + ": " + printable(key);
    if (settings.origins.contains(key))
      throw Error(named + " set again (first at " + settings.origins[key] + ")");
    if (value.empty()) throw Error(named + " has no value");
    setDemSetting(settings, key, value, named);
  }
  if (file.bad()) throw Error("reading config '" + path + "' failed");
  // A mesh named relative to the config file is found wherever the command runs.
  if (!settings.particleMesh.empty() && !settings.particleMesh.starts_with("builtin:") &&
      std::filesystem::path(settings.particleMesh).is_relative())
    settings.particleMesh =
        (std::filesystem::path(path).parent_path() / settings.particleMesh).string();
  return settings;
}

DemSettings mergedDemSettings(DemSettings base, const DemSettings& overrides) {
  if (!overrides.scenario.empty()) base.scenario = overrides.scenario;
  if (overrides.particles) base.particles = overrides.particles;
  if (overrides.seed) base.seed = overrides.seed;
  if (overrides.restitution) base.restitution = overrides.restitution;
  if (overrides.friction) base.friction = overrides.friction;
  if (overrides.offset) base.offset = overrides.offset;
  if (overrides.steps) base.steps = overrides.steps;
  if (overrides.outputEvery) base.outputEvery = overrides.outputEvery;
  if (!overrides.particleMesh.empty()) base.particleMesh = overrides.particleMesh;
  if (overrides.particleRadius) base.particleRadius = overrides.particleRadius;
  if (!overrides.contactModel.empty()) base.contactModel = overrides.contactModel;
  for (const auto& [key, origin] : overrides.origins)
    base.origins[key] = origin;
  return base;
}

void checkDemCombination(const DemSettings& settings) {
  const std::string scenario = settings.scenario.empty() ? "hopper" : settings.scenario;
  const auto reject = [&](const char* key, const char* scenarios) {
    const auto found = settings.origins.find(key);
    if (found != settings.origins.end())
      throw Error(found->second + " applies to " + scenarios + " only, not to " + scenario);
  };
  if (scenario == "two-particles") {
    reject("particles", "settle and hopper");
    reject("seed", "settle and hopper");
  } else {
    reject("offset", "two-particles");
  }
  if (settings.particleRadius && settings.particleMesh.empty())
    throw Error(settings.origins.at("particle_radius") + " needs particle_mesh (--particle-mesh)");
}

}  // namespace delta::cli
