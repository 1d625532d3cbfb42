"""Oscillating curved-face follower: its geometry against computations that do not use its formulas.

- the cam outline against the brute-force envelope of the face's circle, placed at every cam angle
  from the swing s(theta) alone (kinematic inversion: the circle's centre at the arm's end);
- pressure angle, the contact's travel on the face, the pitch curve's curvature and the sliding
  speed from positions only (finite differences of the inverted centre curve, of the cam's rotation
  and of the arm's swing);
- the oscillating roller of R_f = R_c: the same pitch geometry, outline, loads and stress, and the
  same design constraints;
- the face-travel constraint: the sizing binds on it exactly where the contact reaches the face's
  edge when the face is narrow, the problem and the run report a face too narrow, a wide face
  leaves the pressure angle binding;
- scene errors name the key; every solver designs the built-in scene (slow).
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import cli
from camjax.errors import SceneError
from camjax.followers import get
from camjax.followers.oscillating_curved_face import geometry as curved_geo
from camjax.followers.oscillating_curved_face import problem as P
from camjax.followers.oscillating_roller import problem as roller_problem
from camjax.laws import get_law
from camjax.program import MotionProgram, Segment, evaluate
from camjax.scene import builtin_scene_text, parse_scene

SWING = math.radians(20.0)
# rise-dwell-return-dwell with an asymmetric pair of laws, so that the rotation matters
PROGRAM = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), SWING), Segment("dwell", 60),
                                       Segment("return", 100, get_law("cycloidal"), SWING), Segment("dwell", 80)])
D, L, RC, RB = 80.0, 60.0, 20.0, 25.0  # a convex cam: no undercut, a single contact everywhere
ROTATIONS = ("ccw", "cw")


def psi0(rb=RB, rc=RC, d=D, l=L):
    """The arm's start angle from the triangle pivot - cam centre - circle centre (law of cosines)."""
    return math.acos((d**2 + l**2 - (rb + rc) ** 2) / (2 * d * l))


def circle_centres(kin, rotation, rb=RB, rc=RC):
    """The face circle's centre C = (d - l cos psi, l sin psi) seen from the cam (kinematic
    inversion, NumPy): the fixed-frame point x is the cam point R(-sigma theta) x."""
    th, psi = np.asarray(kin.theta), psi0(rb, rc) + np.asarray(kin.s)
    cx, cy = D - L * np.cos(psi), L * np.sin(psi)
    a = -th if rotation == "ccw" else th
    return np.cos(a) * cx - np.sin(a) * cy, np.sin(a) * cx + np.cos(a) * cy


def to_fixed(x, y, th, rotation):
    """Cam-frame points at cam angle ``th`` -> the fixed frame."""
    a = th if rotation == "ccw" else -th
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def from_positions(rotation, n=36_000):
    """(kin, psi, circle centre, contact point, unit normal towards the centre, pitch curvature),
    fixed frame, by central differences of the inverted centre curve only."""
    kin = evaluate(PROGRAM, n)
    x, y = circle_centres(kin, rotation)
    h = 2 * np.pi / n
    d1 = lambda v: (np.roll(v, -1) - np.roll(v, 1)) / (2 * h)  # noqa: E731
    d2 = lambda v: (np.roll(v, -1) - 2 * v + np.roll(v, 1)) / h**2  # noqa: E731
    th = np.asarray(kin.theta)
    tx, ty = to_fixed(d1(x), d1(y), th, rotation)
    norm = np.hypot(tx, ty)
    nx, ny = -ty / norm, tx / norm
    cx, cy = to_fixed(x, y, th, rotation)
    flip = np.where(nx * cx + ny * cy < 0, -1.0, 1.0)  # away from the cam centre (a convex cam)
    nx, ny = nx * flip, ny * flip
    turn = -1.0 if rotation == "ccw" else 1.0  # a ccw cam traces its pitch curve clockwise
    kappa = turn * (d1(x) * d2(y) - d1(y) * d2(x)) / (d1(x) ** 2 + d1(y) ** 2) ** 1.5
    psi = psi0() + np.asarray(kin.s)
    return kin, psi, (cx, cy), (cx - RC * nx, cy - RC * ny), (nx, ny), kappa


def _near_joints(n, width=2):
    """Samples within ``width`` of a joint, where a jump of s''' puts differences O(h) off."""
    near = np.zeros(n, bool)
    for start in PROGRAM.start_deg:
        near[(np.arange(-width, width + 1) + round(start * n / 360)) % n] = True
    return near


