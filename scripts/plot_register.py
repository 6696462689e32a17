"""Plots the identifiability sweep and the convergence history of a `biomechreg register` run.

Usage: /usr/bin/python3 scripts/plot_register.py OUT_DIR
Reads OUT_DIR/report.json, OUT_DIR/history.csv (`register --outputs ...,history`) and, when present,
OUT_DIR/sweep.csv (`--outputs ...,sweep`; the demo writes both), and writes OUT_DIR/sweep.png: Phi*(E) over the
sweep (coarse mesh) with the estimate, and Phi* of the fine-mesh inner solves against E.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


if len(sys.argv) != 2:
    sys.exit(__doc__)
out = sys.argv[1]
for needed in ("report.json", "history.csv"):
    if not os.path.isfile(f"{out}/{needed}"):
        sys.exit(f"error: {out}/{needed} is missing (run register with --outputs all, or the demo)")
report = json.load(open(f"{out}/report.json"))
history = rows(f"{out}/history.csv")
if not history or not any(k.startswith("E_") for k in history[0]):
    sys.exit(f"error: {out}/history.csv holds no estimated modulus to plot")
sweep = rows(f"{out}/sweep.csv") if os.path.isfile(f"{out}/sweep.csv") else []
ecol = next(k for k in history[0] if k.startswith("E_"))
name = ecol[2:-4]
estimate = report["youngs_modulus_kPa"][name]
fig, ax = plt.subplots(1, 2, figsize=(11, 4))
if sweep:
    ax[0].semilogx([float(r[ecol]) for r in sweep], [float(r["phi_mm2"]) for r in sweep], "o-",
                   label="sweep (coarse mesh)")
else:
    ax[0].text(0.5, 0.5, "no sweep.csv (register --outputs sweep)", ha="center", transform=ax[0].transAxes)
ax[0].axvline(estimate, color="r", ls="--", label=f"estimate {estimate:.1f} kPa")
ax[0].set(xlabel=f"E of {name} [kPa]", ylabel="Phi* [mm^2]",
          title="identifiable" if report["identifiable"] else "NOT identifiable")
ax[0].legend()
fine = [r for r in history if r["stage"] == "fine"]
outer = [r for r in history if r["stage"] == "outer"]
ax[1].plot([float(r[ecol]) for r in fine], [float(r["phi_mm2"]) for r in fine], "x", label="fine inner solves")
ax[1].plot([float(r[ecol]) for r in outer], [float(r["phi_mm2"]) for r in outer], "o-", label="accepted outer iterates")
ax[1].set(xlabel=f"E of {name} [kPa]", ylabel="Phi* [mm^2]", title="fine mesh (outer search over log E)")
ax[1].legend()
fig.tight_layout()
fig.savefig(f"{out}/sweep.png", dpi=100)
print(f"wrote {out}/sweep.png")
