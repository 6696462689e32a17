#!/usr/bin/env bash
# FEM registration side by side with the Demons a user would pick instead (issue 19, item 4; not a test).
#   1. PAIRS pelvis phantom pairs on the demo's grid (200 x 160 x 160 voxels of 1 mm, bladder +8 mm, rectum +4 mm,
#      prostate 100 kPa, phantom seeds 1..PAIRS);
#   2. per pair, RUNS runs of each method, timed with /usr/bin/time (wall clock, peak resident memory):
#      - fem: `biomechreg register --uncertainty none --outputs field,report` (the point estimate);
#      - fem+interval: the same with the default rescan interval (4 rescans), and fem+interval8 with 8 rescans
#        (INTERVAL_RUNS runs each, default RUNS);
#      - plastimatch: `plastimatch register`, native demons (xform=vf optim=demons impl=plastimatch), 3 stages at
#        res 4/2/1 x 50 iterations (its defaults otherwise), on the raw CTs (the seeds are visible to it);
#      - itk-demons: `biomechreg demons` (ITK diffeomorphic Demons, our baseline: 3 levels x 50 iterations,
#        prostate flattened, histogram matching);
#      - identity: no run;
#   3. the seed TRE of every field through `biomechreg compare` with the fields given (no recomputation);
#   4. scaling (one run each): image size 128^3 (1.5 mm), 160^3 (1.2 mm) and 256^3 (0.75 mm) of the same anatomy
#      for fem and plastimatch (itk-demons up to 160^3: at 256^3 it takes over ten minutes), and the FEM mesh
#      size by --mesh-scale 1.5, 1, 0.75, 0.5 on pair 1.
#   5. benchmarks/summarize_side_by_side.py: medians, ratios against plastimatch and itk-demons measured in the
#      same run, CSV, PNG and a markdown table.
# Usage: benchmarks/run_side_by_side_benchmark.sh [PAIRS] [RUNS]   (about 30 minutes for 2 pairs x 3 runs on 2 cores)
# Resumable: run again with the same WORK_DIR and finished runs are kept.
# A quick smoke run: MAIN_GRID="64,48,48 3" SIZES="32 6" MESH_SCALES=1.5 INTERVAL=off ... 1 1
# METHODS (default "fem plastimatch itk-demons") chooses the methods timed on the main pairs, e.g. METHODS="fem
# plastimatch" to re-time FEM against plastimatch alone (ITK's Demons takes over two minutes per run).
# Writes side_by_side_runs.csv, side_by_side_summary.md, side_by_side.png to OUT_DIR (default benchmarks/results).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
pairs="${1:-2}"
runs="${2:-3}"
read -r main_size main_spacing <<< "${MAIN_GRID:-200,160,160 1}"
sizes="${SIZES-128 1.5,160 1.2,256 0.75}" # set and empty: no image-size study
mesh_scales="${MESH_SCALES-1.5 1 0.75 0.5}" # set and empty: no mesh-size study
interval="${INTERVAL:-on}"
interval_runs="${INTERVAL_RUNS:-$runs}"
IFS=, read -r nx ny nz <<< "$main_size"
main_voxels=$((nx * ny * nz))
read -r -a main_methods <<< "${METHODS:-fem plastimatch itk-demons}"
out="${OUT_DIR:-$root/benchmarks/results}"
mkdir -p "$out"
work="${WORK_DIR:-$(mktemp -d)}"
mkdir -p "$work"
[ -n "${WORK_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
log="$work/log.txt"
command -v plastimatch > /dev/null || { echo "plastimatch is missing (scripts/setup.sh installs it)" >&2; exit 1; }
# A copy of the binary: a rebuild during the run must not change it.
cp "${BUILD_DIR:-$root/build}/bin/biomechreg" "$work/biomechreg"
bin="$work/biomechreg"
csv="$work/runs.csv"
echo "study,pair,method,run,voxels,tetrahedra,wall_s,peak_MB" > "$csv"

# timed STUDY PAIR METHOD RUN VOXELS DIR COMMAND...: runs COMMAND under /usr/bin/time, appends a row.
timed() {
  local study=$1 pair=$2 method=$3 run=$4 voxels=$5 dir=$6
  shift 6
  mkdir -p "$dir"
  # A run that finished in an earlier, interrupted invocation with the same WORK_DIR is not repeated.
  [ -f "$dir/time.txt" ] || /usr/bin/time -f "%e %M" -o "$dir/time.txt.part" "$@" >> "$log" 2>&1
  [ -f "$dir/time.txt" ] || mv "$dir/time.txt.part" "$dir/time.txt"
  local tets=""
  [ -f "$dir/report.json" ] && tets=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['mesh']['tetrahedra'])" "$dir/report.json")
  read -r wall kb < "$dir/time.txt"
  # One row per run, also when a method is both in METHODS and the interval loop (fem+interval).
  grep -q "^$study,$pair,$method,$run," "$csv" ||
    echo "$study,$pair,$method,$run,$voxels,$tets,$wall,$((kb / 1024))" >> "$csv"
}

