"""The package against the command line: the same registration, the same bits. On a spheres phantom of 64^3 voxels
of 1 mm (voxels at which register states the rescans' interval, and a fit inside the search bounds):
`biomechreg register` with the interval, then register() on the images it read; the modulus, the interval and every
voxel of the field (written as doubles) must be equal, not close: both run the same library code on the same inputs
with the BLAS on one thread (configure_numerics(), as the CLI)."""

import json
import subprocess
import time

import numpy as np
import pytest

import biomechreg

pytestmark = pytest.mark.cli


@pytest.fixture(scope="module")
def spheres_dir(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("spheres")
    subprocess.run([cli, "phantom", "--scene", "spheres", "--size", "64,64,64", "--spacing", "1,1,1",
                    "--true-E-kPa", "60", "--out", str(out)], check=True, stdout=subprocess.DEVNULL)
    return out


def run_cli(cli, spheres_dir, out):
    command = [cli, "register", "--moving-ct", f"{spheres_dir}/moving_ct.nrrd",
               "--moving-labels", f"{spheres_dir}/moving_labels.nrrd", "--fixed-ct", f"{spheres_dir}/fixed_ct.nrrd",
               "--fixed-labels", f"{spheres_dir}/fixed_labels.nrrd", "--scene", f"{spheres_dir}/scene.json",
               "--resamples", "3", "--field-precision", "double", "--out", str(out)]
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def test_register_equals_the_command_line(cli, spheres_dir, tmp_path):
    cli_seconds = run_cli(cli, spheres_dir, tmp_path / "cli")
    report = json.loads((tmp_path / "cli" / "report.json").read_text())

    biomechreg.configure_numerics()
    start = time.perf_counter()
    result = biomechreg.register(biomechreg.read_image(f"{spheres_dir}/moving_labels.nrrd", "labels"),
                                 biomechreg.read_image(f"{spheres_dir}/fixed_labels.nrrd", "labels"),
                                 biomechreg.read_scene(f"{spheres_dir}/scene.json"),
                                 moving_ct=biomechreg.read_image(f"{spheres_dir}/moving_ct.nrrd"), resamples=3)
    python_seconds = time.perf_counter() - start
    print("\nregister on the spheres phantom: CLI %.2f s (process, reading and writing included), Python %.2f s"
          % (cli_seconds, python_seconds))

    (name, modulus), = result.youngs_modulus.items()
    assert modulus == report["youngs_modulus_kPa"][name]
    interval = report["youngs_modulus_interval"][name]
    assert interval["lower_end_determined"] and interval["upper_end_determined"]  # an interval is stated
    assert result.intervals[name]["interval95"] == interval["interval_95_kPa"]
    assert result.report["youngs_modulus_kPa"] == report["youngs_modulus_kPa"]
    assert result.report["youngs_modulus_interval"] == report["youngs_modulus_interval"]
    cli_field = biomechreg.read_image(tmp_path / "cli" / "field.nrrd", "field")
    assert cli_field.array.dtype == np.float64
    np.testing.assert_array_equal(result.field.array, cli_field.array)
    assert result.field.origin == cli_field.origin and result.field.spacing == cli_field.spacing
    cli_warped = biomechreg.read_image(tmp_path / "cli" / "warped_labels.nrrd", "labels")
    np.testing.assert_array_equal(result.warped_labels.array, cli_warped.array)


def test_written_outputs_match_the_command_line(cli, spheres_dir, tmp_path):
    run_cli(cli, spheres_dir, tmp_path / "cli")
    biomechreg.configure_numerics()
    result = biomechreg.register(biomechreg.read_image(f"{spheres_dir}/moving_labels.nrrd", "labels"),
                                 biomechreg.read_image(f"{spheres_dir}/fixed_labels.nrrd", "labels"),
                                 biomechreg.read_scene(f"{spheres_dir}/scene.json"),
                                 moving_ct=biomechreg.read_image(f"{spheres_dir}/moving_ct.nrrd"), resamples=3)
    result.write(tmp_path / "py", outputs="field,warped_labels,report")
    for name in ["field.nrrd", "warped_labels.nrrd"]:
        a = biomechreg.read_image(tmp_path / "py" / name, "field" if name == "field.nrrd" else "labels")
        b = biomechreg.read_image(tmp_path / "cli" / name, "field" if name == "field.nrrd" else "labels")
        np.testing.assert_array_equal(a.array.astype(np.float32), b.array.astype(np.float32))
