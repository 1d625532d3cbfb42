"""Roller follower geometry and contact, checked against computations that do not use the formulas:
positions only (kinematic inversion + finite differences), closed forms, the follower riding on the
exported profile, finite differences through R_b, R_f and e."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from outline import max_over_outline, turn

from camjax import contact, loads
from camjax.followers.flat import geometry as flat_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.laws import get_law
from camjax.program import MotionProgram, Segment, evaluate, motion_at

# rise-dwell-return-dwell with an asymmetric pair of laws, so that offset and rotation matter
PROGRAM = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), 10.0), Segment("dwell", 60),
                                       Segment("return", 100, get_law("cycloidal"), 10.0), Segment("dwell", 80)])
CASES = [("ccw", 4.0), ("cw", 4.0), ("ccw", -3.0), ("cw", 0.0)]


class _Compiled:
    """The module's functions, each one compiled program per rotation and shape (the same values as
    the module's own, op by op: each operation otherwise compiles and dispatches on its own)."""

    def __init__(self, module, names):
        for name in names:
            setattr(self, name, jax.jit(getattr(module, name), static_argnames="rotation"))


roller = _Compiled(roller_geo, ("roller_pressure_angle", "roller_pitch_curvature", "roller_geometry",
                                "roller_profile", "roller_pitch_curve"))
flat = _Compiled(flat_geo, ("flat_profile",))


def inversion(rb, rf, e, kin, rotation):
    """Pitch curve by kinematic inversion, in NumPy: the roller centre (e, d + s) of the fixed frame
    seen from a cam turned by theta (ccw: the cam point at R(theta) P is in contact, so P = R(-theta) p)."""
    th, s = np.asarray(kin.theta), np.asarray(kin.s)
    p = np.stack([np.full_like(s, e), math.sqrt((rb + rf) ** 2 - e**2) + s])
    a = -th if rotation == "ccw" else th
    return np.cos(a) * p[0] - np.sin(a) * p[1], np.sin(a) * p[0] + np.cos(a) * p[1]


@pytest.mark.parametrize("rotation,e", CASES)
def test_pressure_angle_from_positions_only(rotation, e):
    n = 36_000
    kin = evaluate(PROGRAM, n)
    rb, rf = 25.0, 6.0
    x, y = inversion(rb, rf, e, kin, rotation)
    # tangent by periodic central differences, turned back into the fixed (follower) frame; the
    # pressure angle is the angle of the contact normal from the axis = of the tangent from x
    tx, ty = np.roll(x, -1) - np.roll(x, 1), np.roll(y, -1) - np.roll(y, 1)
    th = np.asarray(kin.theta)
    a = th if rotation == "ccw" else -th
    fx, fy = np.cos(a) * tx - np.sin(a) * ty, np.sin(a) * tx + np.cos(a) * ty
    phi_fd = np.arctan(fy / fx)
    phi = roller.roller_pressure_angle(rb, rf, e, kin, rotation)
    # central differences at 0.01 deg: O(h^2) = 3e-9 relative in the tangent times |P'''|/|P'| ~ 10
    np.testing.assert_allclose(phi, phi_fd, rtol=0, atol=1e-7)
    np.testing.assert_allclose(roller.roller_geometry(rb, rf, e, kin, rotation).pressure_angle, phi_fd,
                               rtol=0, atol=1e-7)