# ---------------------------------------------------------------------------- geometry


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ROTATIONS)
def test_outline_is_the_brute_force_envelope_of_the_face_circle(rotation):
    """Every outline point's distance from the cam centre is the first hit, along its ray, of the
    face's circle at any of 72 000 cam angles (parabola through the best three), to 1e-7 mm."""
    kin = evaluate(PROGRAM, 120)
    x, y = (np.asarray(v) for v in curved_geo.profile(D, L, RC, RB + RC, kin, rotation))
    cx, cy = circle_centres(evaluate(PROGRAM, 72_000), rotation)
    r = np.hypot(x, y)
    dx, dy = x / r, y / r
    proj = dx[:, None] * cx[None, :] + dy[:, None] * cy[None, :]
    miss = cx[None, :] ** 2 + cy[None, :] ** 2 - proj**2  # squared distance of the centre from the ray
    near = proj - np.sqrt(np.maximum(RC**2 - miss, 0.0))  # where the ray enters the circle
    hit = np.where((miss <= RC**2) & (near > 0), near, np.inf)
    j = np.argmin(hit, axis=1)
    rows = np.arange(len(r))
    a, b, c = hit[rows, j - 1], hit[rows, j], hit[rows, (j + 1) % hit.shape[1]]
    brute = b - (a - c) ** 2 / (8 * (a - 2 * b + c))  # the parabola's vertex through the three
    # the hit distance is smooth in the circle's angle: the vertex errs by O(h^3) at h = 0.005 deg
    np.testing.assert_allclose(r, brute, rtol=0, atol=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ROTATIONS)
def test_pressure_angle_face_travel_and_curvature_from_positions(rotation):
    n = 36_000
    kin, psi, (cx, cy), (px, py), (nx, ny), kappa_fd = from_positions(rotation, n)
    g = curved_geo.geometry(D, L, RC, RB + RC, kin, rotation)
    assert np.all(np.asarray(g.cam_radius_of_curvature) > 0)  # the brute force assumes a convex cam
    m = np.stack([np.sin(psi), np.cos(psi)])  # the direction the circle's centre moves in
    u = np.stack([-np.cos(psi), np.sin(psi)])  # along the arm, away from the pivot
    # phi: the normal's angle from the centre's path, positive when it leans away from the pivot
    phi_fd = np.arctan2(nx * u[0] + ny * u[1], nx * m[0] + ny * m[1])
    # central differences at 0.01 deg: O(h^2) = 3e-9 relative times |P'''|/|P'| ~ 10
    np.testing.assert_allclose(g.pressure_angle, phi_fd, rtol=0, atol=1e-7)
    # the contact's place on the face, off the face's axis (the line through C along m), towards
    # the pivot: -(P - C) . u (lengths of ~100 mm, normals to 1e-7: 1e-5 mm)
    travel_fd = -((px - cx) * u[0] + (py - cy) * u[1])
    np.testing.assert_allclose(curved_geo.face_travel(D, L, RC, RB + RC, kin, rotation), travel_fd, rtol=0, atol=1e-5)
    x, y = (np.asarray(v) for v in curved_geo.profile(D, L, RC, RB + RC, kin, rotation))
    fx, fy = to_fixed(x, y, np.asarray(kin.theta), rotation)
    np.testing.assert_allclose(fx, px, rtol=0, atol=1e-5)
    np.testing.assert_allclose(fy, py, rtol=0, atol=1e-5)
    # the pitch curve's curvature from second differences (O(h^2) and round-off, ~1e-8 1/mm; O(h)
    # across a jump of s''')
    near = _near_joints(n)
    np.testing.assert_allclose(np.asarray(g.pitch_curvature)[~near], kappa_fd[~near], rtol=0, atol=1e-7)
    np.testing.assert_allclose(np.asarray(g.cam_radius_of_curvature)[~near], (1.0 / kappa_fd - RC)[~near],
                               rtol=1e-5)


