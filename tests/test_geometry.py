"""Follower geometry: curvature, minimum base radius, face width, profile, roller follower."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import reference_motion

from camjax.followers.flat import geometry as flat_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.laws import get_law
from camjax.program import MotionProgram, Segment, evaluate


def test_min_base_radius_reference_case(default_arrays):
    rb, i = flat_geo.flat_min_base_radius(default_arrays.kin)
    # SPEC 5: about 24 mm, critical at 315 deg. Exact on the 1 deg grid: the return's
    # -(s + s'') at 315 deg = -(h (1 - p(1/4)) - h 2 pi / beta^2) with p(1/4) = 1/4 - 1/(2 pi)
    h, beta = 5.0, math.radians(60)
    s = h * (1 - (0.25 - 1 / (2 * math.pi)))
    assert int(i) == 315
    assert float(rb) == pytest.approx(-(s - h * 2 * math.pi / beta**2), abs=1e-12)
    assert float(rb) == pytest.approx(24.10, abs=0.01)


def test_min_base_radius_dense_independent():
    # dense NumPy search over the return (the binding segment): the continuous minimum lies
    # within the 1 deg grid's resolution of the sampled one
    x = np.linspace(0, 1, 600_001)
    s, _, a = reference_motion(300.0 + 60.0 * x)  # the return, 300..360 deg
    dense = np.max(-(s + a))
    kin = evaluate(MotionProgram.from_segments(
        [Segment("dwell", 100), Segment("rise", 80, get_law("cycloidal"), 5.0), Segment("dwell", 120),
         Segment("return", 60, get_law("cycloidal"), 5.0)]), 36_000)
    sampled, _ = flat_geo.flat_min_base_radius(kin)
    # grid 0.01 deg (dx = 1.7e-4 in x): a sampled maximum misses the true one by at most
    # max|f"| (dx/2)^2 / 2 ~ 1130 * 7e-9 / 2 = 4e-6 mm; and the sample never exceeds it
    assert dense - 5e-6 <= float(sampled) <= dense + 1e-12


def test_face_width(default_arrays):
    kin = default_arrays.kin
    # symmetric: 2 max |s'| = 2 * h * 2 / beta_return = 19.0986 mm (SPEC: about 19 mm at 330 deg)
    assert float(flat_geo.flat_face_width(kin)) == pytest.approx(2 * 5.0 * 2 / math.radians(60), rel=1e-12)
    asym = float(flat_geo.flat_face_width(kin, symmetric=False))
    assert asym == pytest.approx(5.0 * 2 / math.radians(80) + 5.0 * 2 / math.radians(60), rel=1e-12)
    np.testing.assert_array_equal(flat_geo.flat_contact_offset(kin), kin.ds)


@pytest.mark.parametrize("rb", [24.2, 30.0, 80.0])
def test_profile_touches_the_follower_face(default_arrays, rb):
    kin = default_arrays.kin
    x, y = flat_geo.flat_profile(rb, kin)
    normal = (jnp.sin(kin.theta), jnp.cos(kin.theta))
    dist = x * normal[0] + y * normal[1]
    np.testing.assert_allclose(dist, rb + kin.s, atol=1e-9)
    # the contact point sits s' along the face from the follower axis
    along = x * jnp.cos(kin.theta) - y * jnp.sin(kin.theta)
    np.testing.assert_allclose(along, kin.ds, atol=1e-9)


def test_profile_curvature_matches_rho(default_arrays):
    # independent check of rho = R_b + s + s'': curvature of the profile curve by finite differences
    rb = 30.0
    prog = MotionProgram.from_segments(
        [Segment("dwell", 100), Segment("rise", 80, get_law("cycloidal"), 5.0), Segment("dwell", 120),
         Segment("return", 60, get_law("cycloidal"), 5.0)])
    kin = evaluate(prog, 36_000)
    x, y = (np.asarray(v) for v in flat_geo.flat_profile(rb, kin))
    dt = 2 * np.pi / 36_000
    xd, yd = np.gradient(x, dt), np.gradient(y, dt)
    xdd, ydd = np.gradient(xd, dt), np.gradient(yd, dt)
    rho_fd = (xd**2 + yd**2) ** 1.5 / np.abs(xd * ydd - yd * xdd)
    rho = np.asarray(flat_geo.flat_radius_of_curvature(rb, kin))
    inner = slice(10, -10)
    # O(dt^2) differencing, worst next to the joints where s''' jumps (measured 1.8e-4)
    np.testing.assert_allclose(rho_fd[inner], rho[inner], rtol=5e-4)


def test_roller_zero_offset_matches_spec_formula(default_arrays):
    kin = default_arrays.kin
    rb, rf = 30.0, 8.0
    g = roller_geo.roller_geometry(rb, rf, 0.0, kin)
    rp = rb + rf
    w = rp + kin.s
    spec = (w**2 + kin.ds**2) ** 1.5 / (w**2 + 2 * kin.ds**2 - kin.d2s * w)
    np.testing.assert_allclose(g.pitch_radius_of_curvature, spec, rtol=1e-12)
    np.testing.assert_allclose(g.pressure_angle, jnp.arctan(kin.ds / (kin.s + rp)), atol=1e-14)


def test_roller_with_offset_against_pitch_curve_finite_differences():
    prog = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), 10.0),
                                        Segment("dwell", 60), Segment("return", 120, get_law("poly_3_4_5"), 10.0),
                                        Segment("dwell", 60)])
    kin = evaluate(prog, 36_000)
    rb, rf, e = 25.0, 6.0, 4.0
    g = roller_geo.roller_geometry(rb, rf, e, kin)
    x, y = (np.asarray(v) for v in roller_geo.roller_pitch_curve(rb, rf, e, kin))
    dt = 2 * np.pi / 36_000
    xd, yd = np.gradient(x, dt), np.gradient(y, dt)
    xdd, ydd = np.gradient(xd, dt), np.gradient(yd, dt)
    rho_fd = (xd**2 + yd**2) ** 1.5 / np.abs(xd * ydd - yd * xdd)
    inner = slice(10, -10)
    np.testing.assert_allclose(rho_fd[inner], np.abs(g.pitch_radius_of_curvature)[inner], rtol=2e-3)
    # pressure angle = angle between the pitch-curve normal and the follower axis, i.e.
    # sin(phi) = (unit tangent) . (axis direction (sin theta, cos theta)); periodic central
    # differences at 0.01 deg are O(h^2) ~ 1e-8 rad accurate
    tx, ty = (np.roll(x, -1) - np.roll(x, 1)) / 2, (np.roll(y, -1) - np.roll(y, 1)) / 2
    th = np.asarray(kin.theta)
    phi_fd = np.arcsin((tx * np.sin(th) + ty * np.cos(th)) / np.hypot(tx, ty))
    np.testing.assert_allclose(g.pressure_angle, phi_fd, rtol=0, atol=1e-7)


def test_roller_profile_is_roller_radius_from_pitch_curve():
    prog = MotionProgram.from_segments([Segment("rise", 180, get_law("cycloidal"), 8.0),
                                        Segment("return", 180, get_law("cycloidal"), 8.0)])
    kin = evaluate(prog, 3600)
    px, py = roller_geo.roller_pitch_curve(30.0, 5.0, 3.0, kin)
    cx, cy = roller_geo.roller_profile(30.0, 5.0, 3.0, kin)
    np.testing.assert_allclose(np.hypot(px - cx, py - cy), 5.0, atol=1e-9)


def test_gradients_finite_far_below_feasible(default_arrays):
    kin = default_arrays.kin

    def f(rb):
        rho = flat_geo.flat_radius_of_curvature(rb, kin)
        g = roller_geo.roller_geometry(rb, 5.0, 2.0, kin)
        return jnp.sum(rho) + jnp.sum(g.pressure_angle) + jnp.sum(jnp.tanh(g.pitch_radius_of_curvature))

    for rb in [1e-3, 0.5, 5.0, 24.10211504108169, 40.0]:
        val, grad = jax.value_and_grad(f)(rb)
        assert np.isfinite(val) and np.isfinite(grad), rb