@pytest.mark.parametrize("rotation,e", CASES)
def test_pitch_curvature_sign_and_size_from_positions(rotation, e):
    n = 36_000
    kin = evaluate(PROGRAM, n)
    rb, rf = 5.0, 6.0  # small enough for concave stretches (and an undercut: rho_c < 0 somewhere)
    x, y = inversion(rb, rf, e, kin, rotation)
    h = 2 * np.pi / n
    d1 = lambda v: (np.roll(v, -1) - np.roll(v, 1)) / (2 * h)  # noqa: E731
    d2 = lambda v: (np.roll(v, -1) - 2 * v + np.roll(v, 1)) / h**2  # noqa: E731
    # a convex closed curve has the sign of its turning direction: ccw cams trace their pitch
    # curve clockwise (polar angle -theta), so convex means negative cross product there
    turn = -1.0 if rotation == "ccw" else 1.0
    kappa_fd = turn * (d1(x) * d2(y) - d1(y) * d2(x)) / (d1(x) ** 2 + d1(y) ** 2) ** 1.5
    kappa = np.asarray(roller.roller_pitch_curvature(rb, rf, e, kin, rotation))
    # second differences: O(h^2) truncation plus eps |P| / h^2 round-off (measured 1.4e-8 1/mm)
    # away from the joints; on a joint s''' of
    # the 3-4-5 jumps and the difference across it is O(h) off (measured 1.6e-5 1/mm at R_p = 11)
    near_joint = np.zeros(n, bool)
    for start in PROGRAM.start_deg:
        near_joint[(np.arange(-2, 3) + round(start * n / 360)) % n] = True
    np.testing.assert_allclose(kappa_fd[~near_joint], kappa[~near_joint], rtol=0, atol=1e-7)
    np.testing.assert_allclose(kappa_fd, kappa, rtol=0, atol=5e-5)
    assert kappa.min() < 0 < kappa.max()  # this cam has concave stretches: both signs are tested
    g = roller.roller_geometry(rb, rf, e, kin, rotation)
    np.testing.assert_allclose(g.pitch_radius_of_curvature * kappa, 1.0, rtol=1e-12)
    convex = kappa > 0
    np.testing.assert_allclose(g.cam_radius_of_curvature, 1 / kappa - rf, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(g.undercut_margin)[convex], (1 / kappa - rf)[convex], rtol=1e-12)
    assert np.all(np.asarray(g.undercut_margin)[~convex] > 1e300)  # concave parts cannot undercut


def test_cw_cam_is_the_mirror_image_of_ccw_with_mirrored_offset():
    kin = evaluate(PROGRAM, 720)
    for f in (roller.roller_profile, roller.roller_pitch_curve):
        xc, yc = f(25.0, 6.0, 4.0, kin, "cw")
        xa, ya = f(25.0, 6.0, -4.0, kin, "ccw")
        np.testing.assert_allclose(xc, -xa, atol=1e-12)
        np.testing.assert_allclose(yc, ya, atol=1e-12)
    xc, yc = flat.flat_profile(30.0, kin, "cw")
    xa, ya = flat.flat_profile(30.0, kin, "ccw")
    np.testing.assert_allclose(xc, -xa, atol=1e-12)
    np.testing.assert_allclose(yc, ya, atol=1e-12)


def harmonic_rise(beta_deg, lift):
    return MotionProgram.from_segments([Segment("rise", beta_deg, get_law("harmonic"), lift),
                                        Segment("dwell", 180 - beta_deg),
                                        Segment("return", beta_deg, get_law("harmonic"), lift),
                                        Segment("dwell", 180 - beta_deg)])


@pytest.mark.parametrize("beta_deg,lift,limit_deg", [(90, 8.0, 30.0), (60, 5.0, 25.0), (120, 20.0, 40.0)])
def test_pressure_angle_limited_prime_radius_of_harmonic_rise_closed_form(beta_deg, lift, limit_deg):
    # s = h/2 (1 - cos x), x = pi theta / beta, e = 0: tan phi = A sin x / (a - b cos x) with
    # A = pi h / (2 beta), a = R_p + h/2, b = h/2; d/dx = 0 at cos x = b/a gives
    # max tan phi = A / sqrt(a^2 - b^2), so the limit binds at R_p = sqrt(h^2/4 + A^2 / tan^2 lim) - h/2
    beta, lim = math.radians(beta_deg), math.radians(limit_deg)
    a_coef = math.pi * lift / (2 * beta)
    closed = math.sqrt(lift**2 / 4 + (a_coef / math.tan(lim)) ** 2) - lift / 2
    kin = evaluate(harmonic_rise(beta_deg, lift), 360_000)
    rp = roller_geo.roller_min_prime_radius_for_pressure_angle(kin, 0.0, lim)
    # the sampled max of a smooth function misses the true one by <= max|f''| (dtheta/2)^2 / 2
    # ~ 100 * 7.6e-11 / 2 mm: 1e-8 mm covers it
    assert float(rp) == pytest.approx(closed, abs=1e-8)
    # and at that radius the largest pressure angle sits on the limit
    phi = roller.roller_pressure_angle(float(rp), 0.0, 0.0, kin)
    assert float(jnp.max(jnp.abs(phi))) == pytest.approx(lim, abs=1e-12)


