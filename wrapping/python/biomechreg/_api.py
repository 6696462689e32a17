"""The package's functions: the C++ pipelines (itkBiomechanicalPipelines.h) on numpy arrays. Units: mm, kPa,
mN; images in LPS with ITK's geometry."""

import numpy as np

from . import _biomechreg as _engine
from ._images import Image, as_image, engine_tuple, from_engine

__all__ = ["register", "simulate", "make_phantom", "markers", "dose", "conformal_plan", "warp", "read_image",
           "write_image", "read_scene", "parse_scene", "read_landmarks", "configure_numerics",
           "set_number_of_threads", "get_number_of_threads"]

# register()'s keywords: biomechreg register's options, each a field of RegistrationSettings.
_REGISTER_KEYWORDS = {
    "uncertainty": "uncertainty.method",          # --uncertainty rescan|bootstrap|curvature|none
    "resamples": "uncertainty.resamples",         # --resamples
    "uncertainty_seed": "uncertainty.seed",       # --uncertainty-seed
    "uncertainty_threads": "uncertainty.threads",  # --uncertainty-threads
    "quantiles": "uncertainty.quantiles",         # --uncertainty-quantiles calibrated|student
    "mesh_scale": "mesh_scale",                   # --mesh-scale
    "coarse_factor": "coarse_factor",             # --coarse-factor
    "sweep_samples": "estimator.number_of_sweep_samples",
    "max_outer_iterations": "estimator.maximum_outer_iterations",
    "outer_tolerance": "estimator.outer_gradient_tolerance",
    "limit_element_inversion": "estimator.limit_element_inversion",  # --element-inversion limit
    "wall_motion": "walls.motion",                # --wall-motion normal|free|traction|pressure
    "wall_spacing_mm": "walls.control_spacing",   # --wall-spacing-mm
    "wall_regularization": "walls.regularization",
    "interpolate_slices": "interpolate_slices",   # --slice-interpolation on
    "push_field": "push_field",
    "element_state": "element_state",
}

# make_phantom()'s keywords beyond PhantomSettings' own fields: biomechreg phantom's names.
_PHANTOM_ALIASES = {"true_E_kPa": "prostate_E", "true_nu": "prostate_nu", "tissue_E_kPa": "tissue_E",
                    "tumour_E_kPa": "tumour_E", "truth_mesh_scale": "truth_refinement"}


def _set_path(settings, path, value, keyword):
    *parents, leaf = path.split(".")
    target = settings
    for name in parents:
        target = getattr(target, name)
    try:
        setattr(target, leaf, value)
    except TypeError as error:
        raise TypeError("%s: %s" % (keyword, error)) from None


def _registration_settings(settings, keywords):
    settings = _engine.RegistrationSettings() if settings is None else settings
    for keyword, value in keywords.items():
        if keyword not in _REGISTER_KEYWORDS:
            raise TypeError("register() got an unexpected keyword argument %r (known: %s)" % (
                keyword, ", ".join(sorted(_REGISTER_KEYWORDS))))
        _set_path(settings, _REGISTER_KEYWORDS[keyword], value, keyword)
    return settings


