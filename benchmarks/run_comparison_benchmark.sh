#!/usr/bin/env bash
# FEM against Demons on seed landmarks, and error against run time (not a test; dissertation Table 3.5).
#   1. `biomechreg phantom-set`: PAIRS pelvis phantom pairs (default 5) with different bladder/rectum wall
#      displacements, prostate moduli and seed positions (reproducible), 1.25 x 1.25 x 2.5 mm voxels;
#   2. `biomechreg compare` with the default settings: identity, FEM and Demons (prostate flattened, as the
#      dissertation did) -> TRE per seed, Dice/HD95, Jacobian statistics, paired t-tests, checkerboards;
#   3. the settings sweep: FEM mesh sizes x1.5 / x0.75, no coarse-to-fine sweep, a loose outer stop
#      (2 iterations); Demons with 1 / 2 levels, 10 / 100 iterations per level, fast symmetric forces,
#      and without flattening (the seeds then show in the images and guide Demons);
#   4. scripts/plot_compare.py: one table and one plot of TRE, HD95 and Dice against run time.
# Usage: benchmarks/run_comparison_benchmark.sh [PAIRS]   (about 20 minutes for 5 pairs on 2 cores)
# Writes benchmarks/results/comparison_summary.md (the default run's table and t-tests),
# comparison_error_vs_time.csv/.png, comparison_tre_boxplot.png, comparison_checkerboard_*.png.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
pairs="${1:-5}"
out="$root/benchmarks/results"
mkdir -p "$out"
work="${WORK_DIR:-$(mktemp -d)}"
[ -n "${WORK_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
log="$work/log.txt"

echo "phantom set: $pairs pairs -> $work/phantoms"
"$bin" phantom-set --count "$pairs" --seed 1 --out "$work/phantoms" > "$log"
list="$work/phantoms/pairs.csv"

# compare TAG METHODS [OPTIONS...]
compare() {
  local tag=$1 methods=$2
  shift 2
  echo "compare: $tag ($methods) $*"
  "$bin" compare --pairs "$list" --out "$work/$tag" --tag "$tag" --methods "$methods" "$@" >> "$log"
}
compare default identity,fem,demons
compare fem-mesh-x1.5 fem --mesh-scale 1.5
compare fem-mesh-x0.75 fem --mesh-scale 0.75
compare fem-no-coarse-to-fine fem --coarse-factor 1
compare fem-outer-2 fem --max-outer-iterations 2
compare demons-1-level demons --demons-levels 1
compare demons-2-levels demons --demons-levels 2
compare demons-10-iterations demons --demons-iterations 10
compare demons-100-iterations demons --demons-iterations 100
compare demons-symmetric demons --demons-variant symmetric
compare demons-not-flattened demons --flatten none

dirs=()
for d in "$work"/*/; do
  [ -f "$d/per_pair.csv" ] && dirs+=("${d%/}")
done
/usr/bin/python3 "$root/scripts/plot_compare.py" "$work/default" "${dirs[@]}" | tee "$work/table.md"
cp "$work/default/summary.md" "$out/comparison_summary.md"
{
  echo
  echo "## Error against run time (benchmarks/run_comparison_benchmark.sh, $pairs pairs)"
  echo
  cat "$work/table.md"
} >> "$out/comparison_summary.md"
cp "$work/default/error_vs_time.csv" "$out/comparison_error_vs_time.csv"
cp "$work/default/error_vs_time.png" "$out/comparison_error_vs_time.png"
cp "$work/default/tre_boxplot.png" "$out/comparison_tre_boxplot.png"
for m in fem demons; do
  cp "$work/default/pair1/checkerboard_$m.png" "$out/comparison_checkerboard_pair1_$m.png"
done
echo
cat "$work/default/summary.md"
echo "wrote $out/comparison_summary.md, comparison_error_vs_time.{csv,png}, comparison_tre_boxplot.png"
