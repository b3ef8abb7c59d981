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
// Settle: the settle scenario (granulates dropped into an open box) with 100 and 1000
// particles, at the end of the scenario's own run (the pile at rest, where a settle spends most
// of its steps), with each law; brought there once (free fall in long steps, then the
// scenario's steps: about a minute for 100, a quarter of an hour for 1000 on one core) and kept
// like the hopper's with DELTA_BENCH_DEM_STATES.
//   build/bench/delta_bench_dem --benchmark_filter='Settle/particles:100/'
//
// Counters: steps_per_s, particle_steps_per_s; contacts_per_step (contact points after
// filter(h); the volume law: overlap regions), raw_contacts_per_step (triangle pairs within 2ε;
// the volume law: intersection segments), contact_pairs_per_step
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
#include <limits>
#include <map>
#include <string>
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

/// A world brought to the state a benchmark times, and the steps that led there.
struct PreparedWorld {
  dem::World world;
  std::size_t freeFallSteps = 0;
  std::size_t settlingSteps = 0;
};

/// The world named `name`, made by `make` (which returns a PreparedWorld) once per process, or
/// read from DELTA_BENCH_DEM_STATES/`name`.ckpt when it is there (and kept there when it is
/// made).
template <class Make>
const PreparedWorld& preparedWorld(const std::string& name, const Make& make) {
  static std::map<std::string, PreparedWorld> cache;
  const auto found = cache.find(name);
  if (found != cache.end()) return found->second;
  std::filesystem::path kept;
  if (const char* states = std::getenv("DELTA_BENCH_DEM_STATES"); states && *states)
    kept = std::filesystem::path(states) / (name + ".ckpt");
  if (!kept.empty() && std::filesystem::exists(kept)) {
    dem::Checkpoint checkpoint = dem::loadCheckpoint(kept);
    PreparedWorld prepared{std::move(checkpoint.world), 0, 0};
    std::sscanf(checkpoint.note.c_str(), "%zu %zu", &prepared.freeFallSteps,
                &prepared.settlingSteps);
    std::fprintf(stderr, "%s: the state kept in %s\n", name.c_str(), kept.c_str());
    return cache.emplace(name, std::move(prepared)).first->second;
  }
  PreparedWorld prepared = make();
  if (!kept.empty())
    dem::saveCheckpoint(
        kept, prepared.world,
        std::to_string(prepared.freeFallSteps) + " " + std::to_string(prepared.settlingSteps));
  return cache.emplace(name, std::move(prepared)).first->second;
}

/// Progress of a world being prepared, every 500 steps, on stderr.
void reportPreparing(const std::string& name, const PreparedWorld& prepared) {
  if (prepared.settlingSteps % 500 != 0) return;
  const dem::StepStatistics& statistics = prepared.world.statistics();
  std::fprintf(stderr,
               "%s: step %zu, t = %.4f s, %zu contact points, %zu + %zu pairs tested, step %.3g s "
               "(contact detection %.3g s)\n",
               name.c_str(), prepared.settlingSteps, prepared.world.time(),
               statistics.contactPoints, statistics.particlePairsTested,
               statistics.obstaclePairsTested, statistics.totalSeconds,
               statistics.contactDetectionSeconds);
}

std::string caseName(const char* scenario, std::size_t count, dem::ParticleKind kind,
                     dem::ContactModel model) {
  return std::string(scenario) + "-" + std::to_string(count) +
         (kind == dem::ParticleKind::Sphere ? "-spheres" : "-granulates") +
         (model == dem::ContactModel::volume ? "-volume" : "-point");
}

/// The hopper with `count` particles brought into the funnel (see the top).
const PreparedWorld& funnelWorld(std::size_t count, dem::ParticleKind kind, dem::ContactModel model,
                                 std::size_t maxSettlingSteps) {
  const std::size_t maxSteps = fromEnvironment("DELTA_BENCH_DEM_SETTLING_STEPS", maxSettlingSteps);
  const std::string name = caseName("hopper", count, kind, model) + "-" + std::to_string(maxSteps);
  return preparedWorld(name, [&] {
    PreparedWorld prepared{std::move(dem::hopper(count, 1, kind, model).world), 0, 0};
    prepared.freeFallSteps = delta::bench::fallFreely(prepared.world, kFreeFallStride);
    const double target = kContactsPerParticle * static_cast<double>(count);
    while (prepared.settlingSteps < maxSteps &&
           static_cast<double>(prepared.world.statistics().contactPoints) < target) {
      prepared.world.step();
      ++prepared.settlingSteps;
      reportPreparing(name, prepared);
    }
    return prepared;
  });
}

