"""Curved-face (mushroom) follower: its geometry against computations that do not use its formulas.

- the cam outline against the brute-force envelope of the face's circle, placed at every cam angle
  from the motion s(theta) alone (kinematic inversion; the outline is the first point of each ray
  from the cam centre that some circle position reaches);
- pressure angle, the contact's travel on the face, the cam surface's radius of curvature, the
  sliding speed and the Hertz stress from positions only (finite differences of the inverted
  centre curve and of the cam's and follower's motions);
- the flat face as R_c -> infinity (pressure angle, contact point, radius of curvature, outline,
  stress, sliding speed; and the design problem's face need);
- the face-travel constraint: the sizing binds on it exactly where the contact reaches the face's
  edge, the problem and the run report it when the face is too narrow, and not when it is wide.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import reference_motion

import camjax
from camjax import contact
from camjax.errors import SceneError
from camjax.followers.curved_face import geometry as curved_geo
from camjax.followers.curved_face import problem as P
from camjax.followers.flat import geometry as flat_geo
from camjax.laws import get_law
from camjax.program import MotionProgram, Segment, evaluate
from camjax.scene import builtin_scene_text, parse_scene, with_samples

# rise-dwell-return-dwell with an asymmetric pair of laws, so that offset and rotation matter
PROGRAM = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), 10.0), Segment("dwell", 60),
                                       Segment("return", 100, get_law("cycloidal"), 10.0), Segment("dwell", 80)])
CASES = [("ccw", 4.0), ("cw", 4.0), ("ccw", -3.0), ("cw", 0.0)]
RB, RC = 30.0, 60.0  # a convex cam: no undercut, single contact everywhere
MATRIX_SAMPLES = 90  # the sample count of tests/cache_matrix.py's runs of the built-in scene


def centres(rb, rc, e, kin, rotation):
    """The face circle's centre (e, d + s) of the fixed frame seen from the cam (kinematic
    inversion, NumPy): ccw, the cam point P at R(theta) P is in contact, so P = R(-theta) p."""
    th, s = np.asarray(kin.theta), np.asarray(kin.s)
    p = np.stack([np.full_like(s, e), math.sqrt((rb + rc) ** 2 - e**2) + s])
    a = -th if rotation == "ccw" else th
    return np.cos(a) * p[0] - np.sin(a) * p[1], np.sin(a) * p[0] + np.cos(a) * p[1]


def to_fixed(x, y, th, rotation):
    """Cam-frame points at cam angle ``th`` -> the fixed (follower) frame."""
    a = th if rotation == "ccw" else -th
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def from_positions(rb, rc, e, rotation, n=36_000):
    """Contact point (fixed frame), unit normal (fixed frame, towards the face's centre), the pitch
    curve's curvature, by central differences of the inverted centre curve only."""
    kin = evaluate(PROGRAM, n)
    x, y = centres(rb, rc, e, kin, rotation)
    h = 2 * np.pi / n
    d1 = lambda v: (np.roll(v, -1) - np.roll(v, 1)) / (2 * h)  # noqa: E731
    d2 = lambda v: (np.roll(v, -1) - 2 * v + np.roll(v, 1)) / h**2  # noqa: E731
    th = np.asarray(kin.theta)
    tx, ty = to_fixed(d1(x), d1(y), th, rotation)  # tangent of the centre curve, fixed frame
    norm = np.hypot(tx, ty)
    nx, ny = -ty / norm, tx / norm  # a normal; point it away from the cam centre (up, +y)
    flip = np.where(ny < 0, -1.0, 1.0)
    nx, ny = nx * flip, ny * flip
    cx, cy = to_fixed(x, y, th, rotation)  # = (e, d + s)
    contact_x, contact_y = cx - rc * nx, cy - rc * ny
    turn = -1.0 if rotation == "ccw" else 1.0  # ccw cams trace their pitch curve clockwise
    kappa = turn * (d1(x) * d2(y) - d1(y) * d2(x)) / (d1(x) ** 2 + d1(y) ** 2) ** 1.5
    return kin, contact_x, contact_y, nx, ny, kappa


def _near_joints(n, width=2, program=PROGRAM):
    """Samples within ``width`` of a joint, where a jump of s''' puts differences O(h) off."""
    near = np.zeros(n, bool)
    for start in program.start_deg:
        near[(np.arange(-width, width + 1) + round(start * n / 360)) % n] = True
    return near


# ---------------------------------------------------------------------------- geometry


@pytest.mark.slow
@pytest.mark.parametrize("rotation,e", CASES)
def test_outline_is_the_brute_force_envelope_of_the_face_circle(rotation, e):
    """Every outline point's distance from the cam centre is the first hit, along its ray, of the
    face's circle at any of 72 000 cam angles (parabola through the best three), to 1e-7 mm."""
    kin = evaluate(PROGRAM, 120)
    x, y = (np.asarray(v) for v in curved_geo.profile(RB, RC, e, kin, rotation))
    dense = evaluate(PROGRAM, 72_000)
    cx, cy = centres(RB, RC, e, dense, rotation)
    r = np.hypot(x, y)
    dx, dy = x / r, y / r
    proj = dx[:, None] * cx[None, :] + dy[:, None] * cy[None, :]  # (120, 72 000)
    miss = cx[None, :] ** 2 + cy[None, :] ** 2 - proj**2  # squared distance of the centre from the ray
    near = proj - np.sqrt(np.maximum(RC**2 - miss, 0.0))  # where the ray enters the circle
    hit = np.where((miss <= RC**2) & (near > 0), near, np.inf)  # circles ahead of the cam centre
    j = np.argmin(hit, axis=1)
    rows = np.arange(len(r))
    a, b, c = hit[rows, j - 1], hit[rows, j], hit[rows, (j + 1) % hit.shape[1]]
    brute = b - (a - c) ** 2 / (8 * (a - 2 * b + c))  # the parabola's vertex through the three
    # the hit distance is smooth in the circle's angle: the vertex errs by O(h^3) at h = 0.005 deg
    np.testing.assert_allclose(r, brute, rtol=0, atol=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("rotation,e", CASES)
def test_pressure_angle_face_travel_and_curvature_from_positions(rotation, e):
    n = 36_000
    kin, px, py, nx, ny, kappa_fd = from_positions(RB, RC, e, rotation, n)
    g = curved_geo.geometry(RB, RC, e, kin, rotation)
    # the pressure angle is the normal's angle from the axis, positive when it leans to -x
    phi_fd = np.arctan2(-nx, ny)
    # central differences at 0.01 deg: O(h^2) = 3e-9 relative times |P'''|/|P'| ~ 10
    np.testing.assert_allclose(g.pressure_angle, phi_fd, rtol=0, atol=1e-7)
    # the contact's place on the face, off the axis x = e: R_c sin phi (lengths of ~100 mm: 1e-5 mm)
    np.testing.assert_allclose(curved_geo.face_travel(RB, RC, e, kin, rotation), px - e, rtol=0, atol=1e-5)
    cx, cy = (np.asarray(v) for v in curved_geo.contact_point(RB, RC, e, kin, rotation))
    np.testing.assert_allclose(cx, px, rtol=0, atol=1e-5)
    np.testing.assert_allclose(cy, py, rtol=0, atol=1e-5)
    # the cam surface's radius: rho_pitch - R_c, the pitch curve's curvature from second
    # differences (O(h^2) and eps |P| / h^2 round-off, ~1e-8 1/mm; O(h) across a jump of s''')
    near = _near_joints(n)
    np.testing.assert_allclose(np.asarray(g.pitch_curvature)[~near], kappa_fd[~near], rtol=0, atol=1e-7)
    rho_c = 1.0 / kappa_fd - RC
    np.testing.assert_allclose(np.asarray(g.cam_radius_of_curvature)[~near], rho_c[~near], rtol=1e-5)


@pytest.mark.parametrize("rotation,e", CASES)
def test_sliding_speed_is_the_relative_speed_of_cam_and_face_at_the_contact(rotation, e):
    """The cam's material point at the contact and the face move (finite differences of the cam's
    rotation and of s): their relative velocity is tangent (no separation, no penetration) and its
    length is the reported sliding speed."""
    n, omega = 36_000, 25.0
    kin, px, py, nx, ny, _ = from_positions(RB, RC, e, rotation, n)
    th, h = np.asarray(kin.theta), 2 * np.pi / n
    # the cam's material point P (cam frame) at theta -/+ h, seen in the fixed frame
    bx, by = to_fixed(px, py, -th, rotation)  # back to the cam frame
    ahead = to_fixed(bx, by, th + h, rotation)
    behind = to_fixed(bx, by, th - h, rotation)
    vx = (ahead[0] - behind[0]) / (2 * h) * omega
    vy = (ahead[1] - behind[1]) / (2 * h) * omega - (np.roll(kin.s, -1) - np.roll(kin.s, 1)) / (2 * h) * omega
    np.testing.assert_allclose(vx * nx + vy * ny, 0.0, atol=1e-5 * omega)  # tangent: O(h^2) of ~1e2 mm
    speed = np.hypot(vx, vy) * 1e-3  # m/s
    got = np.asarray(curved_geo.sliding_speed_m_s(RB, RC, e, kin, omega, rotation))
    np.testing.assert_allclose(got, speed, rtol=1e-7)


@pytest.mark.slow  # a run at 3600 samples (compiles)
def test_hertz_stress_is_specs_line_contact_of_cam_and_crowned_face():
    """sigma = 0.564 sqrt((F / cos phi / w)(1/rho_c + 1/R_c) / K) with rho_c and phi from positions
    (SPEC 3), against the follower's stress curve of the built-in scene's cam and follower (its
    [design] left out: the closed form holds at any R_c, and no solve is needed to draw at 30 mm;
    grid extrema: the curves are the samples' either way, and the run's sizing, which is not
    checked here, then compiles no exact-extrema program at 3600 samples)."""
    text = builtin_scene_text("curved-face")
    scene = with_samples(parse_scene(text[: text.index("\n[design]")], "curved-face"), 3600)
    scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, extrema="grid"))
    run = camjax.run_design(scene, base_radius_mm=30.0)
    c = scene.contact
    f = run.curves
    rho_c = np.asarray(f.pitch_rho_mm) - f.roller_radius_mm
    phi = np.deg2rad(f.pressure_angle_deg)
    k = (1 - c.cam.poisson**2) / c.cam.E_MPa + (1 - c.follower.poisson**2) / c.follower.E_MPa
    sigma = 0.564 * np.sqrt(f.force_N / np.cos(phi) / c.cam_width_mm * (1 / rho_c + 1 / f.roller_radius_mm) / k)
    np.testing.assert_allclose(f.stress_MPa, sigma, rtol=1e-12)  # the same closed form, rearranged
    # and rho_c itself from positions at the scene's (zero) offset
    kin = evaluate(scene.motion.program, 3600)
    x, y = centres(30.0, f.roller_radius_mm, 0.0, kin, "ccw")
    hh = 2 * np.pi / 3600
    d1 = lambda v: (np.roll(v, -1) - np.roll(v, 1)) / (2 * hh)  # noqa: E731
    d2 = lambda v: (np.roll(v, -1) - 2 * v + np.roll(v, 1)) / hh**2  # noqa: E731
    kappa = -(d1(x) * d2(y) - d1(y) * d2(x)) / (d1(x) ** 2 + d1(y) ** 2) ** 1.5
    # second differences at 0.1 deg: O(h^2) ~ 1e-6 relative on ~50 mm radii (O(h) at the joints)
    near = _near_joints(3600, program=scene.motion.program)
    np.testing.assert_allclose(rho_c[~near], (1 / kappa - f.roller_radius_mm)[~near], rtol=1e-4)


