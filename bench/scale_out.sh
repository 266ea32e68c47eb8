#!/usr/bin/env bash
# Scale-out preprocessing on this machine: the generated plant preprocessed by one process
# (`terawalk preprocess`), by `mpirun -np 1` and by `mpirun -np 2` (`preprocess --mpi`), in
# alternating rounds so all see the same machine noise; then each brick as a process of its own
# (`preprocess plan`, one `preprocess brick --job J` per brick, `preprocess merge`, as Slurm runs
# them), for each brick's time and peak memory and the merge's. Every package is compared with
# the one-process package byte for byte.
#
#   bench/scale_out.sh [TRIANGLES]   (default 50M; WORK=dir RUNS=n BRICK_TRIANGLES=n)
#
# Needs an optimized build (TW=path/to/terawalk, default build/release/tools/terawalk), mpirun and
# GNU time.
set -euo pipefail
cd "$(dirname "$0")/.."
tris=${1:-50M}
tw=$(realpath "${TW:-build/release/tools/terawalk}")
work=${WORK:-/tmp/tw-scale-out}
runs=${RUNS:-3}
brick_triangles=${BRICK_TRIANGLES:-1000000}
mkdir -p "$work"
plant="$work/plant-$tris.tws"
[ -f "$plant" ] || $tw -q gen plant --triangles "$tris" --seed 1 --no-db -o "$plant"
options=(--brick-triangles "$brick_triangles")
# mpirun binds each rank to one core by default (two ranks or fewer): a rank then runs all its
# threads there, and the merge's visibility rays at half speed on two cores.
mpirun=(mpirun --oversubscribe --allow-run-as-root --bind-to none)
timed() {  # timed NAME COMMAND...: wall seconds and peak KiB into $work/NAME.time
  /usr/bin/time -f "%e %M" -o "$work/$1.time" "${@:2}" > "$work/$1.log" 2>&1
}
for run in $(seq 1 "$runs"); do
  timed "one-$run" "$tw" -q preprocess "$plant" -o "$work/one.twk" "${options[@]}"
  timed "np1-$run" "${mpirun[@]}" -np 1 "$tw" -q preprocess --mpi "$plant" -o "$work/np1.twk" "${options[@]}"
  timed "np2-$run" "${mpirun[@]}" -np 2 "$tw" -q preprocess --mpi "$plant" -o "$work/np2.twk" "${options[@]}"
  cmp "$work/one.twk" "$work/np1.twk" && cmp "$work/one.twk" "$work/np2.twk"
done
# Each step a process of its own.
rm -rf "$work/steps.work"
timed plan "$tw" -q preprocess plan "$plant" --work "$work/steps.work" "${options[@]}"
jobs=$(sed -n 's/^plan: \([0-9][0-9]*\) brick jobs.*/\1/p' "$work/plan.log")
for j in $(seq 0 $((jobs - 1))); do
  timed "brick-$j" "$tw" -q preprocess brick --work "$work/steps.work" --job "$j"
done
timed merge "$tw" -q preprocess merge --work "$work/steps.work" -o "$work/steps.twk"
cmp "$work/one.twk" "$work/steps.twk"
python3 - "$work" "$tris" "$runs" "$jobs" "$brick_triangles" <<'PY'
import re, statistics, sys
work, tris, runs, jobs, brick_triangles = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
def timing(name):
    wall, kib = open(f"{work}/{name}.time").read().split()[-2:]
    return float(wall), int(kib) / 1024
print(f"plant {tris}, {jobs} bricks of at most {brick_triangles} triangles, {runs} rounds; every package byte-identical")
rows = {}
for mode in ("one", "np1", "np2"):
    walls = [timing(f"{mode}-{r}")[0] for r in range(1, runs + 1)]
    rows[mode] = statistics.median(walls)
    print(f"{mode:4s} median {rows[mode]:8.2f} s  runs {', '.join(f'{w:.2f}' for w in walls)}")
print(f"speed-up np2 against np1: {rows['np1'] / rows['np2']:.2f}x; against one process: {rows['one'] / rows['np2']:.2f}x")
line = re.compile(r"brick (\d+) of \d+: (\d+) triangles, (\d+) clusters, ([0-9.]+) s, peak ([0-9.]+) MiB")
bricks = []
for j in range(jobs):
    m = line.search(open(f"{work}/brick-{j}.log").read())
    wall, peak = timing(f"brick-{j}")
    bricks.append((int(m.group(1)), int(m.group(2)), float(m.group(4)), wall, peak))
plan_wall, plan_peak = timing("plan")
merge_wall, merge_peak = timing("merge")
print(f"plan  {plan_wall:.2f} s, peak {plan_peak:.0f} MiB; merge {merge_wall:.2f} s, peak {merge_peak:.0f} MiB")
print("brick triangles build_s process_s peak_MiB")
for b in bricks:
    print(f"{b[0]:5d} {b[1]:9d} {b[2]:7.2f} {b[3]:9.2f} {b[4]:8.0f}")
builds = [b[2] for b in bricks]
print(f"bricks: build {sum(builds):.1f} s in all, median {statistics.median(builds):.2f} s, largest {max(builds):.2f} s;"
      f" process median {statistics.median(b[3] for b in bricks):.2f} s; peak median {statistics.median(b[4] for b in bricks):.0f} MiB, largest {max(b[4] for b in bricks):.0f} MiB;"
      f" {sum(b[1] for b in bricks) / sum(builds) / 1e6:.3f} M triangles/s a brick process")
PY
