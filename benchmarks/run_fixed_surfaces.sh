#!/usr/bin/env bash
# The fixed organs' surfaces at clinical slices (not a test): pelvis phantom pairs at in-plane voxels drawn from
# U(0.8, 1.2) mm and slices of SLICE_MM (default 3), the fixed grid shifted by a random sub-voxel offset, moduli
# log-uniform in 30-500 kPa, bladder walls 3-10 mm and rectum walls 2-6 mm (all drawn from SEED). Each phantom is written with both kinds of sub-voxel data of the
# fixed organs (`phantom --outline-fractions on --fractions on`) and registered three times with `register`'s
# defaults: from the fixed label map (voxels), from the area fractions of the organs' exact outlines on each fixed
# slice (outlines: what an RTSTRUCT drawn on the fixed scan gives `register`) and from their volume fractions
# (volume: a partial-volume segmentation), the last two through --fixed-probabilities. Records per run the fit, the
# stated estimate and interval, the prostate's surface RMS and the inverted elements.
# Usage: benchmarks/run_fixed_surfaces.sh [N (default 10)] [SEED (default 7401)]
# Writes benchmarks/results/clinical_geometry/fixed_surfaces_runs.csv, fixed_surfaces.csv, fixed_surfaces.png and
# prints the table (summarize_fixed_surfaces.py).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
count="${1:-10}"
seed="${2:-7401}"
slice="${SLICE_MM:-3}"
out="$root/benchmarks/results/clinical_geometry"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
csv="$out/fixed_surfaces_runs.csv"
echo "surfaces,pair,true_E_kPa,bladder_mm,rectum_mm,seed,spacing_mm,fit_kPa,estimate_kPa,lo95_kPa,hi95_kPa,lower_determined,upper_determined,not_determined,prostate_rms_mm,inverted_elements,register_s" > "$csv"

/usr/bin/python3 - "$count" "$seed" > "$work/draws.txt" <<'PY'
import math, random, sys
n, seed = int(sys.argv[1]), int(sys.argv[2])
rng = random.Random(seed)
pairs = [(math.exp(rng.uniform(math.log(30), math.log(500))), rng.uniform(3, 10), rng.uniform(2, 6)) for _ in range(n)]
for k, (E, b, r) in enumerate(pairs):
    print(f"{E:.1f} {b:.2f} {r:.2f} {seed * 100 + k + 1} {rng.uniform(0.8, 1.2):.4f}")
PY

k=0
while read -r E bladder rectum s inplane; do
  k=$((k + 1))
  ph="$work/ph"
  rm -rf "$ph"
  size="$(awk "BEGIN{printf \"%d,%d,%d\", 200 / $inplane + 0.5, 160 / $inplane + 0.5, 160 / $slice + 0.5}")"
  "$bin" phantom --scene pelvis --size "$size" --spacing "$inplane,$inplane,$slice" --true-E-kPa "$E" \
    --bladder-mm "$bladder" --rectum-mm "$rectum" --seed "$s" --fixed-grid-shift-voxels 0.5 \
    --outline-fractions on --fractions on --out "$ph" > "$work/ph.log" 2>&1 ||
    { echo "phantom failed: pair $k"; tail -3 "$work/ph.log"; continue; }
  for surfaces in voxels outlines volume; do
    extra=()
    if [ "$surfaces" != voxels ]; then
      prefix=fixed_fraction_
      [ "$surfaces" = outlines ] && prefix=fixed_outline_fraction_
      list=""
      for f in "$ph/$prefix"*.nrrd; do
        organ="$(basename "$f" .nrrd)"
        list="${list:+$list,}${organ#"$prefix"}=$f"
      done
      extra=(--fixed-probabilities "$list")
    fi
    rm -rf "$work/reg"
    t0=$(date +%s.%N)
    "$bin" register --moving-ct "$ph/moving_ct.nrrd" --moving-labels "$ph/moving_labels.nrrd" \
      --fixed-ct "$ph/fixed_ct.nrrd" --fixed-labels "$ph/fixed_labels.nrrd" --scene "$ph/scene.json" \
      --outputs report --out "$work/reg" "${extra[@]}" > "$work/reg.log" 2>&1 ||
      { echo "register failed: pair $k $surfaces"; tail -3 "$work/reg.log"; continue; }
    t1=$(date +%s.%N)
    /usr/bin/python3 - "$work/reg/report.json" "$surfaces" "$k" "$E" "$bladder" "$rectum" "$s" "$inplane" "$slice" \
      "$(awk "BEGIN{print $t1 - $t0}")" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1]))
surfaces, k, E, bladder, rectum, s, inplane, slice_mm, t = sys.argv[2:11]
i = rep["youngs_modulus_interval"]["prostate"]
print(f'{surfaces},{k},{E},{bladder},{rectum},{s},{inplane}x{inplane}x{slice_mm},{i["fit_kPa"]:.3f},'
      f'{i["estimate_kPa"]:.3f},{i["interval_95_kPa"][0]:.3f},{i["interval_95_kPa"][1]:.3f},'
      f'{int(i["lower_end_determined"])},{int(i["upper_end_determined"])},{int(bool(i.get("not_determined_reason")))},'
      f'{rep["surface_distance_mm"]["prostate"]["rms"]:.4f},{rep.get("inverted_elements", "")},{float(t):.1f}')
PY
    tail -1 "$csv"
  done
done < "$work/draws.txt"

/usr/bin/python3 "$root/benchmarks/summarize_fixed_surfaces.py" "$csv" "$out"
