#!/usr/bin/env python3
"""What the fixed segmentation alone determines of the prostate's modulus (issue 16; not a test).

Inverse-crime phantoms: the neo-Hookean truth is simulated on exactly the mesh the estimation uses (the truth meshed
from the moving label map's voxels, `--truth-geometry voxels --truth-refine-size-mm 0 --truth-mesh-scale 0.75`, and
the estimation scene given the truth's mesh sizes), loaded by one uniform pressure per lumen, the law the estimation
assumes (`register --wall-motion pressure`). Model, mesh and load law are then exact; what is left between the
estimate and the truth is the fixed scan's binary label map (sampled on its own grid, shifted by up to half a voxel)
and the optimizer. Three measurements:
  estimates  scenes A (bladder 2.2, rectum 1.0 kPa) and B (1.35, 1.5 kPa) of the Table 3.6 analog x prostate E in
             {50, 100, 150} kPa at 1 mm voxels, and both scenes at 100 kPa at 0.5 mm voxels; N seeds per row.
  profiles   for the first pair of each 100 kPa row: Phi*(E), the objective [mm^2] minimized over the two
             pressures at E held fixed (bounds_kPa [E, 1.0001 E]), at 0.5, 0.7, 1, 1.3, 1.6 and 2.2 x the truth.
  signal     for the same pairs: what E acts on, the prostate's truth displacement beyond its best rigid motion
             (RMS and largest over the fixed prostate's voxels) and its affine strain; and the floor it is read
             against, the moving mesh registered to its own label map (fixed = moving, E held at the truth):
             the distance of the prostate's surface nodes from that map's surface (RMS and mean signed).
Usage: benchmarks/run_identifiability_benchmark.py [N seeds per row (3)] [SEED (53)]
  BUILD_DIR (default ./build) selects the binary; the work directory is temporary. REUSE_RUNS=1 reads the
  estimates and profiles of an earlier run from the results directory and measures only the signal (the
  phantoms are remade from their seeds: the same pairs); REUSE_SIGNAL=1 with it reads the signal too (summary only).
Writes benchmarks/results/identifiability_runs.csv, identifiability_profile.csv, identifiability_signal.csv,
identifiability.csv and identifiability.png, and prints the three tables (units: kPa, mm, mm^2, s)."""
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from field_tre import read_nrrd  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(os.environ.get("BUILD_DIR", os.path.join(ROOT, "build")), "bin", "biomechreg")
OUT = os.path.join(ROOT, "benchmarks", "results")
SCENES = {"A": (2.2, 1.0), "B": (1.35, 1.5)}  # bladder, rectum pressure [kPa] (Table 3.6 analog)
TRUTH_MESH_SCALE = 0.75
# The truth's mesh sizes at TRUTH_MESH_SCALE (PhantomSettings::truthRefinement: the pelvis base sizes, facet
# 6 mm and facet distance 0.5 mm, times the scale, the facet distance x 0.8 more); its cell sizes are the
# estimation scene's already.
TRUTH_FACET_SIZE_MM = 6.0 * TRUTH_MESH_SCALE
TRUTH_FACET_DISTANCE_MM = 0.5 * TRUTH_MESH_SCALE * 0.8
PROFILE_FACTORS = (0.5, 0.7, 1.0, 1.3, 1.6, 2.2)


def run(args, log):
    with open(log, "w") as f:
        subprocess.run([BIN, *args], check=True, stdout=f, stderr=subprocess.STDOUT)


def phantom(ph, scene, E, spacing, seed):
    bladder, rectum = SCENES[scene]
    size = "200,160,160" if spacing == 1.0 else "400,320,320"
    run(["phantom", "--scene", "pelvis", "--size", size, "--spacing", f"{spacing},{spacing},{spacing}",
         "--model", "neo_hookean", "--true-E-kPa", str(E), "--tissue-E-kPa", "10", "--bladder-kPa", str(bladder),
         "--rectum-kPa", str(rectum), "--fixed-grid-shift-voxels", "0.5", "--truth-geometry", "voxels",
         "--truth-refine-size-mm", "0", "--truth-mesh-scale", str(TRUTH_MESH_SCALE), "--seed", str(seed),
         "--out", ph], ph + ".log")