plastimatch_command() { # FIXED MOVING VF -> command file on stdout
  printf '[GLOBAL]\nfixed=%s\nmoving=%s\nvf_out=%s\n\n[STAGE]\nxform=vf\noptim=demons\nimpl=plastimatch\nres=4 4 4\nmax_its=50\n\n[STAGE]\nres=2 2 2\n\n[STAGE]\nres=1 1 1\n' "$1" "$2" "$3"
}

# run_methods STUDY PAIR RUN VOXELS PHANTOM_DIR [METHODS...]
run_methods() {
  local study=$1 pair=$2 run=$3 voxels=$4 p=$5
  shift 5
  for method in "$@"; do
    local dir="$work/$study/$pair/$method/run$run"
    case "$method" in
      fem) timed "$study" "$pair" fem "$run" "$voxels" "$dir" "$bin" register --moving-ct "$p/moving_ct.nrrd" \
          --moving-labels "$p/moving_labels.nrrd" --fixed-ct "$p/fixed_ct.nrrd" --fixed-labels "$p/fixed_labels.nrrd" \
          --scene "$p/scene.json" --uncertainty none --outputs field,report --out "$dir" ;;
      fem+interval | fem+interval8) timed "$study" "$pair" "$method" "$run" "$voxels" "$dir" "$bin" register \
          --moving-ct "$p/moving_ct.nrrd" --moving-labels "$p/moving_labels.nrrd" --fixed-ct "$p/fixed_ct.nrrd" \
          --fixed-labels "$p/fixed_labels.nrrd" --scene "$p/scene.json" --outputs field,report --out "$dir" \
          $([ "$method" = fem+interval8 ] && echo --resamples 8) ;;
      plastimatch) mkdir -p "$dir"
        plastimatch_command "$p/fixed_ct.nrrd" "$p/moving_ct.nrrd" "$dir/field.nrrd" > "$dir/command.txt"
        timed "$study" "$pair" plastimatch "$run" "$voxels" "$dir" plastimatch register "$dir/command.txt" ;;
      itk-demons) timed "$study" "$pair" itk-demons "$run" "$voxels" "$dir" "$bin" demons \
          --moving-ct "$p/moving_ct.nrrd" --fixed-ct "$p/fixed_ct.nrrd" --moving-labels "$p/moving_labels.nrrd" \
          --fixed-labels "$p/fixed_labels.nrrd" --flatten 2 --out "$dir" ;;
    esac
  done
}

