#!/usr/bin/env python3
"""How far the phantom's truth field is from converged (issue 15, item 1; not a test).

Usage: truth_convergence.py FINEST_DIR COARSER_DIR... [--csv OUT.csv]

Each DIR is a `biomechreg phantom` output of one anatomy at another --truth-mesh-scale. Every coarser truth field
(truth_field.nrrd, the fixed -> moving pull-back [mm]) is compared with the finest over the voxels whose fixed
label (the finest phantom's fixed_labels.nrrd) is soft tissue or prostate: the largest |du| in the prostate and
its share of the largest |u| there, the 99th percentile of |du| over tissue and prostate, and the RMS of |du|.
Prints a markdown table and writes it as CSV when asked.
"""
import csv
import gzip
import json
import sys

import numpy as np

TISSUE, PROSTATE = 1, 2


def read_nrrd(path):
    """The data of a NRRD file (raw or gzip encoding) as a flat array, and its header fields."""
    raw = open(path, "rb").read()
    end = raw.index(b"\n\n")
    header = {}
    for line in raw[:end].decode().splitlines()[1:]:
        if ":" in line and not line.startswith("#"):
            key, value = line.split(":", 1)
            header[key.strip()] = value.strip()
    data = raw[end + 2:]
    if header.get("encoding") == "gzip":
        data = gzip.decompress(data)
    dtypes = {"double": np.float64, "float": np.float32, "int": np.int32, "short": np.int16,
              "unsigned char": np.uint8, "uchar": np.uint8}
    return np.frombuffer(data, dtype=dtypes[header["type"]]), header


def truth_summary(directory):
    """Tetrahedra and nodes of the truth's mesh, and its geometry, from truth.json."""
    mesh = json.load(open(f"{directory}/truth.json"))["truth_mesh"]
    return mesh["tetrahedra"], mesh["nodes"], mesh.get("geometry", "voxels")


def main(argv):
    out = None
    if "--csv" in argv:
        k = argv.index("--csv")
        out = argv[k + 1]
        argv = argv[:k] + argv[k + 2:]
    if len(argv) < 2:
        sys.exit(__doc__)
    finest, coarser = argv[0], argv[1:]
    labels, _ = read_nrrd(f"{finest}/fixed_labels.nrrd")
    reference, _ = read_nrrd(f"{finest}/truth_field.nrrd")
    reference = reference.reshape(-1, 3)
    prostate = labels == PROSTATE
    inside = prostate | (labels == TISSUE)
    umax = np.linalg.norm(reference[prostate], axis=1).max()
    rows = []
    for directory in coarser:
        field, _ = read_nrrd(f"{directory}/truth_field.nrrd")
        du = np.linalg.norm(field.reshape(-1, 3) - reference, axis=1)
        tets, nodes, geometry = truth_summary(directory)
        rows.append({"phantom": directory, "geometry": geometry, "tetrahedra": tets, "nodes": nodes,
                     "max_du_prostate_mm": du[prostate].max(), "max_du_prostate_pct": 100 * du[prostate].max() / umax,
                     "p99_du_mm": np.percentile(du[inside], 99), "rms_du_mm": np.sqrt(np.mean(du[inside] ** 2))})
    tets, nodes, geometry = truth_summary(finest)
    print(f"reference: {finest} ({geometry}, {tets} tetrahedra); max |u| in the prostate {umax:.3f} mm\n")
    print("| phantom | geometry | tetrahedra | max du in the prostate [mm] (% of max u) | 99th pct du [mm] | RMS du [mm] |")
    print("|---|---|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['phantom']} | {r['geometry']} | {r['tetrahedra']} | {r['max_du_prostate_mm']:.3f} "
              f"({r['max_du_prostate_pct']:.2f} %) | {r['p99_du_mm']:.3f} | {r['rms_du_mm']:.4f} |")
    if out:
        with open(out, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            writer.writeheader()
            writer.writerows(rows)


if __name__ == "__main__":
    main(sys.argv[1:])
