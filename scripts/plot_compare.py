"""Plots and tabulates `biomechreg compare` runs.

Usage: /usr/bin/python3 scripts/plot_compare.py OUT [RUN_DIR ...]
Each RUN_DIR is the --out of one `biomechreg compare` run (its per_pair.csv, per_landmark.csv; the run's
--tag names its setting). With one RUN_DIR equal to OUT, writes OUT/tre_boxplot.png (TRE per seed by
method). With several (a settings sweep), also writes OUT/error_vs_time.csv and OUT/error_vs_time.png:
for every (method, tag), the mean seed TRE, mean HD95 and mean Dice over all pairs against the median
compute time per pair, and prints the table (markdown). Lengths in mm, times in s.
"""
import csv
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


out = sys.argv[1]
runs = sys.argv[2:] or [out]
landmarks, pairs = [], []
for d in runs:
    landmarks += rows(f"{d}/per_landmark.csv")
    pairs += rows(f"{d}/per_pair.csv")

# TRE box plot per (method, tag).
groups = OrderedDict()
for r in landmarks:
    groups.setdefault((r["method"], r["tag"]), []).append(float(r["tre_mm"]))
fig, ax = plt.subplots(figsize=(max(5, 0.9 * len(groups) + 2), 4))
ax.boxplot(list(groups.values()), labels=[m if len(runs) == 1 else f"{m}\n{t}" for m, t in groups], showmeans=True)
ax.set_ylabel("seed target registration error [mm]")
ax.set_title("TRE per seed (box: quartiles, triangle: mean)")
ax.tick_params(axis="x", labelsize=7)
fig.tight_layout()
fig.savefig(f"{out}/tre_boxplot.png", dpi=120)

# Error against run time, one point per (method, tag).
summary = OrderedDict()
for r in pairs:
    summary.setdefault((r["method"], r["tag"]), []).append(r)
table = []
for (method, tag), rs in summary.items():
    tre = groups[(method, tag)]
    times = [float(r["seconds"]) for r in rs if r["seconds"] != ""]
    table.append(dict(method=method, tag=tag, pairs=len(rs), seeds=len(tre), tre=statistics.mean(tre),
                      tre_max=max(tre), hd95=statistics.mean(float(r["hd95_mean_mm"]) for r in rs),
                      dice=statistics.mean(float(r["dice_mean"]) for r in rs),
                      jmin=min(float(r["jacobian_min"]) for r in rs),
                      time=statistics.median(times) if times else float("nan")))
with open(f"{out}/error_vs_time.csv", "w") as f:
    f.write("# mean over pairs (TRE over every seed); time: median compute time per pair [s]\n"
            "method,tag,pairs,seeds,tre_mean_mm,tre_max_mm,hd95_mean_mm,dice_mean,jacobian_min,median_seconds\n")
    for t in table:
        f.write(f'{t["method"]},{t["tag"]},{t["pairs"]},{t["seeds"]},{t["tre"]:.4f},{t["tre_max"]:.4f},'
                f'{t["hd95"]:.4f},{t["dice"]:.5f},{t["jmin"]:.4f},{t["time"]:.2f}\n')
print("| method | setting | pairs | seeds | TRE mean [mm] | TRE max [mm] | HD95 [mm] | Dice | min J | median time [s] |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for t in table:
    print(f'| {t["method"]} | {t["tag"]} | {t["pairs"]} | {t["seeds"]} | {t["tre"]:.2f} | {t["tre_max"]:.2f} | '
          f'{t["hd95"]:.2f} | {t["dice"]:.4f} | {t["jmin"]:.3f} | {t["time"]:.1f} |')

colors = {"fem": "tab:blue", "demons": "tab:orange", "identity": "tab:gray"}
fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
for t in table:
    x = max(t["time"], 0.05)  # the identity takes no time; drawn at the left edge of the log axis
    for a, key, label in ((ax[0], "tre", "seed TRE, mean [mm]"), (ax[1], "hd95", "HD95, mean of organs [mm]"),
                          (ax[2], "dice", "Dice, mean of organs")):
        a.scatter(x, t[key], color=colors.get(t["method"], "k"), label=t["method"])
        a.annotate(t["tag"], (x, t[key]), fontsize=6, xytext=(3, 3), textcoords="offset points")
        a.set_xscale("log")
        a.set_xlabel("compute time per pair (median) [s]")
        a.set_ylabel(label)
handles, labels = ax[0].get_legend_handles_labels()
unique = OrderedDict(zip(labels, handles))
ax[0].legend(unique.values(), unique.keys())
fig.suptitle("Error against run time (identity = no registration, the floor)")
fig.tight_layout()
fig.savefig(f"{out}/error_vs_time.png", dpi=120)
print(f"\nwrote {out}/tre_boxplot.png, {out}/error_vs_time.png and {out}/error_vs_time.csv")
