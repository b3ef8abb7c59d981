#!/usr/bin/env bash
# The main job on a built-in default: set up and build (scripts/setup.sh), then describe a real
# mesh (CGAL's armadillo) and a built-in primitive, find the contacts of two particles (written
# to build/contacts.vtp for ParaView), the signed distances of 100,000 points to the armadillo
# (build/distances.vtp) and time the triangle–triangle solvers.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build
./build/delta --version
./build/delta info data/meshes/armadillo.off
./build/delta info builtin:granulate:1
./build/delta contact builtin:granulate:3 builtin:granulate:4 --translate-b 1.8,0.2,0.1 --eps 0.05 \
  --filter 0.1 --out build/contacts.vtp
./build/delta distance data/meshes/armadillo.off --points builtin:uniform:100000 --signed \
  --out build/distances.vtp
./build/delta bench kernels --pairs 200000
