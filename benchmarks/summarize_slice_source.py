#!/usr/bin/env python3
"""Summary of the slice-source study (run_slice_source_study.sh): per way of registering (moving and fixed
slice thickness), the median and spread of the fit's log error over the pairs, the share fitted too stiff, the
median |error| in percent, the prostate's surface RMS and the inverted elements. The four ways share the
pairs, so the paired difference against "both at 1 mm" is also reported (median and range).
Usage: summarize_slice_source.py RUNS.csv OUT_DIR  (writes OUT_DIR/slice_source.csv and slice_source.png)."""
import csv
import math
import os
import statistics
import sys


def load(path):
    rows = list(csv.DictReader(open(path)))
    ways = {}
    for r in rows:
        ways.setdefault((float(r["moving_slice_mm"]), float(r["fixed_slice_mm"])), {})[int(r["pair"])] = r
    return ways


def summarize(ways):
    base = ways.get((1.0, 1.0), {})
    table = []
    for (m, f), pairs in sorted(ways.items()):
        errs = [float(r["log_error"]) for r in pairs.values()]
        paired = [float(r["log_error"]) - float(base[k]["log_error"]) for k, r in pairs.items() if k in base]
        table.append({
            "moving_slice_mm": m, "fixed_slice_mm": f, "pairs": len(errs),
            "median_log_error": statistics.median(errs), "min_log_error": min(errs), "max_log_error": max(errs),
            "too_stiff": sum(e > 0 for e in errs),
            "median_abs_error_pct": 100 * statistics.median(abs(math.exp(e) - 1) for e in errs),
            "median_paired_shift": statistics.median(paired) if paired else float("nan"),
            "min_paired_shift": min(paired) if paired else float("nan"),
            "max_paired_shift": max(paired) if paired else float("nan"),
            "median_prostate_rms_mm": statistics.median(float(r["prostate_rms_mm"]) for r in pairs.values()),
            "median_inverted": statistics.median(int(r["inverted_elements"] or 0) for r in pairs.values()),
            "median_register_s": statistics.median(float(r["register_s"]) for r in pairs.values()),
        })
    return table


def plot(ways, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not found: no plot")
        return
    fig, ax = plt.subplots(figsize=(7, 4))
    labels = []
    for i, ((m, f), pairs) in enumerate(sorted(ways.items())):
        errs = [100 * (math.exp(float(r["log_error"])) - 1) for r in pairs.values()]
        ax.scatter([i] * len(errs), errs, alpha=0.7)
        ax.plot([i - 0.25, i + 0.25], [statistics.median(errs)] * 2, "k-")
        labels.append(f"moving {m:g} mm\nfixed {f:g} mm")
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_xticks(range(len(labels)), labels)
    ax.set_ylabel("fitted / true modulus - 1 [%]")
    ax.set_title("Point estimate by slice thickness of each scan (median: bar)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    runs, out = sys.argv[1], sys.argv[2]
    ways = load(runs)
    table = summarize(ways)
    keys = list(table[0].keys())
    with open(os.path.join(out, "slice_source.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        for row in table:
            w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in row.items()})
    print("| moving [mm] | fixed [mm] | pairs | median log error (range) | too stiff | median abs error [%] |"
          " paired shift vs 1/1 mm (range) | prostate RMS [mm] | inverted | register [s] |")
    print("|---:|---:|---:|---|---:|---:|---|---:|---:|---:|")
    for r in table:
        print(f'| {r["moving_slice_mm"]:g} | {r["fixed_slice_mm"]:g} | {r["pairs"]} | '
              f'{r["median_log_error"]:+.3f} ({r["min_log_error"]:+.3f} to {r["max_log_error"]:+.3f}) | '
              f'{r["too_stiff"]}/{r["pairs"]} | {r["median_abs_error_pct"]:.0f} | '
              f'{r["median_paired_shift"]:+.3f} ({r["min_paired_shift"]:+.3f} to {r["max_paired_shift"]:+.3f}) | '
              f'{r["median_prostate_rms_mm"]:.2f} | {r["median_inverted"]:.0f} | {r["median_register_s"]:.1f} |')
    plot(ways, os.path.join(out, "slice_source.png"))


if __name__ == "__main__":
    main()
