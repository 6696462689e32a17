#!/usr/bin/env bash
# Neo-Hookean estimation benchmark (not a test; issue 16, dissertation Tables 3.6 and 3.7): pelvis phantoms
# (200 x 160 x 160 voxels of 1 mm) whose truth is the neo-Hookean model on the phantom's converged independent
# mesh, loaded by pressure in the bladder and the rectum (the walls move as the tissue lets them; prescribed wall
# motions squeeze thin tissue flat, which no neo-Hookean state allows), registered with `biomechreg register`.
# Usage: benchmarks/run_neo_hookean_benchmark.sh [N realizations per row (default 3)] [SEED (default 36)]
#   DESIGN=table36 (default): scenes A (bladder 2.2 kPa, rectum 1.0 kPa) and B (1.35 and 1.5 kPa), whose
#     largest wall motions (about 8/4 and 5/6 mm at 10 kPa tissue) are Table 3.1's scenes', x prostate E in
#     {50, 100, 150, 200} kPa; neo-Hookean truth and estimation.
#   DESIGN=table37: scene A with the truth's soft tissue at 20 kPa (and the pressures doubled, so that the walls
#     move as much) while the estimation scene assumes 10 kPa (phantom --tissue-E-kPa 20): the images fix only
#     the ratio of the moduli, so expect half the truth.
#   DESIGN=filling: bladder fillings of 5, 10, 20 and 25 mm (the bladder wall's largest motion in the truth; the
#     pressure found by a secant search on a coarser truth mesh), prostate 100 kPa, rectum 0.5 kPa; each pair
#     estimated with the neo-Hookean and with the linear model: E error, surface RMS, seed TRE, times.
#   REGISTER_ARGS: the settings of every register run (default "--wall-motion pressure": one unknown uniform
#   pressure per lumen, docs/estimation.md; "--wall-motion traction --wall-spacing-mm 30 --wall-regularization
#   0.0001" for smooth tractions that may vary along a wall; add "--uncertainty none" for point estimates only,
#   "--mesh-scale 1.5" for the ~37k-tetrahedron mesh); APPEND=1 adds rows; START=K skips the pairs before K;
#   TAG=T names the results DESIGN_T.
# Writes benchmarks/results/neo_hookean_runs_DESIGN[_TAG].csv (one row per estimation) and, through
# summarize_neo_hookean.py, neo_hookean_DESIGN[_TAG].csv, .png and a printed table.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
count="${1:-3}"
seed="${2:-36}"
design="${DESIGN:-table36}"
register_args="${REGISTER_ARGS---wall-motion pressure}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
csv="$out/neo_hookean_runs_$design${TAG:+_$TAG}.csv"
if [ "${APPEND:-0}" != 1 ] || [ ! -s "$csv" ]; then
  echo "design,row,pair,estimation_model,true_E_kPa,truth_tissue_kPa,assumed_tissue_kPa,bladder_kPa,rectum_kPa,bladder_max_mm,rectum_max_mm,seed,estimate_kPa,fit_kPa,lo68_kPa,hi68_kPa,lo95_kPa,hi95_kPa,lower_determined,upper_determined,prostate_rms_mm,seed_tre_mm,seed_tre_max_mm,identity_tre_mm,mesh_tetrahedra,outer_iterations,phantom_s,register_s" > "$csv"
fi

# The draws, one line per pair: row E tissue bladder_kPa rectum_kPa target_filling_mm seed (realization-major, so
# that a run stopped early has every row).
/usr/bin/python3 - "$count" "$seed" "$design" > "$work/draws.txt" <<'PY'
import sys
n, seed, design = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
if design == "table36":
    rows = [(f"{name}", E, 10, b, r, 0) for name, b, r in (("A", 2.2, 1.0), ("B", 1.35, 1.5)) for E in (50, 100, 150, 200)]
elif design == "table37":
    rows = [("A-tissue20", E, 20, 4.4, 2.0, 0) for E in (50, 100, 150, 200)]
elif design == "filling":
    rows = [(f"fill{f}", 100, 10, 0, 0.5, f) for f in (5, 10, 20, 25)]
else:
    raise SystemExit(f"unknown DESIGN {design} (table36, table37 or filling)")
k = 0
for i in range(n):
    for row in rows:
        k += 1
        print(*row, seed * 100 + k)
PY

# The bladder pressure [kPa] whose truth moves the bladder wall by FILLING mm at its largest: a secant search in
# log-log on the truth at --truth-mesh-scale 1 (78k tetrahedra; a few seconds a solve), from 1 kPa.
pressure_for_filling() {
  local target="$1" E="$2" rectum="$3" s="$4"
  /usr/bin/python3 - "$bin" "$target" "$E" "$rectum" "$s" "$work/fill" <<'PY'
import json, math, subprocess, sys
bin, target, E, rectum, s, d = sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6]
def filling(p):
    subprocess.run([bin, "phantom", "--scene", "pelvis", "--size", "200,160,160", "--spacing", "1,1,1",
                    "--model", "neo_hookean", "--true-E-kPa", E, "--bladder-kPa", f"{p:.6g}", "--rectum-kPa", rectum,
                    "--truth-mesh-scale", "1", "--seed", s, "--quiet", "--out", d], check=True, stdout=subprocess.DEVNULL)
    return json.load(open(f"{d}/truth.json"))["wall_motion_mm"]["bladder"]["max"]
