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
// HopperScale: the 1000-granulate hopper in its flow, tiled 1, 10 and 100 times side by side
// (tiledHopper: the funnels one obstacle, the floors another): the time per particle-step and
// the memory per particle from 1000 to 100,000 particles.
//   build/bench/delta_bench_dem --benchmark_filter='HopperScale/tiles:100/'
//
// SpheresPeer: the settle scenario's pile of 100 or 1000 spheres at rest, stepped by Δ (peer:0)
// and by LIGGGHTS 3.8 (peer:1; liggghts_peer.h, built where libliggghts-dev is found) with the
// same law and parameters, one thread each; step_time is a step's wall time.
//   build/bench/delta_bench_dem --benchmark_filter='SpheresPeer'
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
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "delta/delta.h"

#include "bench_main.h"
#include "hopper_free_fall.h"
#ifdef DELTA_HAVE_LIGGGHTS
#include "liggghts_peer.h"
#endif
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
const PreparedWorld& settledWorld(std::size_t count, dem::ParticleKind kind,
                                  dem::ContactModel model) {
  const std::string name = caseName("settle", count, kind, model);
  return preparedWorld(name, [&] {
    dem::Scenario scenario = dem::settle(count, 1, kind, model);
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
  const PreparedWorld& settled = settledWorld(count, dem::ParticleKind::Mesh, model);
  const OmpThreads threads(static_cast<int>(state.range(1)));
  timeSteps(state, settled);
}

/// The resident memory of this process (/proc/self/statm), in bytes; 0 if unknown.
double residentBytes() {
  std::FILE* file = std::fopen("/proc/self/statm", "r");
  if (!file) return 0.0;
  unsigned long long size = 0, resident = 0;
  const int read = std::fscanf(file, "%llu %llu", &size, &resident);
  std::fclose(file);
  return read == 2 ? static_cast<double>(resident) * 4096.0 : 0.0;
}

/// `hopper` repeated `tiles` times side by side on a square grid (a plate of `tiles` funnels
/// over one floor): every obstacle's copies merged into one obstacle, so that there are as many
/// obstacles as in one hopper, and every particle copied with its state (its tangential springs
/// start again). Each tile is the same flow; the cost per particle-step should not grow.
dem::World tiledHopper(const dem::World& hopper, std::size_t tiles) {
  delta::Aabb bounds;
  for (const dem::Obstacle& obstacle : hopper.obstacles())
    bounds.extend(obstacle.mesh.bounds());
  const double pitch =
      1.05 * std::max(bounds.upper.x - bounds.lower.x, bounds.upper.y - bounds.lower.y);
  const auto columns = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(tiles))));
  const auto offset = [&](std::size_t tile) {
    return delta::Vec3{pitch * static_cast<double>(tile % columns),
                       pitch * static_cast<double>(tile / columns), 0.0};
  };
  dem::World tiled(hopper.parameters());
  for (const dem::ParticleShape& shape : hopper.shapes())
    tiled.addShape(shape);
  for (const dem::Obstacle& obstacle : hopper.obstacles()) {
    std::vector<delta::Vec3> vertices;
    std::vector<delta::TriangleIndices> triangles;
    for (std::size_t tile = 0; tile < tiles; ++tile) {
      const auto first = static_cast<std::uint32_t>(vertices.size());
      for (const delta::Vec3& vertex : obstacle.mesh.vertices())
        vertices.push_back(vertex + offset(tile));
      for (const delta::TriangleIndices& triangle : obstacle.mesh.triangles())
        triangles.push_back({triangle[0] + first, triangle[1] + first, triangle[2] + first});
    }
    tiled.addObstacle(delta::Mesh(std::move(vertices), std::move(triangles)), obstacle.motion);
  }
  for (std::size_t tile = 0; tile < tiles; ++tile)
    for (const dem::Particle& particle : hopper.particles())
      tiled.addParticle(particle.shape, {particle.position + offset(tile), particle.orientation,
                                         particle.velocity, particle.angularVelocity});
  return tiled;
}

