#!/usr/bin/env python3
"""Background work on the library's executor (not a test): the demo pair registered RUNS times by `biomechreg
register` as built now, whose work beside the caller (the fine mesh while the sweep runs, the resample meshes and
rescan maps while the fit runs) is a bmr::BackgroundTask on TBB's pool, and by BASELINE, a build of the commit
before, which gave each its own thread; alternating rounds (the order reversed every other round), with the point
estimate (--uncertainty none) and with the stated interval (4 rescans); wall time of the whole process each. The
moduli must agree bit for bit.

Usage: BASELINE=path/to/biomechreg benchmarks/run_background_tasks_benchmark.py [RUNS (5)]
       (BUILD_DIR: the build with bin/biomechreg; default build)
Writes benchmarks/results/background_tasks/{background_tasks_runs.csv, background_tasks.csv, background_tasks.png}
and prints the table."""

import os
import pathlib
import sys

from alternating_runs import modulus, prepare, register_command, rounds, summarize, timed, write_csv

ROOT = pathlib.Path(__file__).resolve().parent.parent
CLI = pathlib.Path(os.environ.get("BUILD_DIR", ROOT / "build")) / "bin" / "biomechreg"
OUT = ROOT / "benchmarks" / "results" / "background_tasks"
WAYS = ("own_threads", "tbb_background_tasks")


def main(runs):
    baseline = os.environ.get("BASELINE")
    if not baseline:
        sys.exit("BASELINE=path/to/biomechreg (a build of the commit before the background tasks) is required")
    programs = {"own_threads": baseline, "tbb_background_tasks": CLI}
    pair = prepare(CLI, OUT)
    rows = []
    for run, uncertainty, way in rounds(runs, list(WAYS)):
        out = pair.parent / f"{way}_{uncertainty}_{run}"
        seconds = timed(register_command(programs[way], pair, uncertainty, out))
        rows.append({"run": run, "mode": uncertainty, "way": way, "wall_s": round(seconds, 3),
                     "modulus_kPa": repr(modulus(out))})
    write_csv(OUT / "background_tasks_runs.csv", rows)
    summarize(rows, list(WAYS), "own_threads", OUT, "background_tasks",
              "register on the demo pair: background work on TBB's pool")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
