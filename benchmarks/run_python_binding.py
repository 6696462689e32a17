#!/usr/bin/env python3
"""What the Python package adds to a registration (not a test): the demo pair registered RUNS times by
`biomechreg register` and by a fresh Python process doing the same (import biomechreg, read the four images and the
scene, register, write the same outputs), alternating, both with the point estimate (--uncertainty none) and with
the stated interval (4 rescans). Python runs twice per round: as it starts by default, and with
GLIBC_TUNABLES=glibc.malloc.hugetlb=1, glibc's malloc with huge pages (the package leaves the interpreter's malloc
alone; biomechreg runs on jemalloc with huge pages where built with it: run_malloc_benchmark.py). Wall time of the
whole process each; the moduli must agree bit for bit.

Usage: PYTHONPATH=build/python benchmarks/run_python_binding.py [RUNS (5)]
Writes benchmarks/results/python_binding/{python_binding_runs.csv, python_binding.csv, python_binding.png} and
prints the table (medians, ranges, Python / CLI)."""

import os
import pathlib
import sys

from alternating_runs import modulus, prepare, register_command, rounds, summarize, timed, write_csv

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
WAYS = ("cli", "python", "python_hugepages")


def main(runs):
    pair = prepare(CLI, OUT)
    rows = []
    for run, uncertainty, way in rounds(runs, WAYS):
        out = pair.parent / f"{way}_{uncertainty}_{run}"
        if way == "cli":
            seconds = timed(register_command(CLI, pair, uncertainty, out))
        else:
            env = dict(os.environ)
            if way == "python_hugepages":
                env["GLIBC_TUNABLES"] = "glibc.malloc.hugetlb=1"
            seconds = timed(["/usr/bin/python3", "-c", PYTHON_RUN, str(pair), str(out), uncertainty], env)
        rows.append({"run": run, "mode": uncertainty, "way": way, "wall_s": round(seconds, 3),
                     "modulus_kPa": repr(modulus(out))})
    write_csv(OUT / "python_binding_runs.csv", rows)
    summarize(rows, WAYS, "cli", OUT, "python_binding", "register on the demo pair: CLI and Python")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
