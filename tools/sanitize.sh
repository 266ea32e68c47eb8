#!/usr/bin/env bash
# The readers', the scene's and the package's tests built with AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC, -DTERAWALK_SANITIZE=ON, build/asan): the code that takes
# untrusted bytes, checked on the same inputs the tests feed it, complementing tools/fuzz.sh.
# Then the threaded code's tests under ThreadSanitizer (build/tsan). The rest of the suite (the
# DAG builder, the runtime and GL) is not in these stages: building it once more does not fit
# CI's time (docs/reliability.md, "Sanitizers").
set -euo pipefail
cd "$(dirname "$0")/.."

# build_stage NAME DIR CMAKE_OPTION TEST...: configures DIR with the sanitizer option and builds
# the test programs.
build_stage() {
  local name=$1 dir=$2 option=$3
  shift 3
  local start
  start=$(date +%s)
  mkdir -p "$dir"
  # Line tables only (-g1): enough for the sanitizers' reports to name files and lines.
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "$option" \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" \
    -DTERAWALK_WERROR=OFF -DTERAWALK_BUILD_BENCH=OFF > "$dir/configure.log"
  cmake --build "$dir" --target "$@" -j "$(nproc)"
  echo "sanitize: $# $name programs built in $(( $(date +%s) - start )) s"
}

# run_stage NAME DIR TEST...: runs each test program, stopping at the first failure with its
# output's tail.
run_stage() {
  local name=$1 dir=$2
  shift 2
  local start out t
  start=$(date +%s)
  for t in "$@"; do
    if ! out=$("$dir/tests/$t" --gtest_brief=1 2>&1); then
      printf '%s\n' "$out" | tail -60 >&2
      echo "sanitize: $t FAILED under $name" >&2
      exit 1
    fi
    echo "sanitize: $t ($name): $(printf '%s\n' "$out" | grep -E '^\[  PASSED  \]' | head -1)"
  done
  echo "sanitize: $name stage passed; run in $(( $(date +%s) - start )) s"
}

# The mesh readers and the package on tw_formats alone; the importers (glTF through tinygltf,
# IFC and STEP through OpenCASCADE) run under the same sanitizers in their fuzz targets.
tests=(test_text_scan test_file_reader test_spilled_array test_scene_stats test_ply test_stl
       test_obj test_tws test_project_database test_package test_page_codec
       test_sealed_pipe_runs test_covered_box_faces)
asan_build=${TERAWALK_SANITIZE_BUILD_DIR:-build/asan}
build_stage "AddressSanitizer" "$asan_build" -DTERAWALK_SANITIZE=ON "${tests[@]}"
ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1 \
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  run_stage "AddressSanitizer" "$asan_build" "${tests[@]}"

# ThreadSanitizer over the code that starts threads of its own: the pager's loader threads
# (test_pager) and the package reader's table decompression (test_package). The preprocessor's
# TBB work is left out: Debian's TBB scheduler is not instrumented, so ThreadSanitizer cannot see
# its synchronization and reports every parallel_for and parallel_sort as a race.
tsan_tests=(test_pager test_package)
tsan_build=${TERAWALK_TSAN_BUILD_DIR:-build/tsan}
build_stage "ThreadSanitizer" "$tsan_build" -DTERAWALK_TSAN=ON "${tsan_tests[@]}"
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
  run_stage "ThreadSanitizer" "$tsan_build" "${tsan_tests[@]}"
