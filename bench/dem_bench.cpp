// DEM stepping: the hopper scenario (granulates of 80 triangles flowing through a funnel onto a
// floor, dem/scenarios.h) with 1000 and 10,000 particles, on 1, 2, … OpenMP threads side by side.
//   build/bench/delta_bench_dem --benchmark_filter='particles:1000/'
//   build/bench/delta_bench_dem --benchmark_filter='particles:10000/'
//   build/bench/delta_bench_dem --benchmark_filter='spheres:1'   (the same hopper with spheres)
//
// Each process builds each world once and brings it into the funnel before anything is timed.
// First the lattice falls freely with a time step kFreeFallStride times the scenario's, up to the
// last step that finds no contact: velocity Verlet is exact for a body in free fall that does not
// turn (the particles start at rest and nothing turns them before they touch), so this reaches
// the state the scenario's own steps would, 25 times faster. Then it takes steps at the
// scenario's time step until the flow is under way (kContactsPerParticle contact points a step
// per particle) or max_settling_steps: with 1000 particles that is the flow through the funnel,
// about 15,000 steps after the first contact (4–5 minutes on one core, once per process); with
// 10,000 it stops after 12,000 steps, the lowest layers entering the funnel and the first
// particles touching (2–3 minutes; the flow itself would take hours to reach).
// DELTA_BENCH_DEM_SETTLING_STEPS=N overrides max_settling_steps. Every benchmark then times steps
// on its own copy of that world, so each thread count times the same steps from the same state.
// One iteration is one World::step(); the iteration counts are fixed for the same reason.
// DELTA_BENCH_DEM_STATES=DIR keeps each world brought into the funnel there as a checkpoint
// (dem/checkpoint.h), and starts from it when it is there: later runs skip the minutes of
// settling and time the very same state (delete the files for a state reached by this build).
//
// volume = 1: the hopper with the volume contact law (contact_model = volume: the funnel as 48
// closed convex pieces, the floor a box), brought into its own flow the same way; the issue-24
// target is its step time at most 1.5 times the point law's.
//
// Counters: steps_per_s; contacts_per_step (contact points after filter(h)), contact_pairs_per_step
// and obstacle_pairs_per_step (particle–obstacle pairs the broad phase passed to the narrow
// phase); share_contact_detection, the part of the step time spent in contacts() and filter(h);
// and, for the state timed, its simulated time, the steps that led there, and how many particles
// are below the funnel's top.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "delta/delta.h"

#include "hopper_free_fall.h"
#include "omp_threads.h"

