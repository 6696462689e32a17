"""Plots the dose-volume histograms of a `biomechreg dose` run.

Usage: /usr/bin/python3 scripts/plot_dvh.py OUT_DIR
Reads OUT_DIR/dvh.csv and OUT_DIR/dose_metrics.csv and writes OUT_DIR/dvh.png (through a temporary file, so a
failed run leaves no partial figure): the cumulative DVH of every structure (volume % receiving at least the
dose) with its gEUD in the legend, and the differential DVH (volume % per bin).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


out = sys.argv[1]
dvh = rows(f"{out}/dvh.csv")
metrics = {r["organ"]: r for r in rows(f"{out}/dose_metrics.csv")}
dose = [float(r["dose_Gy"]) for r in dvh]
width = dose[1] - dose[0] if len(dose) > 1 else 1.0
merge = max(1, round(1.0 / width))
fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
for organ, m in metrics.items():
    cumulative = [float(r[f"{organ}_cumulative_pct"]) for r in dvh]
    differential = [float(r[f"{organ}_differential_pct"]) for r in dvh]
    # The differential DVH summed over about 1 Gy: the 0.1 Gy bins of a voxelized organ are mostly empty.
    coarse = [sum(differential[i:i + merge]) for i in range(0, len(differential), merge)]
    label = f"{organ}: gEUD {float(m['gEUD_Gy']):.1f} Gy (a {float(m['a']):g}), D95 {float(m['D95_Gy']):.1f} Gy"
    line, = ax[0].plot(dose, cumulative, label=label)
    ax[1].step(dose[::merge], coarse, where="post", color=line.get_color(), label=organ)
ax[0].set(xlabel="dose [Gy]", ylabel="volume receiving >= dose [%]", title="cumulative DVH", ylim=(0, 102))
ax[0].grid(alpha=0.3)
ax[0].legend(fontsize=7)
ax[1].set(xlabel="dose [Gy]", ylabel=f"volume per {merge * width:g} Gy [%]", title="differential DVH")
ax[1].set_yscale("log")
ax[1].grid(alpha=0.3)
fig.tight_layout()
temporary = f"{out}/.dvh.{os.getpid()}.png"
try:
    fig.savefig(temporary, dpi=100)
    os.replace(temporary, f"{out}/dvh.png")
finally:
    if os.path.exists(temporary):
        os.remove(temporary)
print(f"wrote {out}/dvh.png")
