#!/usr/bin/env bash
# Fidelity of the STEP import: each sample preprocessed as a user would (primitives kept, the
# default meshing) against OpenCASCADE's own BRepMesh of every face at a fine tolerance (0.01 mm,
# everything meshed by it: --cad-primitives off --cad-bspline brepmesh), both rendered at full resolution (--reference) from the same generated
# orbit, then `terawalk compare` (colour within the compare's threshold, 1 px neighbourhood).
#
#   bench/step_fidelity.sh   (TW=binary WORK=dir FRAMES=n SIZE=WxH FINE=metres)
set -euo pipefail
cd "$(dirname "$0")/.."
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-step-fidelity}
frames=${FRAMES:-8}
size=${SIZE:-960x720}
fine=${FINE:-0.00001}
data=../shared/data
mkdir -p "$work"
for name in as1-oc-214 as1_pe_203 Ventilator splinecage; do
  step="$data/$name.stp"
  $tw -q preprocess "$step" -o "$work/$name.twk" > /dev/null 2>&1
  $tw -q preprocess "$step" -o "$work/$name-fine.twk" --cad-primitives off --cad-bspline brepmesh \
    --cad-tolerance "$fine" > /dev/null 2>&1
  # One orbit, generated from the fine package's bounds and saved, so both see the same camera.
  $tw -q render "$work/$name-fine.twk" --orbit "$frames" --size "$size" --reference --png \
    --save-path "$work/$name.path" --out "$work/$name-fine" > /dev/null
  $tw -q render "$work/$name.twk" --path "$work/$name.path" --size "$size" --reference --png \
    --out "$work/$name" > /dev/null
  echo "$name: $(ls -l "$work/$name.twk" | awk '{print $5}') bytes against $(ls -l "$work/$name-fine.twk" | awk '{print $5}') fine"
  $tw -q compare "$work/$name-fine" "$work/$name" 2> /dev/null | grep -E "^match|^shown" | sed 's/^/  /'
done
