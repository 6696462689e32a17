"""Summarizes benchmarks/results/partial_volume_runs.csv (run_partial_volume.sh): per true modulus and fixed
input (binary labels or voxel fractions) the median |error| of the fit and of the stated estimate, the median
95 % interval ratio hi/lo, how often a bound was stated, and the coverage of the 95 % interval. Writes
partial_volume.csv and partial_volume.png into the output directory and prints a markdown table.
Usage: summarize_partial_volume.py RUNS.csv OUT_DIR"""
import csv
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

runs_csv, out = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(runs_csv)))
groups = {}
for r in rows:
    groups.setdefault((float(r["true_E_kPa"]), r["input"]), []).append(r)


def covered(r):
    E = float(r["true_E_kPa"])
    return ((r["lower_determined"] == "0" or E >= float(r["lo95_kPa"]))
            and (r["upper_determined"] == "0" or E <= float(r["hi95_kPa"])))


summary = []
for (E, input_), rs in sorted(groups.items()):
    summary.append(dict(E=E, input=input_, n=len(rs),
                        fit=statistics.median(abs(float(r["fit_kPa"]) / E - 1) for r in rs),
                        stated=statistics.median(abs(float(r["estimate_kPa"]) / E - 1) for r in rs),
                        width=statistics.median(float(r["hi95_kPa"]) / float(r["lo95_kPa"]) for r in rs),
                        bounds=sum(r["upper_determined"] == "0" or r["lower_determined"] == "0" for r in rs) / len(rs),
                        cov95=sum(covered(r) for r in rs) / len(rs),
                        rms=statistics.median(float(r["prostate_rms_mm"]) for r in rs)))

with open(f"{out}/partial_volume.csv", "w") as f:
    f.write("true_E_kPa,input,pairs,fit_median_abs_error,stated_median_abs_error,median_ratio_hi95_lo95,"
            "bound_fraction,coverage95,prostate_rms_mm\n")
    for d in summary:
        f.write(f'{d["E"]:g},{d["input"]},{d["n"]},{d["fit"]:.4f},{d["stated"]:.4f},{d["width"]:.3f},'
                f'{d["bounds"]:.2f},{d["cov95"]:.2f},{d["rms"]:.4f}\n')

print("| true E [kPa] | fixed input | pairs | median abs. error (fit) | median abs. error (stated) | "
      "median hi95/lo95 | bound stated | 95 % coverage | prostate RMS [mm] |")
print("|---:|---|---:|---:|---:|---:|---:|---:|---:|")
for d in summary:
    print(f'| {d["E"]:g} | {d["input"]} | {d["n"]} | {100 * d["fit"]:.1f} % | {100 * d["stated"]:.1f} % | '
          f'{d["width"]:.2f} | {d["bounds"]:.2f} | {d["cov95"]:.2f} | {d["rms"]:.3f} |')

fig, ax = plt.subplots(figsize=(7, 4.5))
for (E, input_), rs in sorted(groups.items()):
    x = [E * (0.95 if input_ == "binary" else 1.05)] * len(rs)
    est = [float(r["estimate_kPa"]) for r in rs]
    ax.errorbar(x, est, yerr=[[e - float(r["lo95_kPa"]) for e, r in zip(est, rs)],
                              [float(r["hi95_kPa"]) - e for e, r in zip(est, rs)]],
                fmt="o" if input_ == "binary" else "s", color="C0" if input_ == "binary" else "C1", capsize=3,
                label=input_ if E == min(k[0] for k in groups) else None)
ax.plot([50, 600], [50, 600], "k--", lw=0.8)
ax.set(xscale="log", yscale="log", xlabel="true prostate E [kPa]", ylabel="stated E and 95 % interval [kPa]",
       title="binary labels against voxel fractions (fixed side)")
ax.legend()
fig.tight_layout()
fig.savefig(f"{out}/partial_volume.png", dpi=120)
print(f"\nwrote {out}/partial_volume.csv, {out}/partial_volume.png")
