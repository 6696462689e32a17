#!/usr/bin/env python3
"""A trained basis of wall motion against the default walls along their normals (not a test; dissertation Table 5.1
and Fig 5.8 analogs for one phantom patient).

One pelvis phantom patient (the default anatomy, 1 mm voxels): a basis trained (`biomechreg train-basis`) on the
surface matching of TRAIN daily scans, bladder walls moved by 3-11 mm and rectum walls by 2-6 mm, half with walls
moved along their normals and half by point loads (`phantom --wall-load point`), so that the examples hold more than
one law. Test pairs never trained on: fillings (bladder, rectum) of (6, 3) and (9, 5) mm with point loads (TEST_LOAD=point,
the default) or walls moved along their normals (TEST_LOAD=normal), at true
moduli 25, 50, 75, 150 and 300 kPa, each with SEEDS realizations (the fixed scan on its own grid shifted by a random
sub-voxel offset, `--fixed-grid-shift-voxels 0.5 --seed S`). Every test pair is registered (point estimate,
`--uncertainty none`) with the default walls and with the basis at K = 1, 2, 4 modes and all of them
(BASIS_MODES=1,2,4,all).

Across patients (`cohort` as the first argument; dissertation section 5.3.2.3 and Table 5.1's unseen patients): a
phantom cohort (`biomechreg phantom-cohort`, each patient its own anatomy and modulus) of TRAIN_PATIENTS + TEST_PATIENTS
patients x FRACTIONS daily scans; the basis trained on the first TRAIN_PATIENTS patients' scans (`train-basis
--patients`: the first patient's walls the atlas, fitted to the others'), every daily scan of the others registered
with the default walls and with the basis (all modes), against the cohort's true moduli.

Usage: benchmarks/run_trained_basis.py [SEEDS (3)] [TRAIN (8)]   (BUILD_DIR: the build with bin/biomechreg)
       benchmarks/run_trained_basis.py cohort [TRAIN_PATIENTS (3)] [TEST_PATIENTS (2)] [FRACTIONS (6)]
Writes benchmarks/results/trained_basis/{trained_basis_LOAD_runs.csv, trained_basis_LOAD.csv, trained_basis_LOAD.png,
basis.json}
(cohort: cohort_runs.csv, cohort.csv, basis_cohort.json) and prints the table: per way and true modulus, the median |error| and its range over the realizations, the median
surface residual [mm] (mean over the organs), the fine stage's inner solves and the median wall time [s]."""

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
OUT = ROOT / "benchmarks" / "results" / "trained_basis"
MODULI = (25.0, 50.0, 75.0, 150.0, 300.0)
TEST_FILLINGS = ((6.0, 3.0), (9.0, 5.0))
MODES = tuple(os.environ.get("BASIS_MODES", "1,2,4,all").split(","))  # the basis sizes compared
TEST_LOAD = os.environ.get("TEST_LOAD", "point")


def phantom(out, bladder, rectum, modulus, load, seed=None):
    command = [str(CLI), "phantom", "--scene", "pelvis", "--size", "200,160,160", "--spacing", "1,1,1",
               "--bladder-mm", str(bladder), "--rectum-mm", str(rectum), "--true-E-kPa", str(modulus),
               "--wall-load", load, "--out", str(out)]
    if seed is not None:
        command += ["--fixed-grid-shift-voxels", "0.5", "--seed", str(seed)]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)


def train(work, count):
    """The basis of \\a count training scans; returns its path."""
    fixed = []
    for i in range(count):
        bladder, rectum = 3.0 + 8.0 * i / max(1, count - 1), 2.0 + 4.0 * ((3 * i) % count) / max(1, count - 1)
        out = work / f"train_{i}"
        phantom(out, bladder, rectum, 100.0, "normal" if i % 2 == 0 else "point")
        fixed.append(str(out / "fixed_labels.nrrd"))
    basis = OUT / "basis.json"
    subprocess.run([str(CLI), "train-basis", "--moving-labels", str(work / "train_0" / "moving_labels.nrrd"),
                    "--fixed-labels", ",".join(fixed), "--scene", str(work / "train_0" / "scene.json"),
                    "--out", str(basis)], check=True)
    return basis