/// The settle scenario with `count` particles at the end of its own run: the pile at rest on
/// the floor of the box (free fall in long steps first, as the hopper's).
const PreparedWorld& settledWorld(std::size_t count, dem::ContactModel model) {
  const std::string name = caseName("settle", count, dem::ParticleKind::Mesh, model);
  return preparedWorld(name, [&] {
    dem::Scenario scenario = dem::settle(count, 1, dem::ParticleKind::Mesh, model);
    PreparedWorld prepared{std::move(scenario.world), 0, 0};
    const double end = static_cast<double>(scenario.steps) * prepared.world.parameters().timeStep;
    prepared.freeFallSteps = delta::bench::fallFreely(prepared.world, kFreeFallStride);
    while (prepared.world.time() < end) {
      prepared.world.step();
      ++prepared.settlingSteps;
      reportPreparing(name, prepared);
    }
    return prepared;
  });
}

/// The highest vertex of the world's obstacles but the last (the floor): the funnel's top.
double funnelTop(const dem::World& world) {
  double top = -std::numeric_limits<double>::infinity();
  for (std::size_t o = 0; o + 1 < world.obstacles().size(); ++o)
    top = std::max(top, world.obstacles()[o].mesh.bounds().upper.z);
  return top;
}

/// Times state.iterations() steps of a copy of `prepared` and reports the counters.
void timeSteps(benchmark::State& state, const PreparedWorld& prepared) {
  dem::World world = prepared.world;
  const double startTime = world.time();
  double contacts = 0.0, contactPairs = 0.0, obstaclePairs = 0.0, rawPoints = 0.0;
  double stepSeconds = 0.0, detectionSeconds = 0.0;
  for (auto _ : state) {
    world.step();
    const dem::StepStatistics& statistics = world.statistics();
    contacts += static_cast<double>(statistics.contactPoints);
    rawPoints += static_cast<double>(statistics.rawContactPoints);
    contactPairs += static_cast<double>(statistics.pairsInContact);
    obstaclePairs += static_cast<double>(statistics.obstaclePairsTested);
    stepSeconds += statistics.totalSeconds;
    detectionSeconds += statistics.contactDetectionSeconds;
  }
  std::size_t triangles = 0;
  for (const dem::Particle& particle : world.particles())
    if (!world.shapes()[particle.shape].isSphere())
      triangles += world.shapes()[particle.shape].mesh().triangleCount();
  const auto steps = static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations());
  state.counters["steps_per_s"] = benchmark::Counter(steps, benchmark::Counter::kIsRate);
  state.counters["particle_steps_per_s"] = benchmark::Counter(
      steps * static_cast<double>(world.particles().size()), benchmark::Counter::kIsRate);
  state.counters["contacts_per_step"] = contacts / steps;
  state.counters["raw_contacts_per_step"] = rawPoints / steps;
  state.counters["contact_pairs_per_step"] = contactPairs / steps;
  state.counters["obstacle_pairs_per_step"] = obstaclePairs / steps;
  state.counters["share_contact_detection"] = detectionSeconds / stepSeconds;
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["start_time_s"] = startTime;
  state.counters["time_step_s"] = world.parameters().timeStep;
  state.counters["free_fall_steps"] = static_cast<double>(prepared.freeFallSteps);
  state.counters["settling_steps"] = static_cast<double>(prepared.settlingSteps);
}

void Hopper(benchmark::State& state) {
  const auto count = static_cast<std::size_t>(state.range(0));
  const auto kind = state.range(3) ? dem::ParticleKind::Sphere : dem::ParticleKind::Mesh;
  const auto model = state.range(4) ? dem::ContactModel::volume : dem::ContactModel::point;
  const PreparedWorld& funnel =
      funnelWorld(count, kind, model, static_cast<std::size_t>(state.range(2)));
  const OmpThreads threads(static_cast<int>(state.range(1)));  // (built before the threads are set)
  timeSteps(state, funnel);
  const double top = funnelTop(funnel.world);
  std::size_t inFunnel = 0;
  for (const dem::Particle& particle : funnel.world.particles())
    inFunnel += particle.position.z < top;
  state.counters["in_funnel"] = static_cast<double>(inFunnel);
}

void Settle(benchmark::State& state) {
  const auto count = static_cast<std::size_t>(state.range(0));
  const auto model = state.range(2) ? dem::ContactModel::volume : dem::ContactModel::point;
  const PreparedWorld& settled = settledWorld(count, model);
  const OmpThreads threads(static_cast<int>(state.range(1)));
  timeSteps(state, settled);
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
  // The settle scenario's pile at rest (issue 25's granulate figures), with each law.
  for (const std::int64_t particles : {100, 1000})
    benchmark::RegisterBenchmark("Settle", Settle)
        ->ArgsProduct({{particles}, threads, {0, 1}})
        ->ArgNames({"particles", "omp_threads", "volume"})
        ->Iterations(particles == 100 ? 1000 : 100)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