# ----------------------------------------------------------------------- the flat limit


@pytest.mark.parametrize("e", [0.0, 2.0])
def test_the_curved_face_tends_to_the_flat_face_as_its_radius_grows(e):
    """Every difference from the flat face's closed forms (SPEC 3: x = s', rho = R_b + s + s'',
    sigma = C / sqrt(rho), sliding omega (R_b + s)) shrinks like 1/R_c: about tenfold per decade,
    and below 1e-4 of its scale at R_c = 1e6 mm."""
    kin, omega = evaluate(PROGRAM, 360), 25.0
    rb = RB
    coeff = jnp.full_like(kin.s, 50.0)  # any positive stress coefficient
    flat_x, flat_y = flat_geo.flat_profile(rb, kin)
    flat = {"contact offset": np.asarray(kin.ds), "pressure angle": np.zeros_like(kin.s),
            "rho": np.asarray(flat_geo.flat_radius_of_curvature(rb, kin)),
            "stress": np.asarray(contact.stress_from_coefficient(coeff, flat_geo.flat_radius_of_curvature(rb, kin))),
            "sliding": omega * (rb + np.asarray(kin.s)) * 1e-3,
            "outline x": np.asarray(flat_x), "outline y": np.asarray(flat_y)}

    def errors(rc):
        g = curved_geo.geometry(rb, rc, e, kin)
        x, y = curved_geo.profile(rb, rc, e, kin)
        rho_eq = rc * (1 - rc * g.pitch_curvature)
        got = {"contact offset": e + curved_geo.face_travel(rb, rc, e, kin), "pressure angle": g.pressure_angle,
               "rho": g.cam_radius_of_curvature, "stress": contact.roller_stress(coeff, g.pressure_angle, rho_eq),
               "sliding": curved_geo.sliding_speed_m_s(rb, rc, e, kin, omega), "outline x": x, "outline y": y}
        return {k: float(np.max(np.abs(np.asarray(got[k]) - flat[k]))) for k in flat}

    e3, e4, e5, e6 = errors(1e3), errors(1e4), errors(1e5), errors(1e6)
    for key in flat:
        scale = max(float(np.max(np.abs(flat[key]))), 1.0)
        assert e6[key] < 1e-4 * scale, (key, e6[key])
        # first order in 1/R_c: tenfold per decade (between 7 and 13: the next order and round-off)
        for a, b in ((e3, e4), (e4, e5)):
            assert 7.0 < a[key] / b[key] < 13.0, (key, a[key], b[key])


