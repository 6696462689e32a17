"""A clinical structure set with no scene file (ctest python_structure_set, slow): a pelvis phantom at
1 x 1 x 2 mm written by plastimatch as a DICOM CT series and an RTSTRUCT per scan, its ROIs named by TG-263
(Prostate, Bladder, Rectum, External) plus one the scene does not need (PTV_7800), no tissue and no bone ROI.
`biomechreg register` without --scene must map the ROIs, take the bone from the CT and state a modulus within the
label-map route's 68 % interval (the same phantom registered from its label maps and scene.json: the interval of
the thick slices' calibration at 2 mm); the bone it took from the CT must overlap the phantom's with Dice >= 0.95
(the phantom's bone is 700 HU, the threshold 250 HU: partial-volume voxels at the boundary and nothing else
differ). Three malformed structure sets (no External; no prostate on the fixed scan; the moving scan's ROIs on
the fixed CT, another frame of reference) are refused with one line naming the file, exit status 1. The same scans
as label maps named by a names table and by a Slicer segmentation's header (no bone label) give the structure
sets' label maps and a modulus in the same interval; a value without a name is refused in one line.

The field's interchange files are read back by readers that are not ours: the DICOM Deformable Spatial
Registration (`rt-export --registration-out`) by pydicom and dicom3tools' IOD checker, the Learn2Reg .npz
(`--outputs field_npz`) by numpy; both must hold the registration's field (float32 rounding only) on its grid and
in its frames of reference, and `warp` through the DICOM object must give the warp through field.nrrd."""

import json
import os
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