p0, f0 = 1.0, filling(1.0)
p1 = p0 * target / f0
for _ in range(4):
    f1 = filling(p1)
    if abs(f1 - target) < 0.02 * target:
        break
    slope = (math.log(f1) - math.log(f0)) / (math.log(p1) - math.log(p0))
    p0, f0, p1 = p1, f1, p1 * math.exp((math.log(target) - math.log(f1)) / max(slope, 0.2))
print(f"{p1:.4g}")
PY
}

# One register run on the phantom in $ph with the given scene, one CSV row.
estimate() {
  local scene="$1" model="$2"
  rm -rf "$work/reg"
  local t0 t1
  t0=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$bin" register --moving-ct "$ph/moving_ct.nrrd" --moving-labels "$ph/moving_labels.nrrd" \
    --fixed-ct "$ph/fixed_ct.nrrd" --fixed-labels "$ph/fixed_labels.nrrd" --scene "$scene" \
    --out "$work/reg" $register_args > "$work/reg.log" 2>&1 || { echo "register failed: pair $k ($model)"; tail -3 "$work/reg.log"; return 0; }
  t1=$(date +%s.%N)
  local tre identity
  tre=$(/usr/bin/python3 "$root/benchmarks/field_tre.py" "$work/reg/field.nrrd" "$ph/landmarks_fixed.csv" "$ph/landmarks_moving.csv")
  identity=$(/usr/bin/python3 - "$ph/truth.json" <<'PY'
import json, math, sys
marks = json.load(open(sys.argv[1]))["landmarks"]
print(f'{sum(math.dist(m["moving_mm"], m["fixed_mm"]) for m in marks) / len(marks):.4f}')
PY
)
  /usr/bin/python3 - "$work/reg/report.json" "$ph/truth.json" "$design,$row,$k,$model,$E,$tissue,10,$bkpa,$rkpa" \
    "$s" "$tre" "$identity" "$tph" "$(awk "BEGIN{print $t1 - $t0}")" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1])); truth = json.load(open(sys.argv[2]))
lead, s, tre, identity, tph, treg = sys.argv[3:9]
wall = truth["wall_motion_mm"]
i = rep.get("youngs_modulus_interval", {}).get("prostate")
interval = ",".join(f"{x:.3f}" for x in (i["fit_kPa"], *i["interval_68_kPa"], *i["interval_95_kPa"])) + \
    f',{int(i["lower_end_determined"])},{int(i["upper_end_determined"])}' if i else ",,,,,,"
print(f'{lead},{wall["bladder"]["max"]:.3f},{wall["rectum"]["max"]:.3f},{s},{rep["youngs_modulus_kPa"]["prostate"]:.3f},'
      f'{interval},{rep["surface_distance_mm"]["prostate"]["rms"]:.4f},{tre},{identity},{rep["mesh"]["tetrahedra"]},'
      f'{rep["iterations"]["fine"]},{float(tph):.1f},{float(treg):.1f}')
PY
  tail -1 "$csv"
}

k=0
while read -r row E tissue bkpa rkpa filling s; do
  k=$((k + 1))
  [ "$k" -lt "${START:-1}" ] && continue
  if [ "$filling" != 0 ]; then
    bkpa=$(pressure_for_filling "$filling" "$E" "$rkpa" "$s")
  fi
  ph="$work/ph"
  rm -rf "$ph"
  t0=$(date +%s.%N)
  "$bin" phantom --scene pelvis --size 200,160,160 --spacing 1,1,1 --model neo_hookean --true-E-kPa "$E" \
    --tissue-E-kPa "$tissue" --bladder-kPa "$bkpa" --rectum-kPa "$rkpa" --fixed-grid-shift-voxels 0.5 --seed "$s" \
    --out "$ph" > "$work/ph.log" 2>&1 || { echo "phantom failed: pair $k"; tail -3 "$work/ph.log"; continue; }
  tph=$(awk "BEGIN{print $(date +%s.%N) - $t0}")
  estimate "$ph/scene.json" neo_hookean
  if [ "$design" = filling ]; then
    /usr/bin/python3 -c 'import json, sys; s = json.load(open(sys.argv[1])); s["model"] = "linear"; json.dump(s, open(sys.argv[2], "w"), indent=2)' \
      "$ph/scene.json" "$ph/scene_linear.json"
    estimate "$ph/scene_linear.json" linear
  fi
done < "$work/draws.txt"

/usr/bin/python3 "$root/benchmarks/summarize_neo_hookean.py" "$csv" "$out"
