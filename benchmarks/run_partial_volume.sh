#!/usr/bin/env bash
# Binary against fractional fixed segmentations (not a test): pelvis phantom pairs (200 x 160 x 160 grid of
# 1 mm voxels, truth on the phantom's finer independent mesh) written with each objective organ's voxel
# fraction (`phantom --fractions on`), each registered twice with the default bootstrap interval: from the
# fixed label map (the staircase) and from the fractions (`register --fixed-probabilities`, the 0.5 level as
# the sub-voxel surface). Records the error of the stated estimate and the width of the 95 % interval.
# Usage: benchmarks/run_partial_volume.sh [SEEDS (default "9101 9102 9103")]   MODULI (default "100 300") kPa;
#        bladder 6 mm and rectum 4 mm walls; THREADS resampling threads (default 2); PHANTOM_ARGS added to every
#        phantom (default "--fixed-grid-shift-voxels 0.5": the fixed scan on its own grid, as two real scans are).
# Writes benchmarks/results/partial_volume_runs.csv, partial_volume.csv, partial_volume.png and prints the
# table (summarize_partial_volume.py).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
seeds="${1:-9101 9102 9103}"
phantom_args="${PHANTOM_ARGS---fixed-grid-shift-voxels 0.5}"
moduli="${MODULI:-100 300}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
csv="$out/partial_volume_runs.csv"
echo "input,true_E_kPa,seed,fit_kPa,estimate_kPa,lo95_kPa,hi95_kPa,lower_determined,upper_determined,sigma_log_E,prostate_rms_mm,register_s" > "$csv"

for E in $moduli; do
  for s in $seeds; do
    ph="$work/ph"
    rm -rf "$ph"
    "$bin" phantom --scene pelvis --size 200,160,160 --spacing 1,1,1 --true-E-kPa "$E" --bladder-mm 6 \
      --rectum-mm 4 --seed "$s" --fractions on $phantom_args --out "$ph" > "$work/ph.log" 2>&1 || { echo "phantom failed: $E $s"; tail -3 "$work/ph.log"; continue; }
    probabilities=""
    for f in "$ph"/fixed_fraction_*.nrrd; do
      organ="$(basename "$f" .nrrd)"
      probabilities="${probabilities:+$probabilities,}${organ#fixed_fraction_}=$f"
    done
    for input in binary fractional; do
      rm -rf "$work/reg"
      extra=()
      [ "$input" = fractional ] && extra=(--fixed-probabilities "$probabilities")
      t0=$(date +%s.%N)
      "$bin" register --moving-ct "$ph/moving_ct.nrrd" --moving-labels "$ph/moving_labels.nrrd" \
        --fixed-ct "$ph/fixed_ct.nrrd" --fixed-labels "$ph/fixed_labels.nrrd" --scene "$ph/scene.json" \
        --out "$work/reg" --uncertainty-threads "${THREADS:-2}" "${extra[@]}" > "$work/reg.log" 2>&1 ||
        { echo "register failed: $E $s $input"; tail -3 "$work/reg.log"; continue; }
      t1=$(date +%s.%N)
      /usr/bin/python3 - "$work/reg/report.json" "$input" "$E" "$s" "$(awk "BEGIN{print $t1 - $t0}")" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1]))
input_, E, s, t = sys.argv[2:6]
i = rep["youngs_modulus_interval"]["prostate"]
print(f'{input_},{E},{s},{i["fit_kPa"]:.3f},{i["estimate_kPa"]:.3f},{i["interval_95_kPa"][0]:.3f},'
      f'{i["interval_95_kPa"][1]:.3f},{int(i["lower_end_determined"])},{int(i["upper_end_determined"])},'
      f'{i["sigma_log_E"]:.4f},{rep["surface_distance_mm"]["prostate"]["rms"]:.4f},{float(t):.1f}')
PY
      tail -1 "$csv"
    done
  done
done

/usr/bin/python3 "$root/benchmarks/summarize_partial_volume.py" "$csv" "$out"