@pytest.mark.parametrize("rotation", ROTATIONS)
def test_sliding_speed_is_the_relative_speed_of_cam_and_face_at_the_contact(rotation):
    """The cam's material point at the contact turns with the cam (sigma omega about the centre),
    the face's with the arm (-s' omega about the pivot, ccw positive; the arm's angle from +x is
    pi - psi): their relative velocity is tangent (no separation) and its length is the sliding speed."""
    n, omega = 36_000, 25.0
    kin, psi, _, (px, py), (nx, ny), _ = from_positions(rotation, n)
    sigma = 1.0 if rotation == "ccw" else -1.0
    h = 2 * np.pi / n
    ds_fd = (np.roll(np.asarray(kin.s), -1) - np.roll(np.asarray(kin.s), 1)) / (2 * h)  # s' from s alone
    cam_v = sigma * omega * np.stack([-py, px])
    arm_rate = -ds_fd * omega
    face_v = arm_rate * np.stack([-py, px - D])
    rel = face_v - cam_v
    np.testing.assert_allclose(rel[0] * nx + rel[1] * ny, 0.0, atol=1e-6 * omega * 100)  # tangent
    speed = np.asarray(curved_geo.sliding_speed_m_s(D, L, RC, RB + RC, kin, omega, rotation))
    # mm/s -> m/s; differences at 0.01 deg (1e-7 of ~1e3 mm/s) and normals to 1e-7
    near = _near_joints(n)
    np.testing.assert_allclose(speed[~near], np.hypot(*rel)[~near] * 1e-3, rtol=0, atol=1e-7)
    # on the dwell at s = 0 the face stands still over the cam's surface: omega R_b
    rest = (np.abs(np.asarray(kin.s)) < 1e-15) & (np.abs(np.asarray(kin.ds)) < 1e-15)
    np.testing.assert_allclose(speed[rest], omega * RB * 1e-3, rtol=1e-12)


# ------------------------------------------------------------------ the roller of R_f = R_c


# 90 samples, the count at which tests/cache_matrix.py designs this type's example scene (the same
# motion): with the tests' compilation cache its design and drawing programs compile once in the suite
SAMPLES = 90
ROLLER_SCENE = builtin_scene_text("oscillating-roller").replace("samples = 360", f"samples = {SAMPLES}")


def _pair(rotation="ccw"):
    """(curved-face scene, oscillating-roller scene of R_f = R_c): the same rocker and loads."""
    roller = parse_scene(ROLLER_SCENE.replace('rotation = "ccw"', f'rotation = "{rotation}"')
                         .replace("roller_radius_mm = 8.0", f"roller_radius_mm = {RC}"))
    text = (ROLLER_SCENE.replace('rotation = "ccw"', f'rotation = "{rotation}"')
            .replace('type = "oscillating_roller"', 'type = "oscillating_curved_face"')
            .replace("roller_radius_mm = 8.0", f"face_radius_mm = {RC}\nface_width_mm = {2 * RC}")
            .replace("pivot_distance_mm = [65.0, 110.0]",
                     f"pivot_distance_mm = [65.0, 110.0]\nface_width_mm = [1.0, {2 * RC}]"))
    return parse_scene(text), roller


@pytest.mark.parametrize("rotation", ROTATIONS)
def test_the_pitch_geometry_loads_and_stress_are_the_oscillating_rollers_of_r_f_equal_r_c(rotation):
    curved, roller = _pair(rotation)
    arrays = camjax.evaluate.scene_arrays(curved)
    a = get("oscillating_curved_face").evaluate(curved, arrays.kin, arrays.cam_speed_rad_s, RB)
    b = get("oscillating_roller").evaluate(roller, arrays.kin, arrays.cam_speed_rad_s, RB)
    for name in ("profile_x_mm", "profile_y_mm", "pitch_x_mm", "pitch_y_mm", "pressure_angle_deg", "rho_mm",
                 "pitch_rho_mm", "undercut_margin_mm", "arm_angle_deg", "pivot_torque_Nm", "contact_force_N",
                 "torque_Nm", "stress_MPa"):
        # the same closed forms of the same numbers: equal to round-off
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-13, atol=1e-12, err_msg=name)


