#!/usr/bin/env bash
# Clinical image sizes (not a test): time and peak memory of `biomechreg register` against the image size, at the
# geometry of pelvic planning CTs (0.977 mm in-plane; 2 mm slices), the field written as float (the default).
# For each size a pelvis phantom pair (8 mm bladder, 4 mm rectum, 100 kPa, fixed grid shifted by up to half a voxel)
# is made once, then registered RUNS times with the default settings and --outputs field,report.
# Usage: benchmarks/run_clinical_size.sh [RUNS (3)]; SIZES="256,256,100 512,512,100 512,512,200" (NX,NY,NZ);
#        SPACING="0.977,0.977,2"; BUILD_DIR (./build); OUT_DIR (benchmarks/results/clinical_size).
# Writes OUT_DIR/clinical_size_runs.csv (one row per run), clinical_size.csv (medians per size), clinical_size.png
# (time and peak memory against voxels) and prints the table. The CPU model and OpenBLAS core type are recorded.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/bin/biomechreg"
runs="${1:-3}"
sizes="${SIZES:-256,256,100 512,512,100 512,512,200}"
spacing="${SPACING:-0.977,0.977,2}"
out="${OUT_DIR:-$root/benchmarks/results/clinical_size}"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cpu="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //; s/,/ /g')"
csv="$out/clinical_size_runs.csv"
echo "size,voxels,spacing_mm,run,phantom_s,register_s,register_peak_MB,field_MB,tetrahedra,inverted_elements,cpu,openblas_coretype" > "$csv"
for size in $sizes; do
  p="$work/p"
  rm -rf "$p"
  t0=$(date +%s.%N)
  "$bin" phantom --scene pelvis --size "$size" --spacing "$spacing" --bladder-mm 8 --rectum-mm 4 --true-E-kPa 100 \
    --fixed-grid-shift-voxels 0.5 --out "$p" > "$work/ph.log" 2>&1 || { echo "phantom $size failed"; tail -3 "$work/ph.log"; exit 1; }
  tph=$(awk "BEGIN{print $(date +%s.%N) - $t0}")
  for run in $(seq 1 "$runs"); do
    rm -rf "$work/reg"
    t1=$(date +%s.%N)
    /usr/bin/time -f "%M" -o "$work/mem" "$bin" register --moving-ct "$p/moving_ct.nrrd" \
      --moving-labels "$p/moving_labels.nrrd" --fixed-ct "$p/fixed_ct.nrrd" --fixed-labels "$p/fixed_labels.nrrd" \
      --scene "$p/scene.json" --outputs field,report --out "$work/reg" > "$work/reg.log" 2>&1 \
      || { echo "register $size failed"; tail -3 "$work/reg.log"; exit 1; }
    treg=$(awk "BEGIN{print $(date +%s.%N) - $t1}")
    /usr/bin/python3 - "$work/reg/report.json" "$size" "$spacing" "$run" "$tph" "$treg" "$(cat "$work/mem")" \
      "$(stat -c %s "$work/reg/field.nrrd")" "$cpu" "${OPENBLAS_CORETYPE:-auto}" >> "$csv" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1]))
size, spacing, run, tph, treg, kb, field_bytes, cpu, core = sys.argv[2:11]
n = 1
for s in size.split(","):
    n *= int(s)
print(f'{size.replace(",", "x")},{n},{spacing.replace(",", "x")},{run},{float(tph):.1f},{float(treg):.1f},'
      f'{int(kb) / 1024:.0f},{int(field_bytes) / 2**20:.0f},{rep["mesh"]["tetrahedra"] if "mesh" in rep else ""},'
      f'{rep.get("inverted_elements", "")},{cpu},{core}')
PY
    tail -1 "$csv"
  done
done
/usr/bin/python3 - "$csv" "$out" <<'PY'
import csv, statistics, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
out = sys.argv[2]
sizes = list(dict.fromkeys(r["size"] for r in rows))
table = []
for s in sizes:
    rs = [r for r in rows if r["size"] == s]
    med = lambda k: statistics.median(float(r[k]) for r in rs)
    table.append((s, int(rs[0]["voxels"]), len(rs), med("register_s"), min(float(r["register_s"]) for r in rs),
                  max(float(r["register_s"]) for r in rs), med("register_peak_MB"), med("field_MB"), float(rs[0]["phantom_s"])))
base = table[0]
with open(f"{out}/clinical_size.csv", "w") as f:
    f.write("size,voxels,runs,register_median_s,register_min_s,register_max_s,peak_median_MB,field_MB,phantom_s,"
            "time_ratio_to_first,voxel_ratio_to_first\n")
    for t in table:
        f.write(",".join(str(x) for x in t) + f",{t[3] / base[3]:.2f},{t[1] / base[1]:.2f}\n")
print("| size | voxels | runs | register [s] median (range) | peak memory [MB] | field [MB] | time / first | voxels / first |")
print("|---|---:|---:|---|---:|---:|---:|---:|")
for t in table:
    print(f"| {t[0]} | {t[1]:,} | {t[2]} | {t[3]:.1f} ({t[4]:.1f}-{t[5]:.1f}) | {t[6]:.0f} | {t[7]:.0f} | "
          f"{t[3] / base[3]:.2f} | {t[1] / base[1]:.2f} |")
fig, ax = plt.subplots(1, 2, figsize=(10, 4))
v = [t[1] / 1e6 for t in table]
ax[0].plot(v, [t[3] for t in table], "o-"); ax[0].set(xlabel="voxels [millions]", ylabel="register [s] (median)")
ax[1].plot(v, [t[6] for t in table], "o-"); ax[1].set(xlabel="voxels [millions]", ylabel="peak memory [MB]")
fig.suptitle(f"register at {rows[0]['spacing_mm']} mm against image size ({rows[0]['cpu']})")
fig.tight_layout()
fig.savefig(f"{out}/clinical_size.png", dpi=100)
print(f"wrote {out}/clinical_size.csv, {out}/clinical_size.png")
PY
