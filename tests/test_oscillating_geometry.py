"""Oscillating (rocker) follower geometry, checked against computations that do not use its closed forms:
positions only (kinematic inversion + finite differences), the envelope of the face lines, a follower
riding on the exported outline, the translating follower as the long-arm limit, dense scans of the
sizing, finite differences through the design."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from outline import max_over_outline, turn

from camjax.followers.flat import geometry as flat_geo
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.laws import get_law
from camjax.program import MotionProgram, Segment, evaluate, motion_at

LIFT = math.radians(20.0)
# rise-dwell-return-dwell with an asymmetric pair of laws, so that the rotation matters
PROGRAM = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), LIFT), Segment("dwell", 60),
                                       Segment("return", 100, get_law("cycloidal"), LIFT), Segment("dwell", 80)])
ROLLER = dict(d=80.0, l=60.0, rf=8.0, rp=35.0)  # pivot distance, arm, roller, prime radius (mm)
FLAT = dict(d=120.0, f=10.0, rb=95.0)  # pivot distance, face offset, base radius (mm)
N_DENSE = 36_000


def sigma_of(rotation):
    return 1.0 if rotation == "ccw" else -1.0


def to_cam(x, y, theta, rotation):
    """Follower frame -> cam frame in NumPy: a cam turning by theta (ccw) sees the fixed point at R(-theta) x."""
    a = -sigma_of(rotation) * theta
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def to_follower(x, y, theta, rotation):
    a = sigma_of(rotation) * theta
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def periodic_differences(n):
    h = 2 * np.pi / n
    d1 = lambda v: (np.roll(v, -1) - np.roll(v, 1)) / (2 * h)  # noqa: E731
    d2 = lambda v: (np.roll(v, -1) - 2 * v + np.roll(v, 1)) / h**2  # noqa: E731
    return d1, d2


def near_joints(n, width=3):
    mask = np.zeros(n, bool)
    for start in PROGRAM.start_deg:
        mask[(np.arange(-width, width + 1) + round(start * n / 360)) % n] = True
    return mask


def roller_pitch_from_positions(d, l, rp, kin, rotation):
    """Roller centre of the fixed frame seen from the cam, from the triangle O-A-C only (NumPy)."""
    psi = math.acos((d**2 + l**2 - rp**2) / (2 * d * l)) + np.asarray(kin.s)
    cx, cy = d - l * np.cos(psi), l * np.sin(psi)
    return (cx, cy), to_cam(cx, cy, np.asarray(kin.theta), rotation)


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_roller_pressure_angle_from_positions_only(rotation):
    d, l, rp = ROLLER["d"], ROLLER["l"], ROLLER["rp"]
    kin = evaluate(PROGRAM, N_DENSE)
    (cx, cy), (x, y) = roller_pitch_from_positions(d, l, rp, kin, rotation)
    d1, _ = periodic_differences(N_DENSE)
    # tangent of the pitch curve in the cam frame, turned back into the fixed frame
    tx, ty = to_follower(d1(x), d1(y), np.asarray(kin.theta), rotation)
    # the normal is perpendicular to the tangent, the roller's path perpendicular to the arm A -> C:
    # phi is the angle between the tangent and the arm; its sign says whether the normal force
    # pulls the arm away from the pivot (the tangent's part along the path, oriented by the
    # direction the curve is traced: clockwise for a ccw cam)
    ax, ay = cx - d, cy
    along_path = tx * ay - ty * ax  # T . (l sin psi, l cos psi), the path direction
    along_arm = tx * ax + ty * ay
    phi_fd = np.arctan2(sigma_of(rotation) * along_path, np.abs(along_arm))
    psi0 = rocker_roller_geo.arm_start_angle(rp, d, l)
    phi = np.asarray(rocker_roller_geo.oscillating_roller_pressure_angle(d, l, psi0, kin, rotation))
    # central differences at 0.01 deg: O(h^2) ~ 3e-9 relative in the tangent; measured 2.7e-8 rad
    np.testing.assert_allclose(phi, phi_fd, rtol=0, atol=1e-7)
    assert np.degrees(np.abs(phi).max()) > 30  # a steep cam: the check covers large angles


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_roller_pitch_curvature_from_positions_only(rotation):
    d, l, rp = ROLLER["d"], ROLLER["l"], ROLLER["rp"]
    kin = evaluate(PROGRAM, N_DENSE)
    _, (x, y) = roller_pitch_from_positions(d, l, rp, kin, rotation)
    d1, d2 = periodic_differences(N_DENSE)
    # ccw cams trace their pitch curve clockwise: convex means a negative cross product there
    turn = -sigma_of(rotation)
    kappa_fd = turn * (d1(x) * d2(y) - d1(y) * d2(x)) / (d1(x) ** 2 + d1(y) ** 2) ** 1.5
    psi0 = rocker_roller_geo.arm_start_angle(rp, d, l)
    kappa = np.asarray(rocker_roller_geo.oscillating_roller_pitch_curvature(d, l, psi0, kin, rotation))
    joint = near_joints(N_DENSE)
    # second differences: O(h^2) truncation + eps |P| / h^2 round-off ~ 1e-8 1/mm away from the
    # joints; across a joint s''' of the 3-4-5 jumps and the difference is O(h) off
    np.testing.assert_allclose(kappa_fd[~joint], kappa[~joint], rtol=0, atol=1e-7)
    np.testing.assert_allclose(kappa_fd, kappa, rtol=0, atol=1e-5)
    if rotation == "cw":
        assert kappa.min() < 0 < kappa.max()  # concave stretches: both signs are tested
    g = rocker_roller_geo.oscillating_roller_geometry(d, l, ROLLER["rf"], rp, kin, rotation)
    np.testing.assert_allclose(g.pitch_radius_of_curvature * kappa, 1.0, rtol=1e-12)
    np.testing.assert_allclose(g.cam_radius_of_curvature, 1 / kappa - ROLLER["rf"], rtol=1e-12)


def test_roller_prime_circle_and_dwell():
    d, l, rp, rf = ROLLER["d"], ROLLER["l"], ROLLER["rp"], ROLLER["rf"]
    kin = evaluate(PROGRAM, 360)
    psi0 = rocker_roller_geo.arm_start_angle(rp, d, l)
    x, y = rocker_roller_geo.oscillating_roller_pitch_curve(d, l, rp, kin)
    r = np.hypot(x, y)
    np.testing.assert_allclose(r[0], rp, rtol=1e-14)  # s = 0 at theta = 0: on the prime circle
    dwell = np.asarray(kin.s) == 0.0
    np.testing.assert_allclose(r[dwell], rp, rtol=1e-14)
    # on a dwell the outline is the base circle R_p - R_f, and its curvature 1 / R_p
    px, py = rocker_roller_geo.oscillating_roller_profile(d, l, rf, rp, kin)
    np.testing.assert_allclose(np.hypot(px, py)[dwell], rp - rf, rtol=1e-13)
    kappa = rocker_roller_geo.oscillating_roller_pitch_curvature(d, l, psi0, kin)
    np.testing.assert_allclose(np.asarray(kappa)[dwell], 1 / rp, rtol=1e-13)
    # a rise swings the roller away from the cam centre
    assert np.all(r[~dwell] > rp)
    assert float(rocker_roller_geo.oscillating_roller_reach_constraint(rp, d, l)) < 0
    assert float(rocker_roller_geo.oscillating_roller_reach_constraint(15.0, d, l)) > 0  # |d - l| = 20 > 15


def riding_arm_angles(d, l, rf, rp, rotation, theta_deg, dense=7200, iters=90):
    """Arm angle of a roller follower riding on the cam outline, from the outline only.

    For each cam angle: turn the outline (rocker_roller_geo.oscillating_roller_profile at any parameter
    tau) into the fixed frame; a point at distance r from the pivot and polar angle beta (seen from
    the pivot) touches the roller centred at A + l (-cos psi, sin psi) when the angle between the arm
    (polar angle pi - psi) and the point is acos((l^2 + r^2 - R_f^2) / (2 l r)); the roller leaves it
    at the larger psi, psi = pi - beta + that angle (taken in (-pi, pi]). The follower rests at the largest such psi over the outline: a
    dense grid over tau brackets the maximizer, golden-section refinement finishes it.
    """

    def arm(tau_deg, th):
        kin = motion_at(PROGRAM, tau_deg)
        x, y = rocker_roller_geo.oscillating_roller_profile(d, l, rf, rp, kin, rotation)
        a = sigma_of(rotation) * th
        xf, yf = turn(x, y, a)
        r = jnp.hypot(xf - d, yf)
        beta = jnp.arctan2(yf, xf - d)
        c = (l**2 + r**2 - rf**2) / (2 * l * r)
        ok = jnp.abs(c) <= 1
        psi = math.pi - beta + jnp.arccos(jnp.where(ok, c, 0.0))
        return jnp.where(ok, jnp.mod(psi + math.pi, 2 * math.pi) - math.pi, -jnp.inf)  # in (-pi, pi]

    return max_over_outline(arm, theta_deg, dense, iters)


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_roller_follower_riding_on_exported_profile_reproduces_the_motion(rotation):
    d, l, rf, rp = 80.0, 60.0, 6.0, 45.0  # no undercut here (checked below): one contact point
    kin = evaluate(PROGRAM, 360)
    g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, rp, kin, rotation)
    assert float(jnp.min(g.undercut_margin)) > 0
    theta_deg = np.arange(0.0, 360.0, 2.5)
    psi = riding_arm_angles(d, l, rf, rp, rotation, theta_deg)
    s = np.asarray(motion_at(PROGRAM, theta_deg).s)
    psi0 = math.acos((d**2 + l**2 - rp**2) / (2 * d * l))
    # golden section to ~1e-17 deg of tau; the rest is float64 round-off of the rotation at ~80 mm
    np.testing.assert_allclose(np.asarray(psi) - psi0, s, rtol=0, atol=1e-9)


def riding_face_angles(d, f, rb, rotation, theta_deg, dense=7200, iters=90):
    """Arm angle of a flat face riding on the cam outline, from the outline only.

    For each cam angle: turn the outline (rocker_flat_geo.oscillating_flat_profile at any parameter tau)
    into the fixed frame. With P - A = R (cos beta, sin beta) seen from the pivot, the face
    {X : m(psi) . (X - A) = -f}, m = (sin psi, cos psi), passes through P where
    R sin(psi + beta) = -f; it leaves P behind (R sin(psi + beta) decreasing) at
    psi = pi + asin(f / R) - beta. The face rests at the largest such psi over the outline (dense
    grid over tau, then golden-section refinement, as for the roller).
    """

    def face(tau_deg, th):
        kin = motion_at(PROGRAM, tau_deg)
        x, y = rocker_flat_geo.oscillating_flat_profile(d, f, rb, kin, rotation)
        a = sigma_of(rotation) * th
        xf, yf = turn(x, y, a)
        r, beta = jnp.hypot(xf - d, yf), jnp.arctan2(yf, xf - d)
        psi = math.pi + jnp.arcsin(f / r) - beta
        return jnp.mod(psi + math.pi, 2 * math.pi) - math.pi  # in (-pi, pi]

    return max_over_outline(face, theta_deg, dense, iters)


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_flat_face_riding_on_exported_profile_reproduces_the_motion(rotation):
    d, f, rb = FLAT["d"], FLAT["f"], FLAT["rb"]
    kin = evaluate(PROGRAM, 360)
    assert float(jnp.min(rocker_flat_geo.oscillating_flat_geometry(d, f, rb, kin, rotation).radius_of_curvature)) > 0
    theta_deg = np.arange(0.0, 360.0, 2.5)
    psi = riding_face_angles(d, f, rb, rotation, theta_deg)
    s = np.asarray(motion_at(PROGRAM, theta_deg).s)
    # golden section to ~1e-17 deg of tau; the rest is float64 round-off at ~100 mm
    np.testing.assert_allclose(np.asarray(psi) - math.asin((rb + f) / d), s, rtol=0, atol=1e-9)


def flat_lines(d, f, rb, kin, rotation):
    """Face lines m . X = p of the fixed frame, seen from the cam (unit normals and distances, NumPy)."""
    psi = math.asin((rb + f) / d) + np.asarray(kin.s)
    mx, my = to_cam(np.sin(psi), np.cos(psi), np.asarray(kin.theta), rotation)
    return mx, my, d * np.sin(psi) - f, psi


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_flat_outline_is_the_envelope_of_the_face_lines(rotation):
    d, f, rb = FLAT["d"], FLAT["f"], FLAT["rb"]
    kin = evaluate(PROGRAM, N_DENSE)
    mx, my, p, psi = flat_lines(d, f, rb, kin, rotation)
    # the envelope point is the limit of the intersection of neighbouring lines (error O(h^2))
    m1x, m1y, p1 = np.roll(mx, 1), np.roll(my, 1), np.roll(p, 1)
    m2x, m2y, p2 = np.roll(mx, -1), np.roll(my, -1), np.roll(p, -1)
    det = m1x * m2y - m1y * m2x
    ex, ey = (p1 * m2y - p2 * m1y) / det, (m1x * p2 - m2x * p1) / det
    x, y = rocker_flat_geo.oscillating_flat_profile(d, f, rb, kin, rotation)
    # O(h^2 |X'''|): measured 1.7e-6 mm at h = 0.01 deg
    np.testing.assert_allclose(x, ex, rtol=0, atol=1e-5)
    np.testing.assert_allclose(y, ey, rtol=0, atol=1e-5)
    # radius of curvature from the outline's positions (checked against the envelope above) by
    # differences at 0.04 deg: differences of line intersections would amplify their round-off
    g = rocker_flat_geo.oscillating_flat_geometry(d, f, rb, kin, rotation)
    rho = np.asarray(g.radius_of_curvature)
    assert rho.min() > 1.0  # a convex cam, so that the positional curvature is well defined
    stride = 4
    cx, cy = np.asarray(x)[::stride], np.asarray(y)[::stride]
    d1, d2 = periodic_differences(N_DENSE // stride)
    turn = -sigma_of(rotation)
    rho_fd = turn * (d1(cx) ** 2 + d1(cy) ** 2) ** 1.5 / (d1(cx) * d2(cy) - d1(cy) * d2(cx))
    joint = near_joints(N_DENSE // stride, width=2)
    # O(h^2) truncation (a circle: rho h^2 / 6 = 2.3e-6 relative; measured max 1.9e-5 relative),
    # eps |X| / h^2 ~ 2e-8 mm round-off; s''' jumps at the joints (O(h) there)
    np.testing.assert_allclose(rho[::stride][~joint], rho_fd[~joint], rtol=5e-5, atol=0)
    # contact point on the face, from positions: its distance from the pivot's foot A - f m along
    # u = (-cos psi, sin psi), and the angle between m and the path of that follower point
    fx, fy = to_follower(np.asarray(x), np.asarray(y), np.asarray(kin.theta), rotation)
    foot_x, foot_y = d - f * np.sin(psi), -f * np.cos(psi)
    xi = (fx - foot_x) * -np.cos(psi) + (fy - foot_y) * np.sin(psi)
    np.testing.assert_allclose(g.contact_distance, xi, rtol=0, atol=1e-9)
    # path direction J (X - A); the pressure angle is the angle between it and the normal m
    vx, vy = -fy, fx - d
    cos_phi = np.abs(vx * np.sin(psi) + vy * np.cos(psi)) / np.hypot(vx, vy)
    np.testing.assert_allclose(np.cos(g.pressure_angle), cos_phi, rtol=0, atol=1e-12)


def test_flat_face_on_a_dwell_rests_on_the_base_circle():
    d, f, rb = FLAT["d"], FLAT["f"], FLAT["rb"]
    kin = evaluate(PROGRAM, 360)
    dwell = np.asarray(kin.s) == 0.0
    x, y = rocker_flat_geo.oscillating_flat_profile(d, f, rb, kin)
    np.testing.assert_allclose(np.hypot(x, y)[dwell], rb, rtol=1e-14)
    g = rocker_flat_geo.oscillating_flat_geometry(d, f, rb, kin)
    np.testing.assert_allclose(np.asarray(g.radius_of_curvature)[dwell], rb, rtol=1e-13)
    # the contact is the foot of the cam centre on the face: d cos psi0 from the pivot's foot
    psi0 = math.asin((rb + f) / d)
    np.testing.assert_allclose(np.asarray(g.contact_distance)[dwell], d * math.cos(psi0), rtol=1e-14)


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_long_arm_roller_approaches_the_translating_roller(rotation):
    # pivot at d = l + e far to the right: the roller centre (d - l cos psi, l sin psi) runs up the
    # line x = e up to y^2 / (2 l), and a lift of s mm is an arm swing of s / l rad
    prog_mm = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), 10.0), Segment("dwell", 60),
                                           Segment("return", 100, get_law("cycloidal"), 10.0),
                                           Segment("dwell", 80)])
    kin_mm = evaluate(prog_mm, 720)
    rb, rf, e = 30.0, 6.0, 4.0
    phi_t = np.asarray(roller_geo.roller_pressure_angle(rb, rf, e, kin_mm, rotation))
    kappa_t = np.asarray(roller_geo.roller_pitch_curvature(rb, rf, e, kin_mm, rotation))
    errors = []
    for l in (1e4, 1e5):
        kin = kin_mm._replace(s=kin_mm.s / l, ds=kin_mm.ds / l, d2s=kin_mm.d2s / l, d3s=kin_mm.d3s / l)
        d = l + e
        g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, rb + rf, kin, rotation)
        errors.append((np.abs(np.asarray(g.pressure_angle) - phi_t).max(),
                       np.abs(np.asarray(g.pitch_curvature) - kappa_t).max()))
    # the path tilts from the axis by psi ~ y / l <= 46 mm / l (4.6e-4 rad at l = 1e5), which bounds
    # the pressure-angle error (measured 2.3e-4 rad); and the error is first order in 1/l: ten
    # times smaller for a ten times longer arm (measured ratios 10.0 and 10.0)
    assert errors[1][0] < 4.6e-4 and errors[1][1] < 5e-6
    for k in (0, 1):
        assert 9.0 < errors[0][k] / errors[1][k] < 11.0


def test_long_arm_flat_face_approaches_the_translating_flat_face():
    prog_mm = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), 10.0), Segment("dwell", 60),
                                           Segment("return", 100, get_law("cycloidal"), 10.0),
                                           Segment("dwell", 80)])
    kin_mm = evaluate(prog_mm, 720)
    rb = 40.0
    rho_t = np.asarray(flat_geo.flat_radius_of_curvature(rb, kin_mm))
    for rotation in ("ccw", "cw"):
        x_t = np.asarray(flat_geo.flat_contact_offset(kin_mm, rotation))
        errors = []
        for d in (1e4, 1e5):  # a face through the pivot (f = 0), nearly along the line of centres
            kin = kin_mm._replace(s=kin_mm.s / d, ds=kin_mm.ds / d, d2s=kin_mm.d2s / d, d3s=kin_mm.d3s / d)
            g = rocker_flat_geo.oscillating_flat_geometry(d, 0.0, rb, kin, rotation)
            # the contact's offset from the cam centre's vertical is d - xi cos psi
            x = d - np.asarray(g.contact_distance) * np.cos(np.asarray(g.arm_angle))
            errors.append((np.abs(np.asarray(g.radius_of_curvature) - rho_t).max(), np.abs(x - x_t).max()))
            np.testing.assert_allclose(g.pressure_angle, 0.0, atol=1e-15)  # face through the pivot
        # the face tilts by psi ~ (R_b + s) / d: the contact point moves by ~(R_b + s)^2 / d <= 0.025 mm
        # at d = 1e5 (measured 0.025), rho by O(1/d) (measured 4.6e-3 mm); first order in 1/d
        assert errors[1][0] < 0.01 and errors[1][1] < 0.026
        for k in (0, 1):
            assert 9.0 < errors[0][k] / errors[1][k] < 11.0


@pytest.mark.slow
@pytest.mark.parametrize("rotation,rf,limit_deg", [("ccw", 8.0, 30.0), ("cw", 8.0, 30.0), ("ccw", 30.0, 60.0)])
def test_roller_min_prime_radius_against_a_dense_scan(rotation, rf, limit_deg):
    d, l = ROLLER["d"], ROLLER["l"]
    kin = evaluate(PROGRAM, 720)
    lim = math.radians(limit_deg)
    sizing = rocker_roller_geo.oscillating_roller_min_prime_radius(kin, d, l, rf, lim, 0.0, rotation)
    assert bool(sizing.found)
    rp = float(sizing.prime_radius_mm)
    assert float(sizing.base_radius_mm) == pytest.approx(rp - rf, abs=1e-12)

    def ok(r):  # judged through the geometry of a prime radius (arccos), not the search's psi0
        g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, r, kin, rotation)
        return (np.abs(np.asarray(g.pressure_angle)).max() <= lim + 1e-12
                and np.asarray(g.undercut_margin).min() >= -1e-9)

    scan = np.arange(rp - 0.05, rp + 0.05, 1e-3)
    first = scan[np.argmax([ok(r) for r in scan])]
    assert not ok(scan[0]) and ok(scan[-1])
    assert first - 1e-3 <= rp <= first + 1e-9
    if limit_deg == 60.0:
        assert bool(sizing.undercut_binds)  # the big roller undercuts before the angle binds


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_flat_min_base_radius_against_a_dense_scan(rotation):
    d, f, rho_min = FLAT["d"], FLAT["f"], 1.0
    kin = evaluate(PROGRAM, 720)
    sizing = rocker_flat_geo.oscillating_flat_min_base_radius(kin, d, f, rho_min, rotation)
    assert bool(sizing.found)
    rb = float(sizing.base_radius_mm)

    def ok(r):
        return np.asarray(rocker_flat_geo.oscillating_flat_geometry(d, f, r, kin, rotation).radius_of_curvature).min() \
            >= rho_min - 1e-9

    scan = np.arange(rb - 0.05, rb + 0.05, 1e-3)
    first = scan[np.argmax([ok(r) for r in scan])]
    assert not ok(scan[0]) and ok(scan[-1])
    assert first - 1e-3 <= rb <= first + 1e-9
    xi = np.asarray(rocker_flat_geo.oscillating_flat_geometry(d, f, rb, kin, rotation).contact_distance)
    assert float(sizing.face_length_mm) == pytest.approx(xi.max() - xi.min(), abs=1e-9)
    assert float(sizing.face_min_mm) > 0  # the contact stays on the cam's side of the pivot


@pytest.mark.slow
def test_gradients_match_finite_differences():
    kin = evaluate(PROGRAM, 720)
    PICK = 200  # one outline point inside the rise (a sum over the outline would drown in round-off)

    def roller(x, rotation):
        d, l, rf, rp = x
        g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, rp, kin, rotation)
        return jnp.stack([jnp.max(jnp.abs(g.pressure_angle)), jnp.sum(g.pitch_curvature),
                          *(c[PICK] for c in rocker_roller_geo.oscillating_roller_profile(d, l, rf, rp, kin, rotation))])

    def flat(x, rotation):
        d, f, rb = x
        g = rocker_flat_geo.oscillating_flat_geometry(d, f, rb, kin, rotation)
        return jnp.stack([jnp.min(g.radius_of_curvature), jnp.max(g.contact_distance), jnp.sum(g.pressure_angle),
                          *(c[PICK] for c in rocker_flat_geo.oscillating_flat_profile(d, f, rb, kin, rotation))])

    for fn, x0 in ((roller, jnp.asarray([80.0, 60.0, 8.0, 35.0])), (flat, jnp.asarray([120.0, 10.0, 95.0]))):
        for rotation in ("ccw", "cw"):
            f = jax.jit(lambda x, r=rotation, fn=fn: fn(x, r))
            jac = jax.jit(jax.jacfwd(f))(x0)
            grad_rows = jax.jit(jax.jacrev(f))(x0)
            np.testing.assert_allclose(jac, grad_rows, rtol=1e-10, atol=1e-12)
            for j in range(x0.shape[0]):
                step = jnp.zeros_like(x0).at[j].set(1e-6)
                fd = (f(x0 + step) - f(x0 - step)) / 2e-6
                # central differences, h = 1e-6: truncation ~h^2 |f'''|, round-off ~eps |f| / h ~ 1e-8
                # (|f| <= 400); max/min rows keep their argmax near x0
                np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-7)


def test_finite_for_infeasible_designs():
    kin = evaluate(PROGRAM, 360)

    def worst(x):
        d, l, rf, rp = x
        g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, rp, kin)
        px, py = rocker_roller_geo.oscillating_roller_profile(d, l, rf, rp, kin)
        h = rocker_flat_geo.oscillating_flat_geometry(d, rf, rp, kin)
        return (jnp.max(jnp.abs(g.pressure_angle)) + jnp.max(roller_geo.roller_undercut_constraint(
            g.pitch_curvature, rf)) + jnp.sum(px + py) + jnp.min(h.radius_of_curvature)
            + jnp.max(h.contact_distance))

    grad = jax.jit(jax.value_and_grad(worst))
    # cannot close (R_p < |d - l|, R_p > d + l), roller bigger than the prime circle, arm swung
    # through the line of centres (R_p at d + l), a face past perpendicular
    for x in [(80.0, 60.0, 8.0, 5.0), (80.0, 60.0, 8.0, 200.0), (80.0, 60.0, 50.0, 30.0),
              (80.0, 60.0, 8.0, 139.9), (20.0, 60.0, 30.0, 50.0)]:
        v, gr = grad(jnp.asarray(x))
        assert np.isfinite(float(v)) and np.all(np.isfinite(np.asarray(gr))), x


def test_the_sizings_prime_radius_in_floats_is_the_centre_distance_op_by_op():
    """The rocker sizing's R_p at the exact boundary (oscillating_roller.follower._centre_distance,
    Python floats) is :func:`roller_centre_distance` evaluated op by op on a 0-d array, bit for bit:
    the reported smallest cam did not move when it left JAX (it holds while XLA's CPU cosine is the
    C library's). 400 arm angles over (0, pi) and three pivot and arm pairs (d > l, d ~ l, d < l)."""
    from camjax.followers.oscillating_roller.follower import _centre_distance

    for d, l in [(90.0, 60.0), (50.0, 48.5), (40.0, 75.0)]:
        for psi in np.linspace(0.01, math.pi - 0.01, 400):
            eager = float(rocker_roller_geo.roller_centre_distance(d, l, jnp.asarray(psi)))
            assert _centre_distance(d, l, float(psi)) == eager, (d, l, psi)
