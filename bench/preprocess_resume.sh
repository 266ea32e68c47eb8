#!/usr/bin/env bash
# Kill-and-resume of `terawalk preprocess`: an uninterrupted run, a run killed (SIGKILL) after
# KILL_AFTER seconds, and `--resume` of it with the same arguments. Prints the three wall times
# and whether the resumed package is byte-identical to the uninterrupted one.
#
#   bench/preprocess_resume.sh [TRIANGLES] [KILL_AFTER_S] [preprocess options...]
#   bench/preprocess_resume.sh 10M 20 --brick-triangles 250000
set -euo pipefail
cd "$(dirname "$0")/.."
triangles=${1:-10M}
kill_after=${2:-20}
shift $(( $# >= 2 ? 2 : $# ))
tw=${TERAWALK:-build/release/tools/terawalk}
[ -x "$tw" ] || { echo "build $tw first (tools/run_main_job.sh does)" >&2; exit 1; }
scratch=$(mktemp -d "${TMPDIR:-/tmp}/terawalk-resume-XXXXXX")
trap 'rm -rf "$scratch"' EXIT

"$tw" gen plant -q --triangles "$triangles" --seed 1 --no-db -o "$scratch/plant.tws" > /dev/null
seconds() { /usr/bin/time -f "%e" -o "$scratch/t" "$@" > "$scratch/out.txt" 2>&1 || true; cat "$scratch/t" | tail -1; }

full=$(seconds "$tw" preprocess -q "$scratch/plant.tws" -o "$scratch/full.twk" "$@")
"$tw" preprocess -q "$scratch/plant.tws" -o "$scratch/resumed.twk" "$@" > /dev/null 2>&1 &
pid=$!
sleep "$kill_after"
kill -KILL "$pid" 2>/dev/null || { echo "the run finished before the kill: lower KILL_AFTER_S" >&2; exit 1; }
wait "$pid" 2>/dev/null || true
resumed=$(seconds "$tw" preprocess -q "$scratch/plant.tws" -o "$scratch/resumed.twk" --resume "$@")
grep -E 'bricks' "$scratch/out.txt" || true
if cmp -s "$scratch/full.twk" "$scratch/resumed.twk"; then same="byte-identical"; else same="DIFFERENT"; fi
echo "plant $triangles ${*}: uninterrupted ${full} s; killed after ${kill_after} s; resume ${resumed} s; package ${same}"
