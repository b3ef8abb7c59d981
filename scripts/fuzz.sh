#!/usr/bin/env bash
# Fuzzes every reader Δ owns (fuzz/: OFF, PLY, OBJ, STL meshes, query points, the DEM config,
# DEM checkpoints), and the queries on the meshes they give, with libFuzzer under
# AddressSanitizer + UndefinedBehaviorSanitizer: builds the targets with clang (in BUILD,
# default build-fuzz/), replays every regression input in tests/fuzz/TARGET/, then fuzzes each
# target for SECONDS (default 20) from seeds: those regression inputs, assimp's test models and
# CGAL's meshes of the target's format, and the corpus earlier runs grew in BUILD/corpus/; the
# targets run side by side, as many as there are cores. Fails on any crash, leak, hang (10 s an
# input) or sanitizer report, leaving the input in BUILD/crashes/TARGET/: add it to
# tests/fuzz/TARGET/ once fixed, as a regression.
#   scripts/fuzz.sh [SECONDS [BUILD]]
# BUILD, when given, is a sanitized clang build already configured with -DDELTA_BUILD_FUZZERS=ON
# (scripts/test.sh passes its ASan build, so that the library is compiled once); otherwise
# build-fuzz/ is set up here.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
build=${2:-build-fuzz}

if [ "$build" = build-fuzz ]; then
  CC=clang CXX=clang++ scripts/setup.sh build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" \
    -DDELTA_SANITIZE=address,undefined -DDELTA_BUILD_FUZZERS=ON -DDELTA_FUZZ_COVERAGE_EVERYWHERE=ON \
    -DDELTA_BUILD_TESTS=OFF -DDELTA_BUILD_BENCH=OFF -DDELTA_BUILD_APPS=OFF
else
  grep -q '^DELTA_BUILD_FUZZERS:BOOL=ON' "$build/CMakeCache.txt" ||
    { echo "fuzz.sh: $build is not configured with -DDELTA_BUILD_FUZZERS=ON" >&2; exit 1; }
  cmake --build "$build" --target fuzz_load_off fuzz_load_ply fuzz_load_obj fuzz_load_stl \
    fuzz_points fuzz_dem_config fuzz_checkpoint fuzz_queries
fi

# Seeds a target starts from, beside its regression inputs: files of its format under 64 KiB.
seeds() {
  case $1 in
    load_off | queries) find data/assimp/OFF data/meshes -maxdepth 2 -name '*.off' -size -64k ;;
    load_ply) find data/assimp/PLY -name '*.ply' -size -64k ;;
    load_obj) find data/assimp/OBJ -name '*.obj' -size -64k ;;
    load_stl) find data/assimp/STL -iname '*.stl' -size -64k ;;
  esac
}

# One target: its regression inputs replayed, then fuzzed from its seeds; what it found in
# BUILD/fuzz_TARGET.out, and BUILD/fuzz_TARGET.failed when it failed.
fuzz_target() {
  local target=$1
  local fuzzer=$build/fuzz/fuzz_$target
  local regressions=tests/fuzz/$target
  local corpus=$build/corpus/$target
  local seed_dir=$build/seeds/$target
  local crashes=$build/crashes/$target/
  mkdir -p "$corpus" "$seed_dir" "$crashes"
  seeds "$target" | while read -r seed; do cp -f "$seed" "$seed_dir/"; done
  if compgen -G "$regressions/*" >/dev/null; then
    local replay=$build/replay_$target.log
    if ! "$fuzzer" "$regressions"/* >"$replay" 2>&1; then
      tail -n 60 "$replay"
      echo "fuzz_$target: a regression input crashes again" >&2
      return 1
    fi
    echo "fuzz_$target: $(grep -c '^Executed' "$replay") regression inputs replayed, no crash"
  fi
  echo "== fuzz_$target: fuzzing for ${seconds}s"
  local log=$build/fuzz_$target.log
  if ! "$fuzzer" -max_total_time="$seconds" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$crashes" "$corpus" "$seed_dir" \
    $([ -d "$regressions" ] && echo "$regressions") >"$log" 2>&1; then
    tail -n 60 "$log"
    echo "fuzz_$target: a crash; the input is in $crashes" >&2
    return 1
  fi
  local runs
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  echo "fuzz_$target: ${runs:-?} inputs run, no crash"
}

# The targets run side by side, one a core (libFuzzer runs one process on one core): each gets
# its SECONDS, and the stage takes its share of the wall clock.
targets=(load_off load_ply load_obj load_stl points dem_config checkpoint queries)
parallel=$(nproc)
for target in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
  rm -f "$build/fuzz_$target.failed"
  { fuzz_target "$target" || touch "$build/fuzz_$target.failed"; } >"$build/fuzz_$target.out" 2>&1 &
done
wait
total=0
failed=0
for target in "${targets[@]}"; do
  cat "$build/fuzz_$target.out"
  if [ -f "$build/fuzz_$target.failed" ]; then
    failed=1
    continue
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/fuzz_$target.log")
  total=$((total + ${runs:-0}))
done
[ "$failed" = 0 ] || exit 1
echo "fuzzing: $total inputs run in all, no crash"
