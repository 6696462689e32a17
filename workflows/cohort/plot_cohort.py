"""Plots of a cohort study (the last step of workflows/cohort/Snakefile).

Usage: python3 plot_cohort.py STUDY
Reads STUDY/cohort_patients.csv (per patient and material: mean, SD of the recovered Young's modulus [kPa] and
the covariates) and writes, for the first material and the covariate t_stage (else the first covariate):
  STUDY/cohort_box.png      per-patient mean modulus per covariate value (dissertation Fig. 3.9): box = quartiles,
                            whiskers = min/max, points = the patients;
  STUDY/cohort_scatter.png  per-patient mean with its SD over the fractions (error bars) against the covariate.
Without a covariate or a result both show a note instead.
"""
import csv
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

study = sys.argv[1]
with open(f"{study}/cohort_patients.csv") as f:
    reader = csv.DictReader(line for line in f if not line.startswith("#"))
    fixed = {"patient", "material", "n", "missing", "mean_kPa", "sd_kPa", "median_kPa", "min_kPa", "max_kPa",
             "undetermined_intervals", "mean_interval_68_width_kPa"}
    rows = list(reader)
    covariates = [c for c in (reader.fieldnames or []) if c not in fixed]

material = rows[0]["material"] if rows else None
covariate = "t_stage" if "t_stage" in covariates else (covariates[0] if covariates else None)
rows = [r for r in rows if r["material"] == material and r["mean_kPa"] != ""]


def empty(path, text):
    fig, ax = plt.subplots(figsize=(5, 3))
    ax.text(0.5, 0.5, text, ha="center", va="center")
    ax.axis("off")
    fig.savefig(path, dpi=120)
    plt.close(fig)


if not rows or covariate is None:
    note = "no covariate" if covariate is None else "no registered fraction"
    empty(f"{study}/cohort_box.png", note)
    empty(f"{study}/cohort_scatter.png", note)
    sys.exit(0)

groups = OrderedDict()
for r in sorted(rows, key=lambda r: float(r[covariate])):
    groups.setdefault(float(r[covariate]), []).append(float(r["mean_kPa"]))
label = (lambda v: f"T{v:g}") if covariate == "t_stage" else (lambda v: f"{v:g}")

fig, ax = plt.subplots(figsize=(5, 4))
ax.boxplot(list(groups.values()), labels=[label(v) for v in groups], whis=(0, 100))
for i, values in enumerate(groups.values(), start=1):
    ax.plot([i] * len(values), values, "o", color="tab:blue", alpha=0.6)
ax.set_xlabel(covariate)
ax.set_ylabel(f"mean recovered E of the {material} [kPa]")
ax.set_title("per-patient mean modulus by covariate")
fig.tight_layout()
fig.savefig(f"{study}/cohort_box.png", dpi=120)
plt.close(fig)

fig, ax = plt.subplots(figsize=(5, 4))
x = [float(r[covariate]) for r in rows]
y = [float(r["mean_kPa"]) for r in rows]
e = [float(r["sd_kPa"]) for r in rows]
ax.errorbar(x, y, yerr=e, fmt="o", capsize=3)
for xi, yi, r in zip(x, y, rows):
    ax.annotate(r["patient"], (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7)
ax.set_xlabel(covariate)
ax.set_ylabel(f"recovered E of the {material} [kPa] (mean ± SD over fractions)")
fig.tight_layout()
fig.savefig(f"{study}/cohort_scatter.png", dpi=120)
plt.close(fig)
print(f"wrote {study}/cohort_box.png and cohort_scatter.png ({len(rows)} patients, covariate {covariate})")
