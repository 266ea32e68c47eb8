#!/usr/bin/env bash
# The main job, end to end, on a fresh Debian 12 machine: install missing packages, build Release,
# generate a sample plant, inspect it, preprocess it into a package, verify the package, render a
# walkthrough of it headless (EGL; Mesa llvmpipe when there is no GPU) along the plant tour, take
# ray-cast snapshots and write a report under out/.
set -euo pipefail
cd "$(dirname "$0")/.."

triangles=${TERAWALK_DEMO_TRIANGLES:-2000000}
out=${TERAWALK_OUT:-out}

tools/install_deps.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DTERAWALK_BUILD_TESTS=OFF
cmake --build build/release -j "$(nproc)" --target terawalk
tw=build/release/tools/terawalk

mkdir -p "$out"
$tw gen plant --triangles "$triangles" --seed 1 -o "$out/plant.tws" --db "$out/plant.db" \
  --mesh "$out/plant.ply" | tee "$out/gen.txt"
$tw info "$out/plant.tws" | tee "$out/info.txt"
$tw info --json "$out/plant.tws" > "$out/info.json"
$tw preprocess "$out/plant.tws" -o "$out/plant.twk" --db "$out/plant.db" | tee "$out/preprocess.txt"
$tw verify "$out/plant.twk" | tee "$out/verify.txt"
$tw info "$out/plant.twk" | tee "$out/package.txt"
# The walkthrough: LOD renders of the plant tour, every 8th path second, frames and statistics.
$tw -q render "$out/plant.twk" --path data/paths/plant-tour.path --fps 0.125 --size 1280x720 \
  --out "$out/walk" --png | tee "$out/render.txt"
$tw snapshot "$out/plant.tws" --out "$out/plant-outside.png" --azimuth 210 --elevation 30 \
  | tee "$out/snapshot.txt"
# A view from inside the first module's second storey (modules start at the site origin).
$tw snapshot "$out/plant.tws" --out "$out/plant-inside.png" --eye 36,-16,13.7 --target 60,-10,13 \
  --fov 70 | tee -a "$out/snapshot.txt"

# Review: a query over the project database the package names, and the sea-water lines it
# finds selected among the plant with all but the water piping X-rayed.
$tw find "$out/plant.twk" "service = ?1" --param 'sea water' --keys > "$out/sea-water.keys"
$tw -q render "$out/plant.twk" --orbit 4 --size 1280x720 --isolate-layer "piping water" \
  --xray-others --select "$out/sea-water.keys" --out "$out/review" --png | tee "$out/review.txt"

# A quick run of the benchmark suite (small plants, every runtime mode, plots): out/bench/report.md.
$tw -q bench --quick --out "$out/bench" --cache "$out/bench-cache" | tee "$out/bench.txt"

{
  echo "# TeraWalk main job report"
  echo
  echo "Generated $(date -u '+%Y-%m-%d %H:%M UTC') on $(nproc) cores."
  echo
  echo "## Generation"; echo; echo '```'; cat "$out/gen.txt"; echo '```'
  echo "## Scene"; echo; echo '```'; cat "$out/info.txt"; echo '```'
  echo "## Preprocess"; echo; echo '```'; cat "$out/preprocess.txt"; echo '```'
  echo "## Package"; echo; echo '```'; cat "$out/verify.txt" "$out/package.txt"; echo '```'
  echo "## Walkthrough (terawalk render, data/paths/plant-tour.path)"; echo
  echo "Per-frame statistics: walk/frames.csv. Mesh clusters and parametric objects (pipes, beams,"
  echo "vessels, drawn as parametrics: docs/parametrics.md) are both counted; triangles_drawn is the"
  echo "mesh clusters', parametric_triangles the parametrics' run-time meshes'."; echo
  echo '```'; cat "$out/render.txt"; echo '```'
  echo; echo "![walk, frame 2](walk/frame_00002.png)"
  echo; echo "![walk, frame 14](walk/frame_00014.png)"
  echo "## Review (terawalk find, render --xray-others --select)"; echo
  echo "$(wc -l < "$out/sea-water.keys") sea-water line keys from the project database, selected"
  echo "among the plant with all but the water piping X-rayed."; echo
  echo "![review, frame 1](review/frame_00001.png)"
  echo "## Snapshot"; echo; echo '```'; cat "$out/snapshot.txt"; echo '```'
  echo; echo "![outside](plant-outside.png)"
  echo; echo "![inside a deck](plant-inside.png)"
  echo "## Benchmark suite (terawalk bench --quick)"; echo
  echo "Tables, plots and sample frames: [bench/report.md](bench/report.md)."
} > "$out/report.md"
echo "Report written to $out/report.md"
