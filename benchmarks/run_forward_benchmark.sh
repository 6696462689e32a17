#!/usr/bin/env bash
# Forward-pipeline benchmark (not a test): per-stage wall time and peak memory of
# `biomechreg simulate` on the pelvis phantom at three mesh sizes, on a 256x256x100 grid.
# Usage: benchmarks/run_forward_benchmark.sh [RUNS (default 3)] [CELL_SIZES_MM (default "8 4.6 2.7")]
# Writes benchmarks/results/forward_runs.csv (every run), forward.csv (medians), forward.png, and prints a table.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
runs="${1:-3}"
sizes="${2:-8 4.6 2.7}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$bin" phantom --scene pelvis --size 256,256,100 --spacing 0.8,0.8,1.6 --out "$work/phantom" > /dev/null
echo "cell_size_mm,run,tetrahedra,nodes,stage,seconds,peak_rss_MB" > "$out/forward_runs.csv"
for h in $sizes; do
  # The estimation scene with the cell sizes scaled; prostate 0.6x finer, surfaces follow.
  /usr/bin/python3 - "$work/phantom/truth_scene.json" "$work/scene_$h.json" "$h" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); h = float(sys.argv[3])
s["mesh"].update({"cell_size_mm": h, "facet_size_mm": 0.75 * h, "facet_distance_mm": max(0.3, 0.19 * h),
                  "cell_size_per_label_mm": {"prostate": 0.625 * h}, "random_seed": 0})
json.dump(s, open(sys.argv[2], "w"), indent=2)
PY
  for r in $(seq 1 "$runs"); do
    log="$work/run_${h}_$r.log"
    /usr/bin/time -v "$bin" simulate --moving-labels "$work/phantom/moving_labels.nrrd" \
      --moving-ct "$work/phantom/moving_ct.nrrd" --scene "$work/scene_$h.json" --out "$work/sim" > "$log" 2> "$log.time"
    rss=$(awk '/Maximum resident set size/{printf "%.0f", $6/1024}' "$log.time")
    tets=$(grep -o '[0-9]* tetrahedra' "$log" | head -1 | cut -d' ' -f1)
    nodes=$(grep -o '[0-9]* nodes' "$log" | head -1 | cut -d' ' -f1)
    awk -v h="$h" -v r="$r" -v t="$tets" -v n="$nodes" -v m="$rss" '
      /^  stage/ {table=1; next}
      table && NF>=2 && $1!="total" { s=$0; sub(/^ +/, "", s); v=$NF; sub(/ +[0-9.]+$/, "", s); gsub(/,/, ";", s); print h "," r "," t "," n "," s "," v "," m }' \
      "$log" >> "$out/forward_runs.csv"
  done
done
/usr/bin/python3 "$root/benchmarks/summarize_forward.py" "$out"
