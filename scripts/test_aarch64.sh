#!/usr/bin/env bash
# The kernels' and queries' tests on AArch64, and the DEM's of its law and turns in vector lanes
# (src/dem/detail/two_lanes.h: Advanced SIMD there), on this x86-64 machine: Debian's cross toolchain
# builds Δ for arm64 (with its NEON and SVE tables) against Debian's arm64 libraries (multiarch),
# and qemu-user runs the tests (its default CPU has SVE, so the tests that run every supported ISA
# take NEON's and SVE's paths, and the default is SVE; then the dispatch tests on a CPU without).
# Idempotent; needs the meshes scripts/setup.sh unpacks. Called by scripts/test.sh.
#   scripts/test_aarch64.sh [BUILD_DIR]   (default BUILD_DIR: build-aarch64)
#   scripts/test_aarch64.sh --install-only (the Debian packages, nothing else)
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  g++-aarch64-linux-gnu qemu-user
  libassimp-dev:arm64 libqhull-dev:arm64 zlib1g-dev:arm64 libgtest-dev:arm64 libcgal-dev:arm64
)
# The arm64 packages come from the same Debian mirror once dpkg knows the architecture.
dpkg --print-foreign-architectures | grep -qx arm64 || dpkg --add-architecture arm64
source scripts/install_missing.sh
install_missing "${packages[@]}"
# scripts/test.sh installs these first of all: the arm64 libraries bring amd64's kernel headers
# to their version (multiarch), and a sanitizer build's precompiled header made before that is
# refused by clang ("has been modified since the precompiled header") when test.sh runs again.
[ "${1:-}" = --install-only ] && exit 0

build=${1:-build-aarch64}
cmake -S . -B "$build" -G Ninja -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DDELTA_BUILD_BENCH=OFF \
  -DDELTA_BUILD_APPS=OFF -DDELTA_BUILD_PYTHON=OFF -DDELTA_WITH_MPI=OFF \
  "-DDELTA_TEST_LAYERS=kernels/;query/;dem/one_point_law;dem/sphere_particles" >/dev/null
cmake --build "$build"
# Every kernels' and queries' test but the slowest whole-algorithm checks (thread counts, tie
# rules, winding-number signs, whole meshes and paths against brute force or a fresh query, the
# node and grid bounds on real meshes), which the native builds run in full; every ISA's kernels,
# descent and lanes are still checked here by the smaller tests that run each supported ISA.
# (Under qemu, on two cores: 195 tests in 88 s; with the six heaviest of those left out
# here also run, 201 in 175 s; with none left out, 233 tests in 300 s.)
(cd "$build" && ctest -j"$(nproc)" --output-on-failure --no-tests=error -E \
  'WindingSign[.]|TieRule[.]|OneAndTwoThreads|AnyThreadCount|SignedAgreesWithTheWindingNumber|ASmallParticleOnALargeMesh|WhateverTheTriangleOrder|RealMeshContacts[.]|SameAsEveryTriangleOnRealMeshes|PenaltyAnswerIsTheAllPairsPenaltyAnswer|AsAFreshQueryAlongAPath|PrunedSearchMatchesEveryPairOnAdversarialScenes|SameSetAsAllPairsByBruteForce|NodeSlab[.]GapNeverExceeds|NeverAboveTheDistanceOnArmadillo')
# And the dispatch on a CPU without SVE (a Cortex-A72, as in many Arm clusters): NEON is the
# widest, and no SVE instruction is reached.
(cd "$build" && QEMU_CPU=cortex-a72 ctest -j"$(nproc)" --output-on-failure --no-tests=error \
  -R 'KernelDispatch|ExactLanes|NearestDescent|LeafCylinder|PointLanes')
