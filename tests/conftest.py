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


def numpy_reference_optimum(alpha: float = 1.0, gamma: float = 1.0) -> tuple[float, float, float, float]:
    """Largest per-angle optimum (R_b, its angle, L, its angle) of the reference case, from scratch.

    An independent NumPy evaluation of SPEC 5 (cycloidal D-R-D-R, 240 rpm, m = 1 kg, k = 3004 N/m,
    x0 = 13 mm, c = 0.345 N s/m, g, w = 10 mm, steel/bronze): per angle, L = max(2|s'|, 5) and
    R = -q + max((gamma 65 C / (2 alpha 1230))^(2/3), (C / 1230)^2), clipped to [5, 40], where
    q = s + s'' and sigma = C / sqrt(R + q) (the stationary point of alpha R/65 + gamma sigma/1230).
    """
    import numpy as np

    deg = np.arange(360.0)
    th = np.deg2rad(deg)
    s, v, a = np.zeros(360), np.zeros(360), np.zeros(360)
    h, b1, b2 = 5.0, np.deg2rad(80.0), np.deg2rad(60.0)
    m = (deg >= 100) & (deg < 180)
    x = (th[m] - np.deg2rad(100)) / b1
    s[m], v[m], a[m] = (h * (x - np.sin(2 * np.pi * x) / (2 * np.pi)), h * (1 - np.cos(2 * np.pi * x)) / b1,
                        h * 2 * np.pi * np.sin(2 * np.pi * x) / b1**2)
    s[(deg >= 180) & (deg < 300)] = h
    m = deg >= 300
    x = (th[m] - np.deg2rad(300)) / b2
    s[m], v[m], a[m] = (h * (1 - (x - np.sin(2 * np.pi * x) / (2 * np.pi))), -h * (1 - np.cos(2 * np.pi * x)) / b2,
                        -h * 2 * np.pi * np.sin(2 * np.pi * x) / b2**2)
    w = 240 * 2 * np.pi / 60
    force = a * w**2 * 1e-3 + 0.345 * v * w * 1e-3 + 3004 * (s + 13.0) * 1e-3 + 9.81
    k = (1 - 0.3**2) / 2.1e5 + (1 - 0.26**2) / 1.15e5
    c = 0.564 * np.sqrt(force / 10.0 / k)
    q = s + a
    rho = np.maximum((gamma * 65 * c / (2 * alpha * 1230)) ** (2 / 3), (c / 1230) ** 2)
    radius = np.clip(-q + rho, 5.0, 40.0)
    width = np.clip(2 * np.abs(v), 5.0, 25.0)
    i, j = int(np.argmax(radius)), int(np.argmax(width))
    return float(radius[i]), float(deg[i]), float(width[j]), float(deg[j])
