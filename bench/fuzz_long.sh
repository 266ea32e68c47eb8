#!/usr/bin/env bash
# Long fuzz runs: every target (or those named) for MINUTES each on a corpus that persists across
# runs (build/fuzz/long-corpus), with TERAWALK_FUZZ_JOBS processes per target. Appends one line
# per target (date, commit, seconds, execs, corpus size, result) to build/fuzz/long-runs.log;
# docs/reliability.md quotes the totals.
#
#   bench/fuzz_long.sh MINUTES [TARGET...]
#   bench/fuzz_long.sh --execs N [TARGET...]     (each target until N executions in all)
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bench/fuzz_long.sh MINUTES|--execs N [TARGET...]"
if [ "${1:-}" = --execs ]; then
  export TERAWALK_FUZZ_RUNS=${2:?$usage}
  minutes=100000
  limit="until $TERAWALK_FUZZ_RUNS execs"
  shift 2
else
  minutes=${1:?$usage}
  limit="${minutes}min"
  shift
fi
export TERAWALK_FUZZ_CORPUS_DIR=${TERAWALK_FUZZ_CORPUS_DIR:-build/fuzz/long-corpus}
mkdir -p build/fuzz
log=build/fuzz/long-runs.log
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(ply obj stl gltf glb tws ifc step package camera_path bcf)
fi
status=0
for t in "${targets[@]}"; do
  if out=$(tools/fuzz.sh $((minutes * 60)) "$t" 2>&1); then result=ok; else result=FAILED; status=1; fi
  line=$(printf '%s\n' "$out" | grep -E "^fuzz_$t:" | tail -1)
  echo "$(date -u +%Y-%m-%dT%H:%M:%SZ) $commit $t $limit jobs=${TERAWALK_FUZZ_JOBS:-1} $result: $line" | tee -a "$log"
  [ "$result" = ok ] || printf '%s\n' "$out" | tail -30
done
exit $status
