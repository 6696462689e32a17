"""Summarizes benchmarks/results/uncertainty_sources_runs.csv (run_uncertainty_sources.sh): per source of the
bootstrap (mesh, grid, slip, all) the spread s = SD(log E*) of its resamples on each pair, next to the fit's
actual |log error| on that pair. Writes uncertainty_sources.csv and uncertainty_sources.png into the output
directory and prints a markdown table.
Usage: summarize_uncertainty_sources.py RUNS.csv OUT_DIR"""
import csv
import math
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SOURCES = ("mesh", "grid", "slip", "all")

runs_csv, out = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(runs_csv)))
pairs = sorted({(float(r["true_E_kPa"]), r["seed"]) for r in rows})

table = []
for E, seed in pairs:
    line = {"true_E_kPa": E, "seed": seed}
    for r in rows:
        if float(r["true_E_kPa"]) == E and r["seed"] == seed:
            line[r["source"]] = float(r["sigma_log_E"])
            line["fit_log_error"] = math.log(float(r["fit_kPa"]) / E)
    table.append(line)

with open(f"{out}/uncertainty_sources.csv", "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["true_E_kPa", "seed", "fit_log_error"] + [f"s_{s}" for s in SOURCES] + ["s_quadrature_sum"])
    for line in table:
        parts = [line.get(s, float("nan")) for s in SOURCES[:3]]
        w.writerow([line["true_E_kPa"], line["seed"], f'{line.get("fit_log_error", float("nan")):.4f}']
                   + [f'{line.get(s, float("nan")):.4f}' for s in SOURCES]
                   + [f"{math.sqrt(sum(p * p for p in parts)):.4f}"])

print("| true E [kPa] | fit log error | s mesh | s grid | s slip | s all | quadrature sum of the three |")
print("|---:|---:|---:|---:|---:|---:|---:|")
for line in table:
    parts = [line.get(s, float("nan")) for s in SOURCES[:3]]
    print(f'| {line["true_E_kPa"]:g} | {line.get("fit_log_error", float("nan")):+.3f} | '
          + " | ".join(f'{line.get(s, float("nan")):.3f}' for s in SOURCES)
          + f" | {math.sqrt(sum(p * p for p in parts)):.3f} |")
medians = {s: statistics.median([line[s] for line in table if s in line]) for s in SOURCES if any(s in l for l in table)}
print("median s per source: " + ", ".join(f"{s} {v:.3f}" for s, v in medians.items()))

fig, ax = plt.subplots(figsize=(7, 4))
width = 0.8 / (len(SOURCES) + 1)
for j, s in enumerate(SOURCES):
    ax.bar([i + j * width for i in range(len(table))], [line.get(s, 0.0) for line in table], width, label=f"s {s}")
ax.bar([i + len(SOURCES) * width for i in range(len(table))], [abs(line.get("fit_log_error", 0.0)) for line in table],
       width, color="k", label="|fit log error|")
ax.set_xticks([i + 0.4 for i in range(len(table))])
ax.set_xticklabels([f'{line["true_E_kPa"]:g} kPa' for line in table])
ax.set_ylabel("SD of log E over resamples")
ax.set_title("Sources of the bootstrap's spread")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/uncertainty_sources.png", dpi=120)
