"""markers(), dose() and conformal_plan() against the command line on a small pelvis phantom (100 x 80 x 40 voxels
of 2 x 2 x 4 mm, a coarse truth): the same library calls, so the same numbers, compared exactly (the reports'
JSON and CSV carry 17 significant digits)."""

import json
import subprocess

import numpy as np
import pytest

import biomechreg

pytestmark = pytest.mark.cli


@pytest.fixture(scope="module")
def pelvis(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("pelvis")
    subprocess.run([cli, "phantom", "--scene", "pelvis", "--size", "100,80,40", "--spacing", "2,2,4",
                    "--truth-mesh-scale", "2", "--bladder-mm", "8", "--rectum-mm", "5", "--out", str(out)],
                   check=True, stdout=subprocess.DEVNULL)
    return out


def test_markers_equal_the_command_line(cli, pelvis, tmp_path):
    subprocess.run([cli, "markers", "--planning-ct", f"{pelvis}/moving_ct.nrrd",
                    "--planning-labels", f"{pelvis}/moving_labels.nrrd", "--scene", f"{pelvis}/scene.json",
                    "--modulus", "prostate=60", "--planning-markers", f"{pelvis}/landmarks_moving.csv",
                    "--treatment-markers", f"{pelvis}/landmarks_tracked.csv",
                    "--treatment-labels", f"{pelvis}/fixed_labels.nrrd", "--out", str(tmp_path / "cli")],
                   check=True, stdout=subprocess.DEVNULL)
    report = json.loads((tmp_path / "cli" / "report.json").read_text())
    biomechreg.configure_numerics()
    result = biomechreg.markers(biomechreg.read_image(f"{pelvis}/moving_labels.nrrd", "labels"),
                                biomechreg.read_image(f"{pelvis}/moving_ct.nrrd"),
                                biomechreg.read_scene(f"{pelvis}/scene.json"),
                                f"{pelvis}/landmarks_moving.csv",
                                biomechreg.read_landmarks(f"{pelvis}/landmarks_tracked.csv"),
                                treatment_labels=biomechreg.read_image(f"{pelvis}/fixed_labels.nrrd", "labels"),
                                moduli={"prostate": 60.0})
    assert result.report["methods"] == report["methods"]
    assert set(result.methods) >= {"fem", "rigid", "tps"}
    fem = result.methods["fem"]
    assert fem["intersection_over_union"] == report["methods"]["fem"]["intersection_over_union"]
    cli_field = biomechreg.read_image(tmp_path / "cli" / "field.nrrd", "field")
    np.testing.assert_array_equal(result.field.array.astype(cli_field.array.dtype), cli_field.array)


def test_dose_equals_the_command_line(cli, pelvis, tmp_path):
    subprocess.run([cli, "dose", "--labels", f"{pelvis}/fixed_labels.nrrd", "--scene", f"{pelvis}/scene.json",
                    "--plan-margin", "5", "--plot", "off", "--out", str(tmp_path / "cli")],
                   check=True, stdout=subprocess.DEVNULL)
    labels = biomechreg.read_image(f"{pelvis}/fixed_labels.nrrd", "labels")
    scene = biomechreg.read_scene(f"{pelvis}/scene.json")
    plan = biomechreg.conformal_plan(labels, scene, margin_mm=5)
    cli_dose = biomechreg.read_image(tmp_path / "cli" / "dose.nrrd")
    np.testing.assert_array_equal(plan.array, cli_dose.array)
    evaluation = biomechreg.dose(labels, plan, scene)
    assert evaluation["metrics_csv"] == (tmp_path / "cli" / "dose_metrics.csv").read_text()
    assert evaluation["dvh_csv"] == (tmp_path / "cli" / "dvh.csv").read_text()
    prostate = evaluation["structures"]["prostate"]
    assert 70.0 < prostate["D95_Gy"] <= 78.0  # inside a 5 mm margin the plan gives the prostate most of Rx
    assert prostate["dvh_cumulative"][0] == 1.0
