"""Medians over runs of the forward benchmark: CSV, a printed table and a PNG plot."""
import csv
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
fields = ["cell_size_mm", "run", "tetrahedra", "nodes", "stage", "seconds", "peak_rss_MB"]
rows = []
with open(f"{out}/forward_runs.csv") as f:
    for raw in list(csv.reader(f))[1:]:
        # A stage name may contain commas: the first four and last two fields are fixed.
        rows.append(dict(zip(fields, raw[:4] + [",".join(raw[4:-2]).strip()] + raw[-2:])))
times = defaultdict(list)
meta = {}
for r in rows:
    key = (float(r["cell_size_mm"]), r["stage"])
    times[key].append(float(r["seconds"]))
    meta[float(r["cell_size_mm"])] = (int(r["tetrahedra"]), int(r["nodes"]), float(r["peak_rss_MB"]))
stages = []
for r in rows:
    if r["stage"] not in stages:
        stages.append(r["stage"])
sizes = sorted(meta, reverse=True)
with open(f"{out}/forward.csv", "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["cell_size_mm", "tetrahedra", "nodes", "peak_rss_MB"] + [f"{s} [s]" for s in stages])
    for h in sizes:
        w.writerow([h, *meta[h]] + [f"{statistics.median(times[(h, s)]):.3f}" for s in stages])
print(f"median wall time [s] over {len(times[(sizes[0], stages[0])])} runs; peak RSS of the whole run")
header = f"{'stage':36s}" + "".join(f"{meta[h][0]:>12d}" for h in sizes)
print(header + "   <- tetrahedra")
for s in stages:
    print(f"{s:36s}" + "".join(f"{statistics.median(times[(h, s)]):12.3f}" for h in sizes))
core = ["mesh (CGAL Mesh_3)", "assemble", "factorize", "solve"]
print(f"{'mesh+assemble+factorize+solve':36s}" + "".join(
    f"{sum(statistics.median(times[(h, s)]) for s in core if (h, s) in times):12.3f}" for h in sizes))
print(f"{'peak RSS [MB]':36s}" + "".join(f"{meta[h][2]:12.0f}" for h in sizes))
fig, ax = plt.subplots(figsize=(8, 5))
x = [meta[h][0] for h in sizes]
for s in stages:
    ax.plot(x, [statistics.median(times[(h, s)]) for h in sizes], marker="o", label=s)
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("tetrahedra")
ax.set_ylabel("median wall time [s]")
ax.set_title("biomechreg simulate, pelvis phantom 256x256x100, 2 cores")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/forward.png", dpi=120)
print(f"wrote {out}/forward.csv and {out}/forward.png")
