"""Tests run in float64 (camjax turns x64 on at import; asserted here).

Shared fixtures: the default scene, its arrays, and the reference case in NumPy (tests/reference.py).
"""

import jax
import pytest
from reference import reference_case

import camjax  # noqa: F401  (enables x64)


def pytest_configure(config):
    assert jax.config.jax_enable_x64, "camjax tests run in float64"


@pytest.fixture(scope="session")
def default_scene():
    return camjax.load_scene()


@pytest.fixture(scope="session")
def default_arrays(default_scene):
    return camjax.scene_arrays(default_scene)


@pytest.fixture(scope="session")
def reference_1deg():
    """The reference case (SPEC 5) in independent NumPy closed forms on the scene's 1 deg grid."""
    return reference_case(360)
