#!/usr/bin/env bash
# What the ocean and the sky cost: the generated plant's orbit (120 frames, 3 degrees apart) and
# its walk inside the decks, each rendered without the setting and with `--ocean --sky
# --waterline -10` (the plant's hull draws 10 m), alternating run after run so both see the same
# machine noise; then the medians, the ratios and the ocean's triangles a frame.
#
#   bench/environment_cost.sh [TRIANGLES]   (default 10M; WORK=dir RUNS=n FPS=f WALK_FPS=f SIZE=WxH)
#
# Needs an optimized build (TW=path/to/terawalk, default build/release/tools/terawalk).
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-10M}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-environment}
runs=${RUNS:-3}
fps=${FPS:-0.5}
walk_fps=${WALK_FPS:-10}
size=${SIZE:-1280x720}
mkdir -p "$work"
plant="$work/plant-$tris"
if [ ! -f "$plant.twk" ]; then
  $tw -q gen plant --triangles "$tris" --seed 1 -o "$plant.tws" --db "$plant.db"
  $tw -q preprocess "$plant.tws" -o "$plant.twk" --db "$plant.db" > /dev/null
fi
setting=(--ocean --sky --waterline -10)
for run in $(seq 1 "$runs"); do
  for state in off on; do
    extra=()
    [ "$state" = on ] && extra=("${setting[@]}")
    $tw -q render "$plant.twk" --orbit 120 --size "$size" "${extra[@]}" --out "$work/orbit-$state-$run" > /dev/null
    $tw -q render "$plant.twk" --path data/paths/plant-decks.path --fps "$fps" --walk-fps "$walk_fps" \
      --size "$size" "${extra[@]}" --out "$work/decks-$state-$run" > /dev/null
  done
done
python3 - "$work" "$tris" "$runs" <<'PY'
import json, statistics, sys
work, tris, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
load = lambda path, state, run: json.load(open(f"{work}/{path}-{state}-{run}/summary.json"))
first = load("orbit", "off", 1)
print(f"plant {tris}, {runs} runs per state, {first['renderer']}, {first['width']}x{first['height']}")
for path in ["orbit", "decks"]:
    rows = {s: [load(path, s, r) for r in range(1, runs + 1)] for s in ["off", "on"]}
    med = lambda s, key: statistics.median(r[key] for r in rows[s])
    ratios = [b["median_frame_ms"] / a["median_frame_ms"] for a, b in zip(rows["off"], rows["on"])]
    print(f"  {path}: {rows['off'][0]['frames']} frames; median frame {med('off', 'median_frame_ms'):.2f} ms off, "
          f"{med('on', 'median_frame_ms'):.2f} ms on; GPU {med('off', 'median_gpu_ms'):.2f} / "
          f"{med('on', 'median_gpu_ms'):.2f} ms; on / off " + ", ".join(f"{v:.3f}" for v in ratios) +
          f" (median {statistics.median(ratios):.3f}); ocean {med('on', 'median_ocean_triangles'):.0f} "
          f"triangles, {med('on', 'median_ocean_cpu_ms'):.2f} ms CPU a frame; model "
          f"{med('off', 'median_all_triangles'):.0f} triangles")
PY