# score STUDY PAIR PHANTOM_DIR: seed TRE of the first run's fields (compare with the fields given).
score() {
  local study=$1 pair=$2 p=$3 d="$work/$1/$2"
  for method in fem plastimatch itk-demons; do
    [ -f "$d/$method/run1/field.nrrd" ] || continue
    local list="$d/$method/pairs.csv"
    printf 'name,moving_ct,moving_labels,fixed_ct,fixed_labels,scene,moving_landmarks,fixed_landmarks,fem_field\n%s,%s,%s,%s,%s,%s,%s,%s,%s\n' \
      "$pair" "$p/moving_ct.nrrd" "$p/moving_labels.nrrd" "$p/fixed_ct.nrrd" "$p/fixed_labels.nrrd" "$p/scene.json" \
      "$p/landmarks_moving.csv" "$p/landmarks_fixed.csv" "$d/$method/run1/field.nrrd" > "$list"
    "$bin" compare --pairs "$list" --out "$d/$method/compare" --methods identity,fem --quiet >> "$log" 2>&1
    /usr/bin/python3 - "$d/$method/compare/per_pair.csv" "$study" "$pair" "$method" >> "$work/tre.csv" <<'PY'
import csv, sys
path, study, pair, method = sys.argv[1:5]
for r in csv.DictReader(l for l in open(path) if not l.startswith("#")):
    name = method if r["method"] == "fem" else "identity"
    if name == "identity" and method != "fem":
        continue
    print(f"{study},{pair},{name},{r['tre_mean_mm']},{r['tre_max_mm']},{r['dice_mean']}")
PY
  done
}

echo "study,pair,method,tre_mean_mm,tre_max_mm,dice_mean" > "$work/tre.csv"
for k in $(seq 1 "$pairs"); do
  p="$work/phantoms/pair$k"
  [ -f "$p/truth.json" ] || "$bin" phantom --size "$main_size" --spacing "$main_spacing,$main_spacing,$main_spacing" \
    --bladder-mm 8 --rectum-mm 4 \
    --true-E-kPa 100 --seed "$k" --out "$p" >> "$log" 2>&1
  echo "pair $k: $runs runs of ${main_methods[*]}; $interval_runs of fem+interval and fem+interval8"
  for r in $(seq 1 "$runs"); do
    run_methods main "pair$k" "$r" "$main_voxels" "$p" "${main_methods[@]}"
  done
  for r in $(seq 1 "$interval_runs"); do
    [ "$interval" != on ] || run_methods main "pair$k" "$r" "$main_voxels" "$p" fem+interval fem+interval8
  done
  score main "pair$k" "$p"
done

IFS=, read -r -a size_specs <<< "$sizes"
for spec in "${size_specs[@]}"; do
  read -r n h <<< "$spec"
  p="$work/phantoms/size$n"
  [ -f "$p/truth.json" ] || "$bin" phantom --size "$n,$n,$n" --spacing "$h,$h,$h" --bladder-mm 8 --rectum-mm 4 \
    --true-E-kPa 100 --seed 1 --out "$p" >> "$log" 2>&1
  echo "image size $n^3 ($h mm)"
  methods=(fem plastimatch)
  [ "$n" -le 160 ] && methods+=(itk-demons)
  run_methods size "size$n" 1 $((n * n * n)) "$p" "${methods[@]}"
  score size "size$n" "$p"
done

for scale in $mesh_scales; do
  echo "FEM mesh scale $scale"
  p="$work/phantoms/pair1"
  dir="$work/mesh/scale$scale"
  timed mesh "scale$scale" fem 1 "$main_voxels" "$dir" "$bin" register --moving-ct "$p/moving_ct.nrrd" \
    --moving-labels "$p/moving_labels.nrrd" --fixed-ct "$p/fixed_ct.nrrd" --fixed-labels "$p/fixed_labels.nrrd" \
    --scene "$p/scene.json" --uncertainty none --outputs field,report --mesh-scale "$scale" --out "$dir"
done

cp "$csv" "$out/side_by_side_runs.csv"
cp "$work/tre.csv" "$out/side_by_side_tre.csv"
/usr/bin/python3 "$root/benchmarks/summarize_side_by_side.py" "$out"
