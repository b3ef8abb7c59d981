// Times the steps of a DEM checkpoint: the same state stepped by two builds (before and after a
// change, binaries alternating) gives a ratio on one state that a benchmark's own preparation
// could not (the builds would settle different piles). Public API only, so that it builds
// against an older Δ as it is.
//
//   build/bench/delta_dem_steps STATE.ckpt [STEPS [REPETITIONS [WARM_UP]]]
//
// Each repetition loads the state, takes WARM_UP steps (default 20: the neighbour list and the
// contact caches filled), then times STEPS steps (default 100); printed: the median wall time a
// step and each repetition's, the phases of the median one (World::statistics, summed), and the
// state's digest after the steps (equal digests, equal states: the builds agree bit for bit).
// Threads: OMP_NUM_THREADS.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "delta/dem/world.h"

namespace {

struct Timing {
  double wall = 0.0;  ///< seconds a step
  double broad = 0.0, detection = 0.0, force = 0.0, integration = 0.0;
  std::string digest;
};

std::size_t count(const char* text, const char* what) {
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (end == text || *end != '\0' || value == 0)
    throw std::runtime_error(std::string(what) + " must be a positive integer, not '" + text + "'");
  return static_cast<std::size_t>(value);
}

Timing timeSteps(const char* path, std::size_t steps, std::size_t warmUp) {
  delta::dem::World world = delta::dem::World::load(path);
  for (std::size_t s = 0; s < warmUp; ++s)
    world.step();
  Timing timing;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t s = 0; s < steps; ++s) {
    world.step();
    const delta::dem::StepStatistics& statistics = world.statistics();
    timing.broad += statistics.broadPhaseSeconds;
    timing.detection += statistics.contactDetectionSeconds;
    timing.force += statistics.forceSeconds;
    timing.integration += statistics.integrationSeconds;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double perStep = 1.0 / static_cast<double>(steps);
  timing.wall = seconds * perStep;
  timing.broad *= perStep;
  timing.detection *= perStep;
  timing.force *= perStep;
  timing.integration *= perStep;
  timing.digest = world.stateDigest();
  return timing;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 2 || argc > 5) {
      std::fprintf(stderr, "usage: %s STATE.ckpt [STEPS [REPETITIONS [WARM_UP]]]\n", argv[0]);
      return 2;
    }
    const std::size_t steps = argc > 2 ? count(argv[2], "STEPS") : 100;
    const std::size_t repetitions = argc > 3 ? count(argv[3], "REPETITIONS") : 3;
    const std::size_t warmUp = argc > 4 ? count(argv[4], "WARM_UP") : 20;
    std::vector<Timing> timings;
    for (std::size_t r = 0; r < repetitions; ++r)
      timings.push_back(timeSteps(argv[1], steps, warmUp));
    std::vector<Timing> sorted = timings;
    std::sort(sorted.begin(), sorted.end(),
              [](const Timing& a, const Timing& b) { return a.wall < b.wall; });
    const Timing& median = sorted[sorted.size() / 2];
    std::printf("%s: %zu steps after %zu, median of %zu: %.2f us a step (", argv[1], steps, warmUp,
                repetitions, 1e6 * median.wall);
    for (std::size_t r = 0; r < timings.size(); ++r)
      std::printf("%s%.2f", r ? " " : "", 1e6 * timings[r].wall);
    std::printf(")\n  broad phase %.2f, contact detection %.2f, forces %.2f, integration %.2f us\n",
                1e6 * median.broad, 1e6 * median.detection, 1e6 * median.force,
                1e6 * median.integration);
    std::printf("  digest %s\n", median.digest.c_str());
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "delta_dem_steps: %s\n", error.what());
    return 1;
  }
}
