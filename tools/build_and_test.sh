#!/usr/bin/env bash
# Builds TeraWalk (warnings as errors) and runs every test with CTest. The README's test command.
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install_deps.sh
build=${TERAWALK_TEST_BUILD_DIR:-build/test}
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTERAWALK_WERROR=ON
cmake --build "$build" -j "$(nproc)"
ctest --test-dir "$build" -j "$(nproc)" --output-on-failure --timeout 900
# Every reader under libFuzzer with ASan and UBSan, 10 s each (docs/reliability.md, "Fuzzing").
tools/fuzz.sh 10
# The readers' and the package's tests under ASan and UBSan (docs/reliability.md, "Sanitizers").
tools/sanitize.sh