@pytest.mark.slow
def test_the_problems_face_need_tends_to_the_flat_faces_width():
    """2 max R_c |sin phi| -> 2 max|s'| (the flat face's L, SPEC 3) as R_c grows (e = 0)."""
    scene = parse_scene(_scene_text(face_radius=100.0, face_width=20.0, design="face_radius_mm = [50.0, 1e7]"))
    problem = P.problem_from_scene(scene)
    flat = 2 * float(jnp.max(jnp.abs(problem.ds_mm)))
    for rc, tol in ((1e5, 1e-3), (1e7, 1e-5)):
        need = float(P.face_width_need(problem, P.Design(30.0, rc, 20.0, 0.0)))
        assert abs(need - flat) < tol * flat, (rc, need, flat)


# --------------------------------------------------------------------- the face's edge


def _scene_text(face_radius=100.0, face_width=20.0, offset=0.0, design="", extra=""):
    return f"""
[motion]
rpm = 240.0
samples = 180
segments = [
  {{ kind = "dwell",  angle_deg = 100 }},
  {{ kind = "rise",   angle_deg = 80, law = "cycloidal", lift_mm = 5.0 }},
  {{ kind = "dwell",  angle_deg = 120 }},
  {{ kind = "return", angle_deg = 60, law = "cycloidal", lift_mm = 5.0 }},
]
[follower]
type = "curved_face"
face_radius_mm = {face_radius}
face_width_mm = {face_width}
offset_mm = {offset}
{extra}
[design]
base_radius_mm = [5.0, 60.0]
face_width_mm = [2.0, 25.0]
alpha = 1.0
gamma = 0.0
{design}
"""


