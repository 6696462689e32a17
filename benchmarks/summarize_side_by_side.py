"""Summarizes benchmarks/run_side_by_side_benchmark.sh: per method the median wall time and peak memory over the
runs and pairs, the seed TRE, and the ratios against plastimatch's and ITK's Demons measured in the same run;
per pair the medians and FEM's ratio to plastimatch; the scaling with image size and with the FEM mesh. Writes side_by_side_summary.md and side_by_side.png."""
import csv
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
runs = list(csv.DictReader(open(f"{out}/side_by_side_runs.csv")))
tre = {(r["study"], r["pair"], r["method"]): r for r in csv.DictReader(open(f"{out}/side_by_side_tre.csv"))}


def median_of(rows, key):
    return statistics.median(float(r[key]) for r in rows)


main = defaultdict(list)
for r in runs:
    if r["study"] == "main":
        main[r["method"]].append(r)
pairs = sorted({r["pair"] for r in runs if r["study"] == "main"})
methods = [m for m in ["fem", "fem+interval", "fem+interval8", "plastimatch", "itk-demons"] if m in main]
wall = {m: median_of(main[m], "wall_s") for m in methods}
lines = [f"# Side by side on {len(pairs)} demo-sized pelvis pairs (200 x 160 x 160 voxels of 1 mm)", "",
         "Median over runs and pairs (runs per method and pair: "
         + ", ".join(f"{m} {len(main[m]) // len(pairs)}" for m in methods) + ").", "",
         "| method | wall [s] | peak memory [MB] | seed TRE mean [mm] | wall / plastimatch | wall / itk-demons |",
         "|---|---:|---:|---:|---:|---:|"]
for m in methods + ["identity"]:
    t = [float(tre[("main", p, m)]["tre_mean_mm"]) for p in pairs if ("main", p, m) in tre]
    tre_text = f"{statistics.median(t):.2f}" if t else "–"
    if m == "identity":
        lines.append(f"| identity | 0 | – | {tre_text} | – | – |")
        continue
    ratios = [f"{wall[m] / wall[b]:.2f}" if b in wall else "–" for b in ["plastimatch", "itk-demons"]]
    lines.append(f"| {m} | {wall[m]:.1f} | {median_of(main[m], 'peak_MB'):.0f} | {tre_text} | {ratios[0]} | {ratios[1]} |")

# Per pair, because the targets are the demo pair's and a machine that slows down during one pair (other tenants of
# the host) moves the pooled ratios: each pair's methods run alternately, so its own ratio is the fair one.
lines += ["", "Per pair (median wall [s] over its runs; FEM / plastimatch within the pair):", "",
          "| pair | " + " | ".join(methods) + " | fem / plastimatch |", "|---|" + "---:|" * (len(methods) + 1)]
for p in pairs:
    medians = {m: median_of([r for r in main[m] if r["pair"] == p], "wall_s") for m in methods
               if any(r["pair"] == p for r in main[m])}
    ratio = f"{medians['fem'] / medians['plastimatch']:.2f}" if {"fem", "plastimatch"} <= medians.keys() else "–"
    lines.append(f"| {p} | " + " | ".join(f"{medians[m]:.2f}" if m in medians else "–" for m in methods)
                 + f" | {ratio} |")

lines += ["", "Image size (one run each, the same anatomy resampled):", "",
          "| voxels | method | wall [s] | peak memory [MB] | seed TRE mean [mm] |", "|---:|---|---:|---:|---:|"]
size_rows = sorted((r for r in runs if r["study"] == "size"), key=lambda r: (int(r["voxels"]), r["method"]))
for r in size_rows:
    t = tre.get(("size", r["pair"], r["method"]))
    lines.append(f"| {int(r['voxels']):,} | {r['method']} | {float(r['wall_s']):.1f} | {r['peak_MB']} | "
                 f"{float(t['tre_mean_mm']):.2f} |" if t else f"| {int(r['voxels']):,} | {r['method']} | "
                 f"{float(r['wall_s']):.1f} | {r['peak_MB']} | – |")
lines += ["", "FEM mesh size on pair 1 (one run each; `--mesh-scale`):", "",
          "| tetrahedra | wall [s] | peak memory [MB] |", "|---:|---:|---:|"]
mesh_rows = sorted((r for r in runs if r["study"] == "mesh"), key=lambda r: int(r["tetrahedra"] or 0))
for r in mesh_rows:
    lines.append(f"| {int(r['tetrahedra']):,} | {float(r['wall_s']):.1f} | {r['peak_MB']} |")
text = "\n".join(lines) + "\n"
open(f"{out}/side_by_side_summary.md", "w").write(text)
print(text)

fig, axes = plt.subplots(1, 3, figsize=(14, 4))
for m in methods:
    t = [float(tre[("main", p, m)]["tre_mean_mm"]) for p in pairs if ("main", p, m) in tre]
    if t:
        axes[0].plot([wall[m]], [statistics.median(t)], "o", label=m)
axes[0].set_xscale("log")
axes[0].set_xlabel("median wall time [s]")
axes[0].set_ylabel("median seed TRE [mm]")
axes[0].set_title("error against run time")
axes[0].legend(fontsize=7)
for m in ["fem", "plastimatch", "itk-demons"]:
    rows = [r for r in size_rows if r["method"] == m]
    if rows:
        axes[1].plot([int(r["voxels"]) for r in rows], [float(r["wall_s"]) for r in rows], "o-", label=m)
# An empty study (SIZES or MESH_SCALES set empty) leaves its panel linear and blank: log axes need data.
if size_rows:
    axes[1].set_xscale("log")
    axes[1].set_yscale("log")
    axes[1].legend(fontsize=7)
axes[1].set_xlabel("voxels")
axes[1].set_ylabel("wall time [s]")
axes[1].set_title("image size")
axes[2].plot([int(r["tetrahedra"]) for r in mesh_rows], [float(r["wall_s"]) for r in mesh_rows], "o-")
if mesh_rows:
    axes[2].set_xscale("log")
    axes[2].set_yscale("log")
axes[2].set_xlabel("tetrahedra")
axes[2].set_ylabel("FEM register wall time [s]")
axes[2].set_title("FEM mesh size")
fig.tight_layout()
fig.savefig(f"{out}/side_by_side.png", dpi=120)