def register(moving_labels, fixed_labels, scene, *, moving_ct=None, fixed_probabilities=None, settings=None,
             callback=None, **keywords):
    """Joint estimation of boundary loads and Young's moduli (itk::RegisterSegmentedPair, ``biomechreg
    register``): the moving labels meshed, the fixed organs' signed distance maps, FEMElasticityOptimizer, the
    fields, the warped images and the stated interval of every unknown modulus.

    moving_labels, fixed_labels: label maps (integer arrays [z, y, x] with geometry: Image, itk.Image,
    SimpleITK.Image); scene: a Scene (read_scene(), or a phantom's ``scene``); moving_ct: warped too when given
    (on the moving labels' grid); fixed_probabilities: {organ: image in [0, 1]} for sub-voxel fixed surfaces;
    settings: a RegistrationSettings (all of them; the keywords override it); callback(event: dict): stages,
    progress, warnings and every inner solve, on any thread, one at a time; raising in it stops the run.

    Keywords (biomechreg register's options, the defaults its): uncertainty ("rescan", "bootstrap",
    "curvature", "none"), resamples (4), uncertainty_seed (1), uncertainty_threads (0: all), quantiles
    ("calibrated", "student"), mesh_scale (1.0), coarse_factor (1.6), sweep_samples (10),
    max_outer_iterations (20), outer_tolerance (1e-4), limit_element_inversion (False), wall_motion
    ("normal", "free", "traction", "pressure"), wall_spacing_mm (0), wall_regularization (0.01),
    interpolate_slices (False), push_field (False), element_state (True).

    Returns a Registration: youngs_modulus [kPa], intervals, modulus_text, report (report.json as a dict),
    field (fixed -> moving [mm]), warped_labels, warped_ct, mesh, dice, warnings, stages, write(directory).
    Raises ValueError for bad input, RuntimeError when the computation fails, KeyboardInterrupt on Ctrl-C
    (the run stops at its next event)."""
    settings = _registration_settings(settings, keywords)
    probabilities = {organ: engine_tuple(image, "fixed_probabilities[%s]" % organ, np.float32)
                     for organ, image in (fixed_probabilities or {}).items()}
    ct = None if moving_ct is None else engine_tuple(moving_ct, "moving_ct", np.float32)
    return _engine.register_pair(engine_tuple(moving_labels, "moving_labels", np.int32),
                                 engine_tuple(fixed_labels, "fixed_labels", np.int32),
                                 ct, probabilities, _scene(scene), settings, callback)


def simulate(moving_labels, scene, *, reference=None, push_field=True, callback=None):
    """The scene's forward problem (itk::SimulateLabelImage, ``biomechreg simulate``): the labels meshed, the
    known loads applied, the pull-back field fixed -> moving [mm] on ``reference``'s grid (default: the
    labels') and, with push_field, the push field on the labels' grid. Returns a Simulation (field,
    push_field, mesh, inverted_elements, warnings, stages)."""
    labels = engine_tuple(moving_labels, "moving_labels", np.int32)
    grid = None if reference is None else engine_tuple(reference, "reference", np.float32)
    return _engine.simulate(labels, _scene(scene), grid, bool(push_field), callback)


def make_phantom(anatomy="pelvis", *, size=None, spacing=None, origin=None, rotate_z_deg=0.0, callback=None,
                 **keywords):
    """A moving/fixed pair with its ground truth (itk::MakePhantomPair, ``biomechreg phantom``): anatomy
    "pelvis" or "spheres"; size (voxels x, y, z) and spacing [mm] of the grid, centred on the origin unless
    ``origin`` is given, rotated by rotate_z_deg about z (an oblique volume); keywords: the fields of PhantomSettings (prostate_E [kPa], bladder_mm, rectum_mm,
    seed, noise_HU, fractions, contour_fractions, model, fixed_grid_shift_voxels, ...) or biomechreg
    phantom's names (true_E_kPa, tissue_E_kPa, truth_mesh_scale, ...). Returns a Phantom (moving_ct,
    fixed_ct, moving_labels, fixed_labels, truth_field, scene, truth_scene, truth, landmarks, write())."""
    settings = _engine.PhantomSettings(anatomy)
    if size is not None or spacing is not None or rotate_z_deg:
        size = tuple(int(n) for n in (size if size is not None else settings.size))
        spacing = tuple(float(s) for s in (spacing if spacing is not None else settings.spacing))
        # Centred on the physical origin, as the command line's --size/--spacing/--rotate-z-deg make it.
        centre, direction = _engine.centered_grid(size, spacing, float(rotate_z_deg) * np.pi / 180.0)
        settings.size, settings.spacing, settings.origin, settings.direction = size, spacing, centre, direction
    if origin is not None:
        settings.origin = tuple(float(o) for o in origin)
    for keyword, value in keywords.items():
        name = _PHANTOM_ALIASES.get(keyword, keyword)
        if name.startswith("_") or not hasattr(settings, name):
            raise TypeError("make_phantom() got an unexpected keyword argument %r" % keyword)
        _set_path(settings, name, value, keyword)
    return _engine.make_phantom(settings, callback)


def _landmarks(points, what):
    if isinstance(points, (str, bytes)) or hasattr(points, "__fspath__"):
        return read_landmarks(points)
    if not isinstance(points, dict):
        raise TypeError("%s: expected {id: (x, y, z)} [mm, LPS] or a landmark file, got %s"
                        % (what, type(points).__name__))
    return {str(k): tuple(float(c) for c in v) for k, v in points.items()}


