#!/usr/bin/env bash
# Calibration benchmark of the stated modulus interval (not a test): N pelvis phantom pairs (200 x 160 x 160
# grid of 1 mm voxels, truth on the phantom's finer independent mesh) with moduli drawn log-uniform over
# 30-500 kPa, bladder walls 3-10 mm and rectum walls 2-6 mm, each registered with `biomechreg register`
# (default settings: the rescan interval). Records per pair the fit, the stated estimate, the 68 % / 95 %
# intervals, whether a bound was stated instead, and the resampled moduli.
# Usage: benchmarks/run_calibration_benchmark.sh [N (default 30)] [SEED (default 2026)]
#        DESIGN=table31: instead of random draws, the dissertation's Table 3.1 rows (two scenes x 50..350 kPa)
#        with N realizations (phantom seeds) each; the rows go to table31_runs.csv and are summarized per row
#        (summarize_table31.py: mean and SD of the error, coverage; table31.csv, table31.png).
#        DESIGN=pressure: the same draws, but each lumen filled by a pressure [kPa] instead of a prescribed
#        motion of its wall along the normals: bladder mm / 3.25 and rectum mm / 3.78 (the linear truth's
#        largest wall motion per kPa at 100 kPa), so that the walls also slide as a pressurized lumen's do; the
#        rows record the truth's largest wall motions (truth.json). Default RUNS_NAME calibration_runs_pressure.
#        REGISTER_ARGS="--wall-motion free" adds settings to every register run; PHANTOM_ARGS to every phantom
#        (default "--fixed-grid-shift-voxels 0.5": the fixed scan on its own grid, offset by a random sub-voxel
#        shift from the moving one, as two real scans are); TAG names the run (default "rescan-shifted");
#        RUNS_NAME names the rows' file (default calibration_runs: benchmarks/results/RUNS_NAME.csv);
#        APPEND=1 adds rows to it instead of starting it afresh; START=K skips the
#        draws before pair K (to resume a run). FACET_SCALE=F multiplies the estimation scene's facet size and
#        facet distance by F (the surface refinement of the mesh-convergence study, run_mesh_convergence.sh).
#        SLICE_MM=T: clinical geometry instead of 1 mm voxels: slices of T mm, in-plane spacing drawn per pair from
#        U(0.8, 1.2) mm, the same field of view (200 x 160 x 160 mm); OBLIQUE_DEG=A also rotates each pair's grids
#        about z by an angle drawn from U(-A, A) degrees. Both draws come after the old ones, so SLICE_MM unset keeps
#        the old draws of a seed. The rows record the spacing, the angle and the estimated state's inverted elements;
#        every row also the bladder's volume change between the scans [mL] (report.json label_volume_ml): what the
#        images show of the filling, the observable a calibration covariate needs.
#        FIXED_SURFACES=outlines: each phantom also writes the area fractions of its fixed organs' exact outlines
#        per slice (`phantom --outline-fractions on`) and register takes them as the fixed organs
#        (--fixed-probabilities): what an RTSTRUCT drawn on the fixed scan gives `register` by default.
# Writes benchmarks/results/calibration_runs.csv, calibration.csv (the summary), calibration.png (reliability
# diagram and errors) and prints the tables (benchmarks/summarize_calibration.py); with SLICE_MM the check of the
# thick slices' calibration instead (summarize_slice_calibration.py check) into RUNS_summary/ beside the runs.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
count="${1:-30}"
seed="${2:-2026}"
design="${DESIGN:-random}"
tag="${TAG:-rescan-shifted}"
phantom_args="${PHANTOM_ARGS---fixed-grid-shift-voxels 0.5}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
default_runs=calibration_runs
[ "$design" = table31 ] && default_runs=table31_runs
[ "$design" = pressure ] && default_runs=calibration_runs_pressure
csv="$out/${RUNS_NAME:-$default_runs}.csv"
header="tag,pair,true_E_kPa,bladder_mm,rectum_mm,seed,fit_kPa,estimate_kPa,lo68_kPa,hi68_kPa,lo95_kPa,hi95_kPa,lower_determined,upper_determined,sigma_log_E,log_bias,resamples,curvature_sigma_log_E,prostate_rms_mm,truth_tetrahedra,phantom_s,register_s,bias_corrected,resamples_kPa,quantiles,spacing_mm,rotate_z_deg,inverted_elements,not_determined,bladder_volume_change_ml"
if [ "${APPEND:-0}" = 1 ] && [ -s "$csv" ] && [ "$(head -1 "$csv")" != "$header" ]; then
  echo "$csv has other columns than this script writes: APPEND=1 needs a file it wrote" >&2
  exit 2
