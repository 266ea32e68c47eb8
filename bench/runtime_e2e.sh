#!/usr/bin/env bash
# End-to-end runtime benchmark on llvmpipe: the LOD walkthrough against the brute-force reference
# over the same camera path in the same run, then image fidelity between them.
#
#   bench/runtime_e2e.sh [TRIANGLES]          (default 10M; WORK=dir RUNS=n FPS=f SIZE=WxH)
#
# Generates the plant, preprocesses it, renders data/paths/plant-tour.path RUNS times in each
# mode (alternating, so both see the same machine noise), writes PNG frames once per mode, runs
# `terawalk compare`, and prints the medians the issue asks for. Needs a Release build:
#   cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release && ninja -C build/release terawalk
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-10M}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-runtime-e2e}
runs=${RUNS:-3}
fps=${FPS:-2.5}
size=${SIZE:-1280x720}
path=data/paths/plant-tour.path
mkdir -p "$work"
plant="$work/plant-$tris"
if [ ! -f "$plant.twk" ]; then
  $tw -q gen plant --triangles "$tris" --seed 1 -o "$plant.tws"
  $tw -q preprocess "$plant.tws" -o "$plant.twk"
fi
for run in $(seq 1 "$runs"); do
  png=()
  [ "$run" = 1 ] && png=(--png)
  $tw -q render "$plant.twk" --path "$path" --fps "$fps" --size "$size" \
    --out "$work/lod-$tris-$run" "${png[@]}" > /dev/null
  $tw -q render "$plant.twk" --path "$path" --fps "$fps" --size "$size" --reference \
    --out "$work/ref-$tris-$run" "${png[@]}" > /dev/null
done
$tw compare "$work/lod-$tris-1" "$work/ref-$tris-1" --out "$work/diff-$tris" --json \
  > "$work/compare-$tris.json"
python3 - "$work" "$tris" "$runs" <<'PY'
import json, statistics, sys
work, tris, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
def load(mode, run): return json.load(open(f"{work}/{mode}-{tris}-{run}/summary.json"))
lod = [load("lod", r) for r in range(1, runs + 1)]
ref = [load("ref", r) for r in range(1, runs + 1)]
med = lambda rows, key: statistics.median(r[key] for r in rows)
print(f"plant {tris}, {lod[0]['frames']} frames per run, {runs} runs per mode, {lod[0]['renderer']}")
for key in ["median_frame_ms", "median_gpu_ms", "median_cpu_cut_ms", "median_triangles",
            "max_triangles", "first_frame_ms", "peak_rss_bytes", "frames_with_ancestor_fallback"]:
    print(f"  {key:32s} lod {med(lod, key):14.2f}   reference {med(ref, key):14.2f}")
print(f"  speed-up (reference / lod median frame ms, per run): " +
      ", ".join(f"{r['median_frame_ms'] / l['median_frame_ms']:.1f}x" for l, r in zip(lod, ref)))
print(f"  budgets: gpu {lod[0]['gpu_budget_bytes'] / 2**20:.0f} MiB, host {lod[0]['host_budget_bytes'] / 2**20:.0f} MiB")
cmp = json.load(open(f"{work}/compare-{tris}.json"))
print("  fidelity vs reference:", json.dumps(cmp.get("summary", cmp))[:400])
PY