def builtin_pelvis_scene():
    """The scene a clinical structure set is registered with (itk::BuiltInPelvisScene): the pelvis phantoms'
    estimation scene, whose stated intervals were calibrated; labels air 0, soft_tissue 1, prostate 2 (modulus
    unknown), bladder 3, rectum 4, bone 5."""
    return _engine.builtin_pelvis_scene()


def read_structure_set(rtstruct, ct, *, roi_map=None, bone_threshold_HU=250.0, minimum_bone_volume_cc=1.0):
    """A planning system's RTSTRUCT, drawn on ``ct``, as the built-in pelvis scene's label map
    (itk::ReadClinicalPelvisAnatomy, what ``biomechreg register`` does without --scene): ROIs matched by TG-263 names
    and synonyms (``roi_map`` {ROI: part} overrides; parts prostate, bladder, rectum, body, bone, ignore), the body
    less the organs as soft tissue, bone from the CT unless a non-femoral bone ROI exists. ``ct``: the path of its
    DICOM series (then the RTSTRUCT's frame of reference is checked against it) or an image. Returns (labels Image,
    mapping dict: part_of_roi, left_out, bone_from_ct, bone_voxels). ValueError naming the file for a missing part
    or an RTSTRUCT of another frame of reference."""
    settings = _engine.ClinicalAnatomySettings()
    settings.bone_threshold_HU, settings.minimum_bone_volume_cc = bone_threshold_HU, minimum_bone_volume_cc
    labels, mapping = _engine.read_structure_set(str(rtstruct), _ct_grid(ct), dict(roi_map or {}), settings)
    return labels, mapping


def read_label_names(path):
    """A label map's names {value: name}: a 3D Slicer segmentation's (.seg.nrrd header; {} when it has none) or a
    names table ("value,name" CSV lines or a Slicer color table "value name r g b a")."""
    return _engine.read_label_names(str(path))


def read_named_label_map(labels, names, ct, *, roi_map=None, bone_threshold_HU=250.0, minimum_bone_volume_cc=1.0):
    """A label map whose values are named (``names``: {value: name} or the path read_label_names() reads) as the
    built-in pelvis scene's label map (itk::ClinicalPelvisAnatomyFromLabelMap, what ``biomechreg register`` does
    without --scene for a label map with --*-label-names or a .seg.nrrd): names mapped as read_structure_set() maps
    ROIs, voxels of unused names as soft tissue, 0 as air, bone from ``ct`` (an image on the same grid, or the path
    of its series) unless a non-femoral bone is named. Returns (labels Image, mapping dict)."""
    if not isinstance(names, dict):
        names = read_label_names(names)
    settings = _engine.ClinicalAnatomySettings()
    settings.bone_threshold_HU, settings.minimum_bone_volume_cc = bone_threshold_HU, minimum_bone_volume_cc
    return _engine.read_named_label_map(engine_tuple(labels, "labels", np.int32), {int(k): str(v) for k, v in
                                        names.items()}, _ct_grid(ct), dict(roi_map or {}), settings)


def read_outline_fractions(rtstruct, ct, rois):
    """Each ROI's exact outlines as area fractions per voxel of ``ct``'s grid (itk::ReadRTStructAreaFractions): the
    fixed organs' sub-voxel surfaces ``biomechreg register`` uses for a fixed RTSTRUCT (--rtstruct-surfaces
    outlines); pass them as register(fixed_probabilities={organ: fractions}). ``ct``: the path of its DICOM series
    or an image. Returns {ROI name: Image in [0, 1]}."""
    return _engine.read_outline_fractions(str(rtstruct), _ct_grid(ct), [str(r) for r in rois])


def write_dicom_registration(field, fixed_series, moving_series, path):
    """The fixed -> moving ``field`` [mm] as a DICOM Deformable Spatial Registration object (what SlicerRT and
    planning systems exchange; itk::WriteDeformableSpatialRegistration): from the frame of reference of the fixed
    scan's DICOM series ``fixed_series`` (a directory; its patient and study are copied) to the moving scan's
    ``moving_series``. The vectors are stored as float32. ValueError naming the input at fault."""
    _engine.write_dicom_registration(engine_tuple(field, "field", np.float64, components=3), str(fixed_series),
                                     str(moving_series), str(path))


