#!/usr/bin/env bash
# Real CAD meshes end to end: how the DAG shrinks, how fast the preprocessor builds it, and what
# the runtime draws on an orbit against the brute-force reference, model by model.
#
#   TW=build/rel/tools/terawalk RUNS=3 bench/cad_meshes.sh [MODEL...]
#
# Models default to ../shared/data/{duplex-mep,kicad_dsub62,stanford-bunny}.obj (any readable
# mesh file may be named, e.g. a plant PLY from `terawalk gen plant --mesh`). Per model:
#  - preprocess RUNS times with --threads 1 and with all cores, alternating; per run the input
#    triangles per second of reading plus the DAG (stages survey + brick + build bricks) and of
#    the whole preprocess;
#  - verify --json: the DAG's levels, their ratios, root clusters, monotone errors;
#  - a generated orbit (24 frames, 1280x720, tau 1) rendered with LOD and with --reference, RUNS
#    alternating rounds for frame times; one round with PNG frames compared (terawalk compare):
#    the match against the reference, and triangles drawn per pixel the reference covers.
# Prints one JSON object per model (and writes them to $WORK/cad-meshes.json).
set -euo pipefail
cd "$(dirname "$0")/.."
tw=${TW:-build/rel/tools/terawalk}
work=${WORK:-/tmp/tw-cad-meshes}
runs=${RUNS:-3}
frames=${FRAMES:-24}
models=("$@")
if [ ${#models[@]} -eq 0 ]; then
  models=(../shared/data/duplex-mep.obj ../shared/data/kicad_dsub62.obj ../shared/data/stanford-bunny.obj)
fi
mkdir -p "$work"
: > "$work/cad-meshes.json"

for model in "${models[@]}"; do
  name=$(basename "${model%.*}")
  dir="$work/$name"
  rm -rf "$dir"
  mkdir -p "$dir"
  # Preprocess: one thread and all cores, alternating.
  for run in $(seq 1 "$runs"); do
    $tw preprocess --threads 1 "$model" -o "$dir/t1.twk" > "$dir/pre-t1-$run.txt" 2>/dev/null
    $tw preprocess "$model" -o "$dir/model.twk" > "$dir/pre-all-$run.txt" 2>/dev/null
  done
  $tw -q verify --json "$dir/model.twk" > "$dir/verify.json"
  $tw -q info --json "$dir/model.twk" > "$dir/info.json"
  # Orbit: the path generated once and replayed by both modes.
  $tw -q render "$dir/model.twk" --orbit "$frames" --size 1280x720 --tau 1 \
    --save-path "$dir/orbit.path" --out "$dir/lod-png" --png > /dev/null
  $tw -q render "$dir/model.twk" --path "$dir/orbit.path" --size 1280x720 --reference \
    --out "$dir/ref-png" --png > /dev/null
  $tw -q compare "$dir/lod-png" "$dir/ref-png" --json > "$dir/compare.json"
  for run in $(seq 1 "$runs"); do
    $tw -q render "$dir/model.twk" --path "$dir/orbit.path" --size 1280x720 --tau 1 \
      --out "$dir/lod-$run" > /dev/null
    $tw -q render "$dir/model.twk" --path "$dir/orbit.path" --size 1280x720 --reference \
      --out "$dir/ref-$run" > /dev/null
  done
  python3 - "$dir" "$name" "$runs" "$(nproc)" <<'PY' | tee -a "$work/cad-meshes.json"
import json, re, statistics, sys
d, name, runs, cores = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
def stages(path):
    text = open(path).read()
    s = {m.group(1): float(m.group(2)) for m in re.finditer(r"^  (\w[\w ]*?)\s+([\d.]+) s$", text, re.M)}
    tris = int(re.search(r"input\s+(\d+) triangles", text).group(1))
    total = float(re.search(r"total\s+([\d.]+) s", text).group(1))
    read_dag = s.get("survey", 0) + s.get("brick", 0) + s.get("build bricks", 0)
    return tris, read_dag, total, s.get("build bricks", 0)
def rates(kind):
    rows = [stages(f"{d}/pre-{kind}-{r}.txt") for r in range(1, runs + 1)]
    tris = rows[0][0]
    return {"read_dag_s": statistics.median(r[1] for r in rows),
            "dag_s": statistics.median(r[3] for r in rows),
            "total_s": statistics.median(r[2] for r in rows),
            "read_dag_mtris_per_s": statistics.median(tris / r[1] / 1e6 for r in rows),
            "total_mtris_per_s": statistics.median(tris / r[2] / 1e6 for r in rows)}, tris
one, tris = rates("t1")
alln, _ = rates("all")
# The DAG's levels as verify reports them; from info's levels for builds whose verify does not.
dag = json.load(open(f"{d}/verify.json")).get("dag")
if dag is None:
    levels = [{"triangles": l["triangles"] - 0, "max_error": l["error_m"]["max"], "ratio": 1.0}
              for l in json.load(open(f"{d}/info.json"))["levels"]]
    for a, b in zip(levels, levels[1:]): b["ratio"] = b["triangles"] / a["triangles"]
    dag = {"levels": levels, "root_clusters": None,
           "halves": all(0.3 <= b["ratio"] <= 0.65 for a, b in zip(levels, levels[1:]) if a["triangles"] > 1000),
           "errors_monotone": all(b["max_error"] >= a["max_error"] for a, b in zip(levels, levels[1:]))}
cmp = json.load(open(f"{d}/compare.json"))
lod_frames = json.load(open(f"{d}/lod-png/frames.json"))["frames"]
per_px = []
for f, c in zip(lod_frames, cmp["per_frame"]):
    covered = c.get("covered_pixels_b")
    if covered: per_px.append((f["triangles_drawn"] + f.get("parametric_triangles", 0)) / covered)
def med(mode, key):
    return statistics.median(json.load(open(f"{d}/{mode}-{r}/summary.json"))[key] for r in range(1, runs + 1))
lod_ms, ref_ms = med("lod", "median_frame_ms"), med("ref", "median_frame_ms")
out = {
    "model": name, "input_triangles": tris, "cores": cores, "runs": runs,
    "levels": [l["triangles"] for l in dag["levels"]],
    "ratios": [round(l["ratio"], 3) for l in dag["levels"][1:]],
    "max_error_per_level": [l["max_error"] for l in dag["levels"]],
    "halves": dag["halves"], "root_clusters": dag["root_clusters"],
    "errors_monotone": dag["errors_monotone"],
    "threads_1": one, "threads_all": alln,
    "dag_speedup_all_over_1": one["dag_s"] / alln["dag_s"] if alln["dag_s"] else None,
    "orbit_frames": len(lod_frames),
    "median_triangles_per_covered_pixel": statistics.median(per_px) if per_px else None,
    "median_covered_pixels": cmp.get("median_covered_pixels_b"),
    "mean_match_pct": cmp["mean_match_pct"], "worst_match_pct": cmp["worst_match_pct"],
    "median_frame_ms": lod_ms, "reference_median_frame_ms": ref_ms,
    "median_gpu_ms": med("lod", "median_gpu_ms"),
    "speedup_vs_reference": ref_ms / lod_ms if lod_ms else None,
}
print(json.dumps(out))
PY
done
