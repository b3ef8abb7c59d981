#!/usr/bin/env bash
# The main job on a built-in default: set up and build (scripts/setup.sh), then describe a real
# mesh (CGAL's armadillo) and a built-in primitive, and time the triangle–triangle solvers.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build
./build/delta --version
./build/delta info data/meshes/armadillo.off
./build/delta info builtin:granulate:1
./build/delta bench kernels --pairs 200000
