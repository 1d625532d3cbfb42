"""The translating knife-edge follower against references independent of its code.

- the roller as R_f -> 0: the same pitch curve and pressure angle at the same prime radius, a cam
  outline within R_f of the knife edge's, its cam-surface radius rho_pitch - R_f, its sizing;
- kinematic inversion: the tip placed at (e, d + s(theta)) in the follower frame (s from a NumPy
  cycloid written here, not from camjax's laws), turned into the cam frame, and the traced outline
  finite-differenced for its pressure angle and radius of curvature, against the reported curves,
  the exported outline and the smallest base circle;
- a [contact] section, or a roller's radius, refused in one line naming the key.
"""

from __future__ import annotations

import math
from dataclasses import replace

import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import cli
from camjax.errors import SceneError
from camjax.evaluate import scene_arrays
from camjax.followers.knife_edge import geometry as knife_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.scene import builtin_scene_text, parse_scene, with_samples

SAMPLES = 180


def _scene(rotation="ccw", offset=2.0, rho_min=None, design=False):
    """The built-in knife-edge scene on 180 samples, with the given turning direction and offset."""
    scene = with_samples(camjax.load_scene("knife-edge"), SAMPLES)
    follower = replace(scene.follower, offset_mm=offset)
    if rho_min is not None:
        follower = replace(follower, min_curvature_radius_mm=rho_min)
    return replace(scene, motion=replace(scene.motion, rotation=rotation), follower=follower,
                   design=scene.design if design else None)


# ------------------------------------------------------------------ s(theta), written here


def _cycloid_s(segments, theta_deg):
    """s (mm) of a program of cycloidal rises and returns and dwells, NumPy: s = h (x - sin(2 pi x) / 2 pi)."""
    theta = np.mod(np.asarray(theta_deg, float), 360.0)
    s, start, level = np.zeros_like(theta), 0.0, 0.0
    for seg in segments:
        end = start + seg["angle_deg"]
        inside = (theta >= start) & (theta < end)
        x = (theta - start) / seg["angle_deg"]
        if seg["kind"] == "dwell":
            s = np.where(inside, level, s)
        else:
            assert seg["law"] == "cycloidal"
            p = x - np.sin(2 * np.pi * x) / (2 * np.pi)
            h = seg["lift_mm"] if seg["kind"] == "rise" else -seg["lift_mm"]
            s = np.where(inside, level + h * p, s)
            level += h
        start = end
    return s


def _traced(scene, base_radius_mm, theta_deg):
    """The tip's point in the cam frame at cam angles ``theta_deg`` (kinematic inversion).

    The tip sits at (e, sqrt(R_b^2 - e^2) + s) of the fixed frame. A cam turning counterclockwise
    by theta shows its cam-fixed point P at R(theta) P, so the cam point under the tip is
    R(-theta) tip; a clockwise cam, R(+theta) tip.
    """
    e = scene.follower.offset_mm
    y = math.sqrt(base_radius_mm**2 - e**2) + _cycloid_s(scene.motion.segments, theta_deg)
    a = -np.radians(theta_deg) if scene.motion.rotation == "ccw" else np.radians(theta_deg)
    return np.cos(a) * e - np.sin(a) * y, np.sin(a) * e + np.cos(a) * y, a


H = 1e-4  # rad: finite-difference step of the traced outline


def _brute_force(scene, base_radius_mm, theta_deg):
    """Pressure angle (rad) and signed curvature (1/mm, convex > 0) of the traced outline at
    ``theta_deg``, from its points at theta and theta +- H alone (central differences)."""
    step = math.degrees(H)
    (x0, y0, a), (xp, yp, _), (xm, ym, _) = (_traced(scene, base_radius_mm, theta_deg + k * step)
                                             for k in (0, 1, -1))
    dx, dy = (xp - xm) / (2 * H), (yp - ym) / (2 * H)
    ddx, ddy = (xp - 2 * x0 + xm) / H**2, (yp - 2 * y0 + ym) / H**2
    # the outline runs clockwise (ccw cam) or counterclockwise (cw cam): convex where it turns towards
    # the cam centre, i.e. the cross product has the sign of the turning direction
    turn = -1.0 if scene.motion.rotation == "ccw" else 1.0
    kappa = turn * (dx * ddy - dy * ddx) / np.hypot(dx, dy) ** 3
    # the contact normal, away from the cam (the side the tip is on), turned back into the fixed frame
    nx, ny = -dy, dx
    away = np.sign(nx * x0 + ny * y0)
    nx, ny = away * nx, away * ny
    fx, fy = np.cos(-a) * nx - np.sin(-a) * ny, np.sin(-a) * nx + np.cos(-a) * ny
    phi = np.arctan2(-fx, fy)  # from the follower axis +Y, positive leaning towards -x
    return phi, kappa


