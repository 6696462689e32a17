#!/usr/bin/env bash
# Which scan's thick slices bias the fitted modulus (a study, not a test)? Each pair is made twice from one
# phantom seed: on 1 mm voxels and with slices of T mm (in-plane 1 mm). The phantom's truth meshes the analytic
# anatomy, so both versions share one truth and differ only in how the labels sample it. Each pair is then
# registered four ways: moving and fixed at 1 mm, moving at 1 mm with the fixed at T mm, moving at T mm with the
# fixed at 1 mm, and both at T mm; the point estimate only (--uncertainty none), so the fit's error is seen
# without the interval. Moduli are drawn log-uniform over 30-200 kPa, fillings as in the calibration benchmark.
# Usage: benchmarks/run_slice_source_study.sh [N (default 8)] [SEED (default 3301)]
#        SLICE_MM=T (default 3); REGISTER_ARGS adds settings to every register; OUT names the result folder
#        (default benchmarks/results/clinical_geometry).
# Writes OUT/slice_source_runs.csv (one row per pair and way) and OUT/slice_source.png, and prints the table
# (benchmarks/summarize_slice_source.py).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
count="${1:-8}"
seed="${2:-3301}"
slice="${SLICE_MM:-3}"
out="${OUT:-$root/benchmarks/results/clinical_geometry}"
mkdir -p "$out"
csv="$out/slice_source_runs.csv"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
echo "pair,seed,true_E_kPa,bladder_mm,rectum_mm,moving_slice_mm,fixed_slice_mm,fit_kPa,log_error,prostate_rms_mm,inverted_elements,register_s" > "$csv"

/usr/bin/python3 - "$count" "$seed" > "$work/draws.txt" <<'PY'
import math, random, sys
n, seed = int(sys.argv[1]), int(sys.argv[2])
rng = random.Random(seed)
for k in range(n):
    E = math.exp(rng.uniform(math.log(30), math.log(200)))
    print(f"{E:.1f} {rng.uniform(3, 10):.2f} {rng.uniform(2, 6):.2f} {seed * 100 + k + 1}")
PY

k=0
while read -r E bladder rectum s; do
  k=$((k + 1))
  for t in 1 "$slice"; do
    rm -rf "$work/ph$t"
    "$bin" phantom --scene pelvis --size "200,160,$(awk "BEGIN{printf \"%d\", 160 / $t + 0.5}")" --spacing "1,1,$t" \
      --true-E-kPa "$E" --bladder-mm "$bladder" --rectum-mm "$rectum" --seed "$s" --fixed-grid-shift-voxels 0.5 \
      --out "$work/ph$t" > "$work/ph.log" 2>&1 || { echo "phantom failed: pair $k, slices $t mm"; tail -3 "$work/ph.log"; exit 1; }
  done
  for way in "1 1" "1 $slice" "$slice 1" "$slice $slice"; do
    read -r m f <<< "$way"
    rm -rf "$work/reg"
    t0=$(date +%s.%N)
    # shellcheck disable=SC2086
    "$bin" register --moving-ct "$work/ph$m/moving_ct.nrrd" --moving-labels "$work/ph$m/moving_labels.nrrd" \
      --fixed-ct "$work/ph$f/fixed_ct.nrrd" --fixed-labels "$work/ph$f/fixed_labels.nrrd" \
      --scene "$work/ph$m/scene.json" --uncertainty none --outputs report --out "$work/reg" ${REGISTER_ARGS:-} \
      > "$work/reg.log" 2>&1 || { echo "register failed: pair $k, moving $m mm, fixed $f mm"; tail -3 "$work/reg.log"; continue; }
    t1=$(date +%s.%N)
    /usr/bin/python3 - "$work/reg/report.json" "$k" "$s" "$E" "$bladder" "$rectum" "$m" "$f" \
      "$(awk "BEGIN{print $t1 - $t0}")" >> "$csv" <<'PY'
import json, math, sys
rep = json.load(open(sys.argv[1]))
k, s, E, bladder, rectum, m, f, treg = sys.argv[2:10]
fit = rep["youngs_modulus_kPa"]["prostate"]
print(f'{k},{s},{E},{bladder},{rectum},{m},{f},{fit:.3f},{math.log(fit / float(E)):.4f},'
      f'{rep["surface_distance_mm"]["prostate"]["rms"]:.4f},{rep.get("inverted_elements", "")},{float(treg):.1f}')
PY
    tail -1 "$csv"
  done
done < "$work/draws.txt"
/usr/bin/python3 "$root/benchmarks/summarize_slice_source.py" "$csv" "$out"
