#!/usr/bin/env bash
# The whole test suite: set up (scripts/setup.sh); every test built with AddressSanitizer +
# UndefinedBehaviorSanitizer; the readers Δ owns fuzzed (scripts/fuzz.sh, clang's libFuzzer under
# ASan + UBSan, 15 s a reader); the threaded tests built with ThreadSanitizer (clang, LLVM
# OpenMP); the kernels' and queries' tests cross-built for AArch64 and run under qemu-user
# (scripts/test_aarch64.sh: the NEON and SVE tables); the library installed and the packages checked as users get them
# (scripts/test_packages.sh: CMake and pkg-config consumers of the static and shared library, the
# wheel in a fresh venv), the immersed-boundary example built against the install and run; then
# every test in the Release build (its ctest summary is the closing line CI reads). Fails on the
# first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

# Every stage's Debian packages before any build: the AArch64 stage's would otherwise update
# system headers under the sanitizer builds' precompiled headers, which clang then refuses on
# the next run (scripts/test_aarch64.sh).
scripts/test_aarch64.sh --install-only

echo "== sanitizer build (ASan + UBSan)"
# Built with clang, as the fuzzers and the TSan build are: GCC takes minutes for each ISA's
# batch table (optimised in every build, src/CMakeLists.txt) once the sanitizers instrument it,
# clang seconds.
# Line tables only (-gline-tables-only): what the sanitizers' reports need, for less compile time
# than full debug information; the library itself at -O1 (src/CMakeLists.txt). The fuzz targets
# are built here too (-DDELTA_BUILD_FUZZERS=ON: coverage in the readers' code only).
CC=clang CXX=clang++ scripts/setup.sh build-asan -DCMAKE_BUILD_TYPE=Debug \
  -DCMAKE_CXX_FLAGS_DEBUG=-gline-tables-only -DDELTA_SANITIZE=address,undefined \
  -DDELTA_BUILD_FUZZERS=ON -DDELTA_BUILD_BENCH=OFF
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 ctest -j"$jobs" --output-on-failure)

echo "== fuzzing (libFuzzer under ASan + UBSan): every reader Δ owns, its regressions replayed"
scripts/fuzz.sh 15 build-asan  # the fuzz targets of the ASan build

echo "== ThreadSanitizer build (clang + LLVM OpenMP): the threaded tests (names contain Thread)"
# Built with clang and LLVM's OpenMP runtime, which TSan understands (GCC's libgomp is not
# instrumented: its barriers would read as races; the tests run OpenMP regions around Δ's
# calls), so the library's loops run on its thread pool while user threads call it concurrently.
# Only the test sources that hold such tests are built (DELTA_TEST_SOURCES_MATCHING).
CC=clang CXX=clang++ scripts/setup.sh build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" -DDELTA_SANITIZE=thread \
  -DDELTA_BUILD_BENCH=OFF -DDELTA_BUILD_APPS=OFF \
  "-DDELTA_TEST_SOURCES_MATCHING=Thread|ParallelFor"
(cd build-tsan && OMP_NUM_THREADS=2 TSAN_OPTIONS="halt_on_error=1 ignore_noninstrumented_modules=1" \
  ctest -j"$jobs" -R "Thread|ParallelFor" --no-tests=error --output-on-failure)

echo "== AArch64 (Debian's cross toolchain, tests under qemu-user): the kernels' and queries' tests, and the DEM's lanes'"
scripts/test_aarch64.sh build-aarch64

echo "== install: the packages as users get them, and the examples against the installed copy"
# The benchmark programs are not built here: no test runs them (scripts/setup.sh).
DELTA_SETUP_WITHOUT_BENCH=1 scripts/setup.sh build
scripts/test_packages.sh  # installs into build/install; shared library, pkg-config, wheel in a venv
cmake -S examples/immersed_boundary -B build/examples/immersed_boundary -G Ninja \
  -DCMAKE_PREFIX_PATH="$PWD/build/install" >/dev/null
cmake --build build/examples/immersed_boundary
./build/examples/immersed_boundary/immersed_boundary data/meshes/fandisk.off build/examples/ib

echo "== release build: every test"
(cd build && ctest -j"$jobs" --output-on-failure)
