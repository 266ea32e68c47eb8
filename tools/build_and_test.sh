#!/usr/bin/env bash
# Builds TeraWalk (warnings as errors) and runs every test with CTest. The README's test command.
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install_deps.sh
build=${TERAWALK_TEST_BUILD_DIR:-build/test}
# -O2 without debug information: about a third of a 2-core machine's build time went to writing
# and linking it. TERAWALK_TEST_DEBUG=1 builds RelWithDebInfo (-O2 -g) for a debugger.
if [ "${TERAWALK_TEST_DEBUG:-0}" = 1 ]; then
  build_type=(-DCMAKE_BUILD_TYPE=RelWithDebInfo)
else
  build_type=(-DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O2 -DNDEBUG"
              "-DCMAKE_C_FLAGS_RELEASE=-O2 -DNDEBUG")
fi
cmake -S . -B "$build" -G Ninja "${build_type[@]}" -DTERAWALK_WERROR=ON
cmake --build "$build" -j "$(nproc)"
ctest --test-dir "$build" -j "$(nproc)" --output-on-failure --timeout 900
# Every reader under libFuzzer with ASan and UBSan, 10 s each (docs/reliability.md, "Fuzzing").
tools/fuzz.sh 10
# The readers' and the package's tests under ASan and UBSan (docs/reliability.md, "Sanitizers").
tools/sanitize.sh