def _max_travel_from_positions(rb, rc, e, program, n=36_000):
    """max |contact x - e| (mm) over the cam angle, from the inverted centre curve's normal."""
    kin = evaluate(program, n)
    th = np.asarray(kin.theta)
    p = np.stack([np.full(n, e), math.sqrt((rb + rc) ** 2 - e**2) + np.asarray(kin.s)])
    x, y = np.cos(-th) * p[0] - np.sin(-th) * p[1], np.sin(-th) * p[0] + np.cos(-th) * p[1]
    tx, ty = to_fixed(np.roll(x, -1) - np.roll(x, 1), np.roll(y, -1) - np.roll(y, 1), th, "ccw")
    return float(np.max(np.abs(rc * ty / np.hypot(tx, ty))))  # R_c |n_x|


@pytest.mark.slow  # a design run (compiles)
def test_a_narrow_face_sets_the_smallest_cam_where_the_contact_reaches_its_edge():
    scene = parse_scene(_scene_text(face_radius=100.0, face_width=8.0))
    follower = camjax.followers.of(scene)
    arrays = camjax.evaluate.scene_arrays(scene)
    m = follower.min_base_radius(scene, arrays)
    assert m.binding == "face_travel"
    # at that R_b the contact reaches the edge W/2 = 4 mm, by positions alone (to the differences'
    # O(h^2) ~ 1e-8 relative and the exact extrema's solve); a little smaller and it runs off
    at = _max_travel_from_positions(m.radius_mm, 100.0, 0.0, scene.motion.program)
    assert abs(at - 4.0) < 1e-6, at
    assert _max_travel_from_positions(m.radius_mm - 0.01, 100.0, 0.0, scene.motion.program) > 4.0 + 1e-4


