"""Seed target registration error of a pull-back displacement field (register's field.nrrd: fixed -> moving, mm,
LPS): each fixed landmark x_f is mapped to x_f + u(x_f), u interpolated trilinearly, and compared with its moving
landmark. Prints the mean and the largest TRE [mm] over the landmarks paired by id, comma-separated.
Reads the NRRD files `register` writes (a 3-vector per voxel, float or double, raw or gzip, axis-aligned or not).
Usage: field_tre.py FIELD.nrrd LANDMARKS_FIXED.csv LANDMARKS_MOVING.csv"""
import csv
import gzip
import re
import sys

import numpy as np
from scipy.ndimage import map_coordinates


def read_nrrd(path):
    """An axis-aligned or oblique NRRD image as an array ([components,] x, y, z) with its origin and
    direction-times-spacing matrix (columns = axes); a vector image's first axis is its components."""
    raw = open(path, "rb").read()
    end = raw.index(b"\n\n")
    header = dict(line.split(": ", 1) for line in raw[:end].decode().splitlines()[1:] if ": " in line)
    sizes = [int(s) for s in header["sizes"].split()]
    dtype = {"float": "<f4", "double": "<f8", "int": "<i4", "short": "<i2", "unsigned char": "u1",
             "uchar": "u1", "unsigned short": "<u2"}[header["type"]]
    if header.get("endian", "little") == "big":
        dtype = dtype.replace("<", ">")
    data = raw[end + 2:]
    if header["encoding"] == "gzip":
        data = gzip.decompress(data)
    elif header["encoding"] != "raw":
        raise SystemExit(f"{path}: encoding {header['encoding']} is not read here")
    values = np.frombuffer(data, dtype=dtype).reshape(sizes[::-1]).transpose()
    axes = [[float(v) for v in re.findall(r"[-+0-9.eE]+", d)] for d in re.findall(r"\(([^)]*)\)",
                                                                                 header["space directions"])]
    origin = np.array([float(v) for v in re.findall(r"[-+0-9.eE]+", header["space origin"])])
    return values, origin, np.array(axes).T


def read_landmarks(path):
    rows = [r for r in csv.reader(line for line in open(path) if not line.startswith("#"))]
    return {r[0]: np.array([float(v) for v in r[1:4]]) for r in rows[1:]}


def main():
    field, origin, matrix = read_nrrd(sys.argv[1])  # [3, x, y, z]
    fixed, moving = read_landmarks(sys.argv[2]), read_landmarks(sys.argv[3])
    errors = []
    for name, x in fixed.items():
        index = np.linalg.solve(matrix, x - origin)
        u = [map_coordinates(field[c], index.reshape(3, 1), order=1, mode="nearest")[0] for c in range(3)]
        errors.append(float(np.linalg.norm(x + np.array(u) - moving[name])))
    print(f"{np.mean(errors):.4f},{np.max(errors):.4f}")


if __name__ == "__main__":
    main()
