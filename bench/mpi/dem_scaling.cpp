// delta_bench_dem_mpi: the DEM hopper split over MPI ranks (dem::DistributedWorld), for strong
// and weak scaling (docs/scaling.md). Run under mpirun:
//
//   mpirun -np P build/bench/delta_bench_dem_mpi [--particles N] [--per-rank] [--spheres]
//                                                 [--settling S] [--steps M] [--repeat R]
//
// Every rank builds hopper(N) (N × P particles with --per-rank: weak scaling) and takes its free
// fall in long steps (exact before the first contact, bench/hopper_free_fall.h); then the ranks
// split it and step together until the flow is under way (0.5 contact points per particle, or
// S steps, default 3000), and time R repetitions (default 3) of M steps (default 30), each
// between two barriers. Rank 0 prints one JSON object: the medians over the repetitions of the
// wall-clock time per step, and each rank's share (particles, ghosts, contact detection,
// communication) over all timed steps, with the commit and the machine's threads.
#include <mpi.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "delta/core/version.h"
#include "delta/dem/mpi/distributed_world.h"
#include "delta/dem/scenarios.h"

#include "../hopper_free_fall.h"

namespace {

namespace dem = delta::dem;

struct Options {
  std::size_t particles = 1000;
  bool perRank = false;
  bool spheres = false;
  std::size_t settling = 3000;
  std::size_t steps = 30;
  std::size_t repeat = 3;
};

Options parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string option = argv[i];
    const auto number = [&] {
      if (i + 1 >= argc) throw std::runtime_error(option + " needs a number");
      return static_cast<std::size_t>(std::strtoull(argv[++i], nullptr, 10));
    };
    if (option == "--particles")
      options.particles = number();
    else if (option == "--per-rank")
      options.perRank = true;
    else if (option == "--spheres")
      options.spheres = true;
    else if (option == "--settling")
      options.settling = number();
    else if (option == "--steps")
      options.steps = number();
    else if (option == "--repeat")
      options.repeat = number();
    else
      throw std::runtime_error("unknown option " + option);
  }
  if (options.particles == 0 || options.steps == 0 || options.repeat == 0)
    throw std::runtime_error("--particles, --steps and --repeat must be positive");
  return options;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

int run(int argc, char** argv) {
  const Options options = parse(argc, argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const std::size_t count =
      options.perRank ? options.particles * static_cast<std::size_t>(ranks) : options.particles;
  dem::Scenario scenario =
      dem::hopper(count, 1, options.spheres ? dem::ParticleKind::Sphere : dem::ParticleKind::Mesh);
  const std::size_t freeFall = delta::bench::fallFreely(scenario.world, 25.0);
  dem::DistributedWorld world(MPI_COMM_WORLD, scenario.world);

  std::size_t settling = 0;
  const double target = 0.5 * static_cast<double>(count);
  while (settling < options.settling &&
         static_cast<double>(world.statistics().contactPoints) < target) {
    world.step();
    ++settling;
  }

  std::vector<double> perStep;
  const dem::RankLoad before = world.load();
  double contacts = 0.0;
  for (std::size_t r = 0; r < options.repeat; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime();
    for (std::size_t s = 0; s < options.steps; ++s) {
      world.step();
      contacts += static_cast<double>(world.part().contacts().size());
    }
    MPI_Barrier(MPI_COMM_WORLD);
    perStep.push_back((MPI_Wtime() - start) / static_cast<double>(options.steps));
  }
  MPI_Allreduce(MPI_IN_PLACE, &contacts, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  dem::RankLoad timed = world.load();  // over the timed steps only
  timed.steps -= before.steps;
  timed.contactDetectionSeconds -= before.contactDetectionSeconds;
  timed.communicationSeconds -= before.communicationSeconds;
  timed.stepSeconds -= before.stepSeconds;
  std::vector<dem::RankLoad> loads(static_cast<std::size_t>(rank == 0 ? ranks : 0));
  MPI_Gather(&timed, sizeof timed, MPI_BYTE, loads.data(), sizeof timed, MPI_BYTE, 0,
             MPI_COMM_WORLD);
  const std::size_t rebalances = world.rebalances();
  const double simulated = world.time();
  if (rank != 0) return 0;

  const double steps = static_cast<double>(options.steps * options.repeat);
  double slowest = 0.0, mean = 0.0;
  for (const dem::RankLoad& load : loads) {
    const double busy = load.stepSeconds - load.communicationSeconds;
    slowest = std::max(slowest, busy);
    mean += busy / static_cast<double>(ranks);
  }
  std::printf(
      "{\"commit\":\"%s\",\"hardware_threads\":%d,\"ranks\":%d,\"threads_per_rank\":%d,"
      "\"particles\":%zu,\"spheres\":%s,\"free_fall_steps\":%zu,\"settling_steps\":%zu,"
      "\"time\":%.6g,\"rebalances\":%zu,\"ms_per_step\":%.4g,\"ms_per_step_runs\":[",
      delta::gitCommit(), omp_get_num_procs(), ranks, omp_get_max_threads(), count,
      options.spheres ? "true" : "false", freeFall, settling, simulated, rebalances,
      1e3 * median(perStep));
  for (std::size_t r = 0; r < perStep.size(); ++r)
    std::printf("%s%.4g", r ? "," : "", 1e3 * perStep[r]);
  std::printf("],\"contacts_per_step\":%.1f,\"imbalance\":%.3f,\"rank_loads\":[", contacts / steps,
              mean > 0.0 ? slowest / mean : 1.0);
  for (std::size_t r = 0; r < loads.size(); ++r) {
    const dem::RankLoad& load = loads[r];
    std::printf(
        "%s{\"rank\":%zu,\"particles\":%zu,\"ghosts\":%zu,\"contact_detection_ms\":%.4g,"
        "\"communication_ms\":%.4g,\"step_ms\":%.4g}",
        r ? "," : "", r, load.particles, load.ghosts, 1e3 * load.contactDetectionSeconds / steps,
        1e3 * load.communicationSeconds / steps, 1e3 * load.stepSeconds / steps);
  }
  std::printf("]}\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int status = 0;
  try {
    status = run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "delta_bench_dem_mpi: %s\n", error.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  MPI_Finalize();
  return status;
}
