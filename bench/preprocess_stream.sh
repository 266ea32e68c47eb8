#!/usr/bin/env bash
# Bounded-memory check of `terawalk preprocess` on a generated plant: two runs with the same
# options under /usr/bin/time (wall time and peak RSS of each), the packages compared byte for
# byte (determinism), `terawalk verify` on the result, and the per-stage summary of the last run.
# With REFERENCE=path/to/other/terawalk, a third run by that binary is compared too (e.g. the
# build before a change that must not alter the output).
#
#   bench/preprocess_stream.sh [TRIANGLES] [preprocess options...]
#   bench/preprocess_stream.sh 50M --memory-budget 2G
#   REFERENCE=/tmp/terawalk-old bench/preprocess_stream.sh 10M
set -euo pipefail
cd "$(dirname "$0")/.."
triangles=${1:-10M}
shift $(( $# >= 1 ? 1 : 0 ))
tw=${TERAWALK:-build/release/tools/terawalk}
[ -x "$tw" ] || { echo "build $tw first (tools/run_main_job.sh does)" >&2; exit 1; }
scratch=$(mktemp -d "${TMPDIR:-/tmp}/terawalk-stream-XXXXXX")
trap 'rm -rf "$scratch"' EXIT

"$tw" gen plant -q --triangles "$triangles" --seed 1 --no-db -o "$scratch/plant.tws" > /dev/null
run() {  # binary output label
  /usr/bin/time -f "%e %M" -o "$scratch/time" "$1" preprocess -q "$scratch/plant.tws" \
    -o "$scratch/$2" "${@:4}" > "$scratch/summary.txt"
  read -r wall rss < "$scratch/time"
  echo "$3: wall ${wall} s, peak RSS $((rss / 1024)) MiB"
}
run "$tw" a.twk "run 1" "$@"
run "$tw" b.twk "run 2" "$@"
cat "$scratch/summary.txt"
if cmp -s "$scratch/a.twk" "$scratch/b.twk"; then echo "two runs: byte-identical"; else echo "two runs: DIFFERENT"; fi
if [ -n "${REFERENCE:-}" ]; then
  run "$REFERENCE" ref.twk "reference $REFERENCE" "$@"
  if cmp -s "$scratch/a.twk" "$scratch/ref.twk"; then echo "reference: byte-identical"; else echo "reference: DIFFERENT"; fi
fi
[ -e "$scratch/a.twk.work" ] && echo "work directory left behind" || true
"$tw" verify -q "$scratch/a.twk" && echo "verify: OK"
echo "preprocess plant $triangles ${*}"
