#!/usr/bin/env python3
"""What the Python package adds to a registration (not a test): the demo pair registered RUNS times by
`biomechreg register` and by a fresh Python process doing the same (import biomechreg, read the four images and the
scene, register, write the same outputs), alternating, both with the point estimate (--uncertainty none) and with
the stated interval (4 rescans). Python runs twice per round: as it starts by default, and with
GLIBC_TUNABLES=glibc.malloc.hugetlb=1, the malloc that biomechreg sets for itself by restarting (the package leaves
the interpreter's malloc alone). Wall time of the whole process each; the moduli must agree bit for bit.

Usage: PYTHONPATH=build/python benchmarks/run_python_binding.py [RUNS (5)]
Writes benchmarks/results/python_binding/{python_binding_runs.csv, python_binding.csv, python_binding.png} and
prints the table (medians, ranges, Python / CLI)."""

import csv
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
CLI = pathlib.Path(os.environ.get("BUILD_DIR", ROOT / "build")) / "bin" / "biomechreg"
OUT = ROOT / "benchmarks" / "results" / "python_binding"

PYTHON_RUN = """
import sys, biomechreg as b
p, out, uncertainty = sys.argv[1:4]
b.configure_numerics()
r = b.register(b.read_image(p + "/moving_labels.nrrd", "labels"), b.read_image(p + "/fixed_labels.nrrd", "labels"),
               b.read_scene(p + "/scene.json"), moving_ct=b.read_image(p + "/moving_ct.nrrd"), uncertainty=uncertainty)
b.read_image(p + "/fixed_ct.nrrd")  # the CLI reads it too (to check it)
r.write(out)
"""


def timed(command, env=None):
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    return time.perf_counter() - start


def modulus(out):
    report = json.loads((pathlib.Path(out) / "report.json").read_text())
    return report["youngs_modulus_kPa"]["prostate"]


def main(runs):
    OUT.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(tempfile.mkdtemp())
    pair = work / "pair"
    subprocess.run([str(CLI), "phantom", "--scene", "pelvis", "--size", "200,160,160", "--spacing", "1,1,1",
                    "--bladder-mm", "8", "--rectum-mm", "4", "--true-E-kPa", "100", "--out", str(pair)],
                   check=True, stdout=subprocess.DEVNULL)
    rows = []
    for run in range(1, runs + 1):
        for uncertainty in ("none", "rescan"):
            order = ("cli", "python", "python_hugepages") if run % 2 else ("python_hugepages", "python", "cli")
            for way in order:
                out = work / f"{way}_{uncertainty}_{run}"
                if way == "cli":
                    seconds = timed([str(CLI), "register", "--moving-ct", f"{pair}/moving_ct.nrrd",
                                     "--moving-labels", f"{pair}/moving_labels.nrrd",
                                     "--fixed-ct", f"{pair}/fixed_ct.nrrd", "--fixed-labels",
                                     f"{pair}/fixed_labels.nrrd", "--scene", f"{pair}/scene.json",
                                     "--uncertainty", uncertainty, "--out", str(out)])
                else:
                    env = dict(os.environ)
                    if way == "python_hugepages":
                        env["GLIBC_TUNABLES"] = "glibc.malloc.hugetlb=1"
                    seconds = timed(["/usr/bin/python3", "-c", PYTHON_RUN, str(pair), str(out), uncertainty], env)
                rows.append({"run": run, "mode": uncertainty, "way": way, "wall_s": round(seconds, 3),
                             "modulus_kPa": repr(modulus(out))})
    with open(OUT / "python_binding_runs.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    summarize(rows)


WAYS = ("cli", "python", "python_hugepages")


def summarize(rows):
    table, summary = [], []
    for mode in ("none", "rescan"):
        moduli = {r["modulus_kPa"] for r in rows if r["mode"] == mode}
        cli = statistics.median(r["wall_s"] for r in rows if r["mode"] == mode and r["way"] == "cli")
        for way in WAYS:
            times = [r["wall_s"] for r in rows if r["mode"] == mode and r["way"] == way]
            summary.append({"mode": mode, "way": way, "median_s": statistics.median(times), "min_s": min(times),
                            "max_s": max(times), "over_cli": statistics.median(times) / cli,
                            "minus_cli_s": statistics.median(times) - cli, "same_modulus": len(moduli) == 1,
                            "modulus_kPa": sorted(moduli)[0]})
    with open(OUT / "python_binding.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(summary)
    print("| register on the demo pair | way | wall [s] median (range) | / CLI | - CLI [s] | same modulus |")
    print("|---|---|---:|---:|---:|---|")
    for s in summary:
        print("| %s | %s | %.2f (%.2f-%.2f) | %.3f | %+.2f | %s (%s kPa) |" % (
            "point estimate" if s["mode"] == "none" else "with the interval", s["way"], s["median_s"], s["min_s"],
            s["max_s"], s["over_cli"], s["minus_cli_s"], "yes" if s["same_modulus"] else "NO", s["modulus_kPa"]))
    plot(rows)


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(figsize=(7, 4))
    labels = []
    for i, mode in enumerate(("none", "rescan")):
        for j, way in enumerate(WAYS):
            values = [r["wall_s"] for r in rows if r["mode"] == mode and r["way"] == way]
            x = len(WAYS) * i + j
            axes.scatter([x] * len(values), values, color="C%d" % j, alpha=0.6)
            axes.hlines(statistics.median(values), x - 0.3, x + 0.3, color="C%d" % j)
            labels.append("%s\n%s" % (way.replace("_", "\n"), "point" if mode == "none" else "interval"))
    axes.set_xticks(range(len(labels)), labels, fontsize=7)
    axes.set_ylabel("wall time of the process [s]")
    axes.set_title("register on the demo pair: CLI and Python (lines: medians)")
    figure.tight_layout()
    figure.savefig(OUT / "python_binding.png", dpi=90)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