def crime_scene(ph, name, fixed_E=None):
    """The phantom's estimation scene with the truth's mesh sizes; with fixed_E, the prostate held at it."""
    scene = json.load(open(os.path.join(ph, "scene.json")))
    scene["mesh"]["facet_size_mm"] = TRUTH_FACET_SIZE_MM
    scene["mesh"]["facet_distance_mm"] = TRUTH_FACET_DISTANCE_MM
    if fixed_E is not None:
        prostate = next(label for label in scene["labels"] if label["name"] == "prostate")
        prostate["youngs_modulus_kPa"] = fixed_E
        prostate["bounds_kPa"] = [fixed_E, fixed_E * 1.0001]
    path = os.path.join(ph, name)
    json.dump(scene, open(path, "w"), indent=1)
    return path


def register(ph, scene_path, out):
    start = time.monotonic()
    run(["register", "--moving-ct", f"{ph}/moving_ct.nrrd", "--moving-labels", f"{ph}/moving_labels.nrrd",
         "--fixed-ct", f"{ph}/fixed_ct.nrrd", "--fixed-labels", f"{ph}/fixed_labels.nrrd", "--scene", scene_path,
         "--wall-motion", "pressure", "--uncertainty", "none", "--outputs", "report", "--out", out], out + ".log")
    report = json.load(open(os.path.join(out, "report.json")))
    report["register_s"] = time.monotonic() - start
    return report


def estimates(work, count, seed):
    rows = [(s, E, 1.0) for s in SCENES for E in (50, 100, 150)] + [(s, 100, 0.5) for s in SCENES]
    out, k = [], 0
    for i in range(count):  # realization-major, so that a run stopped early has every row
        for scene, E, spacing in rows:
            k += 1
            ph = os.path.join(work, f"ph{k}")
            phantom(ph, scene, E, spacing, seed * 100 + k)
            report = register(ph, crime_scene(ph, "scene_crime.json"), os.path.join(work, f"reg{k}"))
            truth_tets = json.load(open(os.path.join(ph, "truth.json")))["truth_mesh"]["tetrahedra"]
            out.append(dict(scene=scene, true_E_kPa=E, spacing_mm=spacing, seed=seed * 100 + k, pair=k,
                            estimate_kPa=round(report["youngs_modulus_kPa"]["prostate"], 3),
                            phi_mm2=round(report["final_phi_mm2"], 4),
                            prostate_rms_mm=round(report["surface_distance_mm"]["prostate"]["rms"], 4),
                            truth_tetrahedra=truth_tets, estimation_tetrahedra=report["mesh"]["tetrahedra"],
                            register_s=round(report["register_s"], 1)))
            print(",".join(str(v) for v in out[-1].values()), flush=True)
    return out


def profiles(work, runs):
    out = []
    for r in runs:
        if r["true_E_kPa"] != 100 or any(p["pair"] == r["pair"] or (p["scene"], p["spacing_mm"]) == (
                r["scene"], r["spacing_mm"]) for p in out):
            continue
        ph = os.path.join(work, f"ph{r['pair']}")
        for factor in PROFILE_FACTORS:
            E = r["true_E_kPa"] * factor
            report = register(ph, crime_scene(ph, f"scene_E{factor}.json", E),
                              os.path.join(work, f"prof{r['pair']}_{factor}"))
            out.append(dict(scene=r["scene"], spacing_mm=r["spacing_mm"], pair=r["pair"], seed=r["seed"],
                            true_E_kPa=r["true_E_kPa"], held_E_kPa=round(E, 3),
                            phi_mm2=round(report["final_phi_mm2"], 4),
                            free_estimate_kPa=r["estimate_kPa"], free_phi_mm2=r["phi_mm2"]))
            print(",".join(str(v) for v in out[-1].values()), flush=True)
    return out