fi
if [ "${APPEND:-0}" != 1 ] || [ ! -s "$csv" ]; then
  echo "$header" > "$csv"
fi

# The draws, one line per pair: E bladder rectum seed. Random: reproducible from SEED (Python's Mersenne
# Twister). table31: the dissertation's rows (scenes A, walls 8/4 mm, and B, 5/6 mm, x 50..350 kPa), N
# realizations of each, realization-major so that a run stopped early still has every row.
/usr/bin/python3 - "$count" "$seed" "$design" "${SLICE_MM:-}" "${OBLIQUE_DEG:-0}" > "$work/draws.txt" <<'PY'
import math, random, sys
n, seed, design, slice_mm, oblique = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4], float(sys.argv[5])
rng = random.Random(seed)
if design == "table31":
    pairs = [(E, b, r) for _ in range(n) for b, r in ((8, 4), (5, 6)) for E in range(50, 351, 50)]
else:
    pairs = [(math.exp(rng.uniform(math.log(30), math.log(500))), rng.uniform(3, 10), rng.uniform(2, 6))
             for _ in range(n)]
for k, (E, b, r) in enumerate(pairs):
    inplane, angle = 1.0, 0.0
    if slice_mm:
        inplane = rng.uniform(0.8, 1.2)
        angle = rng.uniform(-oblique, oblique) if oblique > 0 else 0.0
    print(f"{E:.1f} {b:.2f} {r:.2f} {seed * 100 + k + 1} {inplane:.4f} {angle:.2f}")
PY

k=0
while read -r E bladder rectum s inplane angle; do
  k=$((k + 1))
  [ "$k" -lt "${START:-1}" ] && continue
  ph="$work/ph"
  rm -rf "$ph" "$work/reg"
  walls=(--bladder-mm "$bladder" --rectum-mm "$rectum")
  if [ "$design" = pressure ]; then
    walls=(--bladder-kPa "$(awk "BEGIN{print $bladder / 3.25}")" --rectum-kPa "$(awk "BEGIN{print $rectum / 3.78}")")
  fi
  t0=$(date +%s.%N)
  # shellcheck disable=SC2086
  grid=(--size 200,160,160 --spacing 1,1,1)
  if [ -n "${SLICE_MM:-}" ]; then
    grid=(--size "$(awk "BEGIN{printf \"%d,%d,%d\", 200 / $inplane + 0.5, 160 / $inplane + 0.5, 160 / $SLICE_MM + 0.5}")"
          --spacing "$inplane,$inplane,$SLICE_MM" --rotate-z-deg "$angle")
  fi
  outlines=()
  [ "${FIXED_SURFACES:-voxels}" = outlines ] && outlines=(--outline-fractions on)
  "$bin" phantom --scene pelvis "${grid[@]}" --true-E-kPa "$E" "${walls[@]}" "${outlines[@]}" \
    --seed "$s" $phantom_args --out "$ph" > "$work/ph.log" 2>&1 || { echo "phantom failed: pair $k"; tail -3 "$work/ph.log"; continue; }
  fixed_surfaces=()
  if [ "${#outlines[@]}" -gt 0 ]; then
    list=""
    for f in "$ph"/fixed_outline_fraction_*.nrrd; do
      organ="$(basename "$f" .nrrd)"
      list="${list:+$list,}${organ#fixed_outline_fraction_}=$f"
    done
    fixed_surfaces=(--fixed-probabilities "$list")
  fi
  if [ -n "${FACET_SCALE:-}" ]; then
    /usr/bin/python3 -c "import json, sys; p = sys.argv[1]; s = json.load(open(p)); m = s['mesh']
