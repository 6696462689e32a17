#!/usr/bin/env bash
# Marker-driven deformation and delivered dose (dissertation chapter 4; not a test).
#   1. `biomechreg phantom-set`: PAIRS pelvis phantom pairs (default 8; random prostate moduli 50-300 kPa,
#      bladder 3-8 mm, rectum 2-5 mm, seed placement; 1.25 x 1.25 x 2.5 mm voxels), three implanted seeds each,
#      the treatment seeds tracked with 0.5 mm Gaussian noise per axis (landmarks_tracked.csv);
#   2. `biomechreg markers` from the planning scan and the tracked treatment markers only, assuming a population
#      prostate modulus of ASSUMED_E kPa (default 60; the truth is drawn, not known) -> leave-one-out TRE (against
#      the tracked position of the left-out marker, and against its true position, landmarks_fixed.csv), and
#      prostate IoU and D against the true treatment labels, for FEM, rigid alignment and thin-plate spline;
#   3. `biomechreg dose`: a conformal plan on the planning anatomy (PTV = prostate + margin, 78 Gy, 6 mm penumbra)
#      for margins 5, 7, 9, 11, 13 mm, fixed in the room, scored on the planned anatomy, the true treatment anatomy
#      and the anatomies estimated from the markers (FEM, rigid, spline): gEUD of the prostate (a = -10) and of the
#      anterior rectal wall (a = 8);
#   4. benchmarks/summarize_markers.py: tables, paired t-tests and exact Wilcoxon signed-rank tests, PNG.
# Usage: benchmarks/run_marker_benchmark.sh [PAIRS] [SEED]   (about 1.5 min per pair on 2 cores; WORK_DIR keeps the
# phantoms, and a WORK_DIR that already holds them reuses them)
# Another population: PHANTOM_SET_OPTIONS="--prostate-E-range 15,40 --bladder-range 8,15" (phantom-set's options)
# with STUDY=NAME, which writes into benchmarks/results/markers_NAME/ instead. DOSE=off skips step 3 (the markers
# alone take about 15 s per pair; the folder then holds no markers_dose.csv). MARKERS_OPTIONS adds options to `markers` (e.g. "--control-spacing-mm 16").
# Writes benchmarks/results/markers_pairs.csv, markers_dose.csv, markers_summary.md, markers.png.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
pairs="${1:-8}"
seed="${2:-2031}"
assumed="${ASSUMED_E:-60}"
out="$root/benchmarks/results${STUDY:+/markers_$STUDY}"
mkdir -p "$out"
work="${WORK_DIR:-$(mktemp -d)}"
mkdir -p "$work"
[ -n "${WORK_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
log="$work/log.txt"
# A copy of the binary: a rebuild during the run must not change or remove it.
cp "$bin" "$work/biomechreg"
bin="$work/biomechreg"

if [ -f "$work/phantoms/pairs.csv" ]; then
  echo "phantom set: reusing $work/phantoms"
else
  echo "phantom set: $pairs pairs (seed $seed) -> $work/phantoms"
  # shellcheck disable=SC2086 # the options are words on purpose
  "$bin" phantom-set --count "$pairs" --seed "$seed" ${PHANTOM_SET_OPTIONS:-} --out "$work/phantoms" > "$log"
fi
pairs_csv="$out/markers_pairs.csv"
dose_csv="$out/markers_dose.csv"
echo "pair,true_E_kPa,method,loo_rms_mm,fit_max_mm,iou,mean_surface_distance_mm,fem_seconds,loo_true_rms_mm" \
  > "$pairs_csv.tmp"
echo "pair,margin_mm,anatomy,structure,gEUD_Gy,D95_Gy,Dmean_Gy" > "$dose_csv.tmp"

for dir in "$work"/phantoms/*/; do
  name=$(basename "$dir")
  [ -f "$dir/truth.json" ] || continue
  echo "markers: $name"
  # shellcheck disable=SC2086 # MARKERS_OPTIONS are words on purpose
  "$bin" markers --planning-ct "$dir/moving_ct.nrrd" --planning-labels "$dir/moving_labels.nrrd" \
    --scene "$dir/scene.json" --modulus "prostate=$assumed" --planning-markers "$dir/landmarks_moving.csv" \
    --treatment-markers "$dir/landmarks_tracked.csv" --treatment-labels "$dir/fixed_labels.nrrd" \
    --true-treatment-markers "$dir/landmarks_fixed.csv" ${MARKERS_OPTIONS:-} --out "$dir/markers" >> "$log"
  /usr/bin/python3 - "$dir" "$name" >> "$pairs_csv.tmp" <<'PY'
import json, sys
d, name = sys.argv[1], sys.argv[2]
r = json.load(open(d + "/markers/report.json"))
truth = json.load(open(d + "/truth.json"))
E = truth["youngs_modulus_kPa"]["prostate"]
fem_s = sum(v for k, v in r["wall_time_s"].items() if k.startswith("FEM") or k.startswith("mesh"))
for m, v in r["methods"].items():
    print(f"{name},{E},{m},{v['leave_one_out_rms_mm']},{max(v['fit_residual_mm'])},"
          f"{v['intersection_over_union']},{v['mean_surface_distance_mm']},{fem_s if m == 'fem' else 0},"
          f"{v['leave_one_out_true_rms_mm']}")
PY
  [ "${DOSE:-on}" = off ] && continue
  for margin in 5 7 9 11 13; do
    plan="$dir/plan_$margin"
    "$bin" dose --labels "$dir/moving_labels.nrrd" --scene "$dir/scene.json" --plan-margin "$margin" --plot off \
      --out "$plan" >> "$log"
    declare -A anatomy=([planned]="$dir/moving_labels.nrrd" [true]="$dir/fixed_labels.nrrd"
      [fem]="$dir/markers/warped_labels.nrrd" [rigid]="$dir/markers/warped_labels_rigid.nrrd"
      [tps]="$dir/markers/warped_labels_tps.nrrd")
    for a in planned true fem rigid tps; do
      "$bin" dose --dose "$plan/dose.nrrd" --labels "${anatomy[$a]}" --scene "$dir/scene.json" --plot off \
        --out "$plan/$a" >> "$log"
      /usr/bin/python3 - "$plan/$a/dose_metrics.csv" "$name" "$margin" "$a" >> "$dose_csv.tmp" <<'PY'
import csv, sys
path, name, margin, anatomy = sys.argv[1:5]
for row in csv.DictReader(l for l in open(path) if not l.startswith("#")):
    if row["organ"] in ("prostate", "anterior_rectal_wall", "rectum", "bladder"):
        print(f"{name},{margin},{anatomy},{row['organ']},{row['gEUD_Gy']},{row['D95_Gy']},{row['Dmean_Gy']}")
PY
    done
  done
done
mv "$pairs_csv.tmp" "$pairs_csv"
# The folder holds one run: without the dose study, no dose table of an earlier run stays beside these pairs.
if [ "${DOSE:-on}" = off ]; then rm -f "$dose_csv.tmp" "$dose_csv"; else mv "$dose_csv.tmp" "$dose_csv"; fi
/usr/bin/python3 "$root/benchmarks/summarize_markers.py" "$out"
