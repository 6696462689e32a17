"""Plots the identifiability sweep and the convergence history of a `biomechreg register` run.

Usage: /usr/bin/python3 scripts/plot_register.py OUT_DIR
Reads OUT_DIR/sweep.csv and OUT_DIR/history.csv and writes OUT_DIR/sweep.png: Phi*(E) over the sweep
(coarse mesh) with the estimate from report.json, and Phi* of the fine-mesh inner solves against E.
"""
import csv
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


out = sys.argv[1]
report = json.load(open(f"{out}/report.json"))
sweep = rows(f"{out}/sweep.csv")
history = rows(f"{out}/history.csv")
ecol = next(k for k in sweep[0] if k.startswith("E_"))
name = ecol[2:-4]
fig, ax = plt.subplots(1, 2, figsize=(11, 4))
ax[0].semilogx([float(r[ecol]) for r in sweep], [float(r["phi_mm2"]) for r in sweep], "o-", label="sweep (coarse mesh)")
estimate = report["youngs_modulus_kPa"][name]
ax[0].axvline(estimate, color="r", ls="--", label=f"estimate {estimate:.1f} kPa")
ax[0].set(xlabel=f"E of {name} [kPa]", ylabel="Phi* [mm^2]",
          title="identifiable" if report["identifiable"] else "NOT identifiable")
ax[0].legend()
fine = [r for r in history if r["stage"] == "fine"]
outer = [r for r in history if r["stage"] == "outer"]
ax[1].plot([float(r[ecol]) for r in fine], [float(r["phi_mm2"]) for r in fine], "x", label="fine inner solves")
ax[1].plot([float(r[ecol]) for r in outer], [float(r["phi_mm2"]) for r in outer], "o-", label="accepted outer iterates")
ax[1].set(xlabel=f"E of {name} [kPa]", ylabel="Phi* [mm^2]", title="fine mesh (L-BFGS-B over log E)")
ax[1].legend()
fig.tight_layout()
fig.savefig(f"{out}/sweep.png", dpi=100)
print(f"wrote {out}/sweep.png")
