#!/usr/bin/env bash
# The cohort workflow for real (Snakemake, not a mock) on a 3-patient x 2-fraction phantom cohort of 2 mm voxels:
# 1. a first run on one core is killed (its whole process group) as soon as Snakemake has finished one register job;
# 2. the re-run computes only the missing fractions: the finished report keeps its content and its time stamp,
#    and Snakemake runs 5 register jobs, not 6;
# 3. the report's numbers are checked against the fractions' own report.json files (per-patient n, mean and
#    SD recomputed here to 1e-5 relative; Pearson and Spearman of the means against the stages recomputed here to
#    1e-5) and against the truth (the patients' means in the order of their true moduli; 2 mm voxels bias the
#    moduli themselves, see below);
# 4. a damaged cohort file is refused before anything runs, with its line and column;
# 5. a pair that fails is listed with its log, the command exits 1, and the other pair's result stays.
# Usage: biomechregCohortWorkflow.sh BIOMECHREG WORKDIR
set -euo pipefail
bin="$1"
work="$2"
py=/usr/bin/python3
rm -rf "$work"
mkdir -p "$work"
# The workflow's mechanics on small images: 2 mm voxels are above the limit where register states a modulus, so the
# limit is raised to read the (biased, see below) fits as the cohort's values.
options="--uncertainty none --uncertainty-voxel-limit-mm 2.5"

"$bin" phantom-cohort --out "$work/data" --patients 3 --fractions 2 --seed 4 --size 100,80,80 --spacing 2,2,2 \
  --truth-mesh-scale 1 > "$work/phantom.log" 2>&1 || { cat "$work/phantom.log"; exit 1; }

# 1. Killed part-way.
setsid "$bin" cohort --cohort "$work/data/cohort.csv" --out "$work/study" --cores 1 --register-options "$options" \
  > "$work/run1.log" 2>&1 &
leader=$!
# Killed once Snakemake has finished a register job, not when a report.json appears: a job killed after its
# register wrote the report but before Snakemake recorded it as finished is incomplete, and the re-run rightly
# runs it again (that race failed this test in one of session 40's three full ctest runs).
for _ in $(seq 1 600); do
  if grep -q '^Finished job' "$work/run1.log" 2> /dev/null; then break; fi
  sleep 0.2
done
kill -TERM -- "-$leader" 2> /dev/null || true
wait "$leader" 2> /dev/null || true
sleep 2
# The reports of the jobs Snakemake finished (its log: "output: results/.../report.json", "jobid: N", then
# "Finished job N.").
mapfile -t done_reports < <("$py" - "$work/run1.log" "$work/study" <<'PY'
import re, sys
log, study = sys.argv[1], sys.argv[2]
outputs, finished, output = {}, set(), None
for line in open(log):
    m = re.match(r"\s+output: (results/\S+/report\.json)", line)
    output = m.group(1) if m else output
    m = re.match(r"\s+jobid: (\d+)", line)
    if m and output:
        outputs[m.group(1)], output = output, None
    m = re.match(r"Finished job (\d+)\.", line)
    if m:
        finished.add(m.group(1))
for job in sorted(finished & outputs.keys()):
    print(f"{study}/{outputs[job]}")
PY
)
echo "reports of finished jobs after the kill: ${#done_reports[@]}"
[ "${#done_reports[@]}" -ge 1 ] && [ "${#done_reports[@]}" -lt 6 ] || { echo "FAIL: expected 1-5 reports after the kill"; cat "$work/run1.log"; exit 1; }
declare -A stamp sum
for r in "${done_reports[@]}"; do stamp[$r]=$(stat -c %Y.%y "$r"); sum[$r]=$(md5sum < "$r"); done

# 2. The re-run does only what is missing.
"$bin" cohort --cohort "$work/data/cohort.csv" --out "$work/study" --cores 2 --register-options "$options" \
  > "$work/run2.log" 2>&1 || { echo "FAIL: the re-run failed"; tail -40 "$work/run2.log"; exit 1; }