def read_dicom_registration(path):
    """A DICOM Deformable Spatial Registration object (one grid, identity pre- and post-matrices) as (field Image,
    {"registered_frame_of_reference_uid", "source_frame_of_reference_uid"}): at each grid point of the registered
    (fixed) frame the displacement [mm] into the source (moving) frame, as warp() takes it."""
    return _engine.read_dicom_registration(str(path))


def write_field_npz(field, moving, path):
    """The fixed -> moving ``field`` as a NumPy .npz in Learn2Reg's layout (itk::WriteLearn2RegDisplacement):
    ``disp`` float32 (3, nx, ny, nz) in voxels, fixed voxel (i, j, k) + disp = its continuous index in ``moving``
    (an image, only its grid is used), and both grids' origin, spacing and direction."""
    grid = as_image(moving, "moving")
    dummy = (np.zeros((1, 1, 1), np.float32), grid.spacing, grid.origin, [float(v) for v in grid.direction.ravel()])
    _engine.write_field_npz(engine_tuple(field, "field", np.float64, components=3), dummy, str(path))


def _ct_grid(ct):
    return str(ct) if isinstance(ct, str) or hasattr(ct, "__fspath__") else engine_tuple(ct, "ct", np.float32)


def read_landmarks(path):
    """A landmark file as {id: (x, y, z)} [mm, LPS]: CSV (id,x_mm,y_mm,z_mm), 3D Slicer .fcsv or markups .json
    (RAS converted to LPS as the file says)."""
    return _engine.read_landmarks(str(path))


def markers(planning_labels, planning_ct, scene, planning_markers, treatment_markers, *, treatment_labels=None,
            organ="prostate", box_margin_mm=25.0, control_spacing_mm=8.0, regularization=1e-3, mesh_scale=1.0,
            moduli=None, leave_one_out=True, callback=None):
    """The treatment anatomy from tracked markers (itk::EstimateTreatmentFromMarkers, ``biomechreg markers``,
    dissertation chapter 4): forces on ``organ``'s surface in a static box fitted so that the planning markers
    move onto the treatment ones, against rigid alignment and a thin-plate spline, with leave-one-out errors.

    Markers: {id: (x, y, z)} [mm, LPS] or landmark files, paired by id. moduli: {label: kPa} for the scene's
    unknown labels. treatment_labels (optional): the real treatment organs, for IoU and D per method.
    Returns a Markers: field (treatment -> planning [mm]), warped_ct, methods ({fem, rigid, tps}: residuals,
    leave-one-out errors, IoU, D, warped_labels, field), report (report.json as a dict)."""
    settings = _engine.MarkerSettings()
    settings.organ, settings.box_margin_mm, settings.control_spacing_mm = organ, box_margin_mm, control_spacing_mm
    settings.regularization, settings.mesh_scale = regularization, mesh_scale
    settings.moduli, settings.leave_one_out = dict(moduli or {}), bool(leave_one_out)
    evaluation = None if treatment_labels is None else engine_tuple(treatment_labels, "treatment_labels", np.int32)
    return _engine.markers(engine_tuple(planning_labels, "planning_labels", np.int32),
                           engine_tuple(planning_ct, "planning_ct", np.float32), _scene(scene),
                           _landmarks(planning_markers, "planning_markers"),
                           _landmarks(treatment_markers, "treatment_markers"), evaluation, settings, callback)


def dose(labels, dose_Gy, scene, *, field=None, bin_width_Gy=0.1, volume_doses_Gy=(50.0, 60.0, 65.0, 70.0, 75.0),
         eud_a=None, anterior_rectal_wall=True):
    """DVHs and dose metrics per scene structure (itk::EvaluateDose, ``biomechreg dose``): ``dose_Gy`` [Gy] on
    ``labels``, after warping it through the fixed -> moving ``field`` when given (out(x) = dose(x + d(x))).
    Returns a dict: structures ({name: volume_cc, mean_Gy, D95_Gy, D98_Gy, D2_Gy, gEUD_Gy, eud_a,
    volume_fraction_at_dose, dvh_cumulative, dvh_differential, ...}), bin_width_Gy, dose (the Image evaluated),
    metrics_csv and dvh_csv (the CLI's files' text)."""
    settings = _engine.DoseEvaluationSettings()
    settings.bin_width_Gy = float(bin_width_Gy)
    settings.volume_doses_Gy = [float(d) for d in volume_doses_Gy]
    settings.eud_parameters = dict(eud_a or {})
    settings.anterior_rectal_wall = bool(anterior_rectal_wall)
    displacement = None if field is None else engine_tuple(field, "field", np.float64, components=3)
    return _engine.dose(engine_tuple(labels, "labels", np.int32), engine_tuple(dose_Gy, "dose", np.float32),
                        _scene(scene), displacement, settings)


