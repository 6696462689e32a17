"""Summarizes run_neo_hookean_benchmark.sh: per row (scene or filling) and estimation model, over the phantom
seeds, the error of the estimated prostate modulus (estimates on the scene's search bounds, which register
flags as not identifiable, counted apart) against what the data determine (the truth times the assumed
over the true tissue modulus: the model fixes only the ratio of the moduli, dissertation Table 3.7), the coverage
of the stated intervals when there are any (a stated bound covers when true), the prostate's surface RMS, the seed
TRE (and the identity's) and the register time. Writes neo_hookean_DESIGN.csv and .png, prints a markdown table.
Usage: summarize_neo_hookean.py NEO_HOOKEAN_RUNS_DESIGN.csv OUT_DIR"""
import csv
import os
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from interval_rows import covers, determined  # noqa: E402

runs_csv, out = sys.argv[1:3]
design = os.path.basename(runs_csv)[len("neo_hookean_runs_"):-len(".csv")]
groups = OrderedDict()
for r in csv.DictReader(open(runs_csv)):
    groups.setdefault((r["row"], float(r["true_E_kPa"]), r["estimation_model"]), []).append(r)


SEARCH_BOUNDS_KPA = (20.0, 600.0)  # the phantom scene's prostate bounds_kPa: an estimate there is flagged, not known


def on_bound(r):
    """Whether the estimate lies on the scene's search bounds (register flags it as not identifiable)."""
    E = float(r["estimate_kPa"])
    return E <= SEARCH_BOUNDS_KPA[0] * 1.0001 or E >= SEARCH_BOUNDS_KPA[1] * 0.9999


def expected(r):
    """What the estimate should be: the truth scaled by the assumed over the true tissue modulus [kPa]."""
    return float(r["true_E_kPa"]) * float(r["assumed_tissue_kPa"]) / float(r["truth_tissue_kPa"])


def median(rs, key):
    return statistics.median(float(r[key]) for r in rs)


rows = []
for (name, E, model), rs in groups.items():
    errors = [float(r["estimate_kPa"]) / expected(r) - 1 for r in rs if not on_bound(r)] or [float("nan")]
    with_interval = [r for r in rs if r["lo95_kPa"]]
    rows.append(dict(row=name, E=E, model=model, n=len(rs), expected=expected(rs[0]),
                     filling=median(rs, "bladder_max_mm"), rectum=median(rs, "rectum_max_mm"),
                     median_error=statistics.median(errors), mean_error=statistics.mean(errors),
                     sd_error=statistics.stdev(errors) if len(errors) > 1 else float("nan"),
                     median_abs=statistics.median(abs(e) for e in errors),
                     intervals=len(with_interval), bounds=sum(1 for r in with_interval if not determined(r)),
                     on_bound=sum(1 for r in rs if on_bound(r)),
                     cov68=(sum(covers(r, float(r["lo68_kPa"]) * E / expected(r), float(r["hi68_kPa"]) * E / expected(r))
                                for r in with_interval) / len(with_interval)) if with_interval else float("nan"),
                     cov95=(sum(covers(r, float(r["lo95_kPa"]) * E / expected(r), float(r["hi95_kPa"]) * E / expected(r))
                                for r in with_interval) / len(with_interval)) if with_interval else float("nan"),
                     rms=median(rs, "prostate_rms_mm"), tre=median(rs, "seed_tre_mm"),
                     identity=median(rs, "identity_tre_mm"), seconds=median(rs, "register_s"),
                     tets=median(rs, "mesh_tetrahedra"), errors=errors))

with open(f"{out}/neo_hookean_{design}.csv", "w") as f:
    f.write("row,true_E_kPa,estimation_model,realizations,expected_kPa,bladder_max_mm,rectum_max_mm,"
            "on_search_bound,median_relative_error,mean_relative_error,sd_relative_error,median_abs_relative_error,"
            "intervals,bounds,"
            "coverage68,coverage95,median_prostate_rms_mm,median_seed_tre_mm,median_identity_tre_mm,"
            "median_register_s,median_tetrahedra\n")
    for d in rows:
        f.write(f'{d["row"]},{d["E"]:g},{d["model"]},{d["n"]},{d["expected"]:g},{d["filling"]:.2f},{d["rectum"]:.2f},'
                f'{d["on_bound"]},{d["median_error"]:.4f},{d["mean_error"]:.4f},{d["sd_error"]:.4f},{d["median_abs"]:.4f},'
                f'{d["intervals"]},{d["bounds"]},{d["cov68"]:.2f},{d["cov95"]:.2f},{d["rms"]:.4f},{d["tre"]:.4f},'
                f'{d["identity"]:.4f},{d["seconds"]:.1f},{d["tets"]:.0f}\n')


def pct(x):
    return "–" if x != x else f"{100 * x:+.1f} %"


print(f"\nNeo-Hookean benchmark, design {design} (error against the truth x assumed / true tissue modulus)\n")
print("| row | true E [kPa] | model | n | bladder / rectum max [mm] | on the search bound | median error | "
      "mean ± SD error | 68 % / 95 % coverage (bounds) | prostate RMS [mm] | seed TRE [mm] (identity) | register [s] |")
print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for d in rows:
    cov = "no interval" if not d["intervals"] else f'{d["cov68"]:.2f} / {d["cov95"]:.2f} ({d["bounds"]})'
    sd = "–" if d["sd_error"] != d["sd_error"] else f'{100 * d["sd_error"]:.1f} %'
    print(f'| {d["row"]} | {d["E"]:g} | {d["model"]} | {d["n"]} | {d["filling"]:.1f} / {d["rectum"]:.1f} | '
          f'{d["on_bound"]} | {pct(d["median_error"])} | {pct(d["mean_error"])} ± {sd} | {cov} | {d["rms"]:.3f} | '
          f'{d["tre"]:.3f} ({d["identity"]:.2f}) | {d["seconds"]:.0f} |')

fig, ax = plt.subplots(1, 2, figsize=(13, 4.8))
x_key = "filling" if design.startswith("filling") else "E"
for n, key in enumerate(sorted({(d["row"] if not design.startswith("filling") else "", d["model"]) for d in rows})):
    ds = [d for d in rows if (d["row"] if not design.startswith("filling") else "", d["model"]) == key]
    label = " ".join(k for k in key if k)
    for d in ds:
        ax[0].plot([d[x_key]] * len(d["errors"]), [100 * e for e in d["errors"]], "o", ms=3, alpha=0.4, color=f"C{n}")
    ax[0].plot([d[x_key] for d in ds], [100 * d["median_error"] for d in ds], "o-", color=f"C{n}", label=label)
    ax[1].plot([d[x_key] for d in ds], [d["tre"] for d in ds], "o-", color=f"C{n}", label=f"{label}: seed TRE")
    ax[1].plot([d[x_key] for d in ds], [d["rms"] for d in ds], "s--", color=f"C{n}", label=f"{label}: prostate RMS")
xlabel = "bladder filling (largest wall motion) [mm]" if design.startswith("filling") else "true prostate E [kPa]"
ax[0].axhline(0, color="k", lw=0.8)
for level in (-0.1, 0.1):
    ax[0].axhline(100 * level, color="0.6", lw=0.8, ls=":")
ax[0].set(xlabel=xlabel, ylabel="error of the estimated E [%]", title=f"neo-Hookean truths ({design}; dots: seeds)")
ax[0].legend(fontsize=8)
ax[1].set(xlabel=xlabel, ylabel="mm (medians)", title="seed TRE and prostate surface RMS")
ax[1].legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/neo_hookean_{design}.png", dpi=110)