ran=$(grep -c '^rule register:' "$work/run2.log" || true)
expected=$((6 - ${#done_reports[@]}))
echo "register jobs in the re-run: $ran (expected $expected)"
[ "$ran" -eq "$expected" ] || { echo "FAIL: the re-run ran $ran register jobs, not $expected"; exit 1; }
for r in "${done_reports[@]}"; do
  [ "$(stat -c %Y.%y "$r")" = "${stamp[$r]}" ] && [ "$(md5sum < "$r")" = "${sum[$r]}" ] ||
    { echo "FAIL: $r was recomputed"; exit 1; }
done
for f in cohort_report.md cohort_patients.csv cohort_fractions.csv cohort_correlations.csv cohort_box.png cohort_scatter.png; do
  [ -s "$work/study/$f" ] || { echo "FAIL: $f missing"; exit 1; }
done

# 3. The numbers.
"$py" - "$work" <<'PY'
import csv, glob, json, math, sys
work = sys.argv[1]
def rows(p):
    with open(p) as f:
        return list(csv.DictReader(l for l in f if not l.startswith("#")))
truth = {r["patient"]: r for r in rows(f"{work}/data/truth.csv")}
patients = {r["patient"]: r for r in rows(f"{work}/study/cohort_patients.csv") if r["material"] == "prostate"}
means, stages, true_E, ok = [], [], [], True
for p, t in sorted(truth.items()):
    E = [json.load(open(r))["youngs_modulus_kPa"]["prostate"] for r in sorted(glob.glob(f"{work}/study/results/{p}/*/report.json"))]
    m = sum(E) / len(E)
    sd = math.sqrt(sum((e - m) ** 2 for e in E) / (len(E) - 1))
    r = patients[p]
    print(f"{p}: stage {t['t_stage']}, true {t['true_E_kPa']} kPa, recovered {E} -> mean {m:.2f} (report {r['mean_kPa']}), SD {sd:.3f}")
    ok &= int(r["n"]) == len(E) == 2
    ok &= abs(float(r["mean_kPa"]) - m) <= 1e-5 * m and abs(float(r["sd_kPa"]) - sd) <= 1e-5 * max(sd, 1)
    print(f"  error {100 * (m / float(t['true_E_kPa']) - 1):+.1f} %")
    means.append(m); stages.append(float(t["t_stage"][1:])); true_E.append(float(t["true_E_kPa"]))
# What a cohort study rests on: the patients in the order of their true moduli. Not the moduli themselves:
# 2 mm voxels (beyond the 1.5 mm register warns about) bias stiff prostates low (-31 % at 93 kPa here; the
# 10 x 6 benchmark at 2 mm: -20 ... +16 % per patient).
order = lambda v: sorted(range(len(v)), key=lambda i: v[i])
print(f"order of the recovered means {order(means)}, of the true moduli {order(true_E)}")
ok &= order(means) == order(true_E)
def pearson(x, y):
    mx, my = sum(x) / len(x), sum(y) / len(y)
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    return sxy / math.sqrt(sum((a - mx) ** 2 for a in x) * sum((b - my) ** 2 for b in y))
def ranks(v):
    order = sorted(range(len(v)), key=lambda i: v[i]); r = [0.0] * len(v); i = 0
    while i < len(v):
        j = i
        while j + 1 < len(v) and v[order[j + 1]] == v[order[i]]: j += 1
        for k in range(i, j + 1): r[order[k]] = (i + j) / 2 + 1
        i = j + 1
    return r
corr = {r["method"]: r for r in rows(f"{work}/study/cohort_correlations.csv")}
if len(set(stages)) > 1:
    for method, value in (("pearson", pearson(stages, means)), ("spearman", pearson(ranks(stages), ranks(means)))):
        got = float(corr[method]["coefficient"])
        print(f"{method}: report {got}, recomputed {value}")
        ok &= abs(got - value) <= 1e-5
        ok &= corr[method]["permutation_exact"] == "yes"
else:
    print("all patients share one stage: the report says why there is no correlation")
    ok &= "same for every patient" in open(f"{work}/study/cohort_correlations.csv").read()
sys.exit(0 if ok else 1)
PY

# 4. A damaged cohort file: refused before any job, naming the line and the column (line 3 is P01/F1's).
sed '3s/,T[0-9],/,TX,/' "$work/data/cohort.csv" > "$work/data/bad.csv"
if "$bin" cohort --cohort "$work/data/bad.csv" --out "$work/bad" > "$work/bad.log" 2>&1; then
  echo "FAIL: the damaged cohort was accepted"; exit 1
fi
grep -q 'line 3, column "t_stage"' "$work/bad.log" || { echo "FAIL: the error does not name line 3, t_stage"; cat "$work/bad.log"; exit 1; }
[ ! -e "$work/bad/results" ] || { echo "FAIL: a job ran for the damaged cohort"; exit 1; }

# 5. A pair that fails (a corrupt daily CT) is reported with its log and leaves the other's result alone; the
#    finished pair's report is carried over, so only the failing job runs.
mkdir -p "$work/fail/results/P01/F1"
cp -p "$work/study/results/P01/F1/report.json" "$work/fail/results/P01/F1/"
head -c 1000 "$work/data/P01/F2/daily_ct.nrrd" > "$work/data/P01/F2/corrupt_ct.nrrd"
{ head -n 3 "$work/data/cohort.csv"; sed -n 4p "$work/data/cohort.csv" | sed 's|F2/daily_ct.nrrd|F2/corrupt_ct.nrrd|'; } \
  > "$work/data/failing.csv"
if "$bin" cohort --cohort "$work/data/failing.csv" --out "$work/fail" --cores 2 --register-options "$options" \
  > "$work/fail.log" 2>&1; then
  echo "FAIL: a cohort with a failing pair exited 0"; exit 1
fi
grep -q '1 of 2 fractions have no result' "$work/fail.log" || { echo "FAIL: no count of failed fractions"; tail "$work/fail.log"; exit 1; }
grep -q "P01/F2: \`$work/fail/logs/P01/F2.log\`" "$work/fail/cohort_report.md" || { echo "FAIL: the report does not list P01/F2's log"; exit 1; }
grep -q 'corrupt_ct.nrrd' "$work/fail/logs/P01/F2.log" || { echo "FAIL: the log does not name the corrupt file"; exit 1; }
cmp -s "$work/study/results/P01/F1/report.json" "$work/fail/results/P01/F1/report.json" || { echo "FAIL: P01/F1 lost"; exit 1; }
grep -q '^P01,[0-9]*,prostate,1,1,' "$work/fail/cohort_patients.csv" || { echo "FAIL: P01 should have n 1, 1 missing"; cat "$work/fail/cohort_patients.csv"; exit 1; }
echo "ok"
