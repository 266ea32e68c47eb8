#!/usr/bin/env bash
# End-to-end timing of `terawalk gen plant`: median wall time and peak RSS over several runs,
# measured with /usr/bin/time. Output files go to a scratch directory that is removed afterwards.
#
#   bench/gen_plant_e2e.sh [TRIANGLES] [RUNS] [extra gen options...]
#   bench/gen_plant_e2e.sh 10M 5 --mesh plant.ply
set -euo pipefail
cd "$(dirname "$0")/.."
triangles=${1:-10M}
runs=${2:-5}
shift $(( $# >= 2 ? 2 : $# ))
tw=${TERAWALK:-build/release/tools/terawalk}
[ -x "$tw" ] || { echo "build $tw first (tools/run_main_job.sh does)" >&2; exit 1; }
scratch=$(mktemp -d "${TMPDIR:-/tmp}/terawalk-gen-XXXXXX")
trap 'rm -rf "$scratch"' EXIT

extra=()
for arg in "$@"; do
  # Relative output names land in the scratch directory.
  case "$arg" in -*|/*) extra+=("$arg") ;; *) extra+=("$scratch/$arg") ;; esac
done

times=()
peak=0
for ((i = 0; i < runs; ++i)); do
  /usr/bin/time -f "%e %M" -o "$scratch/time" "$tw" gen plant -q --triangles "$triangles" \
    --seed 1 -o "$scratch/plant.tws" "${extra[@]}" > /dev/null
  read -r wall rss < "$scratch/time"
  times+=("$wall")
  (( rss > peak )) && peak=$rss
done
median=$(printf '%s\n' "${times[@]}" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}')
echo "gen plant --triangles $triangles ${*}: median ${median} s over $runs runs (${times[*]}), peak RSS $((peak / 1024)) MiB"