@pytest.fixture(scope="module")
def label_reference(cli, scans):
    """The phantom registered from its own label maps and scene.json: the label-map route's stated interval."""
    p, out = scans / "phantom", scans / "label_reference"
    run = subprocess.run([cli, "register", "--moving-ct", str(p / "moving_ct.nrrd"),
                          "--moving-labels", str(p / "moving_labels.nrrd"), "--fixed-ct", str(p / "fixed_ct.nrrd"),
                          "--fixed-labels", str(p / "fixed_labels.nrrd"), "--scene", str(p / "scene.json"),
                          "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return json.loads((out / "report.json").read_text())["youngs_modulus_interval"]["prostate"]


def test_structure_sets_register_without_a_scene(cli, scans, label_reference, tmp_path):
    p = scans / "phantom"
    run = register(cli, tmp_path / "rois", dicom(scans, "moving"), dicom(scans, "fixed"))
    assert run.returncode == 0, run.stderr
    print(run.stdout)
    interval = label_reference
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


@pytest.fixture(scope="module")
def cli_registration(cli, scans):
    """register on the structure sets without a scene: the field in double precision and as Learn2Reg's .npz."""
    out = scans / "cli_registration"
    run = register(cli, out, dicom(scans, "moving"), dicom(scans, "fixed"), "--uncertainty", "none",
                   "--field-precision", "double", "--outputs", "default,field_npz")
    assert run.returncode == 0, run.stderr
    return out


def test_the_package_registers_structure_sets_as_the_command_line(cli_registration, scans):
    # What register does without a scene, in Python: the label maps from the structure sets, the fixed organs'
    # outlines as their surfaces, the built-in scene; the same modulus and field as the command line, bit for bit.
    biomechreg.configure_numerics()
    (moving_ct, moving_rtss), (fixed_ct, fixed_rtss) = dicom(scans, "moving"), dicom(scans, "fixed")
    moving, _ = biomechreg.read_structure_set(moving_rtss, moving_ct)
    fixed, mapping = biomechreg.read_structure_set(fixed_rtss, fixed_ct)
    roi = {part: name for name, part in mapping["part_of_roi"].items()}
    outlines = biomechreg.read_outline_fractions(fixed_rtss, fixed_ct, [roi[o] for o in ("prostate", "bladder", "rectum")])
    result = biomechreg.register(moving, fixed, biomechreg.builtin_pelvis_scene(),
                                 fixed_probabilities={o: outlines[roi[o]] for o in ("prostate", "bladder", "rectum")},
                                 uncertainty="none")
    report = json.loads((cli_registration / "report.json").read_text())
    assert result.youngs_modulus["prostate"] == report["youngs_modulus_kPa"]["prostate"]
    np.testing.assert_array_equal(result.field.array,
                                  biomechreg.read_image(cli_registration / "field.nrrd", "field").array)


NAMES = "value,name\n1,External\n2,Prostate\n3,Bladder\n4,Rectum\n"


def named_label_map(scans, scan, out):
    """The phantom's label map as a clinic's: no bone label (bone voxels given to the body), values named by TG-263."""
    labels = biomechreg.read_image(scans / "phantom" / f"{scan}_labels.nrrd", "labels")
    array = labels.array.copy()
    array[array == 5] = 1
    path = out / f"{scan}_labels.nrrd"
    biomechreg.write_image(biomechreg.Image(array, labels.spacing, labels.origin, labels.direction), path)
    return path


def as_slicer_segmentation(path):
    """The label map with the names in its header as 3D Slicer writes a .seg.nrrd (Segment<i>_Name, _LabelValue,
    _Layer key-value lines); the header is text up to its first blank line."""
    data = path.read_bytes()
    end = data.index(b"\n\n")
    keys = "".join("Segment%d_Name:=%s\nSegment%d_LabelValue:=%d\nSegment%d_Layer:=0\n" % (i, name, i, value, i)
                   for i, (value, name) in enumerate([(1, "External"), (2, "Prostate"), (3, "Bladder"), (4, "Rectum")]))
    segmentation = path.with_name(path.name.replace(".nrrd", ".seg.nrrd"))
    segmentation.write_bytes(data[:end + 1] + keys.encode() + data[end + 1:])
    return segmentation


def test_named_label_maps_register_without_a_scene(cli, scans, label_reference, cli_registration, tmp_path):
    # A label map with a names table (moving) and a Slicer segmentation that names its segments (fixed), no bone
    # label: the built-in scene's label maps equal those from the structure sets of the same scans (the organs'
    # voxels and the body from the names, the bone from the CT), and the modulus lies in the label-map route's
    # 68 % interval, as the structure sets' does.
    p = scans / "phantom"
    (tmp_path / "names.csv").write_text(NAMES)
    moving = named_label_map(scans, "moving", tmp_path)
    fixed = as_slicer_segmentation(named_label_map(scans, "fixed", tmp_path))
    command = [cli, "register", "--moving-ct", str(p / "moving_ct.nrrd"), "--moving-labels", str(moving),
               "--moving-label-names", str(tmp_path / "names.csv"), "--fixed-ct", str(p / "fixed_ct.nrrd"),
               "--fixed-labels", str(fixed), "--out", str(tmp_path / "named")]
    run = subprocess.run(command, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    mapping = json.loads((tmp_path / "named" / "structure_set.json").read_text())
    for scan in ("moving", "fixed"):
        assert mapping[scan]["part_of_roi"] == {"Prostate": "prostate", "Bladder": "bladder", "Rectum": "rectum",
                                                "External": "body"} and mapping[scan]["bone_from_ct"]
        from_names = biomechreg.read_image(tmp_path / "named" / f"{scan}_labels_from_rois.nrrd", "labels").array
        from_rois = biomechreg.read_image(cli_registration / f"{scan}_labels_from_rois.nrrd", "labels").array
        print("%s: %.6f of the voxels as from the structure set" % (scan, np.mean(from_names == from_rois)))
        assert np.mean(from_names == from_rois) > 0.999
        # The package reads the segmentation's names and makes the same label map.
        source = fixed if scan == "fixed" else moving
        names = biomechreg.read_label_names(fixed if scan == "fixed" else tmp_path / "names.csv")
        assert names == {1: "External", 2: "Prostate", 3: "Bladder", 4: "Rectum"}
        labels, _ = biomechreg.read_named_label_map(biomechreg.read_image(source, "labels"), names,
                                                    biomechreg.read_image(p / f"{scan}_ct.nrrd"))
        np.testing.assert_array_equal(labels.array, from_names)
    assert biomechreg.read_label_names(moving) == {}  # a plain label map names nothing
    report = json.loads((tmp_path / "named" / "report.json").read_text())
    for scan in ("moving", "fixed"):  # label_volume_ml: the voxels of each label times the voxel's volume
        image = biomechreg.read_image(tmp_path / "named" / f"{scan}_labels_from_rois.nrrd", "labels")
        for organ, value in (("prostate", 2), ("bladder", 3), ("rectum", 4)):
            expected = np.sum(image.array == value) * np.prod(image.spacing) / 1000.0
            assert report["label_volume_ml"][organ][scan] == pytest.approx(expected, rel=1e-12)
    stated = report["youngs_modulus_interval"]["prostate"]
    print("named label maps: %s" % stated["statement"])
    low, high = label_reference["interval_68_kPa"]
    assert low <= stated["estimate_kPa"] <= high

    (tmp_path / "short.csv").write_text(NAMES.replace("4,Rectum", "9,Rectum"))
    unnamed = command[:]
    unnamed[unnamed.index("--moving-label-names") + 1] = str(tmp_path / "short.csv")
    unnamed[unnamed.index("--out") + 1] = str(tmp_path / "unnamed")
    print(one_line_error(subprocess.run(unnamed, capture_output=True, text=True), "label value 4 has no name"))


def frame_of_reference(series):
    import pydicom
    return pydicom.dcmread(next(pathlib.Path(series).glob("*.dcm")), stop_before_pixels=True).FrameOfReferenceUID


def rt_export_registration(cli, field, fixed_ct, moving_ct, path, epoch="1700000000"):
    env = dict(os.environ, SOURCE_DATE_EPOCH=epoch)
    run = subprocess.run([cli, "rt-export", "--reference-ct", str(fixed_ct), "--field", str(field), "--moving-ct",
                          str(moving_ct), "--registration-out", str(path)], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr


def test_the_field_as_a_dicom_registration(cli, scans, cli_registration, tmp_path):
    import pydicom
    (moving_ct, _), (fixed_ct, _) = dicom(scans, "moving"), dicom(scans, "fixed")
    field = biomechreg.read_image(cli_registration / "field.nrrd", "field")
    rt_export_registration(cli, cli_registration / "field.nrrd", fixed_ct, moving_ct, tmp_path / "reg.dcm")

    checker = subprocess.run(["dciodvfy", str(tmp_path / "reg.dcm")], capture_output=True, text=True)
    report = checker.stdout + checker.stderr
    assert "DeformableSpatialRegistration" in report and "Error" not in report, report

    ds = pydicom.dcmread(tmp_path / "reg.dcm")
    assert ds.SOPClassUID == "1.2.840.10008.5.1.4.1.1.66.3" and ds.Modality == "REG"
    assert ds.FrameOfReferenceUID == frame_of_reference(fixed_ct)  # the registered frame: the fixed scan's
    registration = ds.DeformableRegistrationSequence[0]
    assert registration.SourceFrameOfReferenceUID == frame_of_reference(moving_ct)
    for matrix in (registration.PreDeformationMatrixRegistrationSequence[0],
                   registration.PostDeformationMatrixRegistrationSequence[0]):
        np.testing.assert_array_equal(np.array(matrix.FrameOfReferenceTransformationMatrix, float), np.eye(4).ravel())
    grid = registration.DeformableRegistrationGridSequence[0]
    nz, ny, nx, _ = field.array.shape
    assert list(grid.GridDimensions) == [nx, ny, nz]
    np.testing.assert_array_equal(grid.GridResolution, field.spacing)
    # Decimal strings of at most 16 characters: positions to 1e-9 mm here, direction cosines to 1e-12.
    np.testing.assert_allclose(np.array(grid.ImagePositionPatient, float), field.origin, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(grid.ImageOrientationPatient, float),
                               np.concatenate([field.direction[:, 0], field.direction[:, 1]]), rtol=0, atol=1e-12)
    vectors = np.frombuffer(grid.VectorGridData, "<f4").reshape(nz, ny, nx, 3)
    np.testing.assert_array_equal(vectors, field.array.astype(np.float32))

    # Our reader gives the same field back, and warp takes the object in place of field.nrrd.
    back, frames = biomechreg.read_dicom_registration(tmp_path / "reg.dcm")
    np.testing.assert_array_equal(back.array, vectors.astype(np.float64))
    assert frames == {"registered_frame_of_reference_uid": ds.FrameOfReferenceUID,
                      "source_frame_of_reference_uid": registration.SourceFrameOfReferenceUID}
    moving_labels = scans / "cli_registration" / "moving_labels_from_rois.nrrd"
    for name, path in (("nrrd", cli_registration / "field.nrrd"), ("dicom", tmp_path / "reg.dcm")):
        run = subprocess.run([cli, "warp", "--image", str(moving_labels), "--field", str(path), "--labels", "on",
                              "--out", str(tmp_path / name)], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
    through_nrrd = biomechreg.read_image(tmp_path / "nrrd" / "warped.nrrd", "labels").array
    through_dicom = biomechreg.read_image(tmp_path / "dicom" / "warped.nrrd", "labels").array
    # float32 vectors move a sample point by at most ~1e-6 mm: a nearest-neighbour choice can flip only at a tie.
    print("warp through the DICOM object: %.2e of the voxels differ from through field.nrrd" %
          np.mean(through_nrrd != through_dicom))
    assert np.mean(through_nrrd != through_dicom) < 1e-4

    # Deterministic: the same field and series at the same SOURCE_DATE_EPOCH give the same bytes.
    rt_export_registration(cli, cli_registration / "field.nrrd", fixed_ct, moving_ct, tmp_path / "again.dcm")
    assert (tmp_path / "reg.dcm").read_bytes() == (tmp_path / "again.dcm").read_bytes()


def test_a_flipped_oblique_field_round_trips_through_dicom(scans, tmp_path):
    # A left-handed grid (the third axis against the row x column normal) turned 20 degrees about z, anisotropic:
    # written slice-reversed so that DICOM's k runs along the normal, read back as the same vectors at the same
    # points (float32 rounding).
    (moving_ct, _), (fixed_ct, _) = dicom(scans, "moving"), dicom(scans, "fixed")
    a = np.radians(20.0)
    direction = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, -1.0]])
    values = np.random.default_rng(7).normal(0.0, 3.0, (5, 6, 7, 3))
    field = biomechreg.Image(values, spacing=(0.9, 1.1, 2.5), origin=(-40.0, 12.5, 30.0), direction=direction)
    biomechreg.write_dicom_registration(field, fixed_ct, moving_ct, tmp_path / "flipped.dcm")
    back, _ = biomechreg.read_dicom_registration(tmp_path / "flipped.dcm")
    np.testing.assert_array_equal(back.array, values[::-1].astype(np.float32).astype(np.float64))
    np.testing.assert_allclose(back.direction, direction * [1, 1, -1], rtol=0, atol=1e-12)
    last_slice = np.array(field.origin) + direction @ (np.array(field.spacing) * [0, 0, 4])
    np.testing.assert_allclose(back.origin, last_slice, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.spacing, field.spacing, rtol=1e-15)

    sheared = biomechreg.Image(values, spacing=(1, 1, 1), direction=[[1, 0, 0.3], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="oblique stack"):
        biomechreg.write_dicom_registration(sheared, fixed_ct, moving_ct, tmp_path / "sheared.dcm")
    with pytest.raises(ValueError, match="series"):
        biomechreg.write_dicom_registration(field, tmp_path, moving_ct, tmp_path / "nowhere.dcm")
    assert not list(tmp_path.glob("*sheared*")) and not list(tmp_path.glob("*nowhere*"))
    with pytest.raises(ValueError, match="not a Deformable Spatial Registration"):
        biomechreg.read_dicom_registration(next(pathlib.Path(fixed_ct).glob("*.dcm")))
    # Objects another tool could have written wrong, edited with pydicom: a NaN vector, a skewed orientation, a
    # pre-deformation matrix that is not the identity.
    import pydicom
    for name, edit, message in (
            ("nan", lambda grid, item: setattr(grid, "VectorGridData",
                                               np.full(5 * 6 * 7 * 3, np.nan, "<f4").tobytes()), "not finite"),
            ("skewed", lambda grid, item: setattr(grid, "ImageOrientationPatient", [1, 0, 0, 0.5, 1, 0]),
             "orthogonal unit"),
            ("matrix", lambda grid, item: setattr(item.PreDeformationMatrixRegistrationSequence[0],
                                                  "FrameOfReferenceTransformationMatrix",
                                                  [1, 0, 0, 5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]), "identity")):
        ds = pydicom.dcmread(tmp_path / "flipped.dcm")
        item = ds.DeformableRegistrationSequence[0]
        edit(item.DeformableRegistrationGridSequence[0], item)
        ds.save_as(tmp_path / f"{name}.dcm")
        with pytest.raises(ValueError, match=message):
            biomechreg.read_dicom_registration(tmp_path / f"{name}.dcm")


def test_the_field_as_learn2reg_npz(scans, cli_registration):
    # disp[:, i, j, k] is the moving continuous index of fixed voxel (i, j, k) less (i, j, k): recomputed here from
    # the field [mm] and both grids, to float32 rounding of indices up to ~200 (2e-5 voxels); and the moving labels
    # sampled there (nearest, ITK's rounding half up) give register's warped labels.
    field = biomechreg.read_image(cli_registration / "field.nrrd", "field")
    moving = biomechreg.read_image(scans / "cli_registration" / "moving_labels_from_rois.nrrd", "labels")
    npz = np.load(cli_registration / "field.npz")
    nz, ny, nx, _ = field.array.shape
    assert npz["disp"].shape == (3, nx, ny, nz) and npz["disp"].dtype == np.float32
    for prefix, image in (("fixed", field), ("moving", moving)):
        np.testing.assert_array_equal(npz[prefix + "_origin"], image.origin)
        np.testing.assert_array_equal(npz[prefix + "_spacing"], image.spacing)
        np.testing.assert_array_equal(npz[prefix + "_direction"], image.direction)
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    fixed_index = np.stack([i, j, k], axis=-1).astype(float)  # [z, y, x, (i, j, k)]
    to_point = field.direction * np.array(field.spacing)
    points = field.origin + fixed_index @ to_point.T + field.array
    moving_index = (points - moving.origin) @ np.linalg.inv(moving.direction * np.array(moving.spacing)).T
    disp = np.transpose(npz["disp"], (3, 2, 1, 0))  # -> [z, y, x, component]
    np.testing.assert_allclose(disp, moving_index - fixed_index, rtol=0, atol=1e-4)

    nearest = np.floor(fixed_index + disp + 0.5).astype(int)
    inside = np.all((nearest >= 0) & (nearest < np.array(moving.array.shape[::-1])), axis=-1)
    sampled = np.zeros(inside.shape, np.int32)
    sampled[inside] = moving.array[nearest[inside][:, 2], nearest[inside][:, 1], nearest[inside][:, 0]]
    warped = biomechreg.read_image(cli_registration / "warped_labels.nrrd", "labels").array
    print("the .npz's nearest samples give the warped labels in %.6f of the voxels" % np.mean(sampled == warped))
    assert np.mean(sampled == warped) > 0.9999


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
