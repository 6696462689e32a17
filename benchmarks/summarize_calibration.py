"""Summarizes benchmarks/results/calibration_runs.csv (run_calibration_benchmark.sh): per tag (register settings)
the coverage of the stated 68 % and 95 % intervals, the median and 90th-percentile |error| per band of true E,
how often a bound was stated instead, and a reliability diagram. Writes calibration.csv and calibration.png into
the output directory and prints markdown tables.
Usage: summarize_calibration.py RUNS.csv [MORE_RUNS.csv ...] OUT_DIR (the runs of several files together, by tag)"""
import csv
import math
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from interval_rows import covers  # noqa: E402

BANDS = ((30, 150), (150, 300), (300, 500))


def student(z, dof):
    """Student's t quantile from the normal one (Cornish-Fisher, as itkModulusInterval.cxx)."""
    z3, z5, z7 = z ** 3, z ** 5, z ** 7
    return (z + (z3 + z) / (4 * dof) + (5 * z5 + 16 * z3 + 3 * z) / (96 * dof ** 2)
            + (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * dof ** 3))


def calibrated(r):
    """Whether the row's binary stated conformal half-widths (itk::IntervalHalfWidths); older rows had Student's."""
    return r.get("quantiles") == "calibrated"


def level_interval(r, p):
    """The interval at two-sided level p as the row's binary would state it: Student's centre x exp(+-t s
    sqrt(1 + 1/n)); calibrated rows have only their stated 68 and 95 % intervals (None at other levels)."""
    if calibrated(r):
        stated = {0.68: ("lo68_kPa", "hi68_kPa"), 0.95: ("lo95_kPa", "hi95_kPa")}.get(p)
        return (float(r[stated[0]]), float(r[stated[1]])) if stated else None
    n = int(r["resamples"] or 0)
    s = float(r["sigma_log_E"])
    z = statistics.NormalDist().inv_cdf(0.5 + p / 2)
    half = (student(z, n - 1) * math.sqrt(1 + 1 / n) if n >= 3 else z) * s
    c = float(r["estimate_kPa"])
    return c * math.exp(-half), c * math.exp(half)


def pct(values, q):
    v = sorted(values)
    if not v:
        return float("nan")
    k = (len(v) - 1) * q
    f = math.floor(k)
    return v[f] + (v[min(f + 1, len(v) - 1)] - v[f]) * (k - f)


*runs_csvs, out = sys.argv[1:]
rows = [r for runs_csv in runs_csvs for r in csv.DictReader(open(runs_csv))]
def fit_centred(r):
    """A row the benchmark's binary bias-corrected, stated as the code now does by default (centred on the fit;
    UncertaintySettings::correctBias off): fit x/ exp(t s sqrt(1 + 1/n)). Only determined rows are re-centred."""
    if r.get("bias_corrected") != "1" or r["lower_determined"] != "1" or r["upper_determined"] != "1":
        return r
    r = dict(r, estimate_kPa=r["fit_kPa"], bias_corrected="0")
    n, s, fit = int(r["resamples"]), float(r["sigma_log_E"]), float(r["fit_kPa"])
    for p, lo, hi in ((0.6826894921, "lo68_kPa", "hi68_kPa"), (0.95, "lo95_kPa", "hi95_kPa")):
        half = student(statistics.NormalDist().inv_cdf(0.5 + p / 2), n - 1) * math.sqrt(1 + 1 / n) * s
        r[lo], r[hi] = f"{fit * math.exp(-half):.3f}", f"{fit * math.exp(half):.3f}"
    return r


# The calibration set of the conformal half-widths (itkBiomechanicalPipelines.h, RescanCalibrations): the rescan
# run on the default, converged truths, pairs with no resample on a bound, s from each pair's first n rescans.
CONFORMAL_TAGS = ("facets-0.85", "facets-0.85-fresh")
CONFORMAL_RESAMPLES = (4, 8)


