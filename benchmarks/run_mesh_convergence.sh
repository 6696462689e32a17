#!/usr/bin/env bash
# Mesh convergence of the recovered modulus (issue 15, item 1; not a test). Pelvis phantom pairs at 1 mm (200 x 160
# x 160) whose truth is meshed from the analytic anatomy (phantom --truth-geometry anatomy: its surfaces do not move
# with the truth's mesh), one per modulus in MODULI (default "60 150"); each registered with
# `register --uncertainty none` (the point estimate) under several discretizations:
#   - default: the scene as the phantom writes it;
#   - uniform-0.85: --mesh-scale 0.85;
#   - uniform-fine: --mesh-scale 0.58 ... 0.72 (the reference: the mean over its six runs);
#   - prostate-6-1.5: the scene with mesh.refine_near {prostate, 6 mm, 1.5 mm};
#   - prostate-6-2: the same at 2 mm;
#   - walls-4-2.5: refined within 4 mm of the prostate, the bladder and the rectum at 2.5 mm;
#   - facets-0.85: the surface criteria only (facet size and facet distance) scaled by 0.85, the cells as default;
#   - cells-0.85: the cell sizes only (global and per label) scaled by 0.85, the surfaces as default;
#   - prostate-facets-0.85, prostate-facets-0.75: the prostate's surfaces only (mesh.facet_size_per_label_mm and
#     facet_distance_per_label_mm) at 0.85 / 0.75 of the scene's facet criteria;
#   - default-sliver5, facets-0.85-sliver5: with mesh.sliver_bound_deg 5 (the default before session 44).
# A configuration's realizations are runs at --mesh-scale jittered by x0.97, 0.985, 1, 1.015, 1.03: other meshes of
# nearly the same sizes, whose spread is the estimate's noise from the mesh alone.
# Usage: benchmarks/run_mesh_convergence.sh   (about 70 minutes on 2 cores)
# Writes benchmarks/results/mesh_convergence_runs.csv, mesh_convergence.csv, mesh_convergence.png and prints the
# table (benchmarks/summarize_mesh_convergence.py).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
out="$root/benchmarks/results"
mkdir -p "$out"
work="${WORK_DIR:-$(mktemp -d)}"
[ -n "${WORK_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
csv="$out/mesh_convergence_runs.csv"
echo "config,true_E_kPa,mesh_scale,tetrahedra,E_kPa,wall_s" > "$csv"

# scene_with REFINE_JSON IN OUT: the scene with mesh.refine_near set (or as it is for an empty REFINE_JSON).
scene_with() {
  /usr/bin/python3 - "$1" "$2" "$3" <<'PY'
import json, sys
refine, source, target = sys.argv[1:4]
scene = json.load(open(source))
if refine:
    scene["mesh"]["refine_near"] = json.loads(refine)
json.dump(scene, open(target, "w"), indent=1)
PY
}

# scene_scaled WHAT FACTOR IN OUT: the scene with its surface criteria (WHAT = facets: facet size and distance), the
# prostate's surface criteria alone (prostate-facets), the sliver bound set to FACTOR degrees (sliver) or
# its cell sizes (WHAT = cells: global and per label) multiplied by FACTOR.
scene_scaled() {
  /usr/bin/python3 - "$1" "$2" "$3" "$4" <<'PY'
import json, sys
what, factor, source, target = sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4]
scene = json.load(open(source))
mesh = scene["mesh"]
if what == "sliver":
    mesh["sliver_bound_deg"] = factor
elif what == "prostate-facets":
    mesh["facet_size_per_label_mm"] = {"prostate": mesh["facet_size_mm"] * factor}
    mesh["facet_distance_per_label_mm"] = {"prostate": mesh["facet_distance_mm"] * factor}
elif what == "facets":
    mesh["facet_size_mm"] *= factor
    mesh["facet_distance_mm"] *= factor
else:
    mesh["cell_size_mm"] *= factor
    mesh["cell_size_per_label_mm"] = {k: v * factor for k, v in mesh.get("cell_size_per_label_mm", {}).items()}
json.dump(scene, open(target, "w"), indent=1)
PY
}

# estimate CONFIG E SCENE SCALE: one point estimate, appended to the CSV.
estimate() {
  local config=$1 E=$2 scene=$3 scale=$4 p="$work/phantom$2" dir="$work/$1-$2-$4"
  [ -f "$dir/report.json" ] || /usr/bin/time -f "%e" -o "$dir.time" "$bin" register --moving-ct "$p/moving_ct.nrrd" \
    --moving-labels "$p/moving_labels.nrrd" --fixed-ct "$p/fixed_ct.nrrd" --fixed-labels "$p/fixed_labels.nrrd" \
    --scene "$scene" --uncertainty none --outputs report --mesh-scale "$scale" --out "$dir" > "$dir.log" 2>&1
  /usr/bin/python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(','.join(map(str, [sys.argv[2], sys.argv[3], \
sys.argv[4], j['mesh']['tetrahedra'], j['youngs_modulus_kPa']['prostate'], open(sys.argv[5]).read().strip()])))" \
    "$dir/report.json" "$config" "$E" "$scale" "$dir.time" >> "$csv"
}

jitter="0.97 0.985 1 1.015 1.03"
for E in ${MODULI:-60 150}; do
  p="$work/phantom$E"
  [ -f "$p/truth.json" ] || "$bin" phantom --size 200,160,160 --spacing 1,1,1 --true-E-kPa "$E" \
    --truth-geometry anatomy --out "$p" > "$work/phantom$E.log" 2>&1
  echo "true E $E kPa"
  scene_with "" "$p/scene.json" "$work/default-$E.json"
  scene_with '{"labels": ["prostate"], "distance_mm": 6, "size_mm": 1.5}' "$p/scene.json" "$work/prostate-6-1.5-$E.json"
  scene_with '{"labels": ["prostate"], "distance_mm": 6, "size_mm": 2}' "$p/scene.json" "$work/prostate-6-2-$E.json"
  scene_with '{"labels": ["prostate", "bladder", "rectum"], "distance_mm": 4, "size_mm": 2.5}' "$p/scene.json" \
    "$work/walls-4-2.5-$E.json"
  scene_scaled facets 0.85 "$p/scene.json" "$work/facets-0.85-$E.json"
  scene_scaled cells 0.85 "$p/scene.json" "$work/cells-0.85-$E.json"
  scene_scaled prostate-facets 0.85 "$p/scene.json" "$work/prostate-facets-0.85-$E.json"
  scene_scaled prostate-facets 0.75 "$p/scene.json" "$work/prostate-facets-0.75-$E.json"
  scene_scaled sliver 5 "$p/scene.json" "$work/default-sliver5-$E.json"
  scene_scaled sliver 5 "$work/facets-0.85-$E.json" "$work/facets-0.85-sliver5-$E.json"
  for j in $jitter; do
    for config in default prostate-6-1.5 prostate-6-2 walls-4-2.5 facets-0.85 cells-0.85 prostate-facets-0.85 \
      prostate-facets-0.75 default-sliver5 facets-0.85-sliver5; do
      estimate "$config" "$E" "$work/$config-$E.json" "$j"
    done
    estimate uniform-0.85 "$E" "$work/default-$E.json" "$(/usr/bin/python3 -c "print(round(0.85 * $j, 5))")"
  done
  for scale in 0.58 0.6 0.62 0.68 0.7 0.72; do
    estimate uniform-fine "$E" "$work/default-$E.json" "$scale"
  done
done
/usr/bin/python3 "$root/benchmarks/summarize_mesh_convergence.py" "$csv" "$out/mesh_convergence"
