#!/usr/bin/env bash
# Sets up everything Δ needs on Debian 12, as root, and builds it. Idempotent: a second run
# installs nothing, unpacks nothing and rebuilds only what changed.
#   scripts/setup.sh [BUILD_DIR [extra cmake options...]]   (default BUILD_DIR: build)
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  g++ cmake ninja-build git ca-certificates clang libclang-rt-dev libomp-dev
  libassimp-dev libqhull-dev libcli11-dev
  googletest libgtest-dev libgmock-dev libbenchmark-dev
  libcgal-dev libgmp-dev libmpfr-dev
  libcgal-demo assimp-testmodels
  libfcl-dev  # FCL: the peer in bench/kernels_bench.cpp (found there only if installed)
  libembree-dev  # Embree 3: the points–mesh peer in bench/peers (found only if installed)
)
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$package")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Real meshes, into the ignored folder data/: CGAL's data set and assimp's test models.
if [ ! -f data/meshes/armadillo.off ]; then
  echo "setup: unpacking CGAL's meshes into data/meshes"
  mkdir -p data
  tar -xzf /usr/share/doc/libcgal-dev/data.tar.gz -C . --wildcards 'data/meshes/*'
fi
ln -sfn /usr/share/assimp/models data/assimp

build=${1:-build}
shift || true
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build"
