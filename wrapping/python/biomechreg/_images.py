"""Images of the package: a numpy array indexed [z, y, x] with its geometry, and the conversions from and to
the image types of ITK-Python and SimpleITK (taken duck-typed: neither is imported unless the caller uses it)."""

import sys

import numpy as np

__all__ = ["Image", "as_image"]


class Image:
    """A 3-D image: ``array`` indexed [z, y, x] (a displacement field: [z, y, x, 3], vectors in x, y, z order),
    ``spacing`` and ``origin`` in x, y, z order [mm], ``direction`` the 3 x 3 direction cosines (columns: the
    index axes x, y, z in LPS), as ITK stores them. Arrays returned by the package view the library's buffers
    (no copy)."""

    def __init__(self, array, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0), direction=None):
        self.array = np.asarray(array)
        self.spacing = tuple(float(s) for s in spacing)
        self.origin = tuple(float(o) for o in origin)
        d = np.eye(3) if direction is None else np.asarray(direction, dtype=float)
        self.direction = d.reshape(3, 3)

    @property
    def shape(self):
        """The array's shape, [z, y, x] (and 3 for a field)."""
        return self.array.shape

    @property
    def size(self):
        """Voxels along x, y, z (ITK's order)."""
        return tuple(int(n) for n in self.array.shape[2::-1])

    def __array__(self, dtype=None):
        return self.array if dtype is None else self.array.astype(dtype)

    def __repr__(self):
        return "<biomechreg.Image %s %s, spacing %s mm>" % (
            "x".join(str(n) for n in self.size), self.array.dtype, self.spacing)

    def transform_index_to_physical_point(self, index):
        """The LPS point [mm] of a continuous index (x, y, z)."""
        return np.asarray(self.origin) + self.direction @ (np.asarray(self.spacing) * np.asarray(index, float))

    def to_itk(self):
        """An itk.Image (needs the package itk), sharing no memory with this one."""
        import itk
        image = itk.image_from_array(np.ascontiguousarray(self.array), is_vector=self.array.ndim == 4)
        image.SetSpacing(self.spacing)
        image.SetOrigin(self.origin)
        image.SetDirection(itk.matrix_from_array(np.ascontiguousarray(self.direction)))
        return image

    def to_sitk(self):
        """A SimpleITK.Image (needs the package SimpleITK), sharing no memory with this one."""
        import SimpleITK as sitk
        image = sitk.GetImageFromArray(np.ascontiguousarray(self.array), isVector=self.array.ndim == 4)
        image.SetSpacing(self.spacing)
        image.SetOrigin(self.origin)
        image.SetDirection(tuple(self.direction.ravel()))
        return image


def _array_of(image):
    """The voxels of an ITK-Python or SimpleITK image (or any image with an array interface), [z, y, x]."""
    module = type(image).__module__.split(".")[0]
    if module == "SimpleITK":
        return sys.modules["SimpleITK"].GetArrayViewFromImage(image)
    if module == "itk":
        return sys.modules["itk"].array_view_from_image(image)
    return np.asarray(image)


def as_image(image, what="image", spacing=None, origin=None, direction=None):
    """``image`` as an Image: an Image, a numpy array [z, y, x] (geometry from the keywords, else 1 mm, the
    origin at 0 and no rotation), or any object with GetSpacing, GetOrigin, GetDirection and an array view
    (itk.Image, SimpleITK.Image). Raises TypeError for anything else."""
    if isinstance(image, Image):
        return image
    if hasattr(image, "GetSpacing") and hasattr(image, "GetOrigin") and hasattr(image, "GetDirection"):
        direction = np.asarray(image.GetDirection(), dtype=float).reshape(3, 3)
        return Image(_array_of(image), image.GetSpacing(), image.GetOrigin(), direction)
    if isinstance(image, np.ndarray):
        return Image(image, spacing or (1.0, 1.0, 1.0), origin or (0.0, 0.0, 0.0), direction)
    raise TypeError("%s: expected a biomechreg.Image, a numpy array or an image with GetSpacing/GetOrigin/"
                    "GetDirection (itk, SimpleITK), got %s" % (what, type(image).__name__))


def engine_tuple(image, what, dtype, components=1):
    """``image`` as the engine takes it: (C-contiguous array of ``dtype``, spacing, origin, direction as nine
    row-major numbers). Copies only when the array's type or layout differ. ValueError for a wrong dimension or
    non-finite voxels, TypeError for a type that cannot hold ``dtype``'s values."""
    image = as_image(image, what)
    array = image.array
    dims = 3 if components == 1 else 4
    if array.ndim != dims or (components > 1 and array.shape[-1] != components):
        raise ValueError("%s: expected a %d-D array%s, got shape %s" % (
            what, dims, " with a last axis of %d" % components if components > 1 else "", array.shape))
    if np.issubdtype(dtype, np.integer):
        if not np.issubdtype(array.dtype, np.integer) and array.dtype != np.bool_:
            raise TypeError("%s: a label map needs an integer array, got %s" % (what, array.dtype))
        if array.size and array.dtype != dtype and (array.min() < np.iinfo(dtype).min or
                                                    array.max() > np.iinfo(dtype).max):
            raise ValueError("%s: labels outside the range of %s" % (what, np.dtype(dtype).name))
    else:
        if not (np.issubdtype(array.dtype, np.number) or array.dtype == np.bool_) or \
                np.issubdtype(array.dtype, np.complexfloating):
            raise TypeError("%s: expected a real-valued array, got %s" % (what, array.dtype))
        if not np.all(np.isfinite(array)):
            raise ValueError("%s: contains NaN or infinite values" % what)
    array = np.ascontiguousarray(array, dtype=dtype)
    return (array, image.spacing, image.origin, [float(v) for v in image.direction.ravel()])


def from_engine(parts):
    """An Image from the engine's (array, spacing, origin, direction) tuple."""
    return Image(parts[0], parts[1], parts[2], parts[3])