@pytest.mark.slow
def test_a_wide_face_leaves_the_smallest_cam_to_the_other_limits():
    scene = parse_scene(_scene_text(face_radius=100.0, face_width=60.0))
    grid = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, extrema="grid"))
    follower = camjax.followers.of(scene)
    m = follower.min_base_radius(scene, camjax.evaluate.scene_arrays(scene))
    g = follower.min_base_radius(grid, camjax.evaluate.scene_arrays(grid))
    assert m.binding == g.binding == "undercut"
    # the smallest convex cam-surface radius is 0 (min_curvature_radius_mm) there, from positions:
    # 1/kappa - R_c with kappa by second differences at 0.01 deg, whose error ~1e-8 1/mm is
    # R_c^2 1e-8 = 1e-4 mm in rho_c; 0.2 mm smaller and the face undercuts the cam. With grid
    # extrema on the scene's samples; with exact extrema (the default) at every angle (all 36 000
    # dense points), which takes a larger radius than the samples'
    n = 36_000
    every = n // 180  # the scene's samples among the dense ones

    def rho_c_min(rb, stride):
        kin = evaluate(scene.motion.program, n)
        x, y = centres(rb, 100.0, 0.0, kin, "ccw")
        h = 2 * np.pi / n
        d1 = lambda v: (np.roll(v, -1) - np.roll(v, 1)) / (2 * h)  # noqa: E731
        d2 = lambda v: (np.roll(v, -1) - 2 * v + np.roll(v, 1)) / h**2  # noqa: E731
        kappa = -(d1(x) * d2(y) - d1(y) * d2(x)) / (d1(x) ** 2 + d1(y) ** 2) ** 1.5
        return float(np.min(1 / kappa[::stride] - 100.0))

    assert abs(rho_c_min(g.radius_mm, every)) < 1e-3
    assert abs(rho_c_min(m.radius_mm, 1)) < 1e-3
    assert m.radius_mm > g.radius_mm and rho_c_min(g.radius_mm, 1) < -1e-3
    assert rho_c_min(m.radius_mm - 0.2, 1) < -0.1
    # the face's edge is far: the contact stays well inside W/2 = 30 mm
    assert _max_travel_from_positions(m.radius_mm, 100.0, 0.0, scene.motion.program) < 20.0


