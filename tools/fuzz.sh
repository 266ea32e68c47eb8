#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan, tests/fuzz/) and runs each on its seed corpus
# for a while; fails on the first crash, leak, sanitizer report or hang, and says how to replay it.
# The test command runs it briefly; bench/fuzz_long.sh runs it for hours on a corpus that grows.
#
#   tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default 15 s, every target)
#
# Environment: TERAWALK_FUZZ_BUILD_DIR (default build/fuzz); TERAWALK_FUZZ_CORPUS_DIR, a folder
# that keeps what the runs find (default: a temporary one, so the committed seeds never change);
# TERAWALK_FUZZ_JOBS, parallel processes per target (default 1); TERAWALK_FUZZ_RUNS, stop each
# target after this many executions in all (shared among the jobs) instead of after the time.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-15}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(ply obj stl gltf glb tws ifc step package camera_path bcf preprocess_plan)
fi
build=${TERAWALK_FUZZ_BUILD_DIR:-build/fuzz}
jobs=${TERAWALK_FUZZ_JOBS:-1}

start=$(date +%s)
repo=$(pwd)
mkdir -p "$build"
build=$(cd "$build" && pwd)
# Line tables only (-g1): enough for a crash's stack to name files and lines.
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" \
  -DTERAWALK_FUZZ=ON -DTERAWALK_BUILD_TESTS=OFF -DTERAWALK_BUILD_BENCH=OFF > "$build/configure.log"
cmake --build "$build" --target fuzz_targets -j "$(nproc)"
echo "fuzz: targets built in $(( $(date +%s) - start )) s"

corpus_root=${TERAWALK_FUZZ_CORPUS_DIR:-}
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
[ -n "$corpus_root" ] || corpus_root=$scratch/corpus
mkdir -p "$corpus_root"
corpus_root=$(cd "$corpus_root" && pwd)
artifacts=$build/artifacts
mkdir -p "$artifacts"

for t in "${targets[@]}"; do
  exe=$build/tests/fuzz/fuzz_$t
  [ -x "$exe" ] || { echo "fuzz: no target named $t" >&2; exit 2; }
  mkdir -p "$corpus_root/$t"
  options=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
           -artifact_prefix="$artifacts/$t-")
  [ -z "${TERAWALK_FUZZ_RUNS:-}" ] || options+=(-runs=$(( (TERAWALK_FUZZ_RUNS + jobs - 1) / jobs )))
  [ -f "tests/fuzz/dict/$t.dict" ] && options+=(-dict="$repo/tests/fuzz/dict/$t.dict")
  log=$scratch/$t.log
  target_start=$(date +%s)
  status=0
  if [ "$jobs" -gt 1 ]; then
    (cd "$scratch" && "$exe" "${options[@]}" -jobs="$jobs" -workers="$jobs" \
      "$corpus_root/$t" "$repo/tests/fuzz/corpus/$t") > "$log" 2>&1 || status=$?
    rm -f "$scratch"/fuzz-*.log   # the main log already holds what each job wrote
  else
    "$exe" "${options[@]}" "$corpus_root/$t" "tests/fuzz/corpus/$t" > "$log" 2>&1 || status=$?
  fi
  execs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | awk '{s += $2} END {print s + 0}')
  files=$(find "$corpus_root/$t" -type f | wc -l)
  if [ "$status" -ne 0 ] || grep -qE '^==[0-9]+==ERROR|runtime error:|SUMMARY: (Address|Leak|Undefined)' "$log"; then
    echo "fuzz_$t: FAILED after $execs execs (exit $status)" >&2
    grep -E 'ERROR|runtime error|SUMMARY|Test unit written|timeout' "$log" | head -20 >&2
    echo "replay: $exe $artifacts/$t-<file above>; full log kept in $artifacts/$t.log" >&2
    cp "$log" "$artifacts/$t.log"
    exit 1
  fi
  echo "fuzz_$t: $execs execs in $(( $(date +%s) - target_start )) s, corpus $files files, no failure"
done
echo "fuzz: all ${#targets[@]} targets passed in $(( $(date +%s) - start )) s"
