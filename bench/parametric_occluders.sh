#!/usr/bin/env bash
# Parametric occluders on the generated plant (.tws: decks, walls and vessels are parametric
# boxes, extrusions and revolutions): the same plant preprocessed with parametric clusters as
# visibility candidates (the default) and without (`--parametric-occluders off`), then the decks
# walk rendered from each package with --occlusion hzb and pvs, alternating run after run, each
# frame checked against the same cut drawn unculled (--check-occlusion). Prints per package and
# mode the medians of frame time, triangles, parametric instances, clusters culled and pixels
# lost, and the ratios of the two packages side by side.
#
#   bench/parametric_occluders.sh [TRIANGLES]   (default 10M; TW=binary WORK=dir RUNS=n FPS=f SIZE=WxH)
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-10M}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-parametric-occluders}
runs=${RUNS:-3}
fps=${FPS:-0.5}
size=${SIZE:-1280x720}
path=data/paths/plant-decks.path
mkdir -p "$work"
plant="$work/plant-$tris"
[ -f "$plant.tws" ] || $tw -q gen plant --triangles "$tris" --seed 1 --no-db -o "$plant.tws"
for occluders in on off; do
  [ -f "$plant-$occluders.twk" ] ||
    $tw preprocess "$plant.tws" -o "$plant-$occluders.twk" --parametric-occluders "$occluders" \
      > "$work/preprocess-$occluders.txt"
  grep -E "candidates|occluders|parametric:" "$work/preprocess-$occluders.txt" | sed "s/^/$occluders: /"
done
for run in $(seq 1 "$runs"); do
  for mode in hzb pvs; do
    for occluders in on off; do
      $tw -q render "$plant-$occluders.twk" --path "$path" --fps "$fps" --size "$size" \
        --occlusion "$mode" --check-occlusion --out "$work/$mode-$occluders-$run" > /dev/null
    done
  done
done
python3 - "$work" "$tris" "$runs" <<'PY'
import json, statistics, sys
work, tris, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
def load(mode, occ, run): return json.load(open(f"{work}/{mode}-{occ}-{run}/summary.json"))
first = load("hzb", "on", 1)
print(f"plant {tris} (.tws, parametric), decks path, {first['frames']} frames per run, {runs} runs, "
      f"{first['renderer']}, {first['width']}x{first['height']}")
keys = ["median_frame_ms", "median_gpu_ms", "median_triangles", "median_parametric_instances_drawn",
        "median_occlusion_culled", "occlusion_lost_share", "occlusion_max_frame_lost_share"]
for mode in ["hzb", "pvs"]:
    rows = {o: [load(mode, o, r) for r in range(1, runs + 1)] for o in ["on", "off"]}
    print(f" {mode}")
    for key in keys:
        med = {o: statistics.median(r.get(key, float("nan")) for r in rows[o]) for o in rows}
        ratio = med["off"] / med["on"] if med["on"] else float("nan")
        print(f"  {key:36s} with {med['on']:14.6g}  without {med['off']:14.6g}  without/with {ratio:.2f}")
PY
