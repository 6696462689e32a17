#!/usr/bin/env bash
# Scaling by replay (not a test): register on the demo pair, point estimate (--uncertainty none) and with its
# interval (4 rescans), each RUNS times on one core (taskset -c 0, --threads 1) and on two (taskset -c 0,1,
# --threads 2, with --task-trace), alternating; every two-core trace replayed on 1, 2, 4, 8 and 16 workers
# (benchmarks/replay_task_trace.py). The replay on one worker is checked against the measured one-core runs.
# Usage: benchmarks/run_scaling_replay.sh [RUNS (default 3)]
# Writes benchmarks/results/scaling/{scaling_runs.csv, scaling.csv, scaling_breakdown.csv, scaling.png} and the
# first run's two traces (trace_point_1.csv.gz, trace_interval_1.csv.gz), and prints the tables.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
runs="${1:-3}"
out="$root/benchmarks/results/scaling"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The demo's pair (biomechreg with no argument makes the same).
"$bin" phantom --scene pelvis --size 200,160,160 --spacing 1,1,1 --bladder-mm 8 --rectum-mm 4 --true-E-kPa 100 \
  --out "$work/pair" > /dev/null
p="$work/pair"
echo "mode,run,threads,wall_s,trace" > "$out/scaling_runs.csv"
for r in $(seq 1 "$runs"); do
  for mode in point interval; do
    extra=(); [ "$mode" = point ] && extra=(--uncertainty none)
    for t in 1 2; do
      cores=0; [ "$t" = 2 ] && cores=0,1
      trace="$work/trace_${mode}_$r.csv"
      traced=(); [ "$t" = 2 ] && traced=(--task-trace "$trace")
      start=$(date +%s.%N)
      taskset -c "$cores" "$bin" --threads "$t" "${traced[@]}" register --moving-labels "$p/moving_labels.nrrd" \
        --fixed-labels "$p/fixed_labels.nrrd" --moving-ct "$p/moving_ct.nrrd" --fixed-ct "$p/fixed_ct.nrrd" \
        --scene "$p/scene.json" --outputs report "${extra[@]}" --out "$work/reg_${mode}_${t}" > /dev/null
      end=$(date +%s.%N)
      echo "$mode,$r,$t,$(awk -v a="$start" -v b="$end" 'BEGIN{printf "%.3f", b - a}'),$([ "$t" = 2 ] && basename "$trace" || true)" >> "$out/scaling_runs.csv"
    done
  done
done
/usr/bin/python3 "$root/benchmarks/summarize_scaling.py" "$out" "$work" | tee "$out/scaling_table.txt"
# One trace of each kind kept for reading (gzipped; replay_task_trace.py reads it as it is).
rm -f "$out"/trace_*.csv.gz
gzip -c "$work/trace_point_1.csv" > "$out/trace_point_1.csv.gz"
gzip -c "$work/trace_interval_1.csv" > "$out/trace_interval_1.csv.gz"