def nonrigid_deformation(ph):
    """The truth's displacement over the fixed prostate's voxels beyond its best rigid motion (Kabsch) [mm]: RMS,
    largest; and the principal strains of its best affine fit."""
    field, origin, matrix = read_nrrd(os.path.join(ph, "truth_field.nrrd"))
    labels = read_nrrd(os.path.join(ph, "fixed_labels.nrrd"))[0]
    index = np.argwhere(labels == 2)  # PelvisProstate
    x = origin + index @ matrix.T
    y = x + field[:, index[:, 0], index[:, 1], index[:, 2]].T
    xc, yc = x - x.mean(0), y - y.mean(0)
    left, _, right = np.linalg.svd(xc.T @ yc)
    reflection = np.diag([1.0, 1.0, np.sign(np.linalg.det(right.T @ left.T))])
    rotation = right.T @ reflection @ left.T
    beyond = np.linalg.norm(yc - xc @ rotation.T, axis=1)
    affine = np.linalg.lstsq(np.hstack([x, np.ones((len(x), 1))]), y, rcond=None)[0][:3].T
    strains = np.linalg.eigvalsh(0.5 * (affine + affine.T) - np.eye(3))
    return float(np.sqrt(np.mean(beyond ** 2))), float(beyond.max()), strains


def self_registration(work, ph, E):
    """The moving scan registered to itself with E held: the mesh surface's distance from its own label map."""
    same = ph + "_self"
    os.makedirs(same, exist_ok=True)
    for name in ("moving_ct", "moving_labels"):
        for target in (name, name.replace("moving", "fixed")):
            if not os.path.exists(os.path.join(same, target + ".nrrd")):
                os.symlink(os.path.join(ph, name + ".nrrd"), os.path.join(same, target + ".nrrd"))
    report = register(same, crime_scene(ph, "scene_self.json", E), os.path.join(work, os.path.basename(same) + "_reg"))
    return report["surface_distance_mm"]["prostate"]


def signals(work, profile):
    out = []
    for key in dict.fromkeys((p["scene"], p["spacing_mm"], p["seed"], p["true_E_kPa"]) for p in profile):
        scene, spacing, seed, E = key
        ph = os.path.join(work, f"signal{seed}")
        phantom(ph, scene, E, spacing, seed)
        rms, largest, strains = nonrigid_deformation(ph)
        floor = self_registration(work, ph, E)
        out.append(dict(scene=scene, spacing_mm=spacing, seed=seed, true_E_kPa=E,
                        prostate_nonrigid_rms_mm=round(rms, 4), prostate_nonrigid_max_mm=round(largest, 4),
                        principal_strains=" ".join(f"{e:.4f}" for e in strains),
                        self_registration_rms_mm=round(floor["rms"], 4),
                        self_registration_mean_signed_mm=round(floor["mean_signed"], 4)))
        print(",".join(str(v) for v in out[-1].values()), flush=True)
    return out


def read_csv(path):
    """Rows of a CSV this script wrote, numbers as numbers."""
    def number(value):
        try:
            return int(value)
        except ValueError:
            try:
                return float(value)
            except ValueError:
                return value
    return [{k: number(v) for k, v in row.items()} for row in csv.DictReader(open(path))]


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)