def _flat_rho_min_from_positions(rb, n=36_000):
    """The flat-face cam's least radius of curvature (mm) at base radius ``rb``, from positions only:
    the cam is the envelope of the face's lines n(theta) . P = R_b + s(theta), n = (sin, cos) (the
    face at every cam angle, from the reference motion's s alone); consecutive lines meet at the
    envelope's corners P_{i+1/2}, and the arc between two corners over the step h is rho(theta_i)
    (signed along the line's direction t = (cos, -sin): a loop, rho < 0, runs backwards).
    Rounding: corners to ~1e-11 mm (lines h = 0.01 deg apart), rho to ~1e-7 mm."""
    th_deg = np.arange(n) * 360.0 / n
    s, _, _ = reference_motion(th_deg)
    th, h = np.radians(th_deg), 2 * np.pi / n
    p = rb + s
    sn, cs = np.sin(th), np.cos(th)
    sn1, cs1, p1 = np.roll(sn, -1), np.roll(cs, -1), np.roll(p, -1)
    det = sn * cs1 - cs * sn1  # lines i and i + 1: [[sin_i, cos_i], [sin_i+1, cos_i+1]] P = [p_i, p_i+1]
    corner = np.stack([(p * cs1 - p1 * cs) / det, (sn * p1 - sn1 * p) / det])  # P_{i+1/2}
    arc = corner - np.roll(corner, 1, axis=1)  # P_{i+1/2} - P_{i-1/2}
    return float(np.min((arc[0] * cs - arc[1] * sn) / h))


@pytest.mark.slow  # the curved face's sizing at three radii (the program the test above compiles)
def test_the_flat_faces_smallest_cam_honours_its_curvature_limit_as_the_curved_face_does():
    """min_curvature_radius_mm = 2 on the reference motion: the flat face's smallest admissible
    R_b keeps the cam's radius of curvature >= 2 mm and no more, against (a) a root of the least
    radius of curvature from positions (the envelope of the face's lines, reference motion's s
    alone), within 1e-4 mm (measured 4e-6: the 0.01-deg grid misses the least value by up to
    rho'' (h/2)^2 / 2 ~ 3e-5 mm, the corners' rounding ~1e-7 mm); (b) the curved face's at the same limit
    as R_c grows: it approaches the flat face's as c / R_c (c ~ 808 mm^2 here), so Richardson's
    extrapolation of R_c = 1e5 and 1e6 mm lands on the flat face's value to 1e-5 mm (the next
    term, ~c' / R_c^2, and the sizings' tolerances), while R_c = 1e6 alone is 8e-4 mm short."""
    from scipy.optimize import brentq

    limit = "min_curvature_radius_mm = 2.0"
    flat_text = _scene_text(extra=limit).replace('type = "curved_face"\nface_radius_mm = 100.0\n'
                                                 'face_width_mm = 20.0\noffset_mm = 0.0\n', 'type = "flat"\n')
    flat_text = flat_text[:flat_text.index("[design]")]
    flat_scene = parse_scene(flat_text)
    assert flat_scene.follower.type == "flat" and flat_scene.follower.min_curvature_radius_mm == 2.0
    flat = camjax.followers.of(flat_scene).min_base_radius(flat_scene, camjax.evaluate.scene_arrays(flat_scene))
    assert flat.binding == "curvature"
    # (a) from positions: the R_b at which the least radius of curvature is the limit
    brute = brentq(lambda rb: _flat_rho_min_from_positions(rb) - 2.0, 20.0, 35.0, xtol=1e-9)
    assert abs(flat.radius_mm - brute) < 1e-4, (flat.radius_mm, brute)
    assert _flat_rho_min_from_positions(flat.radius_mm) == pytest.approx(2.0, abs=1e-4)
    # (b) the curved face at the same limit, its face wide enough that the limit binds
    curved = {}
    for rc in (1e5, 1e6):
        scene = parse_scene(_scene_text(face_radius=rc, face_width=30.0, extra=limit))
        m = camjax.followers.of(scene).min_base_radius(scene, camjax.evaluate.scene_arrays(scene))
        assert m.binding == "undercut", m
        curved[rc] = m.radius_mm
    assert 1e-4 < flat.radius_mm - curved[1e6] < 1e-3  # short by c / R_c, ...
    assert (flat.radius_mm - curved[1e5]) / (flat.radius_mm - curved[1e6]) == pytest.approx(10.0, rel=1e-2)
    extrapolated = curved[1e6] + (curved[1e6] - curved[1e5]) / 9.0  # ... which Richardson removes
    assert abs(extrapolated - flat.radius_mm) < 1e-5, (extrapolated, flat.radius_mm)


