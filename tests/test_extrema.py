"""Exact extrema over the cam angle: closed forms, dense references, properties, joints, gradients."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import reference_force
from scipy.optimize import minimize_scalar

from camjax import contact, extrema, loads
from camjax.laws import LAWS, get_law, polynomial_law
from camjax.program import (
    MotionProgram,
    Segment,
    evaluate,
    segment_bounds_deg,
    segment_motion,
    time_kinematics,
)

CYC = get_law("cycloidal")
H = 5.0  # lift of the reference case, mm
OMEGA = 240 * 2 * math.pi / 60  # rad/s
TRAIN = loads.FollowerTrain(1.0, 3004.0, 13.0, 0.345, 9.81)
STEEL, BRONZE = contact.Material(2.1e5, 0.3), contact.Material(1.15e5, 0.26)


def ref_program(lift=H):
    return MotionProgram.from_segments(
        [Segment("dwell", 100), Segment("rise", 80, CYC, lift), Segment("dwell", 120),
         Segment("return", 60, CYC, lift)]
    )


def rho(kin, base_radius_mm):
    return base_radius_mm + kin.s + kin.d2s


def force(kin, _=None):
    return loads.kinetostatic_force(TRAIN, time_kinematics(kin, OMEGA))


def stress(kin, base_radius_mm):
    c = contact.stress_coefficient(force(kin), 10.0, STEEL, BRONZE)
    return contact.stress_from_coefficient(c, rho(kin, base_radius_mm))


def dense_reference_max(f, samples=1_000_000):
    """max of f over [0, 360) deg: the best of a dense grid, polished by SciPy in its bracket."""
    t = np.arange(samples) * (360.0 / samples)
    i = int(np.argmax(f(t)))
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, samples - 1)]
    r = minimize_scalar(lambda x: -f(np.array([x]))[0], bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-12})
    return max(-r.fun, f(t[i:i + 1])[0]), r.x


# ------------------------------------------------------------------------- closed forms


def test_flat_face_min_rho_closed_form():
    """Cycloidal return of 60 deg: d(s + s'')/du = 0 at cos 2 pi u = -1 / ((2 pi / beta)^2 - 1) = -1/35.

    With u the rise law's argument (u = 1 - x), -(s + s'') = -h [u - sin(2 pi u)/(2 pi)
    + (2 pi / beta^2) sin 2 pi u] is largest at 2 pi u = pi + acos(1/35).
    """
    prog = ref_program()
    a = math.acos(1.0 / 35.0)
    u = (math.pi + a) / (2 * math.pi)
    sin = -math.sin(a)
    need = -H * (u - sin / (2 * math.pi) + 2 * math.pi / (math.pi / 3) ** 2 * sin)
    angle = 300.0 + 60.0 * (1.0 - u)
    base_radius = 30.0
    kin = evaluate(prog, 360)
    # one compiled program for the refinement (not op by op)
    e = jax.jit(lambda b: extrema.min_of(prog, rho, rho(kin, b), b))(base_radius)
    # value: rounding of a few terms of size ~30 mm (1e-15 relative) is all that remains
    assert float(e.value) == pytest.approx(base_radius - need, rel=1e-12)
    assert float(e.value) < float(jnp.min(rho(kin, base_radius)))  # the grid misses it
    # angle: a smooth minimum fixes its angle to ~sqrt(eps) at worst; Newton does far better
    assert float(e.angle_deg) == pytest.approx(angle, abs=1e-7)
    assert need == pytest.approx(24.11348, abs=1e-5)  # issue 13's figure


def test_cycloidal_peak_acceleration_closed_form():
    """s'' of a cycloidal segment peaks at h 2 pi / beta^2: largest on the 60-deg return, at its x = 3/4."""
    prog = ref_program()
    d2s = lambda kin, _: kin.d2s  # noqa: E731
    kin = evaluate(prog, 7)  # a coarse grid: the bracket alone must suffice
    e = jax.jit(lambda k: extrema.max_of(prog, d2s, d2s(k, None)))(kin)  # one program, not op by op
    assert float(e.value) == pytest.approx(H * 2 * math.pi / math.radians(60) ** 2, rel=1e-13)
    assert float(e.angle_deg) == pytest.approx(345.0, abs=1e-7)


# ---------------------------------------------------------------------- dense references


def test_peak_force_against_dense_scipy_reference():
    ref, ref_angle = dense_reference_max(reference_force)
    prog = ref_program()
    kin = evaluate(prog, 360)
    e = jax.jit(lambda k: extrema.max_of(prog, force, force(k)))(kin)  # one program, not op by op
    # the reference is SciPy's bounded Brent to 1e-12 deg on the 1e6-grid's bracket, so it is
    # good to ~1e-15 relative; both sides are float64 evaluations of ~70 N
    assert float(e.value) == pytest.approx(ref, rel=1e-12)
    assert float(e.angle_deg) == pytest.approx(ref_angle, abs=1e-6)
    assert float(e.value) == pytest.approx(68.457, abs=1e-3)  # issue 13's figure
    grid = float(jnp.max(force(kin)))
    assert (ref - grid) / ref > 1e-4  # the 360-grid is visibly off: the test has teeth


def test_peak_stress_against_dense_reference():
    """sigma = C / sqrt(rho) needs s''' in its slope; a 1e6-sample grid of the same curve agrees."""
    prog = ref_program()
    base_radius = 26.0
    dense = float(jax.jit(lambda b: jnp.max(stress(evaluate(prog, 1_000_000), b)))(base_radius))
    e = jax.jit(lambda b: extrema.max_of(prog, stress, stress(evaluate(prog, 360), b), b))(base_radius)  # one program each
    # a dense grid undershoots a smooth max by <= f'' dtheta^2 / 8: with dtheta = 6.3e-6 rad and
    # f'' / f < 1e4 per rad^2 near the sharp peak that is < 5e-8 relative
    assert 0.0 <= (float(e.value) - dense) / dense < 5e-8


# ------------------------------------------------------------------------- properties

@st.composite
def programs(draw):
    """Random dwell-rise-dwell-return programs from the registered laws."""
    angles = draw(st.lists(st.floats(10.0, 170.0), min_size=4, max_size=4))
    angles = [a * 360.0 / sum(angles) for a in angles]
    angles[-1] = 360.0 - sum(angles[:-1])
    rise, ret = draw(st.sampled_from(sorted(LAWS))), draw(st.sampled_from(sorted(LAWS)))
    lift = draw(st.floats(0.5, 20.0))
    return MotionProgram.from_segments(
        [Segment("dwell", angles[0]), Segment("rise", angles[1], get_law(rise), lift),
         Segment("dwell", angles[2]), Segment("return", angles[3], get_law(ret), lift)])


QUANTITIES = {
    "velocity": lambda kin, _: kin.ds,
    "neg_velocity": lambda kin, _: -kin.ds,
    "accel": lambda kin, _: kin.d2s,
    "jerk": lambda kin, _: kin.d3s,
    "rho_need": lambda kin, _: -(kin.s + kin.d2s),
    "force": force,
}


@pytest.mark.slow
@settings(max_examples=15, deadline=None)
@given(programs(), st.sampled_from(sorted(QUANTITIES)), st.integers(180, 720))
def test_refined_max_never_beaten_by_a_fine_grid(prog, name, samples):
    """The refined max of a coarse grid is >= every sample of a 1e5 grid (to rounding).

    The coarse grid must resolve each segment's shape (here >= 3 samples in a 6.9-deg segment):
    a grid of 2 samples per segment cannot say which half holds the peak.
    """
    q = QUANTITIES[name]

    @jax.jit  # one program per drawn case (its angles and laws are compiled in), not op by op
    def refined_fine_and_limits():
        limits = [jnp.max(q(segment_motion(prog, j, jnp.asarray(b)), None))
                  for j, b in enumerate(segment_bounds_deg(prog))]
        return (extrema.max_of(prog, q, q(evaluate(prog, samples), None)),
                q(evaluate(prog, 100_000), None), jnp.stack(limits))

    e, fine, limits = refined_fine_and_limits()
    fine = np.asarray(fine)
    scale = float(np.max(np.abs(fine)))
    # rounding of one evaluation of the closed form: a few ulps of the largest term
    assert float(e.value) >= fine.max() - 1e-12 * scale
    # and no more than the function reaches: the fine grid's max, or a one-sided limit at a
    # joint (which no sample need reach), up to the fine grid's own miss of a smooth max,
    # f'' dtheta^2 / 8 < 1e-5 of the scale for segments >= 6.9 deg (f'' / f < (2 pi / beta)^4)
    assert float(e.value) <= max(fine.max(), *np.asarray(limits)) + 1e-5 * scale


@pytest.mark.slow
@settings(max_examples=8, deadline=None)
@given(st.sampled_from(["cycloidal", "harmonic", "poly_3_4_5", "poly_4_5_6_7", "modified_sine",
                        "modified_trapezoid"]),
       st.integers(2, 40), st.integers(0, 60))
def test_extremum_on_a_sample_keeps_the_grid_value(law, half_width, start):
    """A rise whose velocity peak (x = 1/2 for these laws, symmetric about it) sits on a sample:
    the refined value is the grid value."""
    samples = 360
    rise = 2 * half_width  # whole degrees, so start + rise / 2 is a sample of the 1-deg grid
    prog = MotionProgram.from_segments(
        [Segment("dwell", start + 10), Segment("rise", rise, get_law(law), 3.0),
         Segment("dwell", 20), Segment("return", 330 - start - rise, CYC, 3.0)])
    v = lambda kin, _: kin.ds  # noqa: E731

    @jax.jit  # one program per drawn case (its angles and law are compiled in), not op by op
    def grid_and_refined():
        grid = v(evaluate(prog, samples), None)
        return grid, extrema.max_of(prog, v, grid)

    grid, e = grid_and_refined()
    peak = float(jnp.max(grid))
    # the grid value is the continuous max here: the refinement may only move it by rounding
    assert float(e.value) == pytest.approx(peak, rel=1e-14)
    if law != "modified_trapezoid":  # its velocity is flat-topped: the angle is not unique there
        assert float(e.angle_deg) == pytest.approx(start + 10 + half_width, abs=1e-6)


# ----------------------------------------------------------------------- joints, dwells


@pytest.mark.slow
def test_extremum_at_a_joint_is_the_one_sided_limit():
    """A harmonic rise ends with s'' = -h pi^2 / (2 beta^2), then a dwell (s'' = 0): the min of s''
    is the left limit at the joint, which no sample reaches (the joint's sample is the dwell's)."""
    beta_deg = 77.3  # the joint at 117.3 deg falls between samples
    prog = MotionProgram.from_segments(
        [Segment("dwell", 40), Segment("rise", beta_deg, get_law("harmonic"), 4.0),
         Segment("dwell", 360 - 40 - 2 * beta_deg), Segment("return", beta_deg, get_law("harmonic"), 4.0)])
    d2s = lambda kin, _: kin.d2s  # noqa: E731
    grid = d2s(evaluate(prog, 360), None)
    e = jax.jit(lambda g: extrema.min_of(prog, d2s, g))(grid)  # one program, not op by op
    exact = -4.0 * math.pi**2 / (2 * math.radians(beta_deg) ** 2)
    assert float(e.value) == pytest.approx(exact, rel=1e-14)
    assert float(e.value) < float(jnp.min(grid))
    assert float(e.angle_deg) in (pytest.approx(40 + beta_deg, abs=1e-9), pytest.approx(360 - beta_deg, abs=1e-9))


@pytest.mark.slow
@pytest.mark.parametrize("law", [None, polynomial_law([1])])
def test_degenerate_segments_keep_the_grid_value(law):
    """A single 360-deg dwell, or constant-velocity rise and return: f' = 0, no NaN, grid value kept."""
    if law is None:
        prog = MotionProgram.from_segments([Segment("dwell", 360)])
    else:
        prog = MotionProgram.from_segments([Segment("rise", 180, law, 2.0), Segment("return", 180, law, 2.0)])
    for q in (lambda kin, _: kin.ds, lambda kin, _: kin.d2s):
        grid = q(evaluate(prog, 360), None)
        e = extrema.max_of(prog, q, grid)
        assert float(e.value) == float(jnp.max(grid))
        assert np.isfinite(float(e.angle_deg))
        g = jax.jit(jax.grad(lambda lifts, q=q, grid=grid: extrema.max_of(  # one program, not op by op
            MotionProgram(prog.kinds, prog.angles_deg, prog.laws, lifts), q, grid).value))(prog.lifts)
        assert np.all(np.isfinite(np.asarray(g)))


@pytest.mark.slow
def test_more_candidates_than_a_short_segment_has_points():
    """Segments of very different sample counts (one holds a single sample) refined together, with
    more candidates than the short one's sub-grid has points: each segment's max is the dense
    brute-force max of its closed form, and its gradient is the envelope theorem's."""
    bounds = ((0.0, 7.0), (7.0, 200.0), (200.0, 360.0))

    def fn(segment, theta_deg, amplitude):  # a few peaks per segment, a different law on each
        return amplitude * jnp.sin(theta_deg * (segment + 1) * math.pi / 50) + 0.01 * theta_deg

    samples = 36  # 10-deg grid: segment 0 holds only the sample at 0 (sub-grid of 3 points)
    theta = np.arange(samples) * (360.0 / samples)
    grid = jnp.concatenate([fn(j, jnp.asarray(theta[(theta >= lo) & (theta < hi)]), 1.0)
                            for j, (lo, hi) in enumerate(bounds)])
    e = jax.jit(lambda g: extrema.refine_max(fn, 1.0, bounds, g, candidates=8))(grid)  # one program, not op by op
    dense = [np.asarray(fn(j, jnp.linspace(lo, hi, 200_001), 1.0)) for j, (lo, hi) in enumerate(bounds)]
    # the dense grid (step <= 1e-3 deg) misses a smooth max by f'' h^2 / 8 < 0.04 * 1e-6 / 8 = 5e-9
    best = max(d.max() for d in dense)
    assert float(e.value) == pytest.approx(best, abs=1e-8)
    assert float(e.value) >= best - 1e-12  # never below a value the function takes
    # the value at the reported angle (on the segment that holds it), and d/d(amplitude) = the
    # sine there (envelope theorem: the angle does not move the value to first order)
    j = next(j for j, (lo, hi) in enumerate(bounds) if lo <= float(e.angle_deg) <= hi)
    assert float(fn(j, e.angle_deg, 1.0)) == pytest.approx(float(e.value), abs=1e-12)
    slope = jax.jit(jax.grad(lambda a: extrema.refine_max(fn, a, bounds, grid, candidates=8).value))(1.0)
    assert float(slope) == pytest.approx(math.sin(float(e.angle_deg) * (j + 1) * math.pi / 50), abs=1e-12)


# ------------------------------------------------------------------ gradients, batching


@pytest.mark.slow
def test_envelope_gradient_matches_finite_differences():
    """d(max sigma)/dR_b and d(max F)/dh by the envelope theorem against central differences."""
    base = ref_program()

    def peak_stress(base_radius, lift):
        prog = MotionProgram(base.kinds, base.angles_deg, base.laws, base.lifts * (lift / H))
        return extrema.max_of(prog, stress, stress(evaluate(prog, 360), base_radius), base_radius).value

    r, h = 26.0, H
    g_r, g_h = jax.jit(jax.grad(peak_stress, argnums=(0, 1)))(r, h)
    peak_stress = jax.jit(peak_stress)  # one program for the four differences, not op by op
    step = 1e-4
    fd_r = (peak_stress(r + step, h) - peak_stress(r - step, h)) / (2 * step)
    fd_h = (peak_stress(r, h + step) - peak_stress(r, h - step)) / (2 * step)
    # central differences: truncation ~ f''' step^2 / 6 ~ 1e-8 relative here, rounding
    # eps f / step ~ 1e-11; the refined max is smooth in the design, so they must agree to 1e-7
    assert float(g_r) == pytest.approx(float(fd_r), rel=1e-7)
    assert float(g_h) == pytest.approx(float(fd_h), rel=1e-7)
    assert float(g_r) < 0.0  # a larger base circle lowers the stress


@pytest.mark.slow
def test_jit_and_vmap_over_designs_match_single_calls():
    prog = ref_program()
    kin = evaluate(prog, 360)

    @jax.jit
    def peak(base_radius):
        return extrema.max_of(prog, stress, stress(kin, base_radius), base_radius)

    radii = jnp.linspace(25.0, 40.0, 5)
    batch = jax.vmap(peak)(radii)
    for i, r in enumerate(radii):
        one = peak(r)
        assert float(batch.value[i]) == pytest.approx(float(one.value), rel=1e-15)
        assert float(batch.angle_deg[i]) == pytest.approx(float(one.angle_deg), abs=1e-12)


def test_grid_extremum_is_the_sample():
    v = jnp.asarray([1.0, 3.0, 2.0, -1.0])
    assert extrema.grid_max(v) == (3.0, 90.0)
    assert extrema.grid_min(v) == (-1.0, 270.0)