@pytest.fixture(scope="module", params=["ccw", "cw"])
def drawn(request):
    """(scene, run) of the knife edge with offset 2 mm drawn at its smallest cam + 1 mm, rounded up."""
    scene = _scene(request.param)
    return scene, camjax.run_design(scene)


@pytest.mark.slow
def test_the_outline_is_the_tip_seen_from_the_cam(drawn):
    scene, run = drawn
    c = run.curves
    x, y, _ = _traced(scene, c.base_radius_mm, c.theta_deg)
    # the same point through two rotations: round-off of lengths ~25 mm
    np.testing.assert_allclose(c.profile_x_mm, x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.profile_y_mm, y, rtol=0, atol=1e-12)


@pytest.mark.slow
def test_pressure_angle_and_curvature_match_finite_differences_of_the_outline(drawn):
    scene, run = drawn
    c = run.curves
    phi, kappa = _brute_force(scene, c.base_radius_mm, c.theta_deg)
    # central differences with H = 1e-4 rad: truncation ~H^2 |P'''| / 6 ~ 1e-8 relative in the
    # tangent, round-off ~eps R / H ~ 1e-11; in the second difference ~eps R / H^2 ~ 1e-7 of |P''|
    np.testing.assert_allclose(np.radians(c.pressure_angle_deg), phi, rtol=0, atol=1e-7)
    reported = 1.0 / c.pitch_rho_mm  # the profile's radius of curvature (saturated at inflections)
    scale = float(np.max(np.abs(kappa)))
    # at a segment joint the third derivative of s jumps (the cycloid's ends): the second difference
    # across it is off by ~H |jump| / 6 ~ 1e-3 mm/rad^2, ~1e-4 of the curvature's scale; elsewhere 1e-6
    joint = np.isin(c.theta_deg, np.asarray(c.segment_starts_deg))
    assert joint.sum() == len(scene.motion.segments)
    np.testing.assert_allclose(reported[~joint], kappa[~joint], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(reported[joint], kappa[joint], rtol=0, atol=1e-4 * scale)
    # the check covers convex parts and (the ccw cam at this radius) concave ones
    assert (kappa > 0).any() and (scene.motion.rotation == "cw" or (kappa < 0).any())


@pytest.mark.slow
def test_the_smallest_cam_is_the_brute_force_one(drawn):
    """The reported smallest base radius (pressure angle binding, exact over the angle) against a
    bisection in R_b of the brute-force pressure angle on a grid of 36 000 angles."""
    scene, run = drawn
    minimum = run.min_base_radius
    assert minimum.binding == "pressure_angle"
    limit = math.radians(scene.follower.max_pressure_angle_deg)
    theta = np.arange(36_000) * 0.01

    def ok(rb):
        return np.max(np.abs(_brute_force(scene, rb, theta)[0])) <= limit

    lo, hi = abs(scene.follower.offset_mm) + 1e-9, 200.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    # the dense grid misses the continuous peak by ~|phi''| (0.01 deg)^2 / 8 ~ 1e-8 rad, and the
    # finite differences add 1e-7 rad: R_b moves by that over d|phi|/dR_b ~ 0.01 rad/mm
    assert minimum.radius_mm == pytest.approx(hi, abs=2e-5)


def test_the_curvature_limit_sizes_the_cam_as_brute_force_does():
    """With min_curvature_radius_mm above the pressure angle's cam, the convex radius binds: the
    reported smallest R_b against a bisection of the brute-force radius at the samples."""
    scene = _scene(rho_min=14.0)
    arrays = scene_arrays(scene)
    f = scene.follower
    sizing = knife_geo.knife_edge_min_base_radius(arrays.kin, f.offset_mm, math.radians(f.max_pressure_angle_deg),
                                                  f.min_curvature_radius_mm)
    assert bool(sizing.undercut_binds)
    theta = np.asarray(arrays.theta_deg)

    def ok(rb):
        kappa = _brute_force(scene, rb, theta)[1]
        return np.all(kappa * f.min_curvature_radius_mm <= 1.0)  # convex radius >= the minimum

    lo, hi = 1.0, 200.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    # both judge the same samples; kappa from differences to 1e-6 relative moves R_b by about
    # 1e-6 rho_min / (d(kappa rho_min)/dR_b ~ 0.1 / mm) ~ 1e-4 mm
    assert float(sizing.prime_radius_mm) == pytest.approx(hi, abs=2e-4)
    assert ok(float(sizing.prime_radius_mm) + 1e-3) and not ok(float(sizing.prime_radius_mm) - 1e-2)


# -------------------------------------------------------------------- the roller, R_f -> 0


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_the_roller_tends_to_the_knife_edge_as_its_radius_vanishes(rotation):
    scene = _scene(rotation)
    kin = scene_arrays(scene).kin
    rp, e = 20.0, scene.follower.offset_mm
    knife = knife_geo.knife_edge_geometry(rp, e, kin, rotation)
    kx, ky = knife_geo.knife_edge_profile(rp, e, kin, rotation)
    for rf in (1e-1, 1e-3, 1e-6):
        roller = roller_geo.roller_geometry(rp - rf, rf, e, kin, rotation)
        # the pitch curve depends on R_p alone: the same pressure angle and pitch radius
        np.testing.assert_allclose(roller.pressure_angle, knife.pressure_angle, rtol=0, atol=1e-14)
        np.testing.assert_allclose(roller.pitch_curvature, knife.curvature, rtol=0, atol=1e-15)
        px, py = roller_geo.roller_pitch_curve(rp - rf, rf, e, kin, rotation)
        np.testing.assert_allclose(px, kx, rtol=0, atol=1e-12)
        np.testing.assert_allclose(py, ky, rtol=0, atol=1e-12)
        # the roller's cam outline lies R_f inside the knife edge's, its radius R_f smaller
        rx, ry = roller_geo.roller_profile(rp - rf, rf, e, kin, rotation)
        np.testing.assert_allclose(np.hypot(rx - kx, ry - ky), rf, rtol=1e-9, atol=1e-13)
        finite = np.abs(knife.radius_of_curvature) < 1e6
        np.testing.assert_allclose(roller.cam_radius_of_curvature[finite], knife.radius_of_curvature[finite] - rf,
                                   rtol=1e-12, atol=1e-9)


def test_the_rollers_smallest_cam_tends_to_the_knife_edges():
    """The roller's smallest prime circle (the undercut binding, rho_min = 14 mm) -> the knife
    edge's smallest base circle as R_f -> 0, with a gap of order R_f."""
    scene = _scene(rho_min=14.0)
    kin = scene_arrays(scene).kin
    f = scene.follower
    lim = math.radians(f.max_pressure_angle_deg)
    knife = float(knife_geo.knife_edge_min_base_radius(kin, f.offset_mm, lim, 14.0).prime_radius_mm)
    gaps = []
    for rf in (1e-1, 1e-2, 1e-3):
        roller = roller_geo.roller_min_prime_radius(kin, rf, f.offset_mm, lim, 14.0)
        gaps.append(float(roller.prime_radius_mm) - knife)
    # the undercut needs rho_pitch >= 14 + R_f: the prime circle grows with R_f, linearly for small R_f
    assert all(0 < g < 10 * rf for g, rf in zip(gaps, (1e-1, 1e-2, 1e-3), strict=True))
    assert gaps[2] < gaps[1] < gaps[0]


@pytest.mark.slow
def test_the_designed_knife_edge_is_the_designed_roller_with_a_vanishing_radius():
    """The built-in knife-edge scene designed, and the same scene as a roller whose radius is fixed
    at 1e-4 mm: the same prime circle, offset and pressure angle."""
    text = builtin_scene_text("knife-edge")
    knife = parse_scene(text)
    roller_text = text.replace('type = "knife_edge"', 'type = "roller"\nroller_radius_mm = 1e-4').replace(
        "offset_mm = [-4.0, 4.0]", "offset_mm = [-4.0, 4.0]\nroller_radius_mm = 1e-4")
    roller = parse_scene(roller_text)
    k, r = camjax.run_design(knife).design.result, camjax.run_design(roller).design.result
    assert k["feasible"] and r["feasible"]
    # the pressure angle binds and depends on R_p only; the solvers meet it to 1e-7 rad, the optimum
    # is flat in e (R_p(e) at its minimum): e agrees to ~sqrt of that, R_p to its square
    assert k["base_radius_mm"] == pytest.approx(r["prime_radius_mm"], rel=1e-5)
    assert k["offset_mm"] == pytest.approx(r["offset_mm"], abs=5e-3)
    assert k["pressure_angle_max_deg"] == pytest.approx(r["pressure_angle_max_deg"], abs=1e-4)


# ------------------------------------------------------------------------ refused scenes


CONTACT = """
[contact]
cam_width_mm = 8.0
cam = { E_MPa = 2.1e5, poisson = 0.3 }
follower = { E_MPa = 2.1e5, poisson = 0.3 }
"""


def test_a_contact_section_is_refused_naming_it(tmp_path, capsys):
    text = builtin_scene_text("knife-edge") + CONTACT
    with pytest.raises(SceneError) as err:
        parse_scene(text)
    assert err.value.field == "contact" and "knife-edge" in str(err.value)
    path = tmp_path / "knife-contact.toml"
    path.write_text(text)
    assert cli.main(["design", str(path), "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "contact: contact stress is not defined for a knife-edge follower" in lines[0]
    assert "[contact]" in lines[0] and not (tmp_path / "out").exists()


def test_a_roller_radius_is_refused_naming_the_key():
    text = builtin_scene_text("knife-edge").replace('type = "knife_edge"',
                                                    'type = "knife_edge"\nroller_radius_mm = 2.0')
    with pytest.raises(SceneError) as err:
        parse_scene(text)
    assert err.value.field == "follower.roller_radius_mm" and "not type = 'knife_edge'" in str(err.value)


def test_an_offset_outside_the_base_circle_is_refused():
    # |e| < R_b is a constraint of the problem: a box with some designs past it is accepted ...
    text = builtin_scene_text("knife-edge").replace("base_radius_mm = [5.0, 60.0]", "base_radius_mm = [3.0, 60.0]")
    assert parse_scene(text).design.bounds("offset_mm") == (-4.0, 4.0)
    # ... one where every design has |e| >= R_b is refused, naming the field and the largest R_b
    text = text.replace("offset_mm = [-4.0, 4.0]", "offset_mm = [61.0, 70.0]")
    with pytest.raises(SceneError) as err:
        parse_scene(text)
    assert err.value.field == "design.offset_mm" and "|e| < 60" in str(err.value)


@pytest.mark.slow
def test_gradients_are_finite_for_an_axis_outside_the_base_circle():
    """A trial design with |e| > R_b (no tip height): objective and constraints finite, with finite
    gradients (the solvers may step there)."""
    import jax

    from camjax.followers.knife_edge import problem as pb

    problem = pb.problem_from_scene(_scene(design=True))
    weights = camjax.family.weights_of(1.0, 0.0)

    def f(d):
        return pb.objective(problem, weights, d) + sum(jax.tree.leaves(pb.constraint_maxima(problem, d)))

    design = pb.Design(jnp.asarray(2.0), jnp.asarray(3.5))
    value, grad = jax.value_and_grad(f)(design)
    assert np.isfinite(float(value)) and all(np.isfinite(float(g)) for g in grad)
