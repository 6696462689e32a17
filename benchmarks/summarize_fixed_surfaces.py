"""The fixed organs' surfaces at clinical slices, from run_fixed_surfaces.sh rows.

Usage: summarize_fixed_surfaces.py RUNS.csv OUT_DIR. Per kind of fixed surface (voxels, outlines, volume): the
fit's log error log(fit / true E) (median and SD over the pairs whose fit stayed inside the search range), its
median paired difference from the voxels' fit on the same pair, the stated estimate's median |error|, the 95 %
statement's coverage (an interval, or a one-sided bound) and how many were not determined, the prostate's surface
RMS and the inverted elements. Writes OUT_DIR/fixed_surfaces.csv and fixed_surfaces.png (log error of the fit
against the true modulus per kind) and prints a markdown table.
"""
import csv
import math
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from interval_rows import covers, write_table  # noqa: E402

UPPER_KPA = 600.0


def inside(r):
    return float(r["fit_kPa"]) < 0.999 * UPPER_KPA


def log_error(r, key="fit_kPa"):
    return math.log(float(r[key]) / float(r["true_E_kPa"]))


def summarize(rows):
    kinds = OrderedDict()
    for r in rows:
        kinds.setdefault(r["surfaces"], []).append(r)
    voxels = {r["pair"]: r for r in kinds.get("voxels", [])}
    table = []
    for kind, group in kinds.items():
        fits = [log_error(r) for r in group if inside(r)]
        paired = [log_error(r) - log_error(voxels[r["pair"]]) for r in group
                  if r["pair"] in voxels and inside(r) and inside(voxels[r["pair"]])]
        stated = [r for r in group if r["not_determined"] != "1"]
        both = [r for r in stated if r["lower_determined"] == "1" and r["upper_determined"] == "1"]
        table.append(OrderedDict(
            surfaces=kind, pairs=len(group), fits_inside=len(fits),
            median_log_error=statistics.median(fits) if fits else float("nan"),
            sd_log_error=statistics.stdev(fits) if len(fits) > 1 else float("nan"),
            median_paired_vs_voxels=statistics.median(paired) if paired else float("nan"),
            median_abs_error_stated_pct=100 * statistics.median(abs(math.exp(log_error(r, "estimate_kPa")) - 1)
                                                                for r in both) if both else float("nan"),
            cover95=sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in stated) / max(len(stated), 1),
            stated=len(stated), not_determined=len(group) - len(stated),
            median_hi95_over_lo95=statistics.median(float(r["hi95_kPa"]) / float(r["lo95_kPa"]) for r in both)
            if both else float("nan"),
            median_prostate_rms_mm=statistics.median(float(r["prostate_rms_mm"]) for r in group),
            median_inverted=statistics.median(int(r["inverted_elements"]) for r in group if r["inverted_elements"])))
    return kinds, table


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    with open(argv[1]) as f:
        rows = list(csv.DictReader(f))
    kinds, table = summarize(rows)
    write_table(f"{argv[2]}/fixed_surfaces.csv", table)
    print("| fixed surfaces | pairs | fit log error: median (SD) | paired vs voxels | stated: median abs. error | "
          "95 % covers (stated) | not determined | median hi95/lo95 | prostate RMS [mm] | inverted |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in table:
        print(f"| {r['surfaces']} | {r['pairs']} | {r['median_log_error']:+.3f} ({r['sd_log_error']:.3f}, "
              f"{r['fits_inside']} inside) | {r['median_paired_vs_voxels']:+.3f} | "
              f"{r['median_abs_error_stated_pct']:.0f} % | {r['cover95']:.2f} ({r['stated']}) | {r['not_determined']} | "
              f"{r['median_hi95_over_lo95']:.2f} | {r['median_prostate_rms_mm']:.3f} | {r['median_inverted']:.0f} |")
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for kind, group in kinds.items():
        ax.scatter([float(r["true_E_kPa"]) for r in group], [log_error(r) for r in group], s=16, label=kind)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xscale("log")
    ax.set_xlabel("true E [kPa]")
    ax.set_ylabel("log(fit / true E)")
    ax.set_title("The fit's error by the fixed organs' surfaces")
    ax.legend()
    fig.tight_layout()
    fig.savefig(f"{argv[2]}/fixed_surfaces.png", dpi=120)


if __name__ == "__main__":
    main(sys.argv)
