#!/usr/bin/env bash
# Review benchmark on llvmpipe: the walk inside the decks of the generated plant with nothing
# hidden, with half the layers hidden (the four piping layers, valves, electrical), and with every
# layer but the equipment X-rayed (`--isolate-layer equipment --xray-others`), alternating run
# after run so every state sees the same machine noise; then the medians and the ratios against
# nothing hidden.
#
#   bench/review_states.sh [TRIANGLES]   (default 10M; WORK=dir RUNS=n FPS=f WALK_FPS=f SIZE=WxH)
#
# Needs a Release build (TW=path/to/terawalk, default build/release/tools/terawalk).
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-10M}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-review}
runs=${RUNS:-3}
fps=${FPS:-0.5}
walk_fps=${WALK_FPS:-10}
size=${SIZE:-1280x720}
path=data/paths/plant-decks.path
mkdir -p "$work"
plant="$work/plant-$tris"
if [ ! -f "$plant.twk" ]; then
  $tw -q gen plant --triangles "$tris" --seed 1 -o "$plant.tws" --db "$plant.db"
  $tw -q preprocess "$plant.tws" -o "$plant.twk" --db "$plant.db" > /dev/null
fi
half=(--hide-layer "piping process" --hide-layer "piping water" --hide-layer "piping utility"
      --hide-layer "piping fire" --hide-layer valves --hide-layer electrical)
xray=(--isolate-layer equipment --xray-others)
for run in $(seq 1 "$runs"); do
  for state in none half xray; do
    extra=()
    [ "$state" = half ] && extra=("${half[@]}")
    [ "$state" = xray ] && extra=("${xray[@]}")
    $tw -q render "$plant.twk" --path "$path" --fps "$fps" --walk-fps "$walk_fps" --size "$size" \
      "${extra[@]}" --out "$work/$state-$tris-$run" > /dev/null
  done
done
python3 - "$work" "$tris" "$runs" <<'PY'
import json, statistics, sys
work, tris, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
def load(state, run): return json.load(open(f"{work}/{state}-{tris}-{run}/summary.json"))
states = {s: [load(s, r) for r in range(1, runs + 1)] for s in ["none", "half", "xray"]}
med = lambda rows, key: statistics.median(r.get(key, float("nan")) for r in rows)
first = states["none"][0]
print(f"plant {tris}, decks, {first['frames']} frames per run, {runs} runs per state, "
      f"{first['renderer']}, {first['width']}x{first['height']}")
for key in ["median_frame_ms", "median_gpu_ms", "median_all_triangles", "median_xray_triangles"]:
    print(f"  {key:20s} " + "  ".join(f"{s} {med(rows, key):10.5g}" for s, rows in states.items()))
for s in ["half", "xray"]:
    ratio = [x["median_frame_ms"] / n["median_frame_ms"] for n, x in zip(states["none"], states[s])]
    print(f"  {s} / none: median frame time " + ", ".join(f"{v:.2f}x" for v in ratio) +
          f" (median {statistics.median(ratio):.2f}x)")
PY
