// The guide, section 6: Δ's DEM case study on MPI ranks (dem::DistributedWorld). Run under
// mpirun by the test Guide.distributed_dem_mpi (where CMake found MPI); checks that the ranks
// together follow the one-process World bit for bit.
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "delta/dem/mpi/distributed_world.h"
#include "delta/dem/scenarios.h"

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int failed = 0;
  {
    delta::dem::World serial = delta::dem::settle(64).world;
    // [guide:begin distributed]
    // every rank builds the same World (a scenario, or shapes and particles from the same seeds)
    delta::dem::DistributedWorld world(MPI_COMM_WORLD, delta::dem::settle(64).world);
    world.run(2000);                            // collective
    delta::dem::Energies e = world.energies();  // summed over the ranks
    double mass = 0.0;                          // of the particles this rank owns
    for (const delta::dem::Particle& p : world.particles())
      mass += world.part().shapes()[p.shape].mass();
    // [guide:end distributed]
    double total = 0.0, expected = 0.0;
    MPI_Allreduce(&mass, &total, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    for (const delta::dem::Particle& p : serial.particles())
      expected += serial.shapes()[p.shape].mass();
    failed += std::fabs(total - expected) > 1e-12 * expected;
    serial.run(2000);
    const std::vector<delta::dem::Particle> all = world.gatherParticles(0);
    if (world.rank() == 0) {
      for (std::size_t i = 0; i < all.size(); ++i)
        failed += std::memcmp(&all[i].position, &serial.particles()[i].position,
                              sizeof(delta::Vec3)) != 0;
      failed += all.size() != serial.particles().size();
      std::printf(
          "%zu particles on %d ranks, kinetic energy %.6g J (one process: %.6g J), %d "
          "positions differ\n",
          all.size(), world.size(), e.kinetic(), serial.energies().kinetic(), failed);
    }
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return failed == 0 ? 0 : 1;
}