def test_the_design_constraints_are_the_oscillating_rollers_of_r_f_equal_r_c():
    curved, roller = _pair()
    pc, pr = P.problem_from_scene(curved), roller_problem.problem_from_scene(roller)
    design = P.Design(*(jnp.asarray(v) for v in (RB, RC, 2 * RC, D, L)))
    as_roller = roller_problem.Design(*(jnp.asarray(v) for v in (RB, RC, D, L)))
    gc, gr = P.constraints(pc, design), roller_problem.constraints(pr, as_roller)
    for name in ("reach", "pressure_angle", "undercut", "stress"):
        np.testing.assert_allclose(getattr(gc, name), getattr(gr, name), rtol=1e-13, atol=1e-12, err_msg=name)
    np.testing.assert_allclose(P.peak_stress(pc, design), roller_problem.peak_stress(pr, as_roller), rtol=1e-13)
    # the face's own constraint from the pressure angle: R_c |sin phi| - W / 2
    phi = roller_problem.pressure_angle(pr, as_roller)
    np.testing.assert_allclose(gc.face_travel, RC * np.abs(np.sin(phi)) - RC, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------- the face's width


def _scene(width, radius=RC, limit=30.0, samples=SAMPLES):
    text = (ROLLER_SCENE.replace('type = "oscillating_roller"', 'type = "oscillating_curved_face"')
            .replace("roller_radius_mm = 8.0", f"face_radius_mm = {radius}\nface_width_mm = {width}")
            .replace("max_pressure_angle_deg = 30.0", f"max_pressure_angle_deg = {limit}")
            .replace(f"samples = {SAMPLES}", f"samples = {samples}"))
    return parse_scene(text.split("\n[design]")[0])


def test_a_narrow_face_binds_the_sizing_where_the_contact_reaches_its_edge():
    """W = 16 mm on R_c = 20 mm: the edge at asin(0.4) = 23.6 deg < 30 deg. At the smallest cam the
    contact reaches the edge (max |R_c sin phi| = W / 2) and nowhere passes it."""
    scene = _scene(16.0)
    follower = get("oscillating_curved_face")
    kin = camjax.evaluate.scene_arrays(scene).kin
    sizing = follower.sizing(scene, kin)
    assert sizing.binding == "face_travel"
    travel = curved_geo.face_travel(D, L, RC, sizing.min_base_radius_mm + RC, kin, scene.motion.rotation)
    # the bisection in the arm angle ends at float64 resolution: 1e-9 mm leaves its round-off
    np.testing.assert_allclose(np.max(np.abs(travel)), 8.0, rtol=0, atol=1e-9)
    # a wide face leaves the pressure angle binding, at a smaller cam
    wide = follower.sizing(_scene(39.0), kin)
    assert wide.binding == "pressure_angle" and wide.min_base_radius_mm < sizing.min_base_radius_mm


@pytest.mark.slow
def test_a_face_too_narrow_is_reported_by_the_problem_and_the_run():
    scene = _scene(16.0)
    run = camjax.run_design(scene, base_radius_mm=20.0)  # below the smallest cam the face admits (24.6 mm)
    assert [v.constraint for v in run.violations] == ["face_width"]
    assert "runs off the face" in run.violations[0].message
    assert np.abs(run.curves.face_travel_mm).max() > 8.0
    data = get("oscillating_curved_face").report(scene, run)
    assert data["evaluated"]["face_travel_ok"] is False and data["evaluated_at"]["feasible"] is False
    # the design problem: the same design with W = 12 mm breaks face_travel by max R_c |sin phi| - 6
    curved, _ = _pair()
    pc = P.problem_from_scene(curved)
    design = P.Design(*(jnp.asarray(v) for v in (RB, RC, 12.0, D, L)))
    ev = P.evaluate(pc, camjax.family.weights_of(1.0, 1.0), design)
    need = float(P.face_width_need(pc, design))
    np.testing.assert_allclose(float(ev.violation.face_travel), need / 2 - 6.0, rtol=1e-12)
    assert "face_travel" in P.violated_constraints(pc, ev.violation)


# ---------------------------------------------------------------------------- scene and solvers


@pytest.mark.parametrize("change,key", [
    (("face_width_mm = 16.0", "face_width_mm = 41.0"), "face_width_mm"),
    (("face_radius_mm = 20.0", "face_radius_mm = 20.0\nroller_radius_mm = 8.0"), "roller_radius_mm"),
    (("face_radius_mm = 20.0", "face_radius_mm = -2.0"), "face_radius_mm"),
])
def test_bad_follower_keys_are_refused_by_name(change, key):
    text = builtin_scene_text("oscillating-curved-face").replace(*change)
    with pytest.raises(SceneError, match=f"follower.{key}"):
        parse_scene(text)


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["gradient", "ga", "hybrid"])
def test_every_solver_designs_the_built_in_scene(solver, tmp_path, capsys):
    """`camjax design` with each solver, global and pointwise: finite, in the box; global designs
    feasible (the contact on the face: 2 max |R_c sin phi| <= W)."""
    for mode in ("global", "pointwise"):
        out = tmp_path / f"{solver}-{mode}"
        code = cli.main(["design", "oscillating-curved-face", "--out", str(out), "--solver", solver, "--mode", mode,
                         "--samples", str(SAMPLES), "--dpi", "30"])
        assert code in (0, 3)
        import json

        data = json.loads((out / "result.json").read_text())
        d = data["design"]
        for var in get("oscillating_curved_face").variables:
            lo, hi = d[f"{var[:-3]}_bounds_mm"]
            assert lo - 1e-9 <= d[var] <= hi + 1e-9, (solver, mode, var)
        if mode == "global":
            assert code == 0 and d["feasible"], (solver, d["violated"])
            assert d["face_travel_max_mm"] <= 0.5 * d["face_width_mm"] + 1e-6