@pytest.mark.parametrize("rotation,e", CASES)
def test_min_prime_radius_for_pressure_angle_with_offset_puts_phi_on_the_limit(rotation, e):
    kin = evaluate(PROGRAM, 3600)
    lim = math.radians(30.0)
    rp = float(roller_geo.roller_min_prime_radius_for_pressure_angle(kin, e, lim, rotation))
    phi = roller.roller_pressure_angle(rp, 0.0, e, kin, rotation)
    assert float(jnp.max(jnp.abs(phi))) == pytest.approx(lim, abs=1e-12)
    # 1 um smaller breaks it (the root is a single monotone crossing in R_p)
    phi = roller.roller_pressure_angle(rp - 1e-3, 0.0, e, kin, rotation)
    assert float(jnp.max(jnp.abs(phi))) > lim


def riding_heights(rb, rf, e, rotation, theta_deg, dense=7200, iters=90):
    """Roller-centre height of a follower riding on the cam outline, from the outline only.

    For each cam angle: turn the outline (points from roller_geo.roller_profile at any parameter
    tau) into the follower frame and find the lowest centre height on the axis x = e with no
    outline point inside the roller: max over tau of y + sqrt(R_f^2 - (x - e)^2). A dense grid
    over tau brackets the maximizer, golden-section refinement in tau finishes it (the height is
    stationary there, so a tau error delta costs ~delta^2 in height).
    """

    def height(tau_deg, th):
        kin = motion_at(PROGRAM, tau_deg)
        x, y = roller.roller_profile(rb, rf, e, kin, rotation)
        a = th if rotation == "ccw" else -th  # follower frame = cam frame turned by the cam angle
        xf, yf = turn(x, y, a)
        gap = rf**2 - (xf - e) ** 2
        return jnp.where(gap >= 0, yf + jnp.sqrt(jnp.where(gap >= 0, gap, 0.0)), -jnp.inf)

    return max_over_outline(height, theta_deg, dense, iters)


@pytest.mark.slow
@pytest.mark.parametrize("rotation,e", [("ccw", 4.0), ("cw", 4.0), ("ccw", 0.0)])
def test_follower_riding_on_exported_profile_reproduces_s(rotation, e):
    rb, rf = 25.0, 6.0  # no undercut here (checked below), so the roller touches one point
    kin_all = evaluate(PROGRAM, 360)
    assert float(jnp.min(roller.roller_geometry(rb, rf, e, kin_all, rotation).undercut_margin)) > 0
    theta_deg = np.arange(0.0, 360.0, 2.5)
    y = riding_heights(rb, rf, e, rotation, theta_deg)
    s = np.asarray(motion_at(PROGRAM, theta_deg).s)
    d = math.sqrt((rb + rf) ** 2 - e**2)
    # golden section to 1e-17 deg of tau; the rest is float64 round-off of sqrt/rotation at ~40 mm
    np.testing.assert_allclose(np.asarray(y) - d, s, rtol=0, atol=1e-9)


@pytest.mark.slow
def test_gradients_through_base_radius_roller_radius_offset_match_finite_differences():
    kin = evaluate(PROGRAM, 720)
    force = 50.0 + 3.0 * kin.s  # any positive follower force profile (N)
    cam, fol = contact.Material(2.1e5, 0.3), contact.Material(2.1e5, 0.3)
    coeff = contact.stress_coefficient(force, 10.0, cam, fol)

    def quantities(x, rotation):
        rb, rf, e = x
        g = roller.roller_geometry(rb, rf, e, kin, rotation)
        rho_eq = roller_geo.roller_equivalent_radius(g.pitch_curvature, rf)
        sigma = contact.roller_stress(coeff, g.pressure_angle, rho_eq)
        return jnp.stack([
            jnp.max(jnp.abs(g.pressure_angle)),
            jnp.max(roller_geo.roller_undercut_constraint(g.pitch_curvature, rf, 0.5)),
            jnp.max(sigma),
            jnp.sum(g.pitch_curvature),
            jnp.sum(jnp.stack(roller.roller_profile(rb, rf, e, kin, rotation))),
        ])

    x0 = jnp.asarray([25.0, 6.0, 4.0])
    for rotation in ("ccw", "cw"):
        f = jax.jit(lambda x, r=rotation: quantities(x, r))
        jac = jax.jit(jax.jacfwd(f))(x0)
        for j in range(3):
            step = jnp.zeros(3).at[j].set(1e-6)
            fd = (f(x0 + step) - f(x0 - step)) / 2e-6
            # central differences with h = 1e-6: truncation ~h^2 |f'''| ~ 1e-12 and round-off
            # ~eps |f| / h ~ 1e-10 |f|; the max-based rows have a fixed argmax near x0
            np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-8)


