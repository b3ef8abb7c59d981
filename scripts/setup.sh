#!/usr/bin/env bash
# Sets up everything Δ needs on Debian 12, as root, and builds it. Idempotent: a second run
# installs nothing, unpacks nothing and rebuilds only what changed.
#   scripts/setup.sh [BUILD_DIR [extra cmake options...]]   (default BUILD_DIR: build)
# With DELTA_SETUP_WITHOUT_BENCH set, the benchmark programs (bench/) are left unbuilt.
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
  libliggghts-dev  # LIGGGHTS 3.8: the sphere DEM peer in bench/dem_bench.cpp (found only if installed)
  python3-dev python3-numpy python3-pytest pybind11-dev  # the Python module delta (python/)
  zlib1g-dev  # the VTK writers compress with zlib (src/io/vtk.cpp)
  python3-vtk9  # VTK's own readers open what Δ writes (python/tests/test_vtk_files.py)
  python3-build python3-venv  # the wheel (pyproject.toml) and the venv that tests it
  pkg-config  # the test of delta.pc (scripts/test_packages.sh)
  ccache  # every build goes through it: the builds of one run share what compiles alike
  doxygen  # the API reference (the docs target) and the test Docs.NoWarnings
  libopenmpi-dev openmpi-bin  # MPI: the distributed DEM (delta::mpi, `delta dem` under mpirun)
)
source scripts/install_missing.sh
install_missing "${packages[@]}"

# Real meshes, into the ignored folder data/: CGAL's data set and assimp's test models.
if [ ! -f data/meshes/armadillo.off ]; then
  echo "setup: unpacking CGAL's meshes into data/meshes"
  mkdir -p data
  tar -xzf /usr/share/doc/libcgal-dev/data.tar.gz -C . --wildcards 'data/meshes/*'
fi
ln -sfn /usr/share/assimp/models data/assimp

build=${1:-build}
shift || true
# ccache: builds that compile a file alike (the Release build, the wheel's, the shared library's:
# the same flags, no debug information) share the object.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache \
  "$@" >/dev/null
if [ -n "${DELTA_SETUP_WITHOUT_BENCH:-}" ]; then
  # Everything but the benchmark programs (scripts/test.sh: no test runs them, and they were a
  # sixth of the Release build's compile time; they stay configured, built by
  # `cmake --build BUILD` or by name).
  mapfile -t targets < <(ninja -C "$build" -t query all | sed -n 's/^ *\([A-Za-z0-9_]*\/all\)$/\1/p' |
    grep -vx 'bench/all')
  cmake --build "$build" --target "${targets[@]}"
else
  cmake --build "$build"
fi

# The Python module: a .pth file in Debian's Python's site-packages points at this build's
# python/ folder, so that `python3 -c "import delta"` works from anywhere (the last build set up
# with Python wins; builds without it, such as the sanitized ones, leave the file alone).
if [ -f "$build/python/delta/__init__.py" ]; then
  python=$(sed -n 's/^Python3_EXECUTABLE:FILEPATH=//p' "$build/CMakeCache.txt")
  python=${python:-/usr/bin/python3}
  site=$("$python" -c 'import site; print(site.getsitepackages()[0])')
  package_dir=$(cd "$build/python" && pwd)
  if [ -w "$(dirname "$site")" ] || [ -w "$site" ]; then
    mkdir -p "$site"
    if [ "$(cat "$site/delta.pth" 2>/dev/null)" != "$package_dir" ]; then
      echo "setup: $site/delta.pth -> $package_dir"
      echo "$package_dir" >"$site/delta.pth"
    fi
    (cd / && "$python" -c 'import delta') || { echo "setup: import delta failed" >&2; exit 1; }
    on_path=$(command -v python3 || true)
    if [ -n "$on_path" ] && [ "$(realpath "$on_path")" != "$(realpath "$python")" ] &&
      ! (cd / && python3 -c 'import delta' 2>/dev/null); then
      echo "setup: note: python3 on PATH ($on_path) is not $python, for which delta is built"
    fi
  else
    echo "setup: cannot write to $site; use PYTHONPATH=$package_dir"
  fi
fi
