"""Summarizes benchmarks/run_cohort_benchmark.sh: the workflow's throughput and the recovered against the true
statistics. Usage: /usr/bin/python3 benchmarks/summarize_cohort.py RESULTS_DIR
Reads cohort_benchmark.csv, cohort_jobs.csv, cohort_patients.csv, cohort_correlations.csv, cohort_truth.csv and
cohort_truth_correlations.csv; writes cohort_patients_vs_truth.csv and cohort_benchmark.png (recovered per-patient
mean +- SD against the true modulus; job times), prints markdown tables. Moduli in kPa, times in s, memory in MB.
"""
import csv
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

d = sys.argv[1]


def rows(name):
    with open(f"{d}/{name}") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


run = rows("cohort_benchmark.csv")[0]
jobs = rows("cohort_jobs.csv")
times = [float(j["wall_s"]) for j in jobs if j["wall_s"]]
memory = [float(j["peak_rss_MB"]) for j in jobs if j["peak_rss_MB"]]
wall, user, sys_s, cores = float(run["workflow_wall_s"]), float(run["user_s"]), float(run["sys_s"]), int(run["cores"])
print(f"## Cohort workflow: {run['patients']} patients x {run['fractions']} fractions on {cores} cores "
      f"(register {run['register_options']})\n")
print("| phantom cohort [s] | workflow wall [s] | jobs | job median [s] | job min-max [s] | sum of jobs / wall "
      "| CPU utilisation | peak RSS median / max [MB] |")
print("|---:|---:|---:|---:|---:|---:|---:|---:|")
print(f"| {float(run['phantom_s']):.0f} | {wall:.0f} | {len(times)} | {statistics.median(times):.1f} | "
      f"{min(times):.1f}-{max(times):.1f} | {sum(times) / wall:.2f} | {(user + sys_s) / (wall * cores):.0%} | "
      f"{statistics.median(memory):.0f} / {max(memory):.0f} |\n")

truth = {r["patient"]: r for r in rows("cohort_truth.csv")}
recovered = [r for r in rows("cohort_patients.csv") if r["material"] == "prostate"]
with open(f"{d}/cohort_patients_vs_truth.csv", "w") as f:
    w = csv.writer(f)
    w.writerow(["patient", "t_stage", "true_E_kPa", "n", "mean_kPa", "sd_kPa", "error_percent"])
    print("| patient | stage | true E | n | recovered mean ± SD | error |")
    print("|---|---|---:|---:|---:|---:|")
    errors = []
    for r in recovered:
        t = truth[r["patient"]]
        if not r["mean_kPa"]:
            print(f"| {r['patient']} | {t['t_stage']} | {t['true_E_kPa']} | 0 | – | – |")
            continue
        e = 100 * (float(r["mean_kPa"]) / float(t["true_E_kPa"]) - 1)
        errors.append(e)
        w.writerow([r["patient"], t["t_stage"], t["true_E_kPa"], r["n"], r["mean_kPa"], r["sd_kPa"], f"{e:.2f}"])
        print(f"| {r['patient']} | {t['t_stage']} | {t['true_E_kPa']} | {r['n']} | {float(r['mean_kPa']):.1f} ± "
              f"{float(r['sd_kPa']):.1f} | {e:+.1f} % |")
    if errors:
        print(f"\nper-patient error: median {statistics.median(errors):+.1f} %, "
              f"range {min(errors):+.1f} … {max(errors):+.1f} %\n")

print("| statistic | truth (true E vs stage) | recovered (mean E vs stage) |")
print("|---|---|---|")
true_c = {r["method"]: r for r in rows("cohort_truth_correlations.csv")}
for r in rows("cohort_correlations.csv"):
    if not r["method"]:
        print(f"| – | – | {r['note']} |")
        continue
    t = true_c.get(r["method"])
    tt = f"{float(t['coefficient']):.3f} (p {float(t['p_approximate']):.4f})" if t else "–"
    print(f"| {r['method']} | {tt} | {float(r['coefficient']):.3f} (p {float(r['p_approximate']):.4f}; "
          f"permutation {r['p_permutation'] or '–'}) |")

fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
for r in recovered:
    if r["mean_kPa"]:
        t = truth[r["patient"]]
        a.errorbar(float(t["true_E_kPa"]), float(r["mean_kPa"]), yerr=float(r["sd_kPa"]), fmt="o", capsize=3)
        a.annotate(f"{r['patient']} {t['t_stage']}", (float(t["true_E_kPa"]), float(r["mean_kPa"])), fontsize=7,
                   textcoords="offset points", xytext=(4, 4))
lims = [min(float(t["true_E_kPa"]) for t in truth.values()) * 0.8, max(float(t["true_E_kPa"]) for t in truth.values()) * 1.2]
a.plot(lims, lims, "k--", lw=0.8)
a.set_xlabel("true prostate E [kPa]")
a.set_ylabel("recovered, mean ± SD over fractions [kPa]")
a.set_title("per patient")
b.hist(times, bins=15)
b.set_xlabel("job wall time [s]")
b.set_ylabel("jobs")
b.set_title(f"{len(times)} registrations, workflow {wall:.0f} s on {cores} cores")
fig.tight_layout()
fig.savefig(f"{d}/cohort_benchmark.png", dpi=120)
print(f"\nwrote {d}/cohort_benchmark.png, cohort_patients_vs_truth.csv")
