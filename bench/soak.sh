#!/usr/bin/env bash
# Soak: a long random walk (teleports, fast flights, turns in place, walks) through a package
# with a GPU budget small enough that pages are evicted every few frames, logged every INTERVAL
# seconds (render --soak-interval: no per-frame log, so the process's own memory is what is
# measured). Reports the slope of resident memory after the first tenth of the run (MiB per
# hour), the pager's queues at the start and the end, evictions, loads, the share of frames
# drawing a coarser ancestor for a missing page, and frame times; draws RSS and the queues over
# time with gnuplot.
#   bench/soak.sh [MINUTES] [PACKAGE]   (default 60 minutes, duplex-mep preprocessed with --up y)
#   env: TW=terawalk binary, WORK=dir, GPU_BUDGET=4M, INTERVAL=10, SIZE=640x360, PLOT=out.png
set -euo pipefail
cd "$(dirname "$0")/.."
minutes=${1:-60}
package=${2:-}
tw=${TW:-build/release/tools/terawalk}
work=${WORK:-/tmp/tw-soak}
budget=${GPU_BUDGET:-4M}
interval=${INTERVAL:-10}
size=${SIZE:-640x360}
mkdir -p "$work"
if [ -z "$package" ]; then
  package="$work/duplex-mep.twk"
  [ -f "$package" ] || $tw -q preprocess ../shared/data/duplex-mep.obj --up y -o "$package"
fi
seconds=$(awk "BEGIN { print int($minutes * 60) }")
# Frames for 300 a second (llvmpipe draws duplex-mep at about 210 at 640x360); --max-seconds
# ends the run, or the path does on a faster machine (the report says how long it ran).
frames=$(( seconds * 300 < 10000000 ? seconds * 300 : 10000000 ))
out="$work/soak-${minutes}m"
rm -rf "$out"
$tw -q render "$package" --random-walk "$frames" --seed 7 --max-seconds "$seconds" \
  --gpu-budget "$budget" --evict-after 2 --size "$size" --soak-interval "$interval" \
  --out "$out" > "$out.summary.json"
python3 - "$out/soak.csv" "$minutes" "$budget" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
mib = lambda b: float(b) / 2**20
t = [float(r["wall_s"]) for r in rows]
rss = [mib(r["rss_bytes"]) for r in rows]
skip = max(1, len(rows) // 10)
xs, ys = t[skip:], rss[skip:]
n = len(xs)
mx, my = sum(xs) / n, sum(ys) / n
slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / max(sum((x - mx) ** 2 for x in xs), 1e-9)
frames = sum(int(r["frames"]) for r in rows)
def tenth(col, first):
    part = rows[skip:2 * skip] if first else rows[-skip:]
    return max(int(r[col]) for r in part)
queue = lambda r: int(r["pages_requested_max"]) + int(r["pages_loading_max"]) + int(r["pages_ready_max"])
medians = sorted(float(r["frame_ms_median"]) for r in rows)
print(f"soak {sys.argv[2]} min, GPU budget {sys.argv[3]}: {frames} frames in {t[-1]:.0f} s "
      f"({frames / t[-1]:.0f} a second), {len(rows)} intervals")
print(f"  RSS: {rss[skip]:.1f} MiB after the first tenth, {rss[-1]:.1f} MiB at the end, "
      f"largest {max(mib(r['rss_max_bytes']) for r in rows):.1f} MiB; slope {slope * 3600:+.2f} MiB per hour")
print(f"  pager queue (requested + loading + ready, largest in an interval): second tenth "
      f"{max(queue(r) for r in rows[skip:2 * skip])}, last tenth {max(queue(r) for r in rows[-skip:])}; "
      f"largest {max(queue(r) for r in rows)}")
print(f"  pages loaded {sum(int(r['pages_loaded']) for r in rows)}, evicted "
      f"{sum(int(r['pages_evicted']) for r in rows)}; frames evicting "
      f"{100.0 * sum(int(r['frames_with_eviction']) for r in rows) / frames:.1f} %, drawing an ancestor "
      f"for a missing page {100.0 * sum(int(r['frames_with_fallback']) for r in rows) / frames:.1f} %; "
      f"page load errors {rows[-1]['page_load_errors']}")
print(f"  frame time: median of the intervals' medians {medians[len(medians) // 2]:.2f} ms, "
      f"largest interval p99 {max(float(r['frame_ms_p99']) for r in rows):.1f} ms, "
      f"longest frame {max(float(r['frame_ms_max']) for r in rows):.1f} ms")
PY
if [ -n "${PLOT:-}" ]; then
  gnuplot <<GP
set terminal pngcairo size 900,420 noenhanced
set output "$PLOT"
set datafile separator ","
set key top left
set xlabel "minutes"
set ylabel "resident memory, MiB"
set y2label "pager queue, pages"
set ytics nomirror
set y2tics
set yrange [0:*]
set y2range [0:*]
set title "terawalk render: $minutes-minute random walk, GPU budget $budget, evict after 2 frames"
plot "$out/soak.csv" every ::1 using (\$1/60):(\$7/1048576) with lines lw 2 title "RSS", \
     "$out/soak.csv" every ::1 using (\$1/60):(\$11+\$12+\$13) axes x1y2 with lines title "queue (requested + loading + ready, max per interval)"
GP
  echo "plot: $PLOT"
fi
