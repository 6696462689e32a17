#!/usr/bin/env python3
"""A change against the build before it (not a test): the demo pair registered RUNS times by `biomechreg register`
as built now (BUILD_DIR) and by BASELINE, a build of the commit before the change; alternating rounds (the order
reversed every other round), with the point estimate (--uncertainty none) and with the stated interval (4 rescans);
wall time of the whole process each. The point estimates must agree bit for bit (the intervals too, unless the
change redraws the resamples).

Usage: BASELINE=path/to/biomechreg benchmarks/run_against_baseline.py NAME BEFORE_LABEL AFTER_LABEL [RUNS (5)]
       (BUILD_DIR: the build with bin/biomechreg; default build)
Writes benchmarks/results/NAME/{NAME_runs.csv, NAME.csv, NAME.png} and prints the table.
Used for: background_tasks own_threads tbb_background_tasks (work beside the caller on TBB's pool);
sweep_first fine_objective_alongside sweep_then_fine (the optimizer without threads of its own)."""

import os
import pathlib
import sys

from alternating_runs import modulus, prepare, register_command, rounds, summarize, timed, write_csv

ROOT = pathlib.Path(__file__).resolve().parent.parent
CLI = pathlib.Path(os.environ.get("BUILD_DIR", ROOT / "build")) / "bin" / "biomechreg"


def main(name, before, after, runs):
    baseline = os.environ.get("BASELINE")
    if not baseline:
        sys.exit("BASELINE=path/to/biomechreg (a build of the commit before the change) is required")
    out_dir = ROOT / "benchmarks" / "results" / name
    programs = {before: baseline, after: CLI}
    pair = prepare(CLI, out_dir)
    rows = []
    for run, uncertainty, way in rounds(runs, [before, after]):
        out = pair.parent / f"{way}_{uncertainty}_{run}"
        seconds = timed(register_command(programs[way], pair, uncertainty, out))
        rows.append({"run": run, "mode": uncertainty, "way": way, "wall_s": round(seconds, 3),
                     "modulus_kPa": repr(modulus(out))})
    write_csv(out_dir / f"{name}_runs.csv", rows)
    summarize(rows, [before, after], before, out_dir, name, f"register on the demo pair: {before} vs {after}")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]) if len(sys.argv) > 4 else 5)
