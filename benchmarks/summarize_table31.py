"""Summarizes the Table 3.1 realizations (run_calibration_benchmark.sh with DESIGN=table31): per row (scene x
true E) the mean and SD over the phantom seeds of the stated estimate's relative error, the coverage of the
stated 68 % and 95 % intervals (a stated bound covers when it is true), and how often a bound was stated.
Writes table31.csv and table31.png into the output directory and prints a markdown table.
Usage: summarize_table31.py TABLE31_RUNS.csv OUT_DIR"""
import csv
import math
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from interval_rows import covers, determined  # noqa: E402

SCENES = {("8.00", "4.00"): "A", ("5.00", "6.00"): "B"}  # bladder / rectum wall displacements [mm]

runs_csv, out = sys.argv[1:3]
groups = OrderedDict()
for r in csv.DictReader(open(runs_csv)):
    scene = SCENES.get((r["bladder_mm"], r["rectum_mm"]), f'{r["bladder_mm"]}/{r["rectum_mm"]}')
    groups.setdefault((scene, float(r["true_E_kPa"])), []).append(r)
rows = []
for (scene, E), rs in sorted(groups.items()):
    det = [r for r in rs if determined(r)]
    err = [float(r["estimate_kPa"]) / E - 1 for r in det]
    fit = [float(r["fit_kPa"]) / E - 1 for r in rs]
    rows.append(dict(scene=scene, E=E, n=len(rs), bounds=len(rs) - len(det),
                     mean=statistics.mean(err) if err else float("nan"),
                     sd=statistics.stdev(err) if len(err) > 1 else float("nan"),
                     fit_mean=statistics.mean(fit), fit_sd=statistics.stdev(fit) if len(fit) > 1 else float("nan"),
                     cov68=sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in rs) / len(rs),
                     cov95=sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in rs) / len(rs),
                     width=statistics.median(float(r["hi95_kPa"]) / float(r["lo95_kPa"]) for r in rs),
                     seconds=statistics.median(float(r["register_s"]) for r in rs), errors=err))

with open(f"{out}/table31.csv", "w") as f:
    f.write("scene,true_E_kPa,realizations,bounds,mean_relative_error,sd_relative_error,fit_mean_relative_error,"
            "fit_sd_relative_error,coverage68,coverage95,median_hi95_over_lo95,median_register_s\n")
    for d in rows:
        f.write(f'{d["scene"]},{d["E"]:g},{d["n"]},{d["bounds"]},{d["mean"]:.4f},{d["sd"]:.4f},{d["fit_mean"]:.4f},'
                f'{d["fit_sd"]:.4f},{d["cov68"]:.2f},{d["cov95"]:.2f},{d["width"]:.3f},{d["seconds"]:.1f}\n')

print("\nTable 3.1 with realizations (errors of the stated estimate over the realizations with a determined interval;"
      " a stated bound counts as covering when true)\n")
print("| scene | true E [kPa] | realizations | bounds stated | mean error | SD error | fit: mean / SD error "
      "| 68 % coverage | 95 % coverage | median hi95/lo95 | median register [s] |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")


def percent(x, sign=""):
    """x as a percentage, or a dash when undetermined (every realization a bound, or one realization's SD)."""
    return "–" if math.isnan(x) else f"{100 * x:{sign}.1f} %"


for d in rows:
    print(f'| {d["scene"]} | {d["E"]:g} | {d["n"]} | {d["bounds"]} | {percent(d["mean"], "+")} | {percent(d["sd"])} | '
          f'{percent(d["fit_mean"], "+")} / {percent(d["fit_sd"])} | {d["cov68"]:.2f} | {d["cov95"]:.2f} | '
          f'{d["width"]:.2f} | {d["seconds"]:.0f} |')
every = [r for rs in groups.values() for r in rs]
print(f'\nall {len(every)} pairs: 68 % coverage '
      f'{sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in every) / len(every):.2f}, 95 % '
      f'{sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in every) / len(every):.2f}, '
      f'bounds {sum(1 for r in every if not determined(r))}')

fig, ax = plt.subplots(1, 2, figsize=(13, 4.8))
for scene, shift, marker in (("A", -4, "o"), ("B", 4, "s")):
    ds = [d for d in rows if d["scene"] == scene]
    for d in ds:
        ax[0].plot([d["E"] + shift] * len(d["errors"]), [100 * e for e in d["errors"]], marker, ms=3, alpha=0.4,
                   color="C0" if scene == "A" else "C1")
    ax[0].errorbar([d["E"] + shift for d in ds], [100 * d["mean"] for d in ds], [100 * d["sd"] for d in ds],
                   fmt=marker + "-", capsize=3, color="C0" if scene == "A" else "C1", label=f"scene {scene}: mean ± SD")
    ax[1].plot([d["E"] + shift for d in ds], [d["cov68"] for d in ds], marker + "-", label=f"{scene}: 68 %")
    ax[1].plot([d["E"] + shift for d in ds], [d["cov95"] for d in ds], marker + "--", label=f"{scene}: 95 %")
ax[0].axhline(0, color="k", lw=0.8)
ax[0].set(xlabel="true prostate E [kPa]", ylabel="error of the stated E [%]",
          title="Table 3.1 over phantom seeds (dots: realizations)")
ax[0].legend()
for level in (0.68, 0.95):
    ax[1].axhline(level, color="0.5", lw=0.8, ls=":")
ax[1].set(xlabel="true prostate E [kPa]", ylabel="fraction of realizations covered", ylim=(0, 1.05),
          title="coverage of the stated intervals per row")
ax[1].legend(fontsize=8, ncol=2)
fig.tight_layout()
fig.savefig(f"{out}/table31.png", dpi=110)
