"""Bad input raises a Python exception naming it (ValueError for values, TypeError for types), never a crash, and
the interpreter goes on working; a failure of the callback or Ctrl-C stops a run cleanly."""

import os
import signal
import threading

import numpy as np
import pytest

import biomechreg


def test_float_labels_are_a_type_error(small_pair):
    labels = small_pair.moving_labels
    as_float = biomechreg.Image(labels.array.astype(np.float32), labels.spacing, labels.origin, labels.direction)
    with pytest.raises(TypeError, match="moving_labels: a label map needs an integer array"):
        biomechreg.register(as_float, small_pair.fixed_labels, small_pair.scene)


def test_two_dimensional_labels_are_a_value_error(small_pair):
    with pytest.raises(ValueError, match="fixed_labels: expected a 3-D array"):
        biomechreg.register(small_pair.moving_labels, np.zeros((24, 24), np.int32), small_pair.scene)


def test_nan_in_the_ct_is_a_value_error(small_pair):
    ct = small_pair.moving_ct
    bad = biomechreg.Image(ct.array.copy(), ct.spacing, ct.origin, ct.direction)
    bad.array[3, 4, 5] = np.nan
    with pytest.raises(ValueError, match="moving_ct: contains NaN"):
        biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene, moving_ct=bad)


def test_nan_spacing_is_a_value_error(small_pair):
    labels = small_pair.fixed_labels
    bad = biomechreg.Image(labels.array, (4.0, float("nan"), 4.0), labels.origin, labels.direction)
    with pytest.raises(ValueError, match="fixed_labels spacing: not a finite number"):
        biomechreg.register(small_pair.moving_labels, bad, small_pair.scene)


def test_ct_on_another_grid_is_a_value_error(small_pair):
    ct = small_pair.moving_ct
    shifted = biomechreg.Image(ct.array, ct.spacing, tuple(o + 1.0 for o in ct.origin), ct.direction)
    with pytest.raises(ValueError, match="moving_ct and moving_labels must lie on one grid"):
        biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene, moving_ct=shifted)


def test_images_that_do_not_overlap_are_a_value_error_from_the_library(small_pair):
    labels = small_pair.fixed_labels
    far = biomechreg.Image(labels.array, labels.spacing, (1000.0, 0.0, 0.0), labels.direction)
    with pytest.raises(ValueError, match="RegisterSegmentedPair: the moving and fixed label images do not overlap"):
        biomechreg.register(small_pair.moving_labels, far, small_pair.scene, uncertainty="none")


def test_settings_errors(small_pair):
    with pytest.raises(TypeError, match="unexpected keyword argument 'resample'"):
        biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene, resample=3)
    with pytest.raises(ValueError, match="method must be one of rescan, bootstrap, curvature, none"):
        biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene, uncertainty="exact")
    with pytest.raises(ValueError, match="meshJitter"):
        biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene,
                            settings=_jittered(2.0))


def test_settings_validate_names_the_setting():
    biomechreg.RegistrationSettings().validate()  # the defaults pass
    settings = biomechreg.RegistrationSettings()
    settings.mesh_scale = 5.0
    with pytest.raises(ValueError, match=r"RegistrationSettings: meshScale must lie in \[0.25, 4\]"):
        settings.validate()


def _jittered(jitter):
    settings = biomechreg.RegistrationSettings()
    settings.uncertainty.mesh_jitter = jitter
    return settings


def test_marker_errors(small_pair):
    with pytest.raises(ValueError, match=r"treatment_markers\[s1\]: expected three finite numbers"):
        biomechreg.markers(small_pair.moving_labels, small_pair.moving_ct, small_pair.scene, {"s1": (0, 0, 0)},
                           {"s1": (0, float("nan"), 0)})
    with pytest.raises(TypeError, match="planning_markers: expected"):
        biomechreg.markers(small_pair.moving_labels, small_pair.moving_ct, small_pair.scene, [(0, 0, 0)], {})


def test_scene_errors(tmp_path):
    with pytest.raises(ValueError, match="cannot open scene file"):
        biomechreg.read_scene(tmp_path / "nothing.json")
    with pytest.raises(ValueError, match="Scene"):
        biomechreg.parse_scene('{"labels": []}')
    with pytest.raises(TypeError, match="scene: expected a Scene"):
        biomechreg.simulate(np.zeros((4, 4, 4), np.int32), 42)


def test_callback_hears_the_stages():
    events = []
    pair = biomechreg.make_phantom("spheres", size=(20, 20, 20), spacing=(4, 4, 4), noise_HU=0.0,
                                   callback=events.append)
    begun = [e["stage"] for e in events if e["event"] == "stage_begin"]
    ended = [e for e in events if e["event"] == "stage_end"]
    assert begun and len(ended) == len(begun)
    assert all(e["seconds"] >= 0.0 for e in ended)
    assert pair.moving_labels.size == (20, 20, 20)


def test_an_exception_in_the_callback_stops_the_run_and_is_raised():
    class Stop(Exception):
        pass

    begun = []

    def stop_at_the_second_stage(event):
        if event["event"] == "stage_begin":
            begun.append(event["stage"])
            if len(begun) == 2:
                raise Stop(event["stage"])

    with pytest.raises(Stop):
        biomechreg.make_phantom("spheres", size=(20, 20, 20), spacing=(4, 4, 4), callback=stop_at_the_second_stage)
    assert len(begun) == 2  # no stage began after the exception
    # The interpreter and the library go on working.
    assert biomechreg.make_phantom("spheres", size=(20, 20, 20), spacing=(4, 4, 4)).truth_field is not None


def test_ctrl_c_stops_a_registration(small_pair):
    # SIGINT from another thread once the estimation runs: KeyboardInterrupt at the next event on this thread.
    started = threading.Event()

    def on_event(event):
        if event["event"] == "stage_begin" and event["stage"] == "estimation":
            started.set()

    timer = threading.Thread(target=lambda: started.wait(60) and os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene, resamples=3,
                            callback=on_event)
    timer.join()
    result = biomechreg.register(small_pair.moving_labels, small_pair.fixed_labels, small_pair.scene,
                                 uncertainty="none")
    assert result.youngs_modulus
