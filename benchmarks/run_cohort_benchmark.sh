#!/usr/bin/env bash
# The cohort workflow end to end on this machine (not a test): a phantom cohort of PATIENTS x FRACTIONS
# (`biomechreg phantom-cohort`: own anatomy, T-stage T1-T3 and stage-linked prostate modulus per patient; GRID,
# default 100 x 80 x 80 voxels of 2 mm, truth mesh scale 0.75), then `biomechreg cohort` through Snakemake on
# CORES cores (one registration per job, 1 thread each; REGISTER_OPTIONS, default "--uncertainty none": the rescan
# interval costs 8 more estimations per pair). Measures the workflow's wall time, its CPU utilisation
# ((user + sys) / (wall x cores), from /usr/bin/time), the time and peak memory of every job, and compares the
# recovered statistics with the truth's.
# Usage: benchmarks/run_cohort_benchmark.sh [PATIENTS (10)] [FRACTIONS (6)]    env: CORES (2), SEED (2026), KEEP=DIR
# Writes benchmarks/results/cohort_jobs.csv, cohort_patients_vs_truth.csv, cohort_benchmark.csv,
# cohort_benchmark.png and prints the table (summarize_cohort.py).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
patients="${1:-10}"
fractions="${2:-6}"
cores="${CORES:-2}"
seed="${SEED:-2026}"
grid="${GRID:---size 100,80,80 --spacing 2,2,2}"
register_options="${REGISTER_OPTIONS:---uncertainty none}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="${KEEP:-$(mktemp -d)}"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work"

start=$(date +%s.%N)
"$bin" phantom-cohort --out "$work/data" --patients "$patients" --fractions "$fractions" --seed "$seed" $grid \
  --truth-mesh-scale 0.75 > "$work/phantom.log" 2>&1
phantom_s=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}')
echo "phantom cohort: ${phantom_s} s"

/usr/bin/time -f "%e %U %S %M" -o "$work/time.txt" "$bin" cohort --cohort "$work/data/cohort.csv" \
  --out "$work/study" --cores "$cores" --register-options "$register_options" > "$work/cohort.log" 2>&1 ||
  { echo "cohort run failed"; tail -20 "$work/cohort.log"; }
read -r wall user sys _ < "$work/time.txt"

# Per job: its wall time (the report's total) and peak memory (the log's last line).
echo "patient,fraction,wall_s,peak_rss_MB" > "$out/cohort_jobs.csv"
for log in "$work"/study/logs/P*/F*.log; do
  f=$(basename "$log" .log); p=$(basename "$(dirname "$log")")
  t=$(awk '$1 == "total" {print $2}' "$log")
  m=$(sed -n 's/^peak memory (resident): \([0-9]*\) MB.*/\1/p' "$log")
  echo "$p,$f,$t,$m" >> "$out/cohort_jobs.csv"
done
echo "patients,fractions,cores,phantom_s,workflow_wall_s,user_s,sys_s,register_options" > "$out/cohort_benchmark.csv"
echo "$patients,$fractions,$cores,$phantom_s,$wall,$user,$sys,$register_options" >> "$out/cohort_benchmark.csv"
cp "$work/study/cohort_patients.csv" "$work/study/cohort_correlations.csv" "$work/study/cohort_report.md" "$out/"
cp "$work/data/truth.csv" "$out/cohort_truth.csv"
cp "$work/data/truth_correlations.csv" "$out/cohort_truth_correlations.csv"
/usr/bin/python3 "$root/benchmarks/summarize_cohort.py" "$out"
