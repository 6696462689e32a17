#!/usr/bin/env python3
"""The demo pair from Python: a pelvis phantom with a known prostate modulus, registered with the stated
interval, and a picture of the result (register_demo.png): the fixed CT with the fixed and the warped prostate,
and the displacement's magnitude.

    PYTHONPATH=build/python python3 examples/python/register_demo.py [OUT_DIR]

(after `cmake --install build`, without PYTHONPATH). About 40 s on 2 cores; the same numbers as
`biomechreg phantom --scene pelvis --size 200,160,160 --spacing 1,1,1 --bladder-mm 8 --rectum-mm 4
--true-E-kPa 100` followed by `biomechreg register` on its files."""

import sys
import time
from pathlib import Path

import numpy as np

import biomechreg


def progress(event):
    if event["event"] == "stage_end":
        print("  %-28s %6.2f s  %s" % (event["stage"], event["seconds"], event["detail"]), flush=True)
    elif event["event"] == "warning":
        print("  warning: " + event["message"], flush=True)


def main(out_dir):
    biomechreg.configure_numerics()  # this script owns its process: the BLAS on one thread, as biomechreg does
    start = time.perf_counter()
    pair = biomechreg.make_phantom("pelvis", size=(200, 160, 160), spacing=(1, 1, 1), bladder_mm=8, rectum_mm=4,
                                   true_E_kPa=100, callback=progress)
    print("phantom: %.1f s, true prostate modulus %.0f kPa" % (time.perf_counter() - start,
                                                               pair.truth["youngs_modulus_kPa"]["prostate"]))
    start = time.perf_counter()
    result = biomechreg.register(pair.moving_labels, pair.fixed_labels, pair.scene, moving_ct=pair.moving_ct,
                                 callback=progress)
    print("register: %.1f s" % (time.perf_counter() - start))
    print(result.modulus_text["prostate"])
    out_dir.mkdir(parents=True, exist_ok=True)
    result.write(out_dir / "register")
    plot(pair, result, out_dir / "register_demo.png")


def plot(pair, result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prostate = pair.scene.labels["prostate"]
    fixed = pair.fixed_labels.array
    k = int(np.argmax((fixed == prostate).sum(axis=(1, 2))))  # the axial slice with the most prostate
    magnitude = np.linalg.norm(result.field.array[k], axis=-1)
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 5))
    left.imshow(pair.fixed_ct.array[k], cmap="gray", vmin=-200, vmax=200)
    left.contour(fixed[k] == prostate, levels=[0.5], colors="lime")
    left.contour(result.warped_labels.array[k] == prostate, levels=[0.5], colors="red", linestyles="dashed")
    left.set_title("fixed CT, prostate: fixed (green), warped moving (red)")
    shown = right.imshow(magnitude, cmap="viridis")
    figure.colorbar(shown, ax=right, label="|u| [mm]")
    right.set_title("displacement fixed -> moving, slice %d" % k)
    for axes in (left, right):
        axes.axis("off")
    figure.suptitle(result.modulus_text["prostate"], fontsize=9)
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    print("wrote " + str(path))


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "biomechreg-python-demo"))