@pytest.mark.slow  # a design run (compiles)
def test_the_problem_and_the_run_report_a_face_too_narrow():
    scene = parse_scene(_scene_text(face_radius=100.0, face_width=8.0))
    problem = P.problem_from_scene(scene)
    w = camjax.family.weights_of(1.0, 0.0)
    narrow, wide = P.Design(25.0, 100.0, 6.0, 0.0), P.Design(25.0, 100.0, 20.0, 0.0)
    need = 2 * _max_travel_from_positions(25.0, 100.0, 0.0, scene.motion.program)
    assert 6.0 < need < 20.0
    ev = P.evaluate(problem, w, narrow)
    # on the 180 samples: within the grid's miss of the continuous max (|f''| h^2 / 8 ~ 1e-3 mm)
    assert abs(float(ev.violation.face_travel) - (need / 2 - 3.0)) < 2e-3
    assert "face_travel" in P.violated_constraints(problem, ev.violation)
    assert "face_travel" not in P.violated_constraints(problem, P.evaluate(problem, w, wide).violation)
    # the solvers' coordinates floor W at the need: every design they see keeps the contact on the face
    floored = P.from_unit(problem, P.to_unit(problem, narrow))
    assert abs(float(floored.face_width_mm) - float(P.face_width_need(problem, narrow))) < 1e-12
    # and a run drawn at a cam too small for the face says so: the scene's 8 mm face at R_b = 15 mm,
    # whose contact runs past the edge by positions alone ([design] left out: a solve would not change
    # the drawing at 15 mm and would compile a program of its own; the sizing's programs are the
    # ones the narrow-face test above compiles)
    assert 2 * _max_travel_from_positions(15.0, 100.0, 0.0, scene.motion.program) > 8.0
    text = _scene_text(face_radius=100.0, face_width=8.0)
    run = camjax.run_design(parse_scene(text[: text.index("[design]")]), base_radius_mm=15.0)
    assert any(v.constraint == "face_width" for v in run.violations)


def test_the_scene_refuses_a_face_wider_than_its_circle():
    with pytest.raises(SceneError, match="follower.face_width_mm"):
        parse_scene(_scene_text(face_radius=5.0, face_width=12.0))
    with pytest.raises(SceneError, match="design.face_width_mm"):
        parse_scene(_scene_text(face_radius=10.0, face_width=12.0, design="face_radius_mm = [10.0, 50.0]"))
    with pytest.raises(SceneError, match="follower.roller_radius_mm"):
        parse_scene(_scene_text(extra="roller_radius_mm = 5.0"))


