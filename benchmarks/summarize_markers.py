"""Summarizes the marker benchmark (benchmarks/run_marker_benchmark.sh): per method the leave-one-out TRE and the
prostate IoU / D over the pairs, paired tests of FEM against rigid alignment and the thin-plate spline (two-sided
paired t-test and exact Wilcoxon signed-rank test), and the gEUD of the estimated against the true treatment
anatomy per margin. Writes markers_summary.md and markers.png into the results folder; prints the tables."""
import csv
import itertools
import math
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
pairs = list(csv.DictReader(open(f"{out}/markers_pairs.csv")))
# Without the dose study (DOSE=off) there is no dose table: the gEUD tables and panel stay empty.
dose_path = f"{out}/markers_dose.csv"
dose = list(csv.DictReader(open(dose_path))) if os.path.exists(dose_path) else []
methods = ["fem", "rigid", "tps", "none"]


def incomplete_beta(a, b, x):
    """Regularized incomplete beta I_x(a, b) by its continued fraction (modified Lentz)."""
    if x <= 0.0 or x >= 1.0:
        return 0.0 if x <= 0.0 else 1.0
    if x > (a + 1.0) / (a + b + 2.0):
        return 1.0 - incomplete_beta(b, a, 1.0 - x)
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)) / a
    f, c, d = 1.0, 1.0, 0.0
    for i in range(400):
        m = i // 2
        if i == 0:
            numerator = 1.0
        elif i % 2 == 0:
            numerator = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
        else:
            numerator = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))
        d = 1.0 + numerator * d
        d = 1.0 / (d if abs(d) > 1e-300 else 1e-300)
        c = 1.0 + numerator / (c if abs(c) > 1e-300 else 1e-300)
        f *= c * d
        if abs(1.0 - c * d) < 1e-14:
            break
    return front * (f - 1.0)


def paired_t(differences):
    """Two-sided p of the paired t-test (t with n - 1 degrees of freedom)."""
    n = len(differences)
    if n < 2:
        return float("nan")
    mean = statistics.mean(differences)
    sd = statistics.stdev(differences)
    if sd == 0.0:
        return 0.0 if mean != 0.0 else 1.0
    t = mean / (sd / math.sqrt(n))
    nu = n - 1
    return incomplete_beta(nu / 2.0, 0.5, nu / (nu + t * t))


def wilcoxon_exact(differences):
    """Two-sided exact p of the Wilcoxon signed-rank test (zeros dropped, tied ranks averaged)."""
    d = [x for x in differences if x != 0.0]
    n = len(d)
    if n == 0:
        return 1.0
    order = sorted(range(n), key=lambda i: abs(d[i]))
    ranks = [0.0] * n
    i = 0
    while i < n:
        j = i
        while j + 1 < n and abs(d[order[j + 1]]) == abs(d[order[i]]):
            j += 1
        for k in range(i, j + 1):
            ranks[order[k]] = (i + j) / 2.0 + 1.0
        i = j + 1
    observed = sum(r for r, x in zip(ranks, d) if x > 0)
    centre = sum(ranks) / 2.0
    extreme = 0
    for signs in itertools.product((0, 1), repeat=n):
        w = sum(r for r, s in zip(ranks, signs) if s)
        extreme += abs(w - centre) >= abs(observed - centre) - 1e-12
    return extreme / 2 ** n


by = {m: {r["pair"]: r for r in pairs if r["method"] == m} for m in methods}
names = sorted(by["fem"])
lines = [f"# Marker-driven deformation: {len(names)} phantom pairs", ""]
lines += ["| method | median LOO TRE [mm] | range | median IoU | range | median D [mm] |", "|---|---:|---:|---:|---:|---:|"]
for m in methods:
    loo = [float(by[m][p]["loo_rms_mm"]) for p in names]
    iou = [float(by[m][p]["iou"]) for p in names]
    dd = [float(by[m][p]["mean_surface_distance_mm"]) for p in names]
    lines.append(f"| {m} | {statistics.median(loo):.2f} | {min(loo):.2f}-{max(loo):.2f} | {statistics.median(iou):.3f} | "
                 f"{min(iou):.3f}-{max(iou):.3f} | {statistics.median(dd):.2f} |")
