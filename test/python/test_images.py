"""Images between numpy and the library: geometry round trips, the warp's direction, no copy where none is
needed. Tolerances: geometry through NRRD is written with 17 significant digits, so round trips are exact to
1e-12; voxel values are exact (the warp of a whole-voxel shift moves values without interpolating)."""

import numpy as np
import pytest

import biomechreg


def rotation(ax, ay, az):
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def oblique_labels():
    rng = np.random.default_rng(7)
    array = rng.integers(0, 5, size=(6, 7, 9), dtype=np.int32)  # [z, y, x]: 9 x 7 x 6 voxels
    return biomechreg.Image(array, spacing=(0.9, 1.1, 2.5), origin=(-10.5, 3.25, 100.0),
                            direction=rotation(0.3, -0.2, 0.7))


def test_nrrd_round_trip_keeps_oblique_anisotropic_geometry(tmp_path):
    image = oblique_labels()
    biomechreg.write_image(image, tmp_path / "labels.nrrd")
    back = biomechreg.read_image(tmp_path / "labels.nrrd", kind="labels")
    assert back.array.dtype == np.int32
    assert back.size == (9, 7, 6)
    np.testing.assert_array_equal(back.array, image.array)
    np.testing.assert_allclose(back.spacing, image.spacing, rtol=0, atol=1e-12)
    np.testing.assert_allclose(back.origin, image.origin, rtol=0, atol=1e-12)
    np.testing.assert_allclose(back.direction, image.direction, rtol=0, atol=1e-12)


def test_zero_field_warp_is_identity_on_an_oblique_grid():
    image = oblique_labels()
    field = biomechreg.Image(np.zeros(image.shape + (3,)), image.spacing, image.origin, image.direction)
    warped = biomechreg.warp(image, field, labels=True)
    np.testing.assert_array_equal(warped.array, image.array)
    assert warped.spacing == image.spacing and warped.origin == image.origin
    np.testing.assert_array_equal(warped.direction, image.direction)


def test_warp_pulls_back_along_the_field():
    # A fixed -> moving field of +2 mm along x: the warped image at x is the moving image at x + 2 mm, i.e. two
    # voxels of 1 mm further along x. A warp in the wrong direction would shift the other way.
    moving = np.zeros((4, 5, 12), dtype=np.float32)
    moving[:, :, 7] = 100.0
    field = np.zeros((4, 5, 12, 3))
    field[..., 0] = 2.0
    warped = biomechreg.warp(biomechreg.Image(moving), biomechreg.Image(field), outside=0.0)
    assert np.argmax(warped.array[0, 0]) == 5
    assert warped.array[0, 0, 5] == 100.0


def test_inputs_of_the_right_type_are_not_copied():
    from biomechreg._images import engine_tuple
    array = np.zeros((3, 4, 5), dtype=np.int32)
    assert engine_tuple(biomechreg.Image(array), "labels", np.int32)[0] is array
    # Another integer type is converted (a copy), values kept.
    converted = engine_tuple(biomechreg.Image(array.astype(np.uint8)), "labels", np.int32)[0]
    assert converted.dtype == np.int32


def test_duck_typed_image():
    class ForeignImage:  # what itk.Image and SimpleITK.Image offer
        def __init__(self, array):
            self._array = array

        def GetSpacing(self):
            return (0.5, 0.75, 3.0)

        def GetOrigin(self):
            return (1.0, 2.0, 3.0)

        def GetDirection(self):
            return tuple(rotation(0.0, 0.0, 0.5).ravel())

        def __array__(self, dtype=None):
            return self._array

    array = np.arange(60, dtype=np.float32).reshape(3, 4, 5)
    image = biomechreg.as_image(ForeignImage(array))
    assert image.spacing == (0.5, 0.75, 3.0) and image.origin == (1.0, 2.0, 3.0)
    np.testing.assert_array_equal(image.direction, rotation(0.0, 0.0, 0.5))
    zero = biomechreg.Image(np.zeros((3, 4, 5, 3)), image.spacing, image.origin, image.direction)
    np.testing.assert_array_equal(biomechreg.warp(ForeignImage(array), zero).array, array)


def test_result_arrays_keep_their_image_alive():
    image = oblique_labels()
    field = biomechreg.Image(np.zeros(image.shape + (3,)), image.spacing, image.origin, image.direction)
    array = biomechreg.warp(image, field, labels=True).array
    import gc
    gc.collect()
    np.testing.assert_array_equal(array, image.array)


@pytest.mark.parametrize("kind", ["ct", "labels", "field"])
def test_read_image_of_a_missing_file_is_a_value_error(tmp_path, kind):
    with pytest.raises(ValueError, match="missing.nrrd"):
        biomechreg.read_image(tmp_path / "missing.nrrd", kind=kind)


def test_learn2reg_npz_of_a_known_shift_on_oblique_grids(tmp_path):
    # A field of one constant vector on an oblique, anisotropic fixed grid, the moving grid another oblique one:
    # disp is the moving continuous index of x + u less the fixed index, computed here in numpy (to float32
    # rounding of indices below 100: 1e-5 voxels).
    fixed = oblique_labels()
    u = np.array([1.5, -2.0, 3.25])
    field = biomechreg.Image(np.broadcast_to(u, fixed.array.shape + (3,)).copy(), fixed.spacing, fixed.origin,
                             fixed.direction)
    moving = biomechreg.Image(np.zeros((5, 8, 8), np.int32), spacing=(1.2, 1.0, 3.0), origin=(-12.0, 0.0, 95.0),
                              direction=rotation(0.1, 0.2, -0.4))
    biomechreg.write_field_npz(field, moving, tmp_path / "field.npz")
    npz = np.load(tmp_path / "field.npz")
    nz, ny, nx = fixed.array.shape
    assert npz["disp"].shape == (3, nx, ny, nz) and npz["disp"].dtype == np.float32
    np.testing.assert_array_equal(npz["moving_direction"], moving.direction)
    index = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"), axis=0).astype(float)
    points = np.einsum("ab,bijk->aijk", fixed.direction * np.array(fixed.spacing), index) + \
        np.array(fixed.origin)[:, None, None, None] + u[:, None, None, None]
    to_index = np.linalg.inv(moving.direction * np.array(moving.spacing))
    expected = np.einsum("ab,bijk->aijk", to_index, points - np.array(moving.origin)[:, None, None, None]) - index
    np.testing.assert_allclose(npz["disp"], expected, rtol=0, atol=1e-5)


def test_label_names_tables(tmp_path):
    (tmp_path / "names.csv").write_text("value,name\n1,External\n2, Prostate \n")
    assert biomechreg.read_label_names(tmp_path / "names.csv") == {1: "External", 2: "Prostate"}
    (tmp_path / "colors.txt").write_text("# a 3D Slicer color table\n0 Background 0 0 0 0\n1\tExternal 200 180 160 255\n")
    assert biomechreg.read_label_names(tmp_path / "colors.txt") == {0: "Background", 1: "External"}
    (tmp_path / "twice.csv").write_text("1,External\n1,Body\n")
    with pytest.raises(ValueError, match="line 2: value 1 named twice"):
        biomechreg.read_label_names(tmp_path / "twice.csv")
    (tmp_path / "bad.csv").write_text("1,External\nx,Prostate\n")
    with pytest.raises(ValueError, match="line 2: expected"):
        biomechreg.read_label_names(tmp_path / "bad.csv")
