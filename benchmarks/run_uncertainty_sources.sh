#!/usr/bin/env bash
# What makes up the stated modulus interval (not a test): on pelvis phantom pairs (200 x 160 x 160 grid of
# 1 mm voxels, truth on the phantom's finer independent mesh), `biomechreg register` with the bootstrap
# varying one source at a time -- the estimation mesh (--uncertainty-mesh-jitter), the scan grid (sub-voxel
# shift and small rotation) and the tangential wall motion (--uncertainty-wall-slip) -- and all of them, so
# that each source's spread s = SD(log E*) of the resamples can be set against the fit's actual error.
# Usage: benchmarks/run_uncertainty_sources.sh [RESAMPLES (default 8)]
#        PAIRS="E:bladder:rectum:seed ..." (default three pairs at 45, 110 and 230 kPa); THREADS (default 2)
#        resampling threads; REGISTER_ARGS adds settings to every run.
# Writes benchmarks/results/uncertainty_sources_runs.csv, uncertainty_sources.csv (per source: median s, and
# the fit's |log error|), uncertainty_sources.png and prints the table (summarize_uncertainty_sources.py).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
resamples="${1:-8}"
pairs="${PAIRS:-45:6:4:7001 110:5:3:7002 230:8:4:7003}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
csv="$out/uncertainty_sources_runs.csv"
echo "source,true_E_kPa,bladder_mm,rectum_mm,seed,fit_kPa,sigma_log_E,log_bias,lo95_kPa,hi95_kPa,upper_determined,resamples_kPa,register_s" > "$csv"

none="--uncertainty-mesh-jitter 0 --uncertainty-shift-voxels 0 --uncertainty-rotation-deg 0 --uncertainty-wall-slip 0"
declare -A sources=(
  [mesh]="$none --uncertainty-mesh-jitter 0.15"
  [grid]="$none --uncertainty-shift-voxels 0.5 --uncertainty-rotation-deg 2"
  [slip]="$none --uncertainty-wall-slip 0.3"
  [all]=""
)
for pair in $pairs; do
  IFS=: read -r E bladder rectum s <<< "$pair"
  ph="$work/ph"
  rm -rf "$ph"
  "$bin" phantom --scene pelvis --size 200,160,160 --spacing 1,1,1 --true-E-kPa "$E" --bladder-mm "$bladder" \
    --rectum-mm "$rectum" --seed "$s" --out "$ph" > "$work/ph.log" 2>&1 || { echo "phantom failed: $pair"; tail -3 "$work/ph.log"; continue; }
  for source in mesh grid slip all; do
    rm -rf "$work/reg"
    t0=$(date +%s.%N)
    # shellcheck disable=SC2086
    "$bin" register --moving-ct "$ph/moving_ct.nrrd" --moving-labels "$ph/moving_labels.nrrd" \
      --fixed-ct "$ph/fixed_ct.nrrd" --fixed-labels "$ph/fixed_labels.nrrd" --scene "$ph/scene.json" \
      --out "$work/reg" --resamples "$resamples" --uncertainty-threads "${THREADS:-2}" ${sources[$source]} \
      ${REGISTER_ARGS:-} > "$work/reg.log" 2>&1 || { echo "register failed: $pair $source"; tail -3 "$work/reg.log"; continue; }
    t1=$(date +%s.%N)
    /usr/bin/python3 - "$work/reg/report.json" "$source" "$E" "$bladder" "$rectum" "$s" \
      "$(awk "BEGIN{print $t1 - $t0}")" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1]))
source, E, bladder, rectum, s, t = sys.argv[2:8]
i = rep["youngs_modulus_interval"]["prostate"]
samples = ";".join(f"{x:.3f}" for x in i["resamples_kPa"])
print(f'{source},{E},{bladder},{rectum},{s},{i["fit_kPa"]:.3f},{i["sigma_log_E"]:.4f},{i["log_bias"]:.4f},'
      f'{i["interval_95_kPa"][0]:.3f},{i["interval_95_kPa"][1]:.3f},{int(i["upper_end_determined"])},{samples},'
      f'{float(t):.1f}')
PY
    tail -1 "$csv"
  done
done

/usr/bin/python3 "$root/benchmarks/summarize_uncertainty_sources.py" "$csv" "$out"
