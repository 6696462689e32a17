"""A clinical structure set with no scene file (ctest python_structure_set, slow): a pelvis phantom at
1 x 1 x 2 mm written by plastimatch as a DICOM CT series and an RTSTRUCT per scan, its ROIs named by TG-263
(Prostate, Bladder, Rectum, External) plus one the scene does not need (PTV_7800), no tissue and no bone ROI.
`biomechreg register` without --scene must map the ROIs, take the bone from the CT and state a modulus within the
label-map route's 68 % interval (the same phantom registered from its label maps and scene.json: the interval of
the thick slices' calibration at 2 mm); the bone it took from the CT must overlap the phantom's with Dice >= 0.95
(the phantom's bone is 700 HU, the threshold 250 HU: partial-volume voxels at the boundary and nothing else
differ). Three malformed structure sets (no External; no prostate on the fixed scan; the moving scan's ROIs on
the fixed CT, another frame of reference) are refused with one line naming the file, exit status 1."""

import json
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import biomechreg

pytestmark = pytest.mark.structure_set

ROIS = {"Prostate": [2], "Bladder": [3], "Rectum": [4], "External": [1, 2, 3, 4, 5], "PTV_7800": [2]}


@pytest.fixture(scope="module")
def scans(cli, tmp_path_factory):
    root = tmp_path_factory.mktemp("structure_set")
    subprocess.run([cli, "phantom", "--scene", "pelvis", "--size", "200,160,80", "--spacing", "1,1,2",
                    "--true-E-kPa", "80", "--bladder-mm", "8", "--rectum-mm", "4", "--out", str(root / "phantom")],
                   check=True, stdout=subprocess.DEVNULL)
    for scan in ("moving", "fixed"):
        write_dicom(root, scan, ROIS)
    return root


