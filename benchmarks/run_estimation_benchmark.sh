#!/usr/bin/env bash
# Elasticity-estimation benchmark after the dissertation (not a test): recovered prostate modulus,
# relative error and wall time of `biomechreg register` on pelvis phantoms whose fixed scans were made
# on a finer, independent mesh. Phantoms on a 200 x 160 x 160 grid of 1 mm voxels.
#   table31: two scenes (bladder/rectum wall displacements 8/4 mm and 5/6 mm) x true E 50..350 kPa
#            (surrounding tissue 10 kPa, nu 0.40 prostate / 0.35 tissue; dissertation Table 3.1)
#   poisson: true prostate nu 0.30..0.49 while the estimation assumes 0.40, true E 50/100/150 (Fig. 3.6)
#   tumour:  a 100 kPa tumour of 10/25/50/75 % of a 50 kPa prostate, recovered as one homogeneous modulus
#            (Table 3.4); the error is against the volume-weighted mean modulus
#   mesh:    estimation mesh 1.5x / 1x / 0.75x the default sizes, RUNS repeats each: error against run time
# Usage: benchmarks/run_estimation_benchmark.sh [RUNS (default 3)]   (STUDIES="table31 poisson mesh")
#        APPEND=1 adds the rows to the existing estimation_runs.csv instead of starting it afresh.
# Writes benchmarks/results/estimation_runs.csv, estimation.csv (medians), estimation.png and prints tables.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
runs="${1:-3}"
studies="${STUDIES:-table31 poisson tumour mesh}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
csv="$out/estimation_runs.csv"
if [ "${APPEND:-0}" != 1 ] || [ ! -s "$csv" ]; then
  echo "study,scene,true_E_kPa,true_nu,mesh_scale,run,recovered_E_kPa,relative_error,tetrahedra,estimation_s,total_s,prostate_rms_mm,identifiable,tumour_fraction,sigma_log_E" > "$csv"
fi

# run STUDY SCENE E NU SCALE RUN BLADDER RECTUM [TUMOUR_FRACTION]
run() {
  local study=$1 scene=$2 E=$3 nu=$4 scale=$5 r=$6 bladder=$7 rectum=$8 tumour=${9:-0}
  local ph="$work/ph_${scene}_${E}_${nu}_${tumour}"
  if [ ! -d "$ph" ]; then
    "$bin" phantom --scene pelvis --size 200,160,160 --spacing 1,1,1 --true-E-kPa "$E" --true-nu "$nu" \
      --bladder-mm "$bladder" --rectum-mm "$rectum" --tumour-fraction "$tumour" --out "$ph" > /dev/null
  fi
  /usr/bin/python3 - "$ph/scene.json" "$work/scene.json" "$scale" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); f = float(sys.argv[3]); m = s["mesh"]
for k in ("cell_size_mm", "facet_size_mm", "facet_distance_mm"):
    m[k] *= f
m["cell_size_per_label_mm"] = {k: v * f for k, v in m.get("cell_size_per_label_mm", {}).items()}
json.dump(s, open(sys.argv[2], "w"), indent=2)
PY
  "$bin" register --moving-ct "$ph/moving_ct.nrrd" --moving-labels "$ph/moving_labels.nrrd" \
    --fixed-ct "$ph/fixed_ct.nrrd" --fixed-labels "$ph/fixed_labels.nrrd" --scene "$work/scene.json" \
    --out "$work/reg" > "$work/reg.log" 2>&1 || { echo "register failed: $study $scene $E $nu $scale"; tail -3 "$work/reg.log"; return; }
  /usr/bin/python3 - "$work/reg/report.json" "$ph/truth.json" "$study" "$scene" "$nu" "$scale" "$r" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1])); truth = json.load(open(sys.argv[2])); study, scene, nu, scale, r = sys.argv[3:8]
# Reference modulus: the prostate's, or with a tumour the volume-weighted mean of prostate and tumour.
f = truth.get("tumour_volume_fraction", 0.0); moduli = truth["youngs_modulus_kPa"]
E = (1 - f) * moduli["prostate"] + f * moduli.get("tumour", 0.0)
Er = rep["youngs_modulus_kPa"]["prostate"]; t = rep["wall_time_s"]
est = sum(v for k, v in t.items() if k.startswith("estimation"))
print(f'{study},{scene},{E:g},{nu},{scale},{r},{Er:.3f},{(Er - E) / E:.4f},{rep["mesh"]["tetrahedra"]},'
      f'{est:.2f},{t["total"]:.2f},{rep["surface_distance_mm"]["prostate"]["rms"]:.4f},{int(rep["identifiable"])},{f:g},'
      f'{rep.get("youngs_modulus_uncertainty", {}).get("prostate", {}).get("sigma_log_E") or ""}')
PY
  tail -1 "$csv"
}

for study in $studies; do
  case "$study" in
    table31)
      for E in 50 100 150 200 250 300 350; do
        run table31 A "$E" 0.40 1 1 8 4
        run table31 B "$E" 0.40 1 1 5 6
      done ;;
    poisson)
      for E in 50 100 150; do
        for nu in 0.30 0.35 0.40 0.45 0.49; do run poisson A "$E" "$nu" 1 1 8 4; done
      done ;;
    tumour)
      for f in 0.10 0.25 0.50 0.75; do run tumour A 50 0.40 1 1 8 4 "$f"; done ;;
    mesh)
      for scale in 1.5 1 0.75; do
        for r in $(seq 1 "$runs"); do run mesh A 100 0.40 "$scale" "$r" 8 4; done
      done ;;
    *) echo "unknown study $study" >&2; exit 2 ;;
  esac
done
/usr/bin/python3 "$root/benchmarks/summarize_estimation.py" "$out"