# ------------------------------------------------------------------------ end to end


@pytest.mark.slow
@pytest.mark.parametrize("solver,mode", [("gradient", "global"), ("ga", "global"), ("hybrid", "global"),
                                         ("gradient", "pointwise")])
def test_every_solver_designs_a_feasible_cam_whose_face_is_just_wide_enough(solver, mode):
    from camjax.solvers.base import solve

    # the built-in scene at 90 samples, as tests/cache_matrix.py designs it, R_c in [40, 200]; the
    # programs are this test's own: the matrix's runs compile the same computations as exported
    # modules (`jit(call)`), which XLA's compilation cache keys apart (a compile ledger of the whole
    # suite: this test's four solve programs compiled here, none loaded)
    text = builtin_scene_text("curved-face").replace("face_radius_mm = [30.0, 300.0]",
                                                      "face_radius_mm = [40.0, 200.0]")
    scene = with_samples(parse_scene(text), MATRIX_SAMPLES)
    problem = P.problem_from_scene(scene)
    sol = solve(problem, (1.0, 0.0), mode=mode, solver=solver, seed=0)
    d = sol.design
    assert bool(sol.feasible), (solver, mode, sol.violation)
    if mode == "global":
        # W is only in the size and the face constraint: the optimum's face is the need, from
        # positions (exact extrema: the need off the grid)
        need = 2 * _max_travel_from_positions(float(d.base_radius_mm), float(d.face_radius_mm), 0.0,
                                              scene.motion.program)
        low = scene.design.bounds("face_width_mm")[0]
        assert abs(float(d.face_width_mm) - max(need, low)) < 1e-5, (solver, float(d.face_width_mm), need)


@pytest.mark.slow
def test_a_huge_fixed_face_radius_designs_the_flat_faces_cam():
    """The reference case (SPEC 5) with R_c fixed at 1e5 mm: the design tends to the flat face's
    (same objective as R_c -> infinity); R_b and W within 1e-3 relative of R_b and L. The flat
    face's optimum in closed form (bisection on R_b, then the exact polish: the solvers' reference,
    the gradient solver's design to the last bit on this scene), a smaller program than a solve."""
    from camjax.followers.flat.optimum import global_optimum
    from camjax.solvers.base import problem_from_scene, solve

    flat_problem = problem_from_scene(camjax.load_scene("default"))
    flat = jax.jit(global_optimum)(flat_problem, camjax.family.weights_of(1.0, 1.0))
    text = builtin_scene_text("curved-face").replace("face_radius_mm = [30.0, 300.0]",
                                                                   "face_radius_mm = 1e5")
    scene = parse_scene(text)
    curved = solve(problem_from_scene(scene), (1.0, 1.0)).design
    assert abs(float(curved.base_radius_mm) - float(flat.base_radius_mm)) < 1e-3 * float(flat.base_radius_mm)
    assert abs(float(curved.face_width_mm) - float(flat.face_width_mm)) < 1e-3 * float(flat.face_width_mm)


@pytest.mark.slow
def test_sweep_and_check_extremes_run_on_the_curved_face(tmp_path):
    import json

    from camjax import cli

    # one weighting per compiled call at 90 samples: the program of the built-in scene's design that
    # tests/cache_matrix.py runs (with the tests' compilation cache it compiles once in the suite)
    assert cli.main(["sweep", "curved-face", "--out", str(tmp_path / "sweep"), "--alpha", "1",
                     "--gamma", "0.1,1,10", "--samples", str(MATRIX_SAMPLES), "--chunk-size", "1"]) in (0, 3)
    front = json.loads((tmp_path / "sweep" / "pareto.json").read_text())
    assert front
    assert cli.main(["check-extremes", "curved-face", "--out", str(tmp_path / "ext"), "--samples",
                     str(MATRIX_SAMPLES)]) == 0
