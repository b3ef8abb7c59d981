#!/usr/bin/env bash
# What a user of an installed Δ gets, checked from the outside (run by scripts/test.sh after the
# Release build, which it needs: build/):
#  1. C++, static (build/): `cmake --install`; the examples built with find_package against the
#     install and run; find_package(delta COMPONENTS mpi) gives delta::mpi; find_package(delta)
#     works where MPI cannot be found; a pkg-config consumer (delta.pc) built and run; the
#     installed Python module imports from the prefix.
#  2. C++, shared (build-shared/, -DBUILD_SHARED_LIBS=ON): libdelta.so with its soname, the
#     example built against it by find_package and by pkg-config, and run.
#  3. Python: a wheel built by `python3 -m build --wheel --no-isolation` (setup.py drives CMake),
#     installed into a fresh virtual environment (with Debian's NumPy and pytest as system site
#     packages), and the whole pytest suite run there against it.
# Fails on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
python=/usr/bin/python3
export CMAKE_CXX_COMPILER_LAUNCHER=ccache  # the wheel compiles as build/ did (scripts/setup.sh)
example=examples/find_package

consume() {  # consume PREFIX NAME [cmake options]: the find_package example against PREFIX
  local prefix=$1 name=$2
  shift 2
  rm -rf "build/examples/$name"
  cmake -S "$example" -B "build/examples/$name" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" "$@" >/dev/null
  cmake --build "build/examples/$name" >/dev/null
  "./build/examples/$name/consumer"
}

pkg_config_consume() {  # pkg_config_consume PREFIX NAME: the same source, built by pkg-config
  local prefix=$1 name=$2 libdir
  libdir=$(dirname "$(find "$prefix" -name delta.pc | head -n1)")
  mkdir -p build/examples
  # shellcheck disable=SC2046
  g++ -O1 $(PKG_CONFIG_PATH=$libdir pkg-config --cflags delta) "$example/main.cpp" \
    -o "build/examples/$name" $(PKG_CONFIG_PATH=$libdir pkg-config --libs delta) \
    -Wl,-rpath,"$(cd "$libdir/.." && pwd)"
  "./build/examples/$name"
}

echo "== packages: the static library installed, consumed by CMake and by pkg-config"
rm -rf build/install build/examples
cmake --install build --prefix build/install >/dev/null
consume "$root/build/install" static
if grep -q '^DELTA_WITH_MPI:BOOL=ON' build/CMakeCache.txt; then
  # find_package(delta COMPONENTS mpi) gives delta::mpi.
  mkdir -p build/examples/mpi_component
  cat >build/examples/mpi_component/CMakeLists.txt <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(delta_mpi_component LANGUAGES CXX)
find_package(delta CONFIG REQUIRED COMPONENTS mpi)
if(NOT TARGET delta::mpi OR NOT TARGET delta::delta)
  message(FATAL_ERROR "COMPONENTS mpi: no delta::mpi")
endif()
CMAKE
  cmake -S build/examples/mpi_component -B build/examples/mpi_component/build \
    -DCMAKE_PREFIX_PATH="$root/build/install" >/dev/null
fi
# Where MPI cannot be found, find_package(delta) still gives delta::delta.
consume "$root/build/install" static_without_mpi -DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON
pkg_config_consume "$root/build/install" pkg_config_static
if grep -q '^DELTA_WITH_MPI:BOOL=ON' build/CMakeCache.txt && command -v mpicxx >/dev/null; then
  # The guide's MPI program, built as the guide says (mpicxx and delta-mpi.pc), on two ranks.
  # shellcheck disable=SC2046
  mpicxx -O1 -DDELTA_GUIDE_WITH_MPI $(PKG_CONFIG_PATH=build/install/lib/pkgconfig pkg-config \
    --cflags delta-mpi) docs/guide/mpi_ranks.cpp -o build/examples/guide_mpi_ranks \
    $(PKG_CONFIG_PATH=build/install/lib/pkgconfig pkg-config --libs delta-mpi)
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
    OMP_NUM_THREADS=1 mpirun -np 2 build/examples/guide_mpi_ranks >/dev/null
  echo "the guide's MPI program, built by mpicxx with delta-mpi.pc, ran on 2 ranks"
fi
module_dir=$(find build/install -path '*-packages/delta' -type d | head -n1)
[ -n "$module_dir" ] || { echo "test_packages: cmake --install installed no Python module" >&2; exit 1; }
(cd / && PYTHONPATH="$root/$(dirname "$module_dir")" "$python" -c "
import delta, sys
assert delta.__file__.startswith('$root/$module_dir'), delta.__file__
print('installed module:', delta.__file__, delta.__version__)")

echo "== packages: the shared library (BUILD_SHARED_LIBS=ON)"
scripts/setup.sh build-shared -DBUILD_SHARED_LIBS=ON -DDELTA_BUILD_TESTS=OFF \
  -DDELTA_BUILD_BENCH=OFF -DDELTA_BUILD_APPS=OFF -DDELTA_BUILD_PYTHON=OFF
rm -rf build-shared/install
cmake --install build-shared --prefix build-shared/install >/dev/null
library=$(find build-shared/install -name 'libdelta.so.*.*.*' | head -n1)
soname=$(objdump -p "$library" | sed -n 's/^ *SONAME *//p')
echo "shared library: $library, soname $soname"
[[ $soname =~ ^libdelta\.so\.[0-9]+\.[0-9]+$ ]] || { echo "test_packages: bad soname '$soname'" >&2; exit 1; }
consume "$root/build-shared/install" shared
loaded=$(ldd build/examples/shared/consumer)
[[ $loaded == *"$root/build-shared/install/lib/libdelta.so.0.1"* ]] ||
  { echo "test_packages: the consumer does not load the installed libdelta.so" >&2; exit 1; }
pkg_config_consume "$root/build-shared/install" pkg_config_shared

echo "== packages: the wheel, in a fresh virtual environment, passes the Python tests"
rm -rf build-python/dist build-python/venv
mkdir -p build-python
"$python" -m build --wheel --no-isolation --outdir build-python/dist . >build-python/wheel.log 2>&1 ||
  { tail -n 40 build-python/wheel.log; exit 1; }
"$python" -m venv --system-site-packages build-python/venv
build-python/venv/bin/python -m pip install --no-index --no-deps -q build-python/dist/*.whl
(cd / && env -u PYTHONPATH DELTA_EXPECT_MODULE="$root/build-python/venv" \
  DELTA_DATA_DIR="$root/data" DELTA_CLI="$root/build/delta" PYTHONDONTWRITEBYTECODE=1 \
  "$root/build-python/venv/bin/python" -m pytest -q -p no:cacheprovider "$root/python/tests")
echo "== packages: all passed"
