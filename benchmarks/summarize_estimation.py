"""Summarizes benchmarks/results/estimation_runs.csv: medians per configuration (estimation.csv),
a plot (estimation.png: recovered vs true E; relative error against run time over mesh sizes)
and markdown tables on stdout."""
import csv
import math
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/estimation_runs.csv")))
groups = OrderedDict()
for r in rows:
    key = (r["study"], r["scene"], r["true_E_kPa"], r["true_nu"], r["mesh_scale"], r.get("tumour_fraction", "0"))
    groups.setdefault(key, []).append(r)

med = []
for (study, scene, E, nu, scale, tumour), rs in groups.items():
    m = lambda k: statistics.median(float(x[k]) for x in rs)  # noqa: E731
    med.append(dict(study=study, scene=scene, E=float(E), nu=float(nu), scale=float(scale), runs=len(rs),
                    Er=m("recovered_E_kPa"), err=m("relative_error"), tets=int(m("tetrahedra")),
                    est=m("estimation_s"), total=m("total_s"), rms=m("prostate_rms_mm"),
                    ident=min(int(x["identifiable"]) for x in rs), tumour=float(tumour or 0),
                    # standard deviation of log E reported by register (empty in rows from before it existed)
                    sigma=statistics.median(float(x.get("sigma_log_E") or "nan") for x in rs)))
with open(f"{out}/estimation.csv", "w") as f:
    f.write("study,scene,true_E_kPa,true_nu,mesh_scale,tumour_fraction,runs,recovered_E_kPa,relative_error,"
            "tetrahedra,estimation_s,total_s,prostate_rms_mm,identifiable,sigma_log_E\n")
    for d in med:
        f.write(f'{d["study"]},{d["scene"]},{d["E"]:g},{d["nu"]:g},{d["scale"]:g},{d["tumour"]:g},{d["runs"]},{d["Er"]:.2f},'
                f'{d["err"]:.4f},{d["tets"]},{d["est"]:.2f},{d["total"]:.2f},{d["rms"]:.4f},{d["ident"]},{d["sigma"]:.4f}\n')

for study in OrderedDict((d["study"], 0) for d in med):
    print(f"\n{study} (medians; times in s, moduli in kPa)\n")
    print("| scene | true E | true nu | tumour fraction | mesh scale | tets | recovered E | rel. error | estimation | total | prostate RMS mm | identifiable | ±1σ (reported) | error / σ |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    for d in med:
        if d["study"] == study:
            print(f'| {d["scene"]} | {d["E"]:g} | {d["nu"]:.2f} | {d["tumour"]:g} | {d["scale"]:g} | {d["tets"]} | {d["Er"]:.1f} | '
                  f'{100 * d["err"]:+.1f} % | {d["est"]:.1f} | {d["total"]:.1f} | {d["rms"]:.3f} | {"yes" if d["ident"] else "no"} | '
                  f'{100 * d["sigma"]:.1f} % | {math.log(d["Er"] / d["E"]) / d["sigma"]:+.2f} |')

fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
for scene, marker in (("A", "o"), ("B", "s")):
    pts = [d for d in med if d["study"] == "table31" and d["scene"] == scene]
    if pts:
        ax[0].plot([d["E"] for d in pts], [d["Er"] for d in pts], marker, label=f"scene {scene}")
lim = [0, 400]
ax[0].plot(lim, lim, "k--", lw=0.8, label="truth")
ax[0].fill_between(lim, [0.9 * v for v in lim], [1.1 * v for v in lim], color="0.85", label="±10 %")
ax[0].set(xlabel="true prostate E [kPa]", ylabel="recovered E [kPa]", title="Table 3.1: recovery")
ax[0].legend()
for E in sorted({d["E"] for d in med if d["study"] == "poisson"}):
    pts = [d for d in med if d["study"] == "poisson" and d["E"] == E]
    ax[1].plot([d["nu"] for d in pts], [100 * d["err"] for d in pts], "o-", label=f"true E {E:g} kPa")
ax[1].axvline(0.40, color="k", lw=0.8, ls="--")
ax[1].set(xlabel="true prostate Poisson ratio (assumed 0.40)", ylabel="relative error of E [%]",
          title="Fig. 3.6: wrong Poisson ratio")
if any(d["study"] == "poisson" for d in med):
    ax[1].legend()
pts = [d for d in med if d["study"] == "mesh"]
if pts:
    ax[2].plot([d["est"] for d in pts], [abs(100 * d["err"]) for d in pts], "o-")
    for d in pts:
        ax[2].annotate(f'{d["tets"]} tets', (d["est"], abs(100 * d["err"])))
ax[2].set(xlabel="estimation wall time [s] (median)", ylabel="|relative error of E| [%]",
          title="error against run time (mesh size)")
fig.tight_layout()
fig.savefig(f"{out}/estimation.png", dpi=110)
print(f"\nwrote {out}/estimation_runs.csv, estimation.csv, estimation.png")
