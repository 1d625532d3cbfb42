"""Laws from points: the smoothing-spline fit against closed forms and SciPy, the fit report and
its noise test, the whole-cycle table, and one-line errors for bad tables."""

from __future__ import annotations

import math
import sys
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

from camjax import cli
from camjax.laws.fit import smoothing_spline
from camjax.laws.table import NOISE_RATIO
from camjax.program import evaluate as program_evaluate
from camjax.program import segment_motion
from camjax.scene import SceneError, load_scene
from camjax.scene.shaped import TableFitWarning

H, BETA = 5.0, 80.0  # a cycloidal rise of 5 mm over 80 deg


def _cycloidal(x):
    return x - np.sin(2 * np.pi * x) / (2 * np.pi)


def _write(path, angles, lifts, header="angle_deg,lift_mm"):
    rows = "\n".join(f"{float(a)!r},{float(v)!r}" for a, v in zip(angles, lifts, strict=True))
    path.write_text(f"{header}\n{rows}\n")


SCENE = """
[motion]
rpm = 240
segments = [
  {{kind = "dwell", angle_deg = 100}},
  {{kind = "rise", law = "table", file = "{file}"{extra}}},
  {{kind = "dwell", angle_deg = 120}},
  {{kind = "return", angle_deg = 60, law = "cycloidal", lift_mm = 5}},
]
[follower]
type = "flat"
"""


def _scene(tmp_path, angles, lifts, extra="", header="angle_deg,lift_mm"):
    _write(tmp_path / "points.csv", angles, lifts, header)
    (tmp_path / "s.toml").write_text(SCENE.format(file="points.csv", extra=extra))
    return load_scene(tmp_path / "s.toml")


def test_cubic_fit_is_scipys_smoothing_spline_at_equal_lam():
    from scipy.interpolate import BSpline, make_smoothing_spline  # here: not at every collection

    rng = np.random.default_rng(1)
    x = np.linspace(0.0, 1.0, 81)
    y = np.sin(3 * x) + 0.01 * rng.normal(size=x.size)
    xx = np.linspace(0.0, 1.0, 1001)
    for lam in (1e-6, 1e-4):
        fit = smoothing_spline(x, y, 3, lam)
        # the same minimizer (natural cubic spline with knots at the data) solved two ways
        np.testing.assert_allclose(BSpline(fit.knots, fit.coeffs, 3)(xx), make_smoothing_spline(x, y, lam=lam)(xx),
                                   rtol=0, atol=1e-10)


@pytest.mark.slow
def test_noise_free_cycloidal_table_fits_to_1e_6_mm_and_its_peak_acceleration_to_1e_3(tmp_path):
    angles = np.arange(0.0, BETA + 0.5)  # every degree
    scene = _scene(tmp_path, angles, H * _cycloidal(angles / BETA))
    fit = scene.motion.segments[1]["fit"]
    theta = np.linspace(100.0, 180.0, 8001)
    kin = segment_motion(scene.motion.program, 1, jnp.asarray(theta))
    exact = H * _cycloidal((theta - 100.0) / BETA)
    assert np.max(np.abs(np.asarray(kin.s) - exact)) < 1e-6  # between the points too, mm
    assert fit["max_residual"] < 1e-6
    peak_a = H * 2 * np.pi / BETA**2  # mm/deg^2
    assert fit["peak_accel"] == pytest.approx(peak_a, rel=1e-3)
    a_rad = float(jnp.max(jnp.abs(kin.d2s)))  # the program's own, mm/rad^2
    assert a_rad == pytest.approx(peak_a * (180 / np.pi) ** 2, rel=1e-3)
    assert fit["peak_velocity"] == pytest.approx(2 * H / BETA, rel=1e-3)
    assert not fit["noisy"] and fit["jerk_noise_ratio"] < NOISE_RATIO


@pytest.mark.slow
def test_noisy_cycloidal_table_keeps_its_peak_acceleration_within_5_percent(tmp_path):
    angles = np.arange(0.0, BETA + 0.5)
    noise = 0.01 * np.random.default_rng(22).normal(size=angles.size)
    # noisy end rows: the scene gives the lift, the rows are checked against it within 2 %
    scene = _scene(tmp_path, angles, H * _cycloidal(angles / BETA) + noise, ", lift_mm = 5")
    fit = scene.motion.segments[1]["fit"]
    assert fit["gcv"]
    assert fit["peak_accel"] == pytest.approx(H * 2 * np.pi / BETA**2, rel=0.05)
    # the residuals are the noise: RMS near 0.01 mm (GCV neither interpolates nor flattens)
    assert 0.005 < fit["rms_residual"] < 0.015


@pytest.mark.slow
def test_too_little_smoothing_on_noisy_points_is_flagged(tmp_path):
    angles = np.arange(0.0, BETA + 0.5)
    noise = 0.01 * np.random.default_rng(22).normal(size=angles.size)
    with pytest.warns(TableFitWarning, match="noise"):
        scene = _scene(tmp_path, angles, H * _cycloidal(angles / BETA) + noise, ", smoothing = 1e-3, lift_mm = 5")
    fit = scene.motion.segments[1]["fit"]
    assert fit["noisy"] and fit["jerk_noise_ratio"] > NOISE_RATIO and not fit["gcv"]
    assert fit["smoothing"] == pytest.approx(1e-3)