def register(pair, out, extra):
    command = [str(CLI), "register", "--moving-ct", f"{pair}/moving_ct.nrrd", "--moving-labels",
               f"{pair}/moving_labels.nrrd", "--fixed-ct", f"{pair}/fixed_ct.nrrd", "--fixed-labels",
               f"{pair}/fixed_labels.nrrd", "--scene", f"{pair}/scene.json", "--uncertainty", "none",
               "--outputs", "report", "--out", str(out)] + extra
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    seconds = time.perf_counter() - start
    report = json.loads((out / "report.json").read_text())
    distances = report["surface_distance_mm"]
    return (report["youngs_modulus_kPa"]["prostate"], statistics.mean(d["rms"] for d in distances.values()),
            distances["prostate"]["rms"], report["iterations"]["fine"], seconds)


def main(seeds, count):
    OUT.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(tempfile.mkdtemp())
    basis = train(work, count)
    ways = [("normals", [])] + [(f"basis_{k}", ["--wall-basis", str(basis)] + ([] if k == "all" else
                                                                                 ["--basis-modes", k]))
                                for k in MODES]
    rows = []
    for (bladder, rectum) in TEST_FILLINGS:
        for modulus in MODULI:
            for seed in range(1, seeds + 1):
                pair = work / f"test_{bladder}_{modulus}_{seed}"
                phantom(pair, bladder, rectum, modulus, TEST_LOAD, seed)
                for way, extra in ways:
                    estimate, rms, prostate, solves, seconds = register(pair, pair / way, extra)
                    rows.append({"way": way, "true_kPa": modulus, "bladder_mm": bladder, "rectum_mm": rectum,
                                 "seed": seed, "estimate_kPa": round(estimate, 4),
                                 "abs_error": round(abs(estimate / modulus - 1.0), 5),
                                 "surface_rms_mm": round(rms, 4), "prostate_rms_mm": round(prostate, 4),
                                 "fine_solves": solves, "wall_s": round(seconds, 3)})
                    print(rows[-1], flush=True)
    with open(OUT / f"trained_basis_{TEST_LOAD}_runs.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    summarize(rows, [w for w, _ in ways])


def summarize(rows, ways):
    summary = []
    for way in ways:
        for modulus in MODULI:
            cell = [r for r in rows if r["way"] == way and r["true_kPa"] == modulus]
            errors = [r["abs_error"] for r in cell]
            summary.append({"way": way, "true_kPa": modulus, "pairs": len(cell),
                            "median_abs_error": statistics.median(errors), "min_abs_error": min(errors),
                            "max_abs_error": max(errors),
                            "median_surface_rms_mm": statistics.median(r["surface_rms_mm"] for r in cell),
                            "median_fine_solves": statistics.median(r["fine_solves"] for r in cell),
                            "median_wall_s": statistics.median(r["wall_s"] for r in cell)})
    with open(OUT / f"trained_basis_{TEST_LOAD}.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(summary)
    print("| way | true E [kPa] | pairs | median abs. error (range) | surface RMS [mm] | fine solves | wall [s] |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for s in summary:
        print("| %s | %g | %d | %.1f %% (%.1f-%.1f %%) | %.3f | %g | %.1f |" % (
            s["way"], s["true_kPa"], s["pairs"], 100 * s["median_abs_error"], 100 * s["min_abs_error"],
            100 * s["max_abs_error"], s["median_surface_rms_mm"], s["median_fine_solves"], s["median_wall_s"]))
    plot(summary, ways)


def plot(summary, ways):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, (error, seconds) = plt.subplots(1, 2, figsize=(10, 4))
    for way in ways:
        cells = [s for s in summary if s["way"] == way]
        error.plot([s["true_kPa"] for s in cells], [100 * s["median_abs_error"] for s in cells], "o-", label=way)
        seconds.plot([s["true_kPa"] for s in cells], [s["median_wall_s"] for s in cells], "o-", label=way)
    error.set(xscale="log", xlabel="true E [kPa]", ylabel="median |error| [%]", title="modulus error")
    seconds.set(xscale="log", xlabel="true E [kPa]", ylabel="register [s]", title="wall time (point estimate)")
    error.legend()
    figure.tight_layout()
    figure.savefig(OUT / f"trained_basis_{TEST_LOAD}.png", dpi=120)


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def cohort_study(train_patients=3, test_patients=2, fractions=6):
    OUT.mkdir(parents=True, exist_ok=True)
    cohort = pathlib.Path(tempfile.mkdtemp()) / "cohort"
    subprocess.run([str(CLI), "phantom-cohort", "--out", str(cohort), "--patients",
                    str(train_patients + test_patients), "--fractions", str(fractions), "--seed", "54"],
                   check=True, stdout=subprocess.DEVNULL)
    scans = read_csv(cohort / "cohort.csv")
    truth = {r["patient"]: float(r["true_E_kPa"]) for r in read_csv(cohort / "truth.csv")}
    patients = list(dict.fromkeys(r["patient"] for r in scans))
    trained, tested = patients[:train_patients], patients[train_patients:]
    listing = cohort / "training.csv"
    listing.write_text("moving_labels,fixed_labels\n" + "".join(
        f"{cohort / r['planning_labels']},{cohort / r['daily_labels']}\n" for r in scans if r["patient"] in trained))
    basis = OUT / "basis_cohort.json"
    subprocess.run([str(CLI), "train-basis", "--patients", str(listing), "--scene",
                    str(cohort / trained[0] / "scene.json"), "--out", str(basis)], check=True)
    rows = []
    for r in (r for r in scans if r["patient"] in tested):
        pair = cohort / r["patient"] / r["fraction"]
        for way, extra in (("normals", []), ("basis_all", ["--wall-basis", str(basis)])):
            out = pair / way
            command = [str(CLI), "register", "--moving-ct", str(cohort / r["planning_ct"]), "--moving-labels",
                       str(cohort / r["planning_labels"]), "--fixed-ct", str(cohort / r["daily_ct"]),
                       "--fixed-labels", str(cohort / r["daily_labels"]), "--scene", str(cohort / r["scene"]),
                       "--uncertainty", "none", "--outputs", "report", "--out", str(out)] + extra
            start = time.perf_counter()
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
            seconds = time.perf_counter() - start
            report = json.loads((out / "report.json").read_text())
            estimate, true = report["youngs_modulus_kPa"]["prostate"], truth[r["patient"]]
            rows.append({"way": way, "patient": r["patient"], "fraction": r["fraction"], "true_kPa": true,
                         "estimate_kPa": round(estimate, 4), "abs_error": round(abs(estimate / true - 1.0), 5),
                         "surface_rms_mm": round(statistics.mean(
                             d["rms"] for d in report["surface_distance_mm"].values()), 4),
                         "fine_solves": report["iterations"]["fine"], "wall_s": round(seconds, 3)})
            print(rows[-1], flush=True)
    with open(OUT / "cohort_runs.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print("| way | scans | median abs. error (range) | surface RMS [mm] | fine solves | wall [s] |")
    print("|---|---:|---:|---:|---:|---:|")
    summary = []
    for way in ("normals", "basis_all"):
        cell = [r for r in rows if r["way"] == way]
        errors = [r["abs_error"] for r in cell]
        summary.append({"way": way, "scans": len(cell), "median_abs_error": statistics.median(errors),
                        "min_abs_error": min(errors), "max_abs_error": max(errors),
                        "median_surface_rms_mm": statistics.median(r["surface_rms_mm"] for r in cell),
                        "median_fine_solves": statistics.median(r["fine_solves"] for r in cell),
                        "median_wall_s": statistics.median(r["wall_s"] for r in cell)})
        s = summary[-1]
        print("| %s | %d | %.1f %% (%.1f-%.1f %%) | %.3f | %g | %.1f |" % (
            way, s["scans"], 100 * s["median_abs_error"], 100 * s["min_abs_error"], 100 * s["max_abs_error"],
            s["median_surface_rms_mm"], s["median_fine_solves"], s["median_wall_s"]))
    with open(OUT / "cohort.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(summary)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "cohort":
        cohort_study(*[int(a) for a in sys.argv[2:]] if len(sys.argv) > 2 else [])
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 3, int(sys.argv[2]) if len(sys.argv) > 2 else 8)