/// Scale: the 1000-granulate hopper brought into its flow (as Hopper's), tiled 1, 10 and 100
/// times: 1000, 10,000 and 100,000 particles in the same flow. Counters: the time per
/// particle-step, and the memory the tiled world adds per particle (the resident size after its
/// first step less before it was made).
void HopperScale(benchmark::State& state) {
  const auto tiles = static_cast<std::size_t>(state.range(0));
  const PreparedWorld& funnel =
      funnelWorld(1000, dem::ParticleKind::Mesh, dem::ContactModel::point, 20000);
  const double before = residentBytes();
  dem::World world = tiledHopper(funnel.world, tiles);
  const OmpThreads threads(static_cast<int>(state.range(1)));
  world.step();
  const double added = residentBytes() - before;
  double contacts = 0.0;
  for (auto _ : state) {
    world.step();
    contacts += static_cast<double>(world.statistics().contactPoints);
  }
  const auto steps = static_cast<double>(state.iterations());
  const double particleSteps = steps * static_cast<double>(world.particles().size());
  state.counters["particles"] = static_cast<double>(world.particles().size());
  state.counters["particle_steps_per_s"] =
      benchmark::Counter(particleSteps, benchmark::Counter::kIsRate);
  state.counters["particle_step_time"] =
      benchmark::Counter(particleSteps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["contacts_per_particle"] = contacts / particleSteps;
  state.counters["bytes_per_particle"] = added / static_cast<double>(world.particles().size());
}

/// Sphere pairs, and spheres and the box's faces, whose surfaces are within 2ε (brute force):
/// that Δ and its peer simulate the same pile.
std::size_t touching(std::span<const delta::Vec3> centres, double radius, double epsilon,
                     const delta::Aabb& box) {
  std::size_t count = 0;
  const double reach = radius + 2.0 * epsilon;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const delta::Vec3& a = centres[i];
    for (std::size_t j = i + 1; j < centres.size(); ++j)
      count += length(a - centres[j]) < 2.0 * radius + 2.0 * epsilon;
    count += (a.z - box.lower.z < reach) + (a.x - box.lower.x < reach) +
             (box.upper.x - a.x < reach) + (a.y - box.lower.y < reach) +
             (box.upper.y - a.y < reach);
  }
  return count;
}

/// Δ's sphere variant of the settled pile against LIGGGHTS on the same spheres (peer = 1; see
/// liggghts_peer.h for how the law is matched), one thread each, in batches of kBatch steps
/// (LIGGGHTS' `run` costs about 2 µs a call besides its steps). Both first take kWarmUp steps
/// (LIGGGHTS builds its tangential histories there), not timed.
void SpheresPeer(benchmark::State& state) {
  constexpr std::size_t kBatch = 100, kWarmUp = 200;
  const auto count = static_cast<std::size_t>(state.range(0));
  const PreparedWorld& settled =
      settledWorld(count, dem::ParticleKind::Sphere, dem::ContactModel::point);
  const OmpThreads threads(1);
  dem::World world = settled.world;
  const delta::Aabb box = world.obstacles().front().mesh.bounds();
  const double radius = world.shapes()[world.particles().front().shape].boundingRadius();
  const double epsilon = world.parameters().epsilon;
  std::vector<delta::Vec3> centres;
  if (state.range(1) == 0) {
    for (std::size_t step = 0; step < kWarmUp; ++step)
      world.step();
    for (auto _ : state)
      for (std::size_t step = 0; step < kBatch; ++step)
        world.step();
    for (const dem::Particle& particle : world.particles())
      centres.push_back(particle.position);
  } else {
#ifdef DELTA_HAVE_LIGGGHTS
    delta::bench::LiggghtsSpheres peer(world, box);
    peer.run(kWarmUp);
    for (auto _ : state)
      peer.run(kBatch);
    centres = peer.positions();
#else
    state.SkipWithError("built without LIGGGHTS (libliggghts-dev)");
    return;
#endif
  }
  const auto steps = static_cast<double>(state.iterations() * kBatch);
  state.counters["steps_per_s"] = benchmark::Counter(steps, benchmark::Counter::kIsRate);
  state.counters["particle_steps_per_s"] =
      benchmark::Counter(steps * static_cast<double>(count), benchmark::Counter::kIsRate);
  state.counters["step_time"] =
      benchmark::Counter(steps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["touching"] = static_cast<double>(touching(centres, radius, epsilon, box));
  double height = 0.0;
  for (const delta::Vec3& centre : centres)
    height += centre.z;
  state.counters["mean_height"] = height / static_cast<double>(count);
}

}  // namespace

int main(int argc, char** argv) {
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
  // The hopper tiled: 1000, 10,000 and 100,000 granulates.
  for (const std::int64_t tiles : {1, 10, 100})
    benchmark::RegisterBenchmark("HopperScale", HopperScale)
        ->ArgsProduct({{tiles}, threads})
        ->ArgNames({"tiles", "omp_threads"})
        ->Iterations(tiles == 100  ? 3
                     : tiles == 10 ? 10
                                   : 50)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  // Δ's spheres against LIGGGHTS (peer = 1) on the settled pile of spheres, one thread.
  for (const std::int64_t particles : {100, 1000})
    benchmark::RegisterBenchmark("SpheresPeer", SpheresPeer)
        ->ArgsProduct({{particles}, {0, 1}})
        ->ArgNames({"particles", "peer"})
        ->Iterations(particles == 100 ? 200 : 50)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  return delta::bench::runBenchmarks(argc, argv);
}