@pytest.mark.slow
def test_table_segments_meet_the_dwells_at_rest(tmp_path):
    angles = np.arange(0.0, BETA + 0.5)
    noise = 0.01 * np.random.default_rng(5).normal(size=angles.size)
    scene = _scene(tmp_path, angles, H * _cycloidal(angles / BETA) + noise, ", lift_mm = 5")
    from camjax.program import joints

    for j in joints(scene.motion.program):
        assert j.flcd_class in ("ok", "perturbation"), j  # pinned levels, v = a = 0 at the ends


@pytest.mark.slow
def test_whole_cycle_table_reproduces_the_program(tmp_path):
    ref_scene = load_scene("default")
    theta = np.arange(360.0)
    s = np.asarray(program_evaluate(ref_scene.motion.program, 360).s)
    _write(tmp_path / "cycle.csv", theta, s)
    (tmp_path / "c.toml").write_text('[motion]\nrpm = 240\ntable = "cycle.csv"\n[follower]\ntype = "flat"\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error", TableFitWarning)
        scene = load_scene(tmp_path / "c.toml")
    got = program_evaluate(scene.motion.program, 360)
    # the data's jerk steps at its four joints with dwells (cycloidal: 4 pi^2 h / beta^3) are
    # rounded by the jerk penalty, which the modified GCV keeps from vanishing (tr H <= n / 2):
    # measured 1.0e-4 mm next to the joints (2e-6 mm with plain GCV, which undersmooths noisy data)
    np.testing.assert_allclose(np.asarray(got.s), s, rtol=0, atol=2e-4)
    fit = scene.motion.segments[0]["fit"]
    assert fit["peak_accel"] == pytest.approx(H * 2 * np.pi / 60.0**2, rel=1e-3)  # the 60 deg return
    assert [seg["kind"] for seg in scene.motion.segments] == ["rise", "return"]


@pytest.mark.parametrize("rows, where", [
    ("0,0\n2,0.1\n1,0.2\n", "row 3 (line 4)"),  # unsorted
    ("0,0\n1,0.1\n1,0.2\n", "row 3 (line 4)"),  # repeated
    ("0,0\n1,nan\n", "row 2 (line 3)"),  # not a finite number
    ("0,0\n1,abc\n", "row 2 (line 3)"),
    ("0,0\n1\n", "row 2 (line 3)"),  # short row
])
def test_bad_rows_are_named(tmp_path, rows, where):
    (tmp_path / "points.csv").write_text("angle_deg,lift_mm\n" + rows)
    (tmp_path / "s.toml").write_text(SCENE.format(file="points.csv", extra=""))
    with pytest.raises(SceneError) as err:
        load_scene(tmp_path / "s.toml")
    msg = str(err.value)
    assert err.value.field == "motion.segments[1].file" and where in msg and "points.csv" in msg, msg
    assert "\n" not in msg


def test_too_few_points_and_unmatched_levels_are_refused(tmp_path):
    angles = np.arange(0.0, BETA + 0.5, 10.0)  # 9 rows < 12 for degree 5
    with pytest.raises(SceneError, match="too few"):
        _scene(tmp_path, angles, H * _cycloidal(angles / BETA))
    angles = np.arange(0.0, BETA + 0.5)
    lifts = H * _cycloidal(angles / BETA) + 0.5  # starts 0.5 mm above the dwell
    with pytest.raises(SceneError, match=r"row 1: lift 0\.5 does not match the level 0"):
        _scene(tmp_path, angles, lifts)
    with pytest.raises(SceneError, match="lacks lift_mm"):
        _scene(tmp_path, angles, lifts, header="angle_deg,lift")


def test_cli_exits_2_on_a_bad_table(tmp_path, capsys):
    (tmp_path / "points.csv").write_text("angle_deg,lift_mm\n0,0\n1,x\n")
    (tmp_path / "s.toml").write_text(SCENE.format(file="points.csv", extra=""))
    assert cli.main(["design", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "points.csv" in err[0] and "row 2" in err[0], err


def test_without_scipy_the_error_names_the_extra(tmp_path, monkeypatch):
    angles = np.arange(0.0, BETA + 0.5)
    monkeypatch.setitem(sys.modules, "scipy", None)
    monkeypatch.setitem(sys.modules, "scipy.interpolate", None)
    with pytest.raises(SceneError, match=r"camjax\[scipy\]"):
        _scene(tmp_path, angles, H * _cycloidal(angles / BETA))


@pytest.mark.slow
def test_smoothing_is_in_scene_units(tmp_path):
    """The same smoothing in (mm, deg) gives the same fit whatever the segment's angle."""
    angles = np.arange(0.0, BETA + 0.5)
    noise = 0.01 * np.random.default_rng(3).normal(size=angles.size)
    scene = _scene(tmp_path, angles, H * _cycloidal(angles / BETA) + noise, ", smoothing = 50.0, lift_mm = 5")
    fit = scene.motion.segments[1]["fit"]
    # refit by hand in degrees: lam_deg * int (f''')^2 dtheta, theta = x * BETA
    x = angles / BETA
    m = 3
    direct = smoothing_spline(x, H * _cycloidal(x) + noise, 5, 50.0 / BETA ** (2 * m - 1),
                              fixed_ends=(0.0, H), rest_order=2)
    assert fit["max_residual"] == pytest.approx(float(np.max(np.abs(direct.residuals))), rel=1e-9)
    assert math.isfinite(fit["peak_jerk"])