def write_dicom(root, scan, rois, name=None):
    """plastimatch's CT series and RTSTRUCT of one scan, one mask per ROI (its values in the phantom's labels)."""
    labels = biomechreg.read_image(root / "phantom" / f"{scan}_labels.nrrd", "labels")
    masks = root / f"masks_{name or scan}"
    shutil.rmtree(masks, ignore_errors=True)
    masks.mkdir()
    for roi, values in rois.items():
        mask = np.isin(labels.array, values).astype(np.int32)
        biomechreg.write_image(biomechreg.Image(mask, labels.spacing, labels.origin, labels.direction),
                               masks / f"{roi}.nrrd")
    out = root / f"dicom_{name or scan}"
    subprocess.run(["plastimatch", "convert", "--input", str(root / "phantom" / f"{scan}_ct.nrrd"),
                    "--input-prefix", str(masks), "--output-dicom", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    ct = out / "ct"
    ct.mkdir(exist_ok=True)
    for image in out.glob("image*.dcm"):
        image.rename(ct / image.name)
    return ct, next(out.glob("rtss*.dcm"))


def register(cli, out, moving, fixed, *extra):
    command = [cli, "register", "--moving-ct", str(moving[0]), "--moving-labels", str(moving[1]),
               "--fixed-ct", str(fixed[0]), "--fixed-labels", str(fixed[1]), "--out", str(out), *extra]
    return subprocess.run(command, capture_output=True, text=True)


def dicom(root, scan):
    return root / f"dicom_{scan}" / "ct", next((root / f"dicom_{scan}").glob("rtss*.dcm"))


def test_structure_sets_register_without_a_scene(cli, scans, tmp_path):
    p = scans / "phantom"
    reference = subprocess.run([cli, "register", "--moving-ct", str(p / "moving_ct.nrrd"),
                                "--moving-labels", str(p / "moving_labels.nrrd"), "--fixed-ct", str(p / "fixed_ct.nrrd"),
                                "--fixed-labels", str(p / "fixed_labels.nrrd"), "--scene", str(p / "scene.json"),
                                "--out", str(tmp_path / "labels")], capture_output=True, text=True)
    assert reference.returncode == 0, reference.stderr
    run = register(cli, tmp_path / "rois", dicom(scans, "moving"), dicom(scans, "fixed"))
    assert run.returncode == 0, run.stderr
    print(run.stdout)
    interval = json.loads((tmp_path / "labels" / "report.json").read_text())["youngs_modulus_interval"]["prostate"]
    stated = json.loads((tmp_path / "rois" / "report.json").read_text())["youngs_modulus_interval"]["prostate"]
    low, high = interval["interval_68_kPa"]
    print("label maps: %s\nstructure sets: %s" % (interval["statement"], stated["statement"]))
    assert low <= stated["estimate_kPa"] <= high

    mapping = json.loads((tmp_path / "rois" / "structure_set.json").read_text())
    for scan in ("moving", "fixed"):
        assert mapping[scan]["part_of_roi"] == {"Prostate": "prostate", "Bladder": "bladder", "Rectum": "rectum",
                                                "External": "body"}
        assert mapping[scan]["left_out"] == ["PTV_7800"] and mapping[scan]["bone_from_ct"]
        derived = biomechreg.read_image(tmp_path / "rois" / f"{scan}_labels_from_rois.nrrd", "labels").array == 5
        truth = biomechreg.read_image(p / f"{scan}_labels.nrrd", "labels").array == 5
        dice = 2.0 * np.sum(derived & truth) / (np.sum(derived) + np.sum(truth))
        print("%s bone Dice %.4f" % (scan, dice))
        assert dice >= 0.95
        # The package reads the structure set into the same label map (from the CT series' directory the CLI
        # read, so with its frame of reference).
        ct_dir, rtss = dicom(scans, scan)
        labels, from_python = biomechreg.read_structure_set(rtss, ct_dir)
        np.testing.assert_array_equal(labels.array, biomechreg.read_image(
            tmp_path / "rois" / f"{scan}_labels_from_rois.nrrd", "labels").array)
        assert from_python["part_of_roi"] == mapping[scan]["part_of_roi"]


def test_the_package_registers_structure_sets_as_the_command_line(cli, scans, tmp_path):
    # What register does without a scene, in Python: the label maps from the structure sets, the fixed organs'
    # outlines as their surfaces, the built-in scene; the same modulus and field as the command line, bit for bit.
    run = register(cli, tmp_path / "cli", dicom(scans, "moving"), dicom(scans, "fixed"), "--uncertainty", "none",
                   "--field-precision", "double")
    assert run.returncode == 0, run.stderr
    biomechreg.configure_numerics()
    (moving_ct, moving_rtss), (fixed_ct, fixed_rtss) = dicom(scans, "moving"), dicom(scans, "fixed")
    moving, _ = biomechreg.read_structure_set(moving_rtss, moving_ct)
    fixed, mapping = biomechreg.read_structure_set(fixed_rtss, fixed_ct)
    roi = {part: name for name, part in mapping["part_of_roi"].items()}
    outlines = biomechreg.read_outline_fractions(fixed_rtss, fixed_ct, [roi[o] for o in ("prostate", "bladder", "rectum")])
    result = biomechreg.register(moving, fixed, biomechreg.builtin_pelvis_scene(),
                                 fixed_probabilities={o: outlines[roi[o]] for o in ("prostate", "bladder", "rectum")},
                                 uncertainty="none")
    report = json.loads((tmp_path / "cli" / "report.json").read_text())
    assert result.youngs_modulus["prostate"] == report["youngs_modulus_kPa"]["prostate"]
    np.testing.assert_array_equal(result.field.array,
                                  biomechreg.read_image(tmp_path / "cli" / "field.nrrd", "field").array)


def one_line_error(run, name):
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 1 and len(lines) == 1 and name in lines[0], run.stderr
    out = pathlib.Path(run.args[run.args.index("--out") + 1])
    assert not out.exists(), "a refused run left %s behind" % out
    return lines[0]


def test_malformed_structure_sets_are_refused_in_one_line(cli, scans, tmp_path):
    no_body = {k: v for k, v in ROIS.items() if k != "External"}
    moving_without_body = write_dicom(scans, "moving", no_body, name="moving_no_body")
    print(one_line_error(register(cli, tmp_path / "a", moving_without_body, dicom(scans, "fixed")),
                         str(moving_without_body[1])))
    no_prostate = {k: v for k, v in ROIS.items() if k != "Prostate"}
    fixed_without_prostate = write_dicom(scans, "fixed", no_prostate, name="fixed_no_prostate")
    print(one_line_error(register(cli, tmp_path / "b", dicom(scans, "moving"), fixed_without_prostate),
                         "prostate"))
    moving_ct, moving_rtss = dicom(scans, "moving")
    fixed_ct, _ = dicom(scans, "fixed")
    print(one_line_error(register(cli, tmp_path / "c", dicom(scans, "moving"), (fixed_ct, moving_rtss)),
                         "frame of reference"))
    with pytest.raises(ValueError, match="needs one ROI for the body"):
        biomechreg.read_structure_set(moving_without_body[1], biomechreg.read_image(moving_without_body[0]))
    with pytest.raises(ValueError, match="another frame of reference"):
        biomechreg.read_structure_set(moving_rtss, fixed_ct)