def summarize(runs, profile, signal):
    groups = {}
    for r in runs:
        groups.setdefault((r["scene"], r["spacing_mm"], r["true_E_kPa"]), []).append(r)
    summary = []
    for (scene, spacing, E), rs in groups.items():
        errors = [100.0 * (r["estimate_kPa"] / E - 1) for r in rs]
        summary.append(dict(scene=scene, spacing_mm=spacing, true_E_kPa=E, pairs=len(rs),
                            median_error_pct=round(statistics.median(errors), 1),
                            min_error_pct=round(min(errors), 1), max_error_pct=round(max(errors), 1),
                            same_mesh=all(r["truth_tetrahedra"] == r["estimation_tetrahedra"] for r in rs),
                            tetrahedra=rs[0]["estimation_tetrahedra"],
                            prostate_rms_mm=round(statistics.median(r["prostate_rms_mm"] for r in rs), 3),
                            register_s=round(statistics.median(r["register_s"] for r in rs), 1)))
    write_csv(os.path.join(OUT, "identifiability.csv"), summary)
    print("\n| scene | voxel [mm] | true E [kPa] | pairs | median error | range | tetrahedra (same as truth) "
          "| prostate RMS [mm] | register [s] |\n|---|---:|---:|---:|---:|---|---:|---:|---:|")
    for s in summary:
        print(f"| {s['scene']} | {s['spacing_mm']} | {s['true_E_kPa']} | {s['pairs']} | {s['median_error_pct']:+.1f} % "
              f"| {s['min_error_pct']:+.1f} … {s['max_error_pct']:+.1f} % | {s['tetrahedra']} ({s['same_mesh']}) "
              f"| {s['prostate_rms_mm']} | {s['register_s']} |")
    print("\nPhi*(E) relative to its value at the truth [%], E held at factor x truth:\n")
    print("| scene | voxel [mm] | " + " | ".join(f"{f} x" for f in PROFILE_FACTORS) + " | free estimate [kPa] |")
    print("|---|---:|" + "---:|" * (len(PROFILE_FACTORS) + 1))
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for key in dict.fromkeys((p["scene"], p["spacing_mm"]) for p in profile):
        ps = [p for p in profile if (p["scene"], p["spacing_mm"]) == key]
        at_truth = next(p["phi_mm2"] for p in ps if p["held_E_kPa"] == p["true_E_kPa"])
        relative = [100.0 * (p["phi_mm2"] / at_truth - 1) for p in ps]
        print(f"| {key[0]} | {key[1]} | " + " | ".join(f"{v:+.2f}" for v in relative) +
              f" | {ps[0]['free_estimate_kPa']} |")
        axes[1].plot([p["held_E_kPa"] for p in ps], relative, "o-", label=f"scene {key[0]}, {key[1]} mm voxels")
    print("\nWhat E acts on against what the label map resolves (100 kPa; the profiled pairs):\n")
    print("| scene | voxel [mm] | prostate beyond rigid: RMS / largest [mm] | principal strains | "
          "self-registration: RMS / mean signed [mm] |\n|---|---:|---:|---|---:|")
    for g in signal:
        print(f"| {g['scene']} | {g['spacing_mm']} | {g['prostate_nonrigid_rms_mm']} / {g['prostate_nonrigid_max_mm']} "
              f"| {g['principal_strains']} | {g['self_registration_rms_mm']} / "
              f"{g['self_registration_mean_signed_mm']} |")
    for (scene, spacing, E), rs in groups.items():
        axes[0].plot([E] * len(rs), [r["estimate_kPa"] for r in rs], "o" if spacing == 1.0 else "s",
                     color="C0" if scene == "A" else "C1", alpha=0.7)
    axes[0].plot([40, 160], [40, 160], "k--", lw=1, label="truth")
    axes[0].plot([], [], "o", color="C0", label="scene A, 1 mm")
    axes[0].plot([], [], "o", color="C1", label="scene B, 1 mm")
    axes[0].plot([], [], "s", color="gray", label="0.5 mm voxels")
    axes[0].set(xlabel="true E [kPa]", ylabel="estimate [kPa]", title="inverse crime: same mesh, model, loads")
    axes[0].legend(fontsize=8)
    axes[1].axhline(0, color="k", lw=0.5)
    axes[1].set(xscale="log", xlabel="prostate E held [kPa]", ylabel="Phi*(E) / Phi*(truth) - 1 [%]",
                title="objective over the pressures, E held (truth 100 kPa)")
    axes[1].legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(os.path.join(OUT, "identifiability.png"), dpi=110)


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 53
    os.makedirs(OUT, exist_ok=True)
    runs_csv, profile_csv = (os.path.join(OUT, f"identifiability_{name}.csv") for name in ("runs", "profile"))
    with tempfile.TemporaryDirectory() as work:
        if os.environ.get("REUSE_RUNS") == "1":
            runs, profile = read_csv(runs_csv), read_csv(profile_csv)
        else:
            runs = estimates(work, count, seed)
            write_csv(runs_csv, runs)
            profile = profiles(work, runs)
            write_csv(profile_csv, profile)
        signal_csv = os.path.join(OUT, "identifiability_signal.csv")
        if os.environ.get("REUSE_SIGNAL") == "1":
            signal = read_csv(signal_csv)
        else:
            signal = signals(work, profile)
            write_csv(signal_csv, signal)
    summarize(runs, profile, signal)


if __name__ == "__main__":
    main()
