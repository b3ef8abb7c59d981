#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

/// What a `delta dem` run is asked to do, from a config file and the command line.
///
/// The config file is text, one `key = value` a line; `#` starts a comment (to the end of the
/// line), blank lines are skipped, keys are lower case and may appear once each:
///
///     # a small settle run
///     scenario      = settle       # two-particles, settle or hopper
///     particles     = 200          # settle, hopper
///     seed          = 7            # settle, hopper: shapes, orientations, placement
///     restitution   = 0.5          # e in [0, 1]
///     friction      = 0.3          # Coulomb μ ≥ 0
///     offset        = 0.25         # two-particles: sideways shift / sum of radii, in [0, 1)
///     steps         = 2000
///     output_every  = 20           # steps between frames written with --out
///     particle_mesh = rock.off     # a closed mesh (or builtin:…) as every particle's shape;
///                                  # a relative path is relative to the config file
///     particle_radius = 0.008      # its bounding radius (m) after scaling
///     contact_model = volume       # point (default) or volume (dem/contact_model.h)
///
/// Every key is also an option (`output_every` is `--output-every`); an option given on the
/// command line overrides the file. Each value is checked as it is read: an error names the
/// file, the line and the key, or the option.
namespace delta::cli {

/// The settings as given: empty where the scenario's own default applies.
///
/// Threading: a value type.
struct DemSettings {
  std::string scenario;  ///< two-particles, settle or hopper; empty: hopper
  std::optional<std::size_t> particles;
  std::optional<std::uint64_t> seed;
  std::optional<double> restitution;
  std::optional<double> friction;
  std::optional<double> offset;
  std::optional<std::size_t> steps;
  std::optional<std::size_t> outputEvery;
  std::string particleMesh;
  std::optional<double> particleRadius;
  std::string contactModel;  ///< "point" or "volume"; empty: point
  /// Where each setting that was given came from, by key: "run.cfg:3: restitution" or
  /// "--restitution", for messages about combinations.
  std::map<std::string, std::string> origins;
};

/// The most particles a run may ask for (memory: about 10 kB each).
inline constexpr std::size_t kMaxDemParticles = 1'000'000;

/// The scenarios built in.
inline constexpr const char* kDemScenarios[] = {"two-particles", "settle", "hopper"};

/// Whether `name` is a built-in scenario.
bool isDemScenario(const std::string& name);

/// Sets `key` (a config key: "output_every") from `text`, checking the value. `origin` names
/// where it came from for the messages ("run.cfg:3: output_every" or "--output-every").
/// Throws delta::Error for an unknown key or a bad value.
void setDemSetting(DemSettings& settings, const std::string& key, const std::string& text,
                   const std::string& origin);

/// Reads a config file (format above). Throws delta::Error naming the file and the line for an
/// unreadable file, a line that is not `key = value`, an unknown or repeated key, or a bad value.
DemSettings readDemConfig(const std::string& path);

/// `base` with every setting that `overrides` has replaced by it.
DemSettings mergedDemSettings(DemSettings base, const DemSettings& overrides);

/// Checks what no single value shows: options that do not apply to the scenario. Throws
/// delta::Error naming the option or the file and line.
void checkDemCombination(const DemSettings& settings);

}  // namespace delta::cli
