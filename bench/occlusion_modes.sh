#!/usr/bin/env bash
# Occlusion benchmark on llvmpipe: the same walk inside the decks rendered with --occlusion off,
# hzb and pvs, alternating run after run so every mode sees the same machine noise, then the
# medians and ratios the occlusion issue asks for, and each mode's pixel loss against the same
# cut drawn without occlusion (--check-occlusion).
#
#   bench/occlusion_modes.sh [TRIANGLES]   (default 10M; WORK=dir RUNS=n FPS=f SIZE=WxH)
#
# The plant is generated with every object tessellated (`gen plant --mesh`): its deck plates,
# walls and vessels are parametric boxes and revolutions in the .tws, which the runtime does not
# draw yet, so only the tessellated plant has floors and walls to hide things behind. Needs a
# Release build:
#   cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release && ninja -C build/release terawalk
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-10M}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-occlusion}
runs=${RUNS:-3}
fps=${FPS:-2}
size=${SIZE:-1280x720}
path=data/paths/plant-decks.path
mkdir -p "$work"
plant="$work/plant-mesh-$tris"
if [ ! -f "$plant.twk" ]; then
  $tw -q gen plant --triangles "$tris" --seed 1 --no-db -o "$plant.tws" --mesh "$plant.ply"
  /usr/bin/time -v $tw preprocess "$plant.ply" -o "$plant.twk" > "$work/preprocess-$tris.txt" 2>&1
fi
for run in $(seq 1 "$runs"); do
  for mode in off hzb pvs; do
    extra=()
    [ "$mode" != off ] && extra=(--check-occlusion)
    $tw -q render "$plant.twk" --path "$path" --fps "$fps" --size "$size" --occlusion "$mode" \
      "${extra[@]}" --out "$work/$mode-$tris-$run" > /dev/null
  done
done
python3 - "$work" "$tris" "$runs" <<'PY'
import json, statistics, sys
work, tris, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
def load(mode, run): return json.load(open(f"{work}/{mode}-{tris}-{run}/summary.json"))
modes = {m: [load(m, r) for r in range(1, runs + 1)] for m in ["off", "hzb", "pvs"]}
med = lambda rows, key: statistics.median(r.get(key, float("nan")) for r in rows)
first = modes["off"][0]
print(f"plant {tris} (tessellated), {first['frames']} frames per run, {runs} runs per mode, "
      f"{first['renderer']}, {first['width']}x{first['height']}")
keys = ["median_frame_ms", "median_gpu_ms", "median_triangles", "median_occlusion_culled",
        "median_hzb_build_ms", "median_hzb_test_ms", "occlusion_lost_share",
        "occlusion_max_frame_lost_share"]
for key in keys:
    print(f"  {key:32s} " + "  ".join(f"{m} {med(rows, key):14.6g}" for m, rows in modes.items()))
for m in ["hzb", "pvs"]:
    ft = [o["median_frame_ms"] / x["median_frame_ms"] for o, x in zip(modes["off"], modes[m])]
    tr = [o["median_triangles"] / max(x["median_triangles"], 1) for o, x in zip(modes["off"], modes[m])]
    print(f"  off / {m}: median frame time " + ", ".join(f"{v:.2f}x" for v in ft) +
          f" (median {statistics.median(ft):.2f}x); triangles " +
          ", ".join(f"{v:.2f}x" for v in tr) + f" (median {statistics.median(tr):.2f}x)")
PY