# The leave-one-out error against the left-out marker's true position (without its tracking noise), when recorded.
with_truth = all(by[m][p].get("loo_true_rms_mm") not in (None, "") for m in methods for p in names)
quantities = [("loo_rms_mm", "LOO TRE [mm]", -1)]
quantities += [("loo_true_rms_mm", "LOO TRE vs truth [mm]", -1)] if with_truth else []
quantities += [("iou", "IoU", 1), ("mean_surface_distance_mm", "D [mm]", -1)]
if with_truth:
    lines += ["", "| method | median LOO TRE against the true positions [mm] | range |", "|---|---:|---:|"]
    for m in methods:
        loo = [float(by[m][p]["loo_true_rms_mm"]) for p in names]
        lines.append(f"| {m} | {statistics.median(loo):.2f} | {min(loo):.2f}-{max(loo):.2f} |")
lines += ["", "Paired tests, FEM against each reference (difference = FEM - reference; two-sided):", "",
          "| reference | quantity | FEM better in | mean difference | paired t p | Wilcoxon exact p |", "|---|---|---:|---:|---:|---:|"]
for ref in ["rigid", "tps"]:
    for key, label, better in quantities:
        diff = [float(by["fem"][p][key]) - float(by[ref][p][key]) for p in names]
        wins = sum(1 for x in diff if better * x > 0)
        lines.append(f"| {ref} | {label} | {wins}/{len(diff)} | {statistics.mean(diff):+.3f} | {paired_t(diff):.4f} | "
                     f"{wilcoxon_exact(diff):.4f} |")

# gEUD: estimated against true treatment anatomy, per margin and structure.
eud = {}
for r in dose:
    eud[(r["pair"], r["margin_mm"], r["anatomy"], r["structure"])] = float(r["gEUD_Gy"])
margins = sorted({int(r["margin_mm"]) for r in dose})
lines += ["", "gEUD error against the true treatment anatomy, |estimated - true| / true, median (max) over pairs:", "",
          "| margin [mm] | structure | true gEUD [Gy] (median) | planned | FEM | rigid | spline |", "|---:|---|---:|---:|---:|---:|---:|"]
for structure in ["prostate", "anterior_rectal_wall"]:
    for margin in margins:
        cells = []
        truths = [eud.get((p, str(margin), "true", structure)) for p in names]
        if None in truths:
            continue
        for a in ["planned", "fem", "rigid", "tps"]:
            errs = [abs(eud[(p, str(margin), a, structure)] - eud[(p, str(margin), "true", structure)]) /
                    eud[(p, str(margin), "true", structure)] for p in names]
            cells.append(f"{100 * statistics.median(errs):.2f} % ({100 * max(errs):.2f} %)")
        lines.append(f"| {margin} | {structure} | {statistics.median(truths):.2f} | " + " | ".join(cells) + " |")
text = "\n".join(lines) + "\n"
open(f"{out}/markers_summary.md", "w").write(text)
print(text)

fig, axes = plt.subplots(1, 3, figsize=(13, 4))
for ax, key, label in zip(axes[:2], ["loo_rms_mm", "iou"], ["leave-one-out TRE [mm]", "prostate IoU"]):
    data = [[float(by[m][p][key]) for p in names] for m in methods]
    ax.boxplot(data, labels=methods)
    for k, values in enumerate(data):
        ax.plot([k + 1] * len(values), values, "k.", alpha=0.5)
    ax.set_ylabel(label)
for structure, style in [("prostate", "o-"), ("anterior_rectal_wall", "s--")]:
    for a, colour in [("fem", "C0"), ("rigid", "C1"), ("tps", "C2"), ("planned", "C7")]:
        med = []
        for margin in margins:
            errs = [100 * abs(eud[(p, str(margin), a, structure)] - eud[(p, str(margin), "true", structure)]) /
                    eud[(p, str(margin), "true", structure)] for p in names if (p, str(margin), "true", structure) in eud]
            med.append(statistics.median(errs) if errs else float("nan"))
        axes[2].plot(margins, med, style, color=colour, label=f"{a}, {structure.replace('_', ' ')}")
axes[2].set_xlabel("PTV margin [mm]")
axes[2].set_ylabel("median |gEUD error| [%]")
axes[2].legend(fontsize=6)
fig.tight_layout()
fig.savefig(f"{out}/markers.png", dpi=120)
