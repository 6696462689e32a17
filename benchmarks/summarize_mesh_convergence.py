#!/usr/bin/env python3
"""Summary of the mesh-convergence study of the recovered modulus (issue 15, item 1; not a test).

Usage: summarize_mesh_convergence.py RUNS.csv [OUT_PREFIX]

RUNS.csv (benchmarks/run_mesh_convergence.sh): config,true_E_kPa,mesh_scale,tetrahedra,E_kPa,wall_s, one row per
point estimate; a configuration's realizations are its runs at slightly jittered --mesh-scale (other meshes of the
same sizes). Per configuration and modulus: the mean and SD of E over the realizations, the median tetrahedra and
wall time, and the mean's offset from the reference configuration's mean (the finest uniform mesh, config
"uniform-fine"; with its standard error from both means' spreads) and from the truth. Prints a markdown table; writes OUT_PREFIX.csv and OUT_PREFIX.png (E against
tetrahedra with one-SD bars, the reference mean as a band).
"""
import csv
import statistics
import sys
from collections import defaultdict

REFERENCE = "uniform-fine"


def main(argv):
    if not argv:
        sys.exit(__doc__)
    rows = list(csv.DictReader(open(argv[0])))
    prefix = argv[1] if len(argv) > 1 else None
    groups = defaultdict(list)
    for r in rows:
        groups[(r["config"], float(r["true_E_kPa"]))].append(r)
    reference = {E: statistics.mean(float(r["E_kPa"]) for r in g)
                 for (config, E), g in groups.items() if config == REFERENCE}
    # The reference mean's own variance (SD^2 / n): part of every offset's standard error.
    reference_var = {E: statistics.variance([float(r["E_kPa"]) for r in g]) / len(g)
                     for (config, E), g in groups.items() if config == REFERENCE and len(g) > 1}
    summary = []
    for (config, E), g in sorted(groups.items(), key=lambda kv: (kv[0][1], statistics.median(
            float(r["tetrahedra"]) for r in kv[1]))):
        values = [float(r["E_kPa"]) for r in g]
        mean = statistics.mean(values)
        sd = statistics.stdev(values) if len(values) > 1 else float("nan")
        ref = reference.get(E)
        summary.append({"config": config, "true_E_kPa": E, "runs": len(values),
                        "tetrahedra": int(statistics.median(float(r["tetrahedra"]) for r in g)),
                        "wall_s": statistics.median(float(r["wall_s"]) for r in g),
                        "mean_E_kPa": mean, "sd_E_kPa": sd,
                        "vs_reference_pct": 100 * (mean / ref - 1) if ref else float("nan"),
                        "se_vs_reference_pct": 100 * ((sd * sd / len(values) if len(values) > 1 else 0.0) +
                                                      reference_var.get(E, 0.0)) ** 0.5 / ref
                        if ref else float("nan"),
                        "vs_truth_pct": 100 * (mean / E - 1)})
    print("| true E [kPa] | configuration | runs | tetrahedra | wall [s] | E mean ± SD [kPa] | vs finest mean "
          "(± SE) | vs truth |")
    print("|---:|---|---:|---:|---:|---:|---:|---:|")
    for s in summary:
        print(f"| {s['true_E_kPa']:.0f} | {s['config']} | {s['runs']} | {s['tetrahedra']} | {s['wall_s']:.1f} | "
              f"{s['mean_E_kPa']:.1f} ± {s['sd_E_kPa']:.1f} | {s['vs_reference_pct']:+.1f} ± "
              f"{s['se_vs_reference_pct']:.1f} % | {s['vs_truth_pct']:+.1f} % |")
    if not prefix:
        return
    with open(prefix + ".csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0].keys()))
        writer.writeheader()
        writer.writerows(summary)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    moduli = sorted({s["true_E_kPa"] for s in summary})
    fig, axes = plt.subplots(1, len(moduli), figsize=(6 * len(moduli), 4.5), squeeze=False)
    for ax, E in zip(axes[0], moduli):
        for s in (s for s in summary if s["true_E_kPa"] == E):
            ax.errorbar(s["tetrahedra"], s["mean_E_kPa"], yerr=s["sd_E_kPa"], fmt="o", capsize=3, label=s["config"])
        if E in reference:
            ax.axhspan(reference[E] * 0.97, reference[E] * 1.03, color="0.85", label="finest mean ± 3 %")
        ax.axhline(E, color="k", ls="--", lw=1, label="truth")
        ax.set_xscale("log")
        ax.set_xlabel("tetrahedra")
        ax.set_ylabel("recovered E [kPa]")
        ax.set_title(f"true E {E:.0f} kPa (anatomy truth)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(prefix + ".png", dpi=120)


if __name__ == "__main__":
    main(sys.argv[1:])
