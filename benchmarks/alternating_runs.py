"""Shared by the benchmarks that time whole `biomechreg register` processes on the demo pair in alternating rounds
(run_python_binding.py, run_malloc_benchmark.py, run_against_baseline.py): the pair, the timed run, the
modulus it stated, and the summary
(medians and ranges per way and mode, the ratio to a baseline way measured in the same rounds, whether every run
stated the same modulus bit for bit) as CSV, a markdown table and a PNG."""

import csv
import json
import pathlib
import statistics
import subprocess
import tempfile
import time

MODES = ("none", "rescan")  # --uncertainty: the point estimate, and with the stated interval


def prepare(cli, out):
    """Creates \a out and a scratch folder holding the demo pair; returns the pair's folder."""
    out.mkdir(parents=True, exist_ok=True)
    pair = pathlib.Path(tempfile.mkdtemp()) / "pair"
    demo_pair(cli, pair)
    return pair


def rounds(runs, ways):
    """(run, mode, way) of \a runs alternating rounds: both modes each round, the ways in order in odd rounds and
    reversed in even ones (so that no way always runs right after another)."""
    for run in range(1, runs + 1):
        for mode in MODES:
            for way in ways if run % 2 else list(reversed(ways)):
                yield run, mode, way


def demo_pair(cli, pair):
    """The demo's phantom pair (pelvis, 1 mm voxels, bladder 8 / rectum 4 mm, 100 kPa) into \\a pair."""
    subprocess.run([str(cli), "phantom", "--scene", "pelvis", "--size", "200,160,160", "--spacing", "1,1,1",
                    "--bladder-mm", "8", "--rectum-mm", "4", "--true-E-kPa", "100", "--out", str(pair)],
                   check=True, stdout=subprocess.DEVNULL)


def register_command(cli, pair, uncertainty, out):
    return [str(cli), "register", "--moving-ct", f"{pair}/moving_ct.nrrd", "--moving-labels",
            f"{pair}/moving_labels.nrrd", "--fixed-ct", f"{pair}/fixed_ct.nrrd", "--fixed-labels",
            f"{pair}/fixed_labels.nrrd", "--scene", f"{pair}/scene.json", "--uncertainty", uncertainty,
            "--out", str(out)]


def timed(command, env=None):
    """Wall time [s] of the whole process."""
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    return time.perf_counter() - start


def modulus(out):
    report = json.loads((pathlib.Path(out) / "report.json").read_text())
    return report["youngs_modulus_kPa"]["prostate"]


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def summarize(rows, ways, baseline, out, name, title):
    """Per mode and way of \\a rows (run, mode, way, wall_s, modulus_kPa): median, range, ratio and difference to
    the way \\a baseline; writes out/NAME.csv and out/NAME.png and prints the table."""
    summary = []
    for mode in MODES:
        moduli = {r["modulus_kPa"] for r in rows if r["mode"] == mode}
        base = statistics.median(r["wall_s"] for r in rows if r["mode"] == mode and r["way"] == baseline)
        for way in ways:
            times = [r["wall_s"] for r in rows if r["mode"] == mode and r["way"] == way]
            summary.append({"mode": mode, "way": way, "median_s": statistics.median(times), "min_s": min(times),
                            "max_s": max(times), "over_baseline": statistics.median(times) / base,
                            "minus_baseline_s": statistics.median(times) - base, "same_modulus": len(moduli) == 1,
                            "modulus_kPa": sorted(moduli)[0]})
    write_csv(out / f"{name}.csv", summary)
    print(f"| register on the demo pair | way | wall [s] median (range) | / {baseline} | - {baseline} [s] | "
          "same modulus |")
    print("|---|---|---:|---:|---:|---|")
    for s in summary:
        print("| %s | %s | %.2f (%.2f-%.2f) | %.3f | %+.2f | %s (%s kPa) |" % (
            "point estimate" if s["mode"] == "none" else "with the interval", s["way"], s["median_s"], s["min_s"],
            s["max_s"], s["over_baseline"], s["minus_baseline_s"], "yes" if s["same_modulus"] else "NO",
            s["modulus_kPa"]))
    plot(rows, ways, out / f"{name}.png", title)


def plot(rows, ways, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(figsize=(7, 4))
    labels = []
    for i, mode in enumerate(MODES):
        for j, way in enumerate(ways):
            values = [r["wall_s"] for r in rows if r["mode"] == mode and r["way"] == way]
            x = len(ways) * i + j
            axes.scatter([x] * len(values), values, color="C%d" % j, alpha=0.6)
            axes.hlines(statistics.median(values), x - 0.3, x + 0.3, color="C%d" % j)
            labels.append("%s\n%s" % (way.replace("_", "\n"), "point" if mode == "none" else "interval"))
    axes.set_xticks(range(len(labels)), labels, fontsize=7)
    axes.set_ylabel("wall time of the process [s]")
    axes.set_title(title + " (lines: medians)")
    figure.tight_layout()
    figure.savefig(path, dpi=90)
