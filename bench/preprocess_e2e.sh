#!/usr/bin/env bash
# End-to-end timing of `terawalk preprocess` on a generated plant: median wall time and peak RSS
# over several runs (/usr/bin/time), the package size per input triangle, and `terawalk verify`.
#
#   bench/preprocess_e2e.sh [TRIANGLES] [RUNS] [preprocess options...]
#   bench/preprocess_e2e.sh 10M 3
#   bench/preprocess_e2e.sh 50M 1 --memory-budget 2G
set -euo pipefail
cd "$(dirname "$0")/.."
triangles=${1:-10M}
runs=${2:-3}
shift $(( $# >= 2 ? 2 : $# ))
tw=${TERAWALK:-build/release/tools/terawalk}
[ -x "$tw" ] || { echo "build $tw first (tools/run_main_job.sh does)" >&2; exit 1; }
scratch=$(mktemp -d "${TMPDIR:-/tmp}/terawalk-pre-XXXXXX")
trap 'rm -rf "$scratch"' EXIT

"$tw" gen plant -q --triangles "$triangles" --seed 1 --no-db -o "$scratch/plant.tws" > /dev/null
times=()
peak=0
for ((i = 0; i < runs; ++i)); do
  /usr/bin/time -f "%e %M" -o "$scratch/time" "$tw" preprocess -q "$scratch/plant.tws" \
    -o "$scratch/plant.twk" "$@" > "$scratch/summary.txt"
  read -r wall rss < "$scratch/time"
  times+=("$wall")
  (( rss > peak )) && peak=$rss
done
median=$(printf '%s\n' "${times[@]}" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}')
cat "$scratch/summary.txt"
"$tw" verify -q "$scratch/plant.twk"
echo "preprocess plant $triangles ${*}: median ${median} s over $runs runs (${times[*]}), peak RSS $((peak / 1024)) MiB"