def conformal_plan(labels, scene, *, margin_mm=5.0, prescription_Gy=78.0, penumbra_mm=6.0, bath_fraction=0.0,
                   bath_length_mm=30.0, prostate="prostate"):
    """A synthetic conformal plan's dose [Gy] on ``labels`` (itk::MakeConformalDosePlan, ``biomechreg dose
    --plan-margin``): the prescription inside the PTV (the prostate grown by margin_mm), an erfc penumbra."""
    settings = _engine.ConformalPlanSettings()
    settings.margin_mm, settings.prescription_Gy, settings.penumbra_mm = margin_mm, prescription_Gy, penumbra_mm
    settings.bath_fraction, settings.bath_length_mm = bath_fraction, bath_length_mm
    return _engine.conformal_plan(engine_tuple(labels, "labels", np.int32), _scene(scene), prostate, settings)


def warp(image, field, *, labels=False, outside=None):
    """``image`` resampled through the fixed -> moving ``field`` [mm] onto the field's grid (ImageWarper):
    nearest neighbour for a label map (labels=True), linear otherwise; points mapped outside take ``outside``
    (default 0, or -1000 HU for a CT)."""
    values = engine_tuple(image, "image", np.int32 if labels else np.float32)
    displacement = engine_tuple(field, "field", np.float64, components=3)
    fill = (0.0 if labels else -1000.0) if outside is None else float(outside)
    return from_engine(_engine.warp(values, displacement, bool(labels), fill))


def read_image(path, kind="ct"):
    """An image file or DICOM series as an Image: kind "ct" or "probability" (float32), "labels" (int32),
    "field" (float64 vectors)."""
    return from_engine(_engine.read_image(str(path), kind))


def write_image(image, path):
    """Writes an Image (NRRD, NIfTI, MetaImage by the extension) through a temporary name: an int32 array as a
    label map, a [z, y, x, 3] array as a field, anything else as float32."""
    image = image if isinstance(image, Image) else Image(np.asarray(image))
    array = image.array
    if array.ndim == 4:
        parts = engine_tuple(image, "image", np.float64, components=3)
    elif np.issubdtype(array.dtype, np.integer):
        parts = engine_tuple(image, "image", np.int32)
    else:
        parts = engine_tuple(image, "image", np.float32)
    _engine.write_image(parts, str(path))


def read_scene(path):
    """A scene file (JSON, docs/scenes.md) as a Scene; ValueError naming the entry at fault."""
    return _engine.read_scene(str(path))


def parse_scene(text, source="<string>"):
    """A scene from JSON text."""
    return _engine.parse_scene(text, source)


def _scene(scene):
    if isinstance(scene, _engine.Scene):
        return scene
    if isinstance(scene, str) and scene.lstrip().startswith("{"):
        return parse_scene(scene)
    if isinstance(scene, str) or hasattr(scene, "__fspath__"):
        return read_scene(scene)
    raise TypeError("scene: expected a Scene, a scene file's path or JSON text, got %s" % type(scene).__name__)


def configure_numerics(blas_threads=1):
    """The process-wide numerical settings the command line makes (bmr::ConfigureNumerics): OpenBLAS on
    ``blas_threads`` threads (1: the same bits on any machine; 0: left alone). The library never calls it on its
    own; call it once, early, when this process is yours. Returns (OpenBLAS found, its thread count)."""
    return _engine.configure_numerics(int(blas_threads))


def set_number_of_threads(threads):
    """ITK's global default number of threads, the library's thread budget (the command line's --threads);
    process-wide, as in ITK."""
    if int(threads) < 1:
        raise ValueError("threads must be >= 1")
    _engine.set_number_of_threads(int(threads))


def get_number_of_threads():
    """ITK's global default number of threads."""
    return _engine.get_number_of_threads()
