#!/usr/bin/env python3
"""The program's malloc (not a test): the demo pair registered RUNS times by `biomechreg register` under each
malloc, alternating (the order reversed every other round), with the point estimate (--uncertainty none) and with
the stated interval (4 rescans); wall time of the whole process each; the moduli must agree bit for bit.

Ways: `jemalloc_hugepages`, the program as built (jemalloc with transparent huge pages, apps/biomechregMalloc.cxx);
`jemalloc_plain`, the same with MALLOC_CONF=thp:never (jemalloc reads the environment after the program's own
setting). With BASELINE=path/to/biomechreg (a build of an earlier commit whose program restarted itself with
GLIBC_TUNABLES=glibc.malloc.hugetlb=1) also `glibc_hugepages_restart`, that program as it ran, and
`glibc_plain`, it with glibc.malloc.hugetlb=0; ratios are then to `glibc_hugepages_restart`, else to
`jemalloc_plain`.

Usage: benchmarks/run_malloc_benchmark.py [RUNS (5)]   (BUILD_DIR: the build with bin/biomechreg; default build)
Writes benchmarks/results/malloc/{malloc_runs.csv, malloc.csv, malloc.png} and prints the table."""

import os
import pathlib
import sys

from alternating_runs import modulus, prepare, register_command, rounds, summarize, timed, write_csv

ROOT = pathlib.Path(__file__).resolve().parent.parent
CLI = pathlib.Path(os.environ.get("BUILD_DIR", ROOT / "build")) / "bin" / "biomechreg"
BASELINE = os.environ.get("BASELINE")
OUT = ROOT / "benchmarks" / "results" / "malloc"


def ways():
    """{name: (program, environment changes)} of each way."""
    listed = {"jemalloc_hugepages": (CLI, {}), "jemalloc_plain": (CLI, {"MALLOC_CONF": "thp:never"})}
    if BASELINE:
        listed["glibc_hugepages_restart"] = (BASELINE, {})
        listed["glibc_plain"] = (BASELINE, {"GLIBC_TUNABLES": "glibc.malloc.hugetlb=0"})
    return listed


def main(runs):
    pair = prepare(CLI, OUT)
    rows = []
    for run, uncertainty, name in rounds(runs, list(ways())):
        program, changes = ways()[name]
        out = pair.parent / f"{name}_{uncertainty}_{run}"
        env = {k: v for k, v in os.environ.items() if k not in ("GLIBC_TUNABLES", "MALLOC_CONF")}
        env.update(changes)
        seconds = timed(register_command(program, pair, uncertainty, out), env)
        rows.append({"run": run, "mode": uncertainty, "way": name, "wall_s": round(seconds, 3),
                     "modulus_kPa": repr(modulus(out))})
    write_csv(OUT / "malloc_runs.csv", rows)
    summarize(rows, list(ways()), "glibc_hugepages_restart" if BASELINE else "jemalloc_plain", OUT, "malloc",
              "register on the demo pair: the program's malloc")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
