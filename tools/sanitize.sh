#!/usr/bin/env bash
# The readers', the scene's and the package's tests built with AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC, -DTERAWALK_SANITIZE=ON, build/asan): the code that takes
# untrusted bytes, checked on the same inputs the tests feed it, complementing tools/fuzz.sh.
# Then the threaded code's tests under ThreadSanitizer (build/tsan). The rest of the suite (the
# DAG builder, the runtime and GL) is not in these stages: building it once more does not fit
# CI's time (docs/reliability.md, "Sanitizers").
set -euo pipefail
cd "$(dirname "$0")/.."

build=${TERAWALK_SANITIZE_BUILD_DIR:-build/asan}
# The mesh readers and the package on tw_formats alone; the importers (glTF through tinygltf,
# IFC and STEP through OpenCASCADE) run under the same sanitizers in their fuzz targets.
tests=(test_text_scan test_file_reader test_spilled_array test_scene_stats test_ply test_stl
       test_obj test_tws test_project_database test_package test_page_codec
       test_sealed_pipe_runs test_covered_box_faces)

start=$(date +%s)
mkdir -p "$build"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTERAWALK_SANITIZE=ON \
  -DTERAWALK_WERROR=OFF -DTERAWALK_BUILD_BENCH=OFF > "$build/configure.log"
cmake --build "$build" --target "${tests[@]}" -j "$(nproc)"
echo "sanitize: ${#tests[@]} test programs built in $(( $(date +%s) - start )) s"

export ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
run_start=$(date +%s)
for t in "${tests[@]}"; do
  if ! out=$("$build/tests/$t" --gtest_brief=1 2>&1); then
    printf '%s\n' "$out" | tail -60 >&2
    echo "sanitize: $t FAILED" >&2
    exit 1
  fi
  echo "sanitize: $t: $(printf '%s\n' "$out" | grep -E '^\[  PASSED  \]' | head -1)"
done
echo "sanitize: AddressSanitizer stage passed; run in $(( $(date +%s) - run_start )) s, $(( $(date +%s) - start )) s in all"

# ThreadSanitizer over the code that starts threads of its own: the pager's loader threads
# (test_pager) and the package reader's table decompression (test_package). The preprocessor's
# TBB work is left out: Debian's TBB scheduler is not instrumented, so ThreadSanitizer cannot see
# its synchronization and reports every parallel_for and parallel_sort as a race.
tsan_build=${TERAWALK_TSAN_BUILD_DIR:-build/tsan}
tsan_tests=(test_pager test_package)
start=$(date +%s)
mkdir -p "$tsan_build"
cmake -S . -B "$tsan_build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTERAWALK_TSAN=ON \
  -DTERAWALK_WERROR=OFF -DTERAWALK_BUILD_BENCH=OFF > "$tsan_build/configure.log"
cmake --build "$tsan_build" --target "${tsan_tests[@]}" -j "$(nproc)"
echo "sanitize: ${#tsan_tests[@]} ThreadSanitizer programs built in $(( $(date +%s) - start )) s"
run_start=$(date +%s)
for t in "${tsan_tests[@]}"; do
  if ! out=$(TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 "$tsan_build/tests/$t" --gtest_brief=1 2>&1); then
    printf '%s\n' "$out" | tail -60 >&2
    echo "sanitize: $t FAILED under ThreadSanitizer" >&2
    exit 1
  fi
  echo "sanitize: $t (ThreadSanitizer): $(printf '%s\n' "$out" | grep -E '^\[  PASSED  \]' | head -1)"
done
echo "sanitize: ThreadSanitizer stage passed; run in $(( $(date +%s) - run_start )) s"
