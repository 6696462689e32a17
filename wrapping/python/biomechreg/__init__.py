"""biomechreg: physics-based deformable registration of segmented CT with joint estimation of tissue elasticity
(ITKBiomechanicalRegistration), from Python.

    import biomechreg as bmr
    pair = bmr.make_phantom("pelvis", size=(200, 160, 160), true_E_kPa=100, bladder_mm=8, rectum_mm=4)
    result = bmr.register(pair.moving_labels, pair.fixed_labels, pair.scene, moving_ct=pair.moving_ct)
    print(result.modulus_text["prostate"])

Images are biomechreg.Image (a numpy array [z, y, x] with spacing, origin and direction in ITK's x, y, z order),
numpy arrays, itk.Image or SimpleITK.Image. Units: mm, kPa, mN. The computation runs with the GIL released;
callback(event) hears its stages and progress; Ctrl-C stops it. docs/python.md has the guide.
"""

from ._api import (builtin_pelvis_scene, configure_numerics, conformal_plan, dose, get_number_of_threads,
                   make_phantom, markers, parse_scene, read_dicom_registration, read_image, read_label_names,
                   read_landmarks, read_named_label_map, read_outline_fractions, read_scene, read_structure_set,
                   register, set_number_of_threads, simulate, warp, write_dicom_registration, write_field_npz,
                   write_image)
from ._biomechreg import (EstimatorSettings, Markers, Phantom, PhantomSettings, Registration, RegistrationSettings,
                          Scene, Simulation, UncertaintySettings, WallLoadSettings)
from ._images import Image, as_image

__version__ = "0.1.0"

__all__ = ["Image", "as_image", "register", "simulate", "make_phantom", "markers", "dose", "conformal_plan", "warp",
           "read_image", "write_image", "read_scene", "parse_scene", "read_landmarks", "read_structure_set",
           "read_label_names", "read_named_label_map",
           "read_outline_fractions", "builtin_pelvis_scene", "write_dicom_registration", "read_dicom_registration",
           "write_field_npz", "configure_numerics",
           "set_number_of_threads", "get_number_of_threads", "RegistrationSettings", "UncertaintySettings",
           "EstimatorSettings", "WallLoadSettings", "PhantomSettings", "Registration", "Simulation", "Phantom",
           "Markers", "Scene"]
