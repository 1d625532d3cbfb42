"""Tests run in float64 (camjax turns x64 on at import; asserted here)."""

import jax
import pytest

import camjax  # noqa: F401  (enables x64)


def pytest_configure(config):
    assert jax.config.jax_enable_x64, "camjax tests run in float64"


@pytest.fixture(scope="session")
def default_scene():
    return camjax.load_scene()


@pytest.fixture(scope="session")
def default_arrays(default_scene):
    return camjax.scene_arrays(default_scene)
