"""Shared fixtures of the Python package's tests (run by ctest: python_biomechreg, python_biomechreg_cli)."""

import os

import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "cli: compares the package with the biomechreg command line (needs "
                                       "BIOMECHREG_CLI)")
    config.addinivalue_line("markers", "structure_set: clinical structure sets without a scene (slow; needs "
                                       "BIOMECHREG_CLI and plastimatch)")


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("BIOMECHREG_CLI")
    if not path:
        pytest.skip("BIOMECHREG_CLI is not set")
    return path


@pytest.fixture(scope="session")
def small_pair():
    """A small spheres phantom (24^3 voxels of 4 mm, no noise): quick to make and to register."""
    import biomechreg
    return biomechreg.make_phantom("spheres", size=(24, 24, 24), spacing=(4, 4, 4), noise_HU=0.0)
