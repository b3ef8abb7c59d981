#!/usr/bin/env bash
# The main job on a built-in default: set up and build (scripts/setup.sh), then the DEM case
# study — two particles colliding (measured restitution) and 27 triangulated granulates falling
# into a box and settling (a ParaView series in build/dem_settle/; again on two MPI ranks,
# build/dem_settle_mpi/) — and the immersed-boundary
# case study (an adaptive grid around CGAL's fandisk following it as it turns, build/ib_fandisk/),
# then describe a real mesh (CGAL's armadillo) and a built-in primitive, find the contacts of two
# particles (build/contacts.vtp), the signed distances of 100,000 points to the armadillo
# (build/distances.vtp) and time the triangle–triangle solvers.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build
./build/delta --version
./build/delta dem two-particles --restitution 0.5 --quiet
./build/delta dem settle --particles 27 --overwrite --out build/dem_settle
# the same settling split over two MPI ranks (one .pvtp piece a rank, build/dem_settle_mpi/);
# the same trajectories as one process
OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 \
  mpirun -np 2 --oversubscribe ./build/delta dem settle --particles 27 --overwrite --out build/dem_settle_mpi
./build/delta ib data/meshes/fandisk.off --levels 6 --steps 5 --rotate 0,0,1,2 --overwrite --out build/ib_fandisk
./build/delta info data/meshes/armadillo.off
./build/delta info builtin:granulate:1
./build/delta contact builtin:granulate:3 builtin:granulate:4 --translate-b 1.8,0.2,0.1 --eps 0.05 \
  --filter 0.1 --out build/contacts.vtp
./build/delta distance data/meshes/armadillo.off --points builtin:uniform:100000 --signed \
  --out build/distances.vtp
./build/delta bench kernels --pairs 200000