def test_roller_stress_closed_forms():
    cam, fol = contact.Material(2.1e5, 0.3), contact.Material(1.15e5, 0.26)
    k = (1 - 0.3**2) / 2.1e5 + (1 - 0.26**2) / 1.15e5
    # SPEC 3 written out: convex and concave cam surface, tilted normal
    for rho_c, phi in [(12.0, 0.3), (-40.0, -0.2), (3.0, 0.0)]:
        sigma = contact.roller_hertz_line_stress(50.0, phi, rho_c, 8.0, 10.0, cam, fol)
        ref = 0.564 * math.sqrt((50.0 / math.cos(phi) / 10.0) * (1 / rho_c + 1 / 8.0) / k)
        assert float(sigma) == pytest.approx(ref, rel=1e-13)
    # a dwell: pitch circle R_p, cam circle R_b = R_p - R_f, two cylinders 1/R_b + 1/R_f
    kin = evaluate(MotionProgram.from_segments([Segment("dwell", 360)]), 8)
    g = roller.roller_geometry(20.0, 8.0, 0.0, kin)
    rho_eq = roller_geo.roller_equivalent_radius(g.pitch_curvature, 8.0)
    sigma = contact.roller_stress(contact.stress_coefficient(50.0, 10.0, cam, fol), g.pressure_angle, rho_eq)
    np.testing.assert_allclose(sigma, 0.564 * math.sqrt(5.0 * (1 / 20.0 + 1 / 8.0) / k), rtol=1e-13)
    assert float(loads.normal_force(50.0, math.radians(60))) == pytest.approx(100.0, rel=1e-14)


def test_everything_finite_for_infeasible_designs():
    kin = evaluate(PROGRAM, 360)
    cam = contact.Material(2.1e5, 0.3)

    def worst(x):
        rb, rf, e = x
        g = roller.roller_geometry(rb, rf, e, kin)
        rho_eq = roller_geo.roller_equivalent_radius(g.pitch_curvature, rf)
        sigma = contact.roller_stress(40.0, g.pressure_angle, rho_eq)
        px, py = roller.roller_profile(rb, rf, e, kin)
        return (jnp.max(sigma) + jnp.max(roller_geo.roller_undercut_constraint(g.pitch_curvature, rf))
                + jnp.max(jnp.abs(g.pressure_angle)) + jnp.sum(px + py)
                + jnp.max(contact.roller_hertz_line_stress(40.0, g.pressure_angle, g.cam_radius_of_curvature,
                                                            rf, 10.0, cam, cam)))

    grad = jax.jit(jax.value_and_grad(worst))
    # undercut (tiny R_b, big roller), |e| >= R_p, a zero base radius, a huge offset
    for x in [(0.5, 20.0, 0.0), (5.0, 2.0, 9.0), (0.0, 1.0, 1.0), (30.0, 6.0, 300.0), (1e-3, 1e-3, 0.0)]:
        v, gr = grad(jnp.asarray(x))
        assert np.isfinite(float(v)) and np.all(np.isfinite(np.asarray(gr))), x


@pytest.mark.parametrize("rotation,e,rf,rho_min", [("ccw", 4.0, 6.0, 0.0), ("cw", 4.0, 15.0, 1.0),
                                                   ("ccw", -2.0, 30.0, 0.5)])
def test_undercut_limited_prime_radius_against_a_dense_scan(rotation, e, rf, rho_min):
    kin = evaluate(PROGRAM, 720)
    rp = float(roller_geo.roller_min_prime_radius_for_undercut(kin, rf, e, rho_min, rotation, lower_mm=abs(e)))
    # scan R_p in 1 um steps around it, judging undercut by the smallest convex cam radius
    # (a different formula: rho_c = 1/kappa - R_f on the convex samples)
    scan = np.arange(rp - 0.05, rp + 0.05, 1e-3)
    curvatures = np.asarray(jax.vmap(lambda r: roller.roller_pitch_curvature(r - rf, rf, e, kin, rotation))(scan))
    ok = [np.all(1 / k[k > 0] - rf >= rho_min) for k in curvatures]  # every radius in one call

    first = scan[np.argmax(ok)]
    assert not ok[0] and ok[-1]
    assert first - 1e-3 <= rp <= first + 1e-12