def conformal_half_widths(rows, n):
    """The split-conformal half-widths for n rescans: the ceil((m + 1) p)-th smallest of the m scores
    |log fit - log E| / s, s from the first n rescans."""
    scores = []
    for r in rows:
        if r["tag"] not in CONFORMAL_TAGS or not r.get("resamples_kPa"):  # older runs have no such column
            continue
        resamples = [float(x) for x in r["resamples_kPa"].split(";")][:n]
        if len(resamples) < n:
            continue
        if max(resamples) >= 599.4 or min(resamples) <= 20.02:
            continue
        s = statistics.stdev(math.log(x) for x in resamples)
        scores.append(abs(math.log(float(r["fit_kPa"]) / float(r["true_E_kPa"]))) / s)
    scores.sort()
    m = len(scores)
    return m, [scores[min(m, math.ceil((m + 1) * p)) - 1] if m else float("nan") for p in (0.68, 0.95)]


recentred = sum(1 for r in rows if r.get("bias_corrected") == "1")
rows = [fit_centred(r) for r in rows]
if recentred:
    print(f"{recentred} rows were bias-corrected by the run's binary and are stated here centred on the fit, as the "
          "code now does (UncertaintySettings::correctBias off)")
tags = OrderedDict()
for r in rows:
    tags.setdefault(r["tag"], []).append(r)