m['facet_size_mm'] *= float(sys.argv[2]); m['facet_distance_mm'] *= float(sys.argv[2]); json.dump(s, open(p, 'w'), indent=1)" \
      "$ph/scene.json" "$FACET_SCALE"
  fi
  t1=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$bin" register --moving-ct "$ph/moving_ct.nrrd" --moving-labels "$ph/moving_labels.nrrd" \
    --fixed-ct "$ph/fixed_ct.nrrd" --fixed-labels "$ph/fixed_labels.nrrd" --scene "$ph/scene.json" \
    --out "$work/reg" "${fixed_surfaces[@]}" ${REGISTER_ARGS:-} > "$work/reg.log" 2>&1 || { echo "register failed: pair $k"; tail -3 "$work/reg.log"; continue; }
  t2=$(date +%s.%N)
  /usr/bin/python3 - "$work/reg/report.json" "$ph/truth.json" "$tag" "$k" "$E" "$bladder" "$rectum" "$s" \
    "$(awk "BEGIN{print $t1 - $t0}")" "$(awk "BEGIN{print $t2 - $t1}")" "${grid[3]}" "$angle" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1])); truth = json.load(open(sys.argv[2]))
num = lambda x: float("nan") if x is None else x  # a modulus not determined has no sigma
tag, k, E, bladder, rectum, s, tph, treg, spacing, angle = sys.argv[3:13]
if "wall_motion_mm" in truth:  # the fillings the truth reached (pressure loads), not the draws
    bladder, rectum = (f'{truth["wall_motion_mm"][w]["max"]:.2f}' for w in ("bladder", "rectum"))
i = rep["youngs_modulus_interval"]["prostate"]
curv = rep.get("youngs_modulus_uncertainty", {}).get("prostate", {}).get("sigma_log_E", "")
tets = truth.get("truth_mesh", {}).get("tetrahedra", "")
volume = rep.get("label_volume_ml", {}).get("bladder")  # what the scans show of the filling (fixed - moving)
bladder_change = f'{volume["fixed"] - volume["moving"]:.2f}' if volume else ""
print(f'{tag},{k},{truth["youngs_modulus_kPa"]["prostate"]:g},{bladder},{rectum},{s},{i["fit_kPa"]:.3f},'
      f'{i["estimate_kPa"]:.3f},{i["interval_68_kPa"][0]:.3f},{i["interval_68_kPa"][1]:.3f},'
      f'{i["interval_95_kPa"][0]:.3f},{i["interval_95_kPa"][1]:.3f},{int(i["lower_end_determined"])},'
      f'{int(i["upper_end_determined"])},{num(i["sigma_log_E"]):.4f},{num(i["log_bias"]):.4f},{len(i["resamples_kPa"])},{curv},'
      f'{rep["surface_distance_mm"]["prostate"]["rms"]:.4f},{tets},{float(tph):.1f},{float(treg):.1f},'
      f'{int(i.get("bias_corrected", True))},{";".join(f"{x:.3f}" for x in i["resamples_kPa"])},'
      f'{i.get("quantiles", "student")},{spacing.replace(",", "x")},{angle},{rep.get("inverted_elements", "")},'
      f'{int(bool(i.get("not_determined_reason")))},{bladder_change}')
PY
  tail -1 "$csv"
done < "$work/draws.txt"

# The earlier runs are kept beside it (calibration_runs_*.csv; docs/history/benchmarks.md): the resimulating bootstrap
# (seed 2026), the rescans on phantoms whose two scans share one grid (2027), the rescans with a sweep each (2028)
# and warm-started at the fit (2029), the last two stated with Student's half-widths and the calibration set of
# the conformal ones; the conformal rescans (2030, calibration_runs.csv) and variants of them; and the
# pressure-filled lumens (DESIGN=pressure, 2031) under the default and under smooth tractions
# (calibration_runs_pressure*.csv, summarized apart in calibration_pressure.csv/png).
if [ "$design" = table31 ]; then
  /usr/bin/python3 "$root/benchmarks/summarize_table31.py" "$csv" "$out"
  exit 0
fi
# Clinical slices state the thick slices' calibration, not rescans: their own check, beside the runs.
if [ -n "${SLICE_MM:-}" ]; then
  mkdir -p "${csv%.csv}_summary"
  /usr/bin/python3 "$root/benchmarks/summarize_slice_calibration.py" check "$csv" "${csv%.csv}_summary"
  exit 0
fi
others=()
for f in "$out"/calibration_runs*.csv; do
  if [ "$f" != "$csv" ]; then others+=("$f"); fi
done
/usr/bin/python3 "$root/benchmarks/summarize_calibration.py" "$csv" "${others[@]}" "$out"