namespace {

namespace dem = delta::dem;
using delta::bench::OmpThreads;
using delta::bench::threadCounts;

/// Free fall is taken in steps this many times the scenario's.
constexpr double kFreeFallStride = 25.0;
/// After the first contact, steps at the scenario's time step until this many contact points a
/// step per particle (the flow is under way), or max_settling_steps.
constexpr double kContactsPerParticle = 0.5;

/// A whole number from the environment, or `fallback`.
std::size_t fromEnvironment(const char* name, std::size_t fallback) {
  const char* text = std::getenv(name);
  return text && *text ? static_cast<std::size_t>(std::strtoull(text, nullptr, 10)) : fallback;
}

/// A hopper world brought into the funnel, and how.
struct FunnelWorld {
  dem::World world;
  std::size_t freeFallSteps = 0;
  std::size_t settlingSteps = 0;
  double funnelTop = 0.0;  ///< the highest vertex of the funnel
};

/// The hopper with `count` particles brought into the funnel once per process (see the top).
const FunnelWorld& funnelWorld(std::size_t count, dem::ParticleKind kind, dem::ContactModel model,
                               std::size_t maxSettlingSteps) {
  using Key = std::tuple<std::size_t, dem::ParticleKind, dem::ContactModel>;
  static std::map<Key, FunnelWorld> cache;
  const auto found = cache.find({count, kind, model});
  if (found != cache.end()) return found->second;
  const std::size_t maxSteps = fromEnvironment("DELTA_BENCH_DEM_SETTLING_STEPS", maxSettlingSteps);
  // A kept state: its file names what made it; its note, the steps that led there.
  std::filesystem::path kept;
  if (const char* states = std::getenv("DELTA_BENCH_DEM_STATES"); states && *states)
    kept = std::filesystem::path(states) /
           ("hopper-" + std::to_string(count) +
            (kind == dem::ParticleKind::Sphere ? "-spheres" : "-granulates") +
            (model == dem::ContactModel::volume ? "-volume" : "-point") + "-" +
            std::to_string(maxSteps) + ".ckpt");
  if (!kept.empty() && std::filesystem::exists(kept)) {
    dem::Checkpoint checkpoint = dem::loadCheckpoint(kept);
    FunnelWorld funnel{std::move(checkpoint.world), 0, 0, 0.0};
    std::sscanf(checkpoint.note.c_str(), "%zu %zu", &funnel.freeFallSteps, &funnel.settlingSteps);
    for (std::size_t o = 0; o + 1 < funnel.world.obstacles().size(); ++o)
      funnel.funnelTop =
          std::max(funnel.funnelTop, funnel.world.obstacles()[o].mesh.bounds().upper.z);
    std::fprintf(stderr, "hopper(%zu): the state kept in %s\n", count, kept.c_str());
    return cache.emplace(Key{count, kind, model}, std::move(funnel)).first->second;
  }
  dem::Scenario scenario = dem::hopper(count, 1, kind, model);
  FunnelWorld funnel{std::move(scenario.world), 0, 0, 0.0};
  funnel.freeFallSteps = delta::bench::fallFreely(funnel.world, kFreeFallStride);
  const double target = kContactsPerParticle * static_cast<double>(count);
  while (funnel.settlingSteps < maxSteps &&
         static_cast<double>(funnel.world.statistics().contactPoints) < target) {
    funnel.world.step();
    if (++funnel.settlingSteps % 500 == 0) {
      const dem::StepStatistics& statistics = funnel.world.statistics();
      std::fprintf(stderr,
                   "hopper(%zu) into the funnel: t = %.4f s, %zu contact points, %zu + %zu pairs "
                   "tested, step %.3g s (contact detection %.3g s)\n",
                   count, funnel.world.time(), statistics.contactPoints,
                   statistics.particlePairsTested, statistics.obstaclePairsTested,
                   statistics.totalSeconds, statistics.contactDetectionSeconds);
    }
  }
  // The funnel's top: the highest vertex of its obstacles (all but the floor, the last).
  for (std::size_t o = 0; o + 1 < funnel.world.obstacles().size(); ++o)
    funnel.funnelTop =
        std::max(funnel.funnelTop, funnel.world.obstacles()[o].mesh.bounds().upper.z);
  if (!kept.empty())
    dem::saveCheckpoint(
        kept, funnel.world,
        std::to_string(funnel.freeFallSteps) + " " + std::to_string(funnel.settlingSteps));
  return cache.emplace(Key{count, kind, model}, std::move(funnel)).first->second;
}

void Hopper(benchmark::State& state) {
  const auto count = static_cast<std::size_t>(state.range(0));
  const auto kind = state.range(3) ? dem::ParticleKind::Sphere : dem::ParticleKind::Mesh;
  const auto model = state.range(4) ? dem::ContactModel::volume : dem::ContactModel::point;
  const FunnelWorld& funnel =
      funnelWorld(count, kind, model, static_cast<std::size_t>(state.range(2)));
  // (built before the threads are set)
  const OmpThreads threads(static_cast<int>(state.range(1)));
  dem::World world = funnel.world;
  const double startTime = world.time();
  double contacts = 0.0, contactPairs = 0.0, obstaclePairs = 0.0;
  double stepSeconds = 0.0, detectionSeconds = 0.0;
  for (auto _ : state) {
    world.step();
    const dem::StepStatistics& statistics = world.statistics();
    contacts += static_cast<double>(statistics.contactPoints);
    contactPairs += static_cast<double>(statistics.pairsInContact);
    obstaclePairs += static_cast<double>(statistics.obstaclePairsTested);
    stepSeconds += statistics.totalSeconds;
    detectionSeconds += statistics.contactDetectionSeconds;
  }
  std::size_t inFunnel = 0, triangles = 0;
  for (const dem::Particle& particle : funnel.world.particles()) {
    inFunnel += particle.position.z < funnel.funnelTop;
    if (!funnel.world.shapes()[particle.shape].isSphere())
      triangles += funnel.world.shapes()[particle.shape].mesh().triangleCount();
  }
  const auto steps = static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations());
  state.counters["steps_per_s"] = benchmark::Counter(steps, benchmark::Counter::kIsRate);
  state.counters["contacts_per_step"] = contacts / steps;
  state.counters["contact_pairs_per_step"] = contactPairs / steps;
  state.counters["obstacle_pairs_per_step"] = obstaclePairs / steps;
  state.counters["share_contact_detection"] = detectionSeconds / stepSeconds;
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["in_funnel"] = static_cast<double>(inFunnel);
  state.counters["start_time_s"] = startTime;
  state.counters["time_step_s"] = world.parameters().timeStep;
  state.counters["free_fall_steps"] = static_cast<double>(funnel.freeFallSteps);
  state.counters["settling_steps"] = static_cast<double>(funnel.settlingSteps);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("delta_version", delta::version());
  benchmark::AddCustomContext("delta_git_commit", delta::gitCommit());
  benchmark::AddCustomContext("omp_num_procs", std::to_string(omp_get_num_procs()));
  const std::vector<std::int64_t> threads = threadCounts();
  // A fixed number of steps, so every thread count times the same steps (see the top).
  // spheres = 1: the same hopper with spherical particles of the granulates' mean volume
  // (the seed's triangles-against-spheres cost ratio); their larger time step reaches the same
  // flow in fewer steps.
  struct HopperCase {
    std::int64_t particles, maxSettlingSteps, iterations, spheres, volume;
  };
  for (const HopperCase& hopper :
       {HopperCase{1000, 20000, 100, 0, 0}, HopperCase{1000, 20000, 100, 0, 1},
        HopperCase{10000, 12000, 50, 0, 0}, HopperCase{1000, 40000, 400, 1, 0}})
    benchmark::RegisterBenchmark("Hopper", Hopper)
        ->ArgsProduct({{hopper.particles},
                       threads,
                       {hopper.maxSettlingSteps},
                       {hopper.spheres},
                       {hopper.volume}})
        ->ArgNames({"particles", "omp_threads", "max_settling_steps", "spheres", "volume"})
        ->Iterations(hopper.iterations)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
