#!/usr/bin/env bash
# Paging after a teleport: renders data/paths/teleport.path (one frame far outside the plant,
# then a jump into a process module) and reports how many frames the cut needs to converge (no
# ancestor standing in for a missing page), the longest frame while it converges, and the pages
# and bytes loaded on the way.
#   bench/runtime_teleport.sh [TRIANGLES]        (default 10M; WORK=dir RUNS=n)
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-10M}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-runtime-e2e}
runs=${RUNS:-3}
mkdir -p "$work"
plant="$work/plant-$tris"
if [ ! -f "$plant.twk" ]; then
  $tw -q gen plant --triangles "$tris" --seed 1 -o "$plant.tws"
  $tw -q preprocess "$plant.tws" -o "$plant.twk"
fi
for run in $(seq 1 "$runs"); do
  $tw -q render "$plant.twk" --path data/paths/teleport.path --fps 30 --max-frames 240 \
    --out "$work/teleport-$tris-$run" > /dev/null
done
python3 - "$work" "$tris" "$runs" <<'PY'
import csv, statistics, sys
work, tris, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
conv, worst, loaded = [], [], []
for r in range(1, runs + 1):
    rows = list(csv.DictReader(open(f"{work}/teleport-{tris}-{r}/frames.csv")))
    after = rows[1:]  # frame 0 is outside; the jump lands on frame 1
    n = next((i for i, row in enumerate(after) if int(row["ancestor_fallbacks"]) == 0), None)
    conv.append(n if n is not None else float("inf"))
    upto = after[: (n or len(after)) + 1]
    worst.append(max(float(row["frame_ms"]) for row in upto))
    loaded.append(sum(int(row["pages_loaded"]) for row in upto))
    print(f"run {r}: converged after {n} frames, longest frame {worst[-1]:.1f} ms, "
          f"{loaded[-1]} pages loaded on the way")
print(f"median: {statistics.median(conv)} frames to converge, longest frame "
      f"{statistics.median(worst):.1f} ms")
PY
