#!/usr/bin/env python3
"""Tables and plot of benchmarks/run_scaling_replay.sh (usage: summarize_scaling.py RESULTS [TRACES]; the traces
named in RESULTS/scaling_runs.csv are read from TRACES, default RESULTS, plain or gzipped): measured one- and two-core wall times (medians of the
runs), the replay of each two-core trace on 1-16 workers (medians), the replay's error on one core, and where the
recorded time goes (regions of parallel tasks, waits, serial)."""
import csv
import os
import statistics
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(__file__))
import replay_task_trace as replay  # noqa: E402

WORKERS = [1, 2, 4, 8, 16]


def main(out, traces):
    runs = list(csv.DictReader(open(os.path.join(out, "scaling_runs.csv"))))
    measured = defaultdict(list)  # (mode, threads) -> seconds
    predicted = defaultdict(list)  # (mode, P) -> seconds
    errors = defaultdict(list)  # mode -> replay on 1 / measured on 1, per run
    parts = defaultdict(lambda: defaultdict(list))  # mode -> part -> seconds
    by_run = {(r["mode"], r["run"], r["threads"]): r for r in runs}
    for r in runs:
        measured[(r["mode"], int(r["threads"]))].append(float(r["wall_s"]))
        if r["trace"]:
            trace = replay.Trace(os.path.join(traces, r["trace"]))
            for p in WORKERS:
                predicted[(r["mode"], p)].append(replay.predict(trace, p))
            one = by_run.get((r["mode"], r["run"], "1"))
            if one:
                errors[r["mode"]].append(replay.predict(trace, 1) / float(one["wall_s"]) - 1.0)
            run_parts = defaultdict(float)
            for part, seconds in replay.breakdown(trace).items():
                run_parts[part if part == "serial" or part.startswith("wait") else "parallel regions"] += seconds
            for part, seconds in run_parts.items():
                parts[r["mode"]][part].append(seconds)
    modes = sorted({m for m, _ in measured}, key=lambda m: m != "point")
    with open(os.path.join(out, "scaling.csv"), "w") as f:
        f.write("mode,workers,measured_s,predicted_s,speedup_vs_2\n")
        for m in modes:
            two = statistics.median(predicted[(m, 2)])
            for p in WORKERS:
                meas = statistics.median(measured[(m, p)]) if measured.get((m, p)) else ""
                pred = statistics.median(predicted[(m, p)])
                f.write(f"{m},{p},{meas},{pred:.3f},{two / pred:.3f}\n")
    with open(os.path.join(out, "scaling_breakdown.csv"), "w") as f:
        f.write("mode,part,seconds_median\n")
        for m in modes:
            for part, values in sorted(parts[m].items()):
                f.write(f"{m},{part},{statistics.median(values):.3f}\n")
    print(f"register on the demo pair, medians of {len(measured[(modes[0], 1)])} runs; replayed from the 2-core traces")
    print("| mode | workers | measured [s] | replayed [s] | speed-up vs 2 |")
    print("|---|---:|---:|---:|---:|")
    for row in csv.DictReader(open(os.path.join(out, "scaling.csv"))):
        meas = f"{float(row['measured_s']):.2f}" if row["measured_s"] else ""
        print(f"| {row['mode']} | {row['workers']} | {meas} | {float(row['predicted_s']):.2f} | "
              f"{float(row['speedup_vs_2']):.2f} |")
    print("\nthe replay on one worker against the measured one-core run (per run):")
    for m in modes:
        print(f"  {m}: " + ", ".join(f"{100 * e:+.1f} %" for e in errors[m]))
    print("\nwhere the 2-core time goes (medians):")
    for m in modes:
        print(f"  {m}: " + ", ".join(f"{k} {statistics.median(v):.2f} s" for k, v in sorted(parts[m].items())))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    for m, color in zip(modes, ["tab:blue", "tab:orange"]):
        ax.plot(WORKERS, [statistics.median(predicted[(m, p)]) for p in WORKERS], "o-", color=color,
                label=f"{m}: replayed")
        ax.plot([1, 2], [statistics.median(measured[(m, t)]) for t in (1, 2)], "s", color=color, mfc="none",
                ms=10, label=f"{m}: measured")
    ax.set_xscale("log", base=2)
    ax.set_xticks(WORKERS)
    ax.set_xticklabels([str(p) for p in WORKERS])
    ax.set_xlabel("workers")
    ax.set_ylabel("register wall time [s]")
    ax.set_ylim(bottom=0)
    ax.legend()
    ax.set_title("register on the demo pair: measured and replayed")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scaling.png"), dpi=120)


if __name__ == "__main__":
    results = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "results", "scaling")
    main(results, sys.argv[2] if len(sys.argv) > 2 else results)