summary = []
for tag, rs in tags.items():
    determined = [r for r in rs if r["lower_determined"] == "1" and r["upper_determined"] == "1"]
    cov68 = sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in rs) / len(rs)
    cov95 = sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in rs) / len(rs)
    cov68d = sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in determined) / max(1, len(determined))
    summary.append(dict(tag=tag, band="all", n=len(rs), cov68=cov68, cov95=cov95, cov68d=cov68d,
                        bounds=sum(1 for r in rs if r not in determined) / len(rs),
                        med=pct([abs(float(r["estimate_kPa"]) / float(r["true_E_kPa"]) - 1) for r in determined], 0.5),
                        p90=pct([abs(float(r["estimate_kPa"]) / float(r["true_E_kPa"]) - 1) for r in determined], 0.9),
                        fitmed=pct([abs(float(r["fit_kPa"]) / float(r["true_E_kPa"]) - 1) for r in rs], 0.5),
                        width=statistics.median(float(r["hi95_kPa"]) / float(r["lo95_kPa"]) for r in rs)))
    for lo, hi in BANDS:
        b = [r for r in rs if lo <= float(r["true_E_kPa"]) < hi]
        if not b:
            continue
        bd = [r for r in b if r in determined]
        err = [abs(float(r["estimate_kPa"]) / float(r["true_E_kPa"]) - 1) for r in bd]
        cov68d = sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in bd) / len(bd) if bd else math.nan
        summary.append(dict(tag=tag, band=f"{lo}-{hi}", n=len(b), cov68d=cov68d,
                            cov68=sum(covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"])) for r in b) / len(b),
                            cov95=sum(covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"])) for r in b) / len(b),
                            bounds=(len(b) - len(bd)) / len(b), med=pct(err, 0.5), p90=pct(err, 0.9),
                            fitmed=pct([abs(float(r["fit_kPa"]) / float(r["true_E_kPa"]) - 1) for r in b], 0.5),
                            width=statistics.median(float(r["hi95_kPa"]) / float(r["lo95_kPa"]) for r in b)))

with open(f"{out}/calibration.csv", "w") as f:
    f.write("tag,band_kPa,pairs,coverage68,coverage95,bound_fraction,median_abs_error,p90_abs_error,"
            "fit_median_abs_error,median_ratio_hi95_lo95,coverage68_determined\n")
    for d in summary:
        f.write(f'{d["tag"]},{d["band"]},{d["n"]},{d["cov68"]:.3f},{d["cov95"]:.3f},{d["bounds"]:.3f},{d["med"]:.4f},'
                f'{d["p90"]:.4f},{d["fitmed"]:.4f},{d["width"]:.3f},{d["cov68d"]:.3f}\n')

print("\n| settings | true E band [kPa] | pairs | 68 % coverage | 68 % coverage, no bound | 95 % coverage | bound stated "
      "| median abs. error (stated) | 90th pct abs. error | median abs. error (fit) | median hi95/lo95 |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for d in summary:
    print(f'| {d["tag"]} | {d["band"]} | {d["n"]} | {d["cov68"]:.2f} | {d["cov68d"]:.2f} | {d["cov95"]:.2f} | '
          f'{d["bounds"]:.2f} | {100 * d["med"]:.1f} % | {100 * d["p90"]:.1f} % | {100 * d["fitmed"]:.1f} % | '
          f'{d["width"]:.2f} |')
for n in CONFORMAL_RESAMPLES:
    m, (k68, k95) = conformal_half_widths(rows, n)
    if m:
        print(f"\nconformal half-widths for {n} rescans from {m} scores of {', '.join(CONFORMAL_TAGS)}: k68 {k68:.3f}, "
              f"k95 {k95:.3f} (RescanCalibrations)")

print("\n| settings | pair | true E | fit | stated | 68 % | 95 % | covered 68/95 |")
print("|---|---:|---:|---:|---|---|---|---|")
for tag, rs in tags.items():
    for r in rs:
        stated = (f'{float(r["estimate_kPa"]):.1f}' if r["upper_determined"] == "1" and r["lower_determined"] == "1"
                  else (f'≥ {float(r["lo95_kPa"]):.1f}' if r["upper_determined"] == "0" else f'≤ {float(r["hi95_kPa"]):.1f}'))
        c68 = covers(r, float(r["lo68_kPa"]), float(r["hi68_kPa"]))
        c95 = covers(r, float(r["lo95_kPa"]), float(r["hi95_kPa"]))
        print(f'| {tag} | {r["pair"]} | {float(r["true_E_kPa"]):.1f} | {float(r["fit_kPa"]):.1f} | {stated} | '
              f'{float(r["lo68_kPa"]):.0f}–{float(r["hi68_kPa"]):.0f} | {float(r["lo95_kPa"]):.0f}–{float(r["hi95_kPa"]):.0f} | '
              f'{"yes" if c68 else "no"} / {"yes" if c95 else "no"} |')

fig, ax = plt.subplots(1, 3, figsize=(16, 5))
levels = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.68, 0.8, 0.9, 0.95, 0.99]
for tag, rs in tags.items():
    stated = [p for p in levels if all(level_interval(r, p) for r in rs)]
    cov = [sum(covers(r, *level_interval(r, p)) for r in rs) / len(rs) for p in stated]
    ax[0].plot(stated, cov, "o-", label=f"{tag} ({len(rs)} pairs)")
    E = [float(r["true_E_kPa"]) for r in rs]
    est = [float(r["estimate_kPa"]) for r in rs]
    lo = [e - float(r["lo95_kPa"]) for e, r in zip(est, rs)]
    hi = [float(r["hi95_kPa"]) - e for e, r in zip(est, rs)]
    ax[1].errorbar(E, est, yerr=[lo, hi], fmt="o", ms=4, capsize=2, label=f"{tag}: stated, 95 %")
    ax[2].plot(E, [100 * (float(r["fit_kPa"]) / e - 1) for r, e in zip(rs, E)], "x", label=f"{tag}: fit")
    ax[2].plot(E, [100 * (s / e - 1) for s, e in zip(est, E)], "o", ms=4, label=f"{tag}: stated")
ax[0].plot([0, 1], [0, 1], "k--", lw=0.8)
ax[0].set(xlabel="nominal level", ylabel="fraction of pairs covered", title="reliability of the stated interval",
          xlim=(0, 1), ylim=(0, 1))
ax[0].legend()
ax[1].plot([30, 600], [30, 600], "k--", lw=0.8)
ax[1].set(xscale="log", yscale="log", xlabel="true prostate E [kPa]", ylabel="stated E [kPa]",
          title="stated estimate and 95 % interval")
ax[1].legend(fontsize=8)
ax[2].axhline(0, color="k", lw=0.8)
ax[2].set(xscale="log", xlabel="true prostate E [kPa]", ylabel="error [%]", title="fit and stated estimate")
ax[2].legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/calibration.png", dpi=110)
print(f"\nwrote {out}/calibration.csv, {out}/calibration.png")
