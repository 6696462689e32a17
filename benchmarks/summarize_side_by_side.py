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
from matplotlib.ticker import NullFormatter  # noqa: E402

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

# One panel per study that ran (SIZES or MESH_SCALES set empty skip theirs).
panels = ["error"] + (["size"] if size_rows else []) + (["mesh"] if mesh_rows else [])
fig, axes = plt.subplots(1, len(panels), figsize=(4.7 * len(panels), 4), squeeze=False)
ax = dict(zip(panels, axes[0]))
times = []
for m in methods:
    t = [float(tre[("main", p, m)]["tre_mean_mm"]) for p in pairs if ("main", p, m) in tre]
    if t:
        ax["error"].plot([wall[m]], [statistics.median(t)], "o", label=m)
        times.append(wall[m])
# Log time only over a decade or more: a log axis over less labels its minor ticks on top of each other.
if times and max(times) > 10 * min(times):
    ax["error"].set_xscale("log")
    ax["error"].xaxis.set_minor_formatter(NullFormatter())
elif times:
    ax["error"].set_xlim(0, 1.1 * max(times))
ax["error"].set_ylim(bottom=0)
ax["error"].set_xlabel("median wall time [s]")
ax["error"].set_ylabel("median seed TRE [mm]")
ax["error"].set_title("error against run time")
ax["error"].legend(fontsize=7)
if size_rows:
    for m in ["fem", "plastimatch", "itk-demons"]:
        rows = [r for r in size_rows if r["method"] == m]
        if rows:
            ax["size"].plot([int(r["voxels"]) for r in rows], [float(r["wall_s"]) for r in rows], "o-", label=m)
    ax["size"].set_xscale("log")
    ax["size"].set_yscale("log")
    ax["size"].legend(fontsize=7)
    ax["size"].set_xlabel("voxels")
    ax["size"].set_ylabel("wall time [s]")
    ax["size"].set_title("image size")
if mesh_rows:
    ax["mesh"].plot([int(r["tetrahedra"]) for r in mesh_rows], [float(r["wall_s"]) for r in mesh_rows], "o-")
    ax["mesh"].set_xscale("log")
    ax["mesh"].set_yscale("log")
    ax["mesh"].set_xlabel("tetrahedra")
    ax["mesh"].set_ylabel("FEM register wall time [s]")
    ax["mesh"].set_title("FEM mesh size")
fig.tight_layout()
fig.savefig(f"{out}/side_by_side.png", dpi=120)
