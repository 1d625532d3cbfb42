"""Follower-train dynamics, jump and compensation against independent references.

References: the closed-form steady state of a 1-DOF oscillator, scipy's solve_ivp, RK4's own
convergence order, scipy's brentq on a NumPy force computed straight from the Fourier
coefficients, and central finite differences. Tolerances are stated where they are used.
"""

from __future__ import annotations

import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
from hypothesis import given, settings
from hypothesis import strategies as st

import camjax
import camjax.cli
from camjax import dynamics as d
from camjax.dynamics import budget, integrate
from camjax.laws import THESIS_NOMINAL
from camjax.scene import DynamicsSpec, SceneError, builtin_scene_text, parse_scene

W_BENCH = 2 * math.pi * 2.96
PLANT = d.Plant(0.357, 0.205, 3050.0)


@pytest.fixture(scope="module")
def bench():
    return camjax.load_scene("thesis-bench")


@pytest.fixture(scope="module")
def bench_cam(bench):
    return d.program_cam(bench)


def _series_numpy(phi, shift=math.pi):
    """theta2 of the program straight from the thesis coefficients: S(phi + pi) - S(pi)."""
    s = THESIS_NOMINAL

    def value(x):
        return s.h0 + sum(h * np.cos(i * x + p) for i, h, p in s.harmonics)

    return value(phi + shift) - value(math.pi)


# --------------------------------------------------------------------- bench figures


def test_bench_scene_parses_to_the_source_data(bench):
    spec = bench.dynamics
    assert (spec.follower, spec.I3, spec.c3, spec.k23) == ("oscillating", 0.357, 0.205, 3050.0)
    assert spec.cam_speed_hz == pytest.approx(2.96, rel=1e-12)
    assert spec.motion_scale == 1.0  # lifts are rad for an oscillating follower
    assert "dynamics" in bench.needs()


def test_bench_natural_frequency_damping_and_resonant_harmonic():
    fn = float(d.natural_frequency_rad_s(PLANT)) / (2 * math.pi)
    zeta = float(d.damping_ratio(PLANT))
    assert fn == pytest.approx(math.sqrt(3050 / 0.357) / (2 * math.pi), rel=1e-14)
    assert fn == pytest.approx(14.71, abs=0.005)
    assert zeta == pytest.approx(0.205 / (2 * math.sqrt(3050 * 0.357)), rel=1e-14)
    assert zeta == pytest.approx(0.0031, abs=0.0001)
    n, ratio = d.resonant_harmonic(PLANT, W_BENCH)
    assert n == 5 and abs(ratio - 1) < 0.01


def test_program_fft_reproduces_the_thesis_series(bench_cam):
    """The 180+180 deg program of the rising half is the full series (band-limited FFT is exact)."""
    phi = np.asarray(d.cam_grid(997))
    got = np.asarray(d.evaluate_cam(bench_cam, phi).f)
    np.testing.assert_allclose(got, _series_numpy(phi), rtol=0, atol=1e-14)


def test_nominal_error_and_exact_compensation(bench_cam):
    phi = d.cam_grid(720)
    nominal = float(d.max_abs(d.tracking_error_harmonics(bench_cam, bench_cam, PLANT, W_BENCH), phi))
    comp = d.compensate_linear(bench_cam, PLANT, W_BENCH)
    compensated = float(d.max_abs(d.tracking_error_harmonics(comp, bench_cam, PLANT, W_BENCH), phi))
    assert nominal == pytest.approx(_errors_numpy(1.0)[0], rel=1e-9)  # independent NumPy, same grid
    # round-off: relative to the 0.48 rad motion, a few ulps at most
    assert compensated < 1e-15 * 0.5


@pytest.mark.slow
def test_time_form_of_the_compensation_equals_the_harmonic_inverse(bench, bench_cam):
    phi = d.cam_grid(512)
    timeform = d.compensate_time(d.program_values(bench, phi), PLANT, W_BENCH)
    harmonic = d.evaluate_cam(d.compensate_linear(bench_cam, PLANT, W_BENCH), phi).f
    np.testing.assert_allclose(timeform, harmonic, rtol=0, atol=1e-13)


def _errors_numpy(est: float, grid: int = 720) -> tuple[float, float]:
    """Independent reference: (nominal, compensated) max tracking error, harmonic by harmonic.

    theta2 = S(phi + pi) - S(pi) has amplitude -h_n (odd n) on cos(n phi). The load follows
    G_true(i n W) times the cam's harmonic; the nominal cam's error is (G_true - 1) a_n, the
    cam compensated with an estimate whose omega_n is est x the true one errs by (G_true/G_est - 1) a_n.
    """
    i3, c3, k23 = 0.357, 0.205, 3050.0

    def g(k, c, n):
        w = n * W_BENCH
        return k / (k - i3 * w**2 + 1j * c * w)

    phi = 2 * np.pi * np.arange(grid) / grid
    nominal = np.zeros(grid)
    compensated = np.zeros(grid)
    for n, h, _ in THESIS_NOMINAL.harmonics:
        a = h * (-1) ** n  # cos(n (phi + pi)) = (-1)^n cos(n phi)
        gt, ge = g(k23, c3, n), g(k23 * est**2, c3 * est, n)
        nominal += np.real(a * (gt - 1) * np.exp(1j * n * phi))
        compensated += np.real(a * (gt / ge - 1) * np.exp(1j * n * phi))
    return float(np.max(np.abs(nominal))), float(np.max(np.abs(compensated)))


def _ratio_numpy(est: float) -> float:
    nominal, compensated = _errors_numpy(est)
    return nominal / compensated


def test_wn_misestimated_by_10_percent(bench_cam):
    """Source 003's claim, measured: compensation cut with omega_n off by -10 % / +10 %.

    The issue asks for >= 5x; the physics gives 4.26x with the estimate 10 % low (the 5th harmonic
    sits on resonance, where G_true / G_est is about -18) and 5.75x with it 10 % high. camjax's
    figures are checked against an independent harmonic-by-harmonic NumPy computation; the low
    side's miss is asserted as a miss so a change that hides it fails.
    """
    phi = d.cam_grid(720)
    nominal = float(d.max_abs(d.tracking_error_harmonics(bench_cam, bench_cam, PLANT, W_BENCH), phi))
    ratios = {}
    for est in (0.9, 1.1):
        c = d.compensate_linear(bench_cam, d.perturbed_plant(PLANT, 1.0, est), W_BENCH)
        ratios[est] = nominal / float(d.max_abs(d.tracking_error_harmonics(c, bench_cam, PLANT, W_BENCH), phi))
        # same grid, same harmonics (the FFT of the sampled series is exact for 9 harmonics)
        assert ratios[est] == pytest.approx(_ratio_numpy(est), rel=1e-9)
    assert ratios[0.9] < 5.0 < ratios[1.1]


def test_speed_and_wn_errors_enter_only_as_their_ratio(bench_cam):
    phi = d.cam_grid(360)
    comp = d.compensate_linear(bench_cam, PLANT, W_BENCH)
    lam = jnp.array([0.8, 0.9, 1.0, 1.1, 1.2])
    kap = jnp.array([0.8, 0.9, 1.0, 1.1, 1.2])
    grid = d.robustness_grid(comp, bench_cam, PLANT, W_BENCH, jnp.array([1.0]), lam, kap, phi)[0]
    ratio = (lam[:, None] / kap[None, :]).ravel()
    at_ratio = d.robustness_grid(comp, bench_cam, PLANT, W_BENCH, jnp.array([1.0]), ratio,
                                 jnp.array([1.0]), phi)[0, :, 0]
    np.testing.assert_allclose(grid.ravel(), at_ratio, rtol=1e-10, atol=1e-15)
    assert float(jnp.max(jnp.diag(grid))) < 1e-15  # lambda = kappa: exact again
    assert float(jnp.min(grid + jnp.eye(5))) > 1e-4  # off the diagonal: a real error


# ------------------------------------------------------------ steady state, integrators


def test_steady_state_matches_the_closed_form_1dof():
    """theta2 = A cos(n phi + p): theta3 = A |G| cos(n phi + p + arg G), |G|, arg G by hand."""
    plant = d.Plant(2.0, 3.0, 5000.0)
    w, n, amp, p = 7.0, 3, 0.2, 0.4
    a = np.zeros(6)
    b = np.zeros(6)
    a[n], b[n] = amp * math.cos(p), -amp * math.sin(p)
    cam = d.CamHarmonics(jnp.asarray(a), jnp.asarray(b))
    phi = np.linspace(0, 2 * math.pi, 50)
    got = np.asarray(d.evaluate_cam(d.steady_state(cam, plant, w), phi).f)
    wf = n * w
    r = wf / math.sqrt(5000 / 2.0)
    zeta = 3.0 / (2 * math.sqrt(5000 * 2.0))
    mag = 1 / math.sqrt((1 - r * r) ** 2 + (2 * zeta * r) ** 2)
    lag = math.atan2(2 * zeta * r, 1 - r * r)
    np.testing.assert_allclose(got, amp * mag * np.cos(n * phi + p - lag), rtol=0, atol=1e-14)


def _forced_oscillator_error(steps_per_cycle: int) -> tuple[float, float, float]:
    """x'' + 2 zeta wn x' + wn^2 x = cos(w t) from rest through periodic_rk4, 20 cycles of
    M steps: (max |x - x_ss| over the last cycle, |X|, wn h) against the closed-form steady
    state x_ss = Re[X e^{i w t}], X = 1 / (wn^2 - w^2 + 2 i zeta wn w)."""
    wn, zeta, w = 2 * math.pi * 3.0, 0.1, 2 * math.pi * 1.0
    dt = 2 * math.pi / w / steps_per_cycle

    def rhs(step, t, y, _):
        time_s = step * dt + t
        return jnp.stack([y[1], jnp.cos(w * time_s) - 2 * zeta * wn * y[1] - wn**2 * y[0]])

    # transient e^{-zeta wn t} after 20 periods: e^{-37.7} = 4e-17, far below the RK4 error
    last = d.periodic_rk4(rhs, jnp.zeros(2), dt, steps_per_cycle, 20)
    x_amp = 1.0 / complex(wn**2 - w**2, 2 * zeta * wn * w)
    t = np.arange(steps_per_cycle) * dt
    exact = np.real(x_amp * np.exp(1j * w * t))
    return float(np.max(np.abs(np.asarray(last[:, 0]) - exact))), abs(x_amp), wn * dt


def test_periodic_rk4_reproduces_the_forced_oscillator_steady_state():
    """Settle-then-record on a damped oscillator under harmonic forcing, against the closed form.

    RK4 reproduces e^{lambda h} up to its (lambda h)^5 / 120 term per step, so the steady state
    carries an error of order |X| (wn h)^4 / 120 (global order 4): that is the tolerance
    (measured: about 1/6 of it). Halving h must divide the error by 2^4 = 16 (14..18 allowed:
    the next term is O(h^5)).
    """
    err_200, x_amp, wn_h = _forced_oscillator_error(200)
    assert err_200 <= x_amp * wn_h**4 / 120
    err_400, _, _ = _forced_oscillator_error(400)
    assert 14.0 < err_200 / err_400 < 18.0


def test_settling_counts_cycles_and_says_when_max_cycles_cuts_it_short():
    """cycles_needed = ceil(ln(1/tol) / (zeta wn T)) + 1 by hand for the bench (zeta wn from
    c3 / (2 I3)); a cap below it gives settled = False and the residual e^{-zeta wn T cycles}."""
    decay = 0.205 / (2 * 0.357)  # zeta wn = c3 / (2 I3), 1/s
    period = 2 * math.pi / W_BENCH
    needed = math.ceil(math.log(1e9) / (decay * period)) + 1
    full = d.settling(PLANT, W_BENCH, 1e-9, 10 * needed)
    assert (full.cycles, full.cycles_needed, full.settled) == (needed, needed, True)
    assert full.residual_factor <= 1e-9
    cut = d.settling(PLANT, W_BENCH, 1e-9, 20)
    assert (cut.cycles, cut.cycles_needed, cut.settled) == (20, needed, False)
    assert cut.residual_factor == pytest.approx(math.exp(-decay * period * 20), rel=1e-12)
    undamped = d.settling(d.Plant(0.357, 0.0, 3050.0), W_BENCH, 1e-9, 50)
    assert (undamped.cycles, undamped.cycles_needed, undamped.settled) == (50, None, False)


def test_rk4_matches_solve_ivp_on_a_transient(bench_cam):
    """From rest, 2 cycles: RK4 (M = 720) against solve_ivp (DOP853, rtol 1e-12)."""
    m, cycles = 720, 2
    u = d.evaluate_cam(bench_cam, d.cam_grid(2 * m)).f
    last = d.integrate_train(PLANT, u, W_BENCH, cycles)

    def rhs(t, y):
        th2 = _series_numpy(W_BENCH * t)
        return [y[1], (3050.0 * (th2 - y[0]) - 0.205 * y[1]) / 0.357]

    period = 2 * math.pi / W_BENCH
    t_eval = period * (cycles - 1 + np.arange(m) / m)
    sol = scipy.integrate.solve_ivp(rhs, (0, t_eval[-1]), [float(u[0]), 0.0], method="DOP853",
                                    t_eval=t_eval, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.asarray(last.angle), sol.y[0], rtol=0, atol=2e-8)


def test_the_cycle_count_is_data_under_its_bound(bench_cam):
    """A program bounded by max_cycles runs every count up to it: 2 and 4 cycles through one
    compiled program (the second count adds nothing to the jit's cache), each equal to the program compiled for its
    own count (no bound: the count is the loop's length) to the last bit (the same RK4 steps in
    the same order; skipped cycles change nothing), and 2 cycles differ from 4 (the transient
    from rest has not decayed: e^{-zeta wn t} ~ 0.8 per cycle here). A count traced under ``jit``
    runs with the bound (the same numbers) and fails without it; a bound below 1 is refused."""
    u = d.evaluate_cam(bench_cam, d.cam_grid(2 * 90)).f
    program = integrate._integrate_train
    bounded = [np.asarray(d.integrate_train(PLANT, u, W_BENCH, 2, max_cycles=6).angle)]
    compiled = program._cache_size()
    bounded.append(np.asarray(d.integrate_train(PLANT, u, W_BENCH, 4, max_cycles=6).angle))
    assert program._cache_size() == compiled
    for c, got in zip((2, 4), bounded, strict=True):
        np.testing.assert_array_equal(got, np.asarray(d.integrate_train(PLANT, u, W_BENCH, c).angle))
    assert np.max(np.abs(bounded[0] - bounded[1])) > 1e-4
    # everything an argument (captured arrays would be folded in as constants: other last bits)
    traced = jax.jit(lambda p, uu, w, c: d.integrate_train(p, uu, w, c, max_cycles=6).angle)(PLANT, u, W_BENCH, 4)
    np.testing.assert_array_equal(np.asarray(traced), bounded[1])
    with pytest.raises(TypeError, match="n_cycles"):
        jax.jit(lambda c: d.integrate_train(PLANT, u, W_BENCH, c))(3)
    with pytest.raises(ValueError, match="max_cycles"):
        d.integrate_train(PLANT, u, W_BENCH, 1, max_cycles=0)


@pytest.mark.slow
def test_harmonic_steady_state_agrees_with_rk4_after_transients(bench_cam):
    """Run RK4 from rest until e^{-zeta wn t} < 1e-9; the harmonic solution is the limit.

    Measured difference 1.4e-7 rad with M = 720 (2.8e-6 of the 0.049 rad error), and it falls
    as M^-4 (RK4): the gap is the integrator's, not the steady state's.
    """
    cycles = d.settling_cycles(PLANT, W_BENCH, 1e-9, DynamicsSpec.max_cycles)
    assert 150 < cycles < 300
    diffs = []
    for m in (360, 720):
        u = d.evaluate_cam(bench_cam, d.cam_grid(2 * m)).f
        load = d.integrate_train(PLANT, u, W_BENCH, cycles).angle
        harm = d.evaluate_cam(d.steady_state(bench_cam, PLANT, W_BENCH), d.cam_grid(m)).f
        diffs.append(float(jnp.max(jnp.abs(load - harm))))
    assert diffs[1] < 3e-7
    assert 10 < diffs[0] / diffs[1] < 22  # fourth order: 2^4 = 16


# --------------------------------------------------------------------------- jump


def _fmin_numpy(hz, phi, ks, x0, i2):
    """min contact force of the bench cam at each speed in ``hz`` (K,), NumPy, from the series."""
    w = 2 * math.pi * np.atleast_1d(hz)[:, None]
    i3, c3, k23 = 0.357, 0.205, 3050.0
    f = _series_numpy(phi)
    d2f = np.zeros_like(phi)
    load = np.full((w.shape[0], phi.size), THESIS_NOMINAL.h0 - _offset())
    for i, h, p in THESIS_NOMINAL.harmonics:
        x = i * (phi + math.pi) + p
        g = k23 / (k23 - i3 * (i * w) ** 2 + 1j * c3 * i * w)
        load += np.real(h * g * np.exp(1j * x))
        d2f += -(i**2) * h * np.cos(x)
    force = i2 * w**2 * d2f + ks * (f + x0) + k23 * (f - load)
    return force.min(axis=1)


def _offset():
    """S(pi): the program's level 0 is the series' value at 180 deg."""
    return THESIS_NOMINAL.h0 + sum(h * math.cos(i * math.pi + p) for i, h, p in THESIS_NOMINAL.harmonics)


def _first_negative_bracket(fmin, speeds):
    vals = fmin(speeds)
    k = int(np.argmax(vals <= 0))
    assert k > 0 and vals[k] <= 0
    return speeds[k - 1], speeds[k]


@pytest.mark.slow
def test_jump_speed_agrees_with_brentq(bench, bench_cam):
    spec = bench.dynamics
    closure = d.closure_of(spec)
    phi = d.cam_grid(720)
    # the cam speed among the scanned speeds, as `camjax dynamics` scans them: the CLI test below
    # then runs this program
    js = d.jump_speed(bench_cam, PLANT, closure, phi, 0.1 * W_BENCH, 10 * W_BENCH, include_rad_s=jnp.asarray([W_BENCH]))
    assert bool(js.found)
    hz = float(js.speed_rad_s) / (2 * math.pi)
    phin = np.asarray(phi)

    def fmin(h):
        return _fmin_numpy(h, phin, spec.spring_rate, spec.spring_preload, spec.I2)

    # bracket independently: a 1 mHz scan of the NumPy force, then brentq
    lo, hi = _first_negative_bracket(fmin, np.arange(0.3, 10.0, 0.001))
    root = scipy.optimize.brentq(lambda h: fmin(h)[0], lo, hi, xtol=1e-14, rtol=1e-14)
    assert hz == pytest.approx(root, rel=1e-9)
    assert hz == pytest.approx(2.9363, abs=1e-3)  # just below 2.96 Hz: the 5th-harmonic resonance


@pytest.mark.slow
def test_min_preload_and_spring_rate_put_the_force_at_zero(bench, bench_cam):
    spec = bench.dynamics
    closure = d.closure_of(spec)
    phi = d.cam_grid(720)
    x0 = d.min_preload(bench_cam, PLANT, closure, W_BENCH, phi)
    ks = d.min_spring_rate(bench_cam, PLANT, closure, W_BENCH, phi)
    f_x0 = d.min_contact_force(bench_cam, PLANT, closure._replace(spring_preload=x0), W_BENCH, phi)
    f_ks = d.min_contact_force(bench_cam, PLANT, closure._replace(spring_rate=ks), W_BENCH, phi)
    assert abs(float(f_x0)) < 1e-9 and abs(float(f_ks)) < 1e-9
    assert float(x0) < spec.spring_preload and float(ks) < spec.spring_rate  # the scene has margin


TRANSLATING = """
[dynamics]
follower = "translating"
I3 = 0.5
c3 = 2.0
k23 = 2.0e5
compute = ["compensation", "jump"]
samples = 1024
harmonics = 200
"""


@pytest.mark.slow
def test_translating_follower_takes_its_spring_from_follower_and_jumps_at_a_root():
    scene = parse_scene(builtin_scene_text("default") + TRANSLATING, "translating")
    spec = scene.dynamics
    assert spec.motion_scale == 1e-3 and spec.I2 == 1.0 and spec.spring_rate == 3004.0
    assert spec.spring_preload == pytest.approx(0.013) and spec.weight == pytest.approx(9.81)
    cam = d.program_cam(scene)
    plant, closure = d.plant_of(spec), d.closure_of(spec)
    phi = d.cam_grid(spec.samples)
    js = d.jump_speed(cam, plant, closure, phi, 2 * math.pi * 0.5, 2 * math.pi * 40)
    assert bool(js.found)
    # independent: the same samples, NumPy FFT, a 1 mHz scan for the bracket, brentq
    s = np.asarray(camjax.program.evaluate(scene.motion.program, 1024).s) * 1e-3
    z = np.fft.rfft(s)[:201] / 1024
    z[1:] *= 2
    n = np.arange(201)
    e = np.exp(1j * n[None, :] * np.asarray(phi)[:, None])  # (N, H+1)
    f, d2f, df = np.real(e @ z), np.real(e @ (-(n**2) * z)), np.real(e @ (1j * n * z))

    def fmin(hz):
        w = 2 * math.pi * np.atleast_1d(hz)[:, None]
        g = 2.0e5 / (2.0e5 - 0.5 * (n * w) ** 2 + 1j * 2.0 * n * w)  # (K, H+1)
        load = np.real((g * z) @ e.T)
        force = 1.0 * w**2 * d2f + 0.345 * w * df + 3004.0 * (f + 0.013) + 2.0e5 * (f - load) + 9.81
        return force.min(axis=1)

    hz = float(js.speed_rad_s) / (2 * math.pi)
    lo, hi = _first_negative_bracket(fmin, np.arange(0.5, 8.0, 0.001))
    root = scipy.optimize.brentq(lambda h: fmin(h)[0], lo, hi, xtol=1e-13, rtol=1e-13)
    assert hz == pytest.approx(root, rel=1e-8)
    # a narrow window at the 21st harmonic's resonance (cycloidal laws are not band-limited):
    # the grid alone (0.15 Hz steps) would step over it; the resonant speeds catch it
    assert round(float(d.natural_frequency_rad_s(plant)) / float(js.speed_rad_s)) == 21


JUMP_SMALL = """I2 = 0.126
samples = 128
harmonics = 20
compute = ["jump"]
"""  # the bench cam has 9 harmonics: 20 of 128 samples hold it exactly


def _jump_summary(closure: str) -> dict:
    """dynamics.json's ``jump`` of the bench train with the force closure ``closure`` (TOML lines)."""
    return d.scene_dynamics(parse_scene(bench_with(BENCH_TRAIN + closure + JUMP_SMALL), "bench")).summary["jump"]


def _assert_jump_consistent(j: dict, cam_speed_hz: float) -> None:
    """The jump report says one thing: a jump speed, or the reason it has none."""
    lo, hi = j["search_range_hz"]
    in_range = lo <= cam_speed_hz <= hi
    assert j["cam_speed_in_range"] is in_range
    status = j["jump_speed_status"]
    assert status in ("found", "lost_at_lowest_speed", "holds_in_range")
    assert (j["jump_speed_hz"] is not None) is (status == "found")
    assert isinstance(j["note"], str) and j["note"]
    if status == "found":
        assert lo < j["jump_speed_hz"] <= hi
    if in_range and j["contact_lost_at_cam_speed"]:  # lost at the cam speed: lost at or below it
        assert status == "lost_at_lowest_speed" or j["jump_speed_hz"] <= cam_speed_hz
    if in_range and status == "holds_in_range":
        assert not j["contact_lost_at_cam_speed"]


@pytest.mark.parametrize("closure, status", [
    # the bench spring: contact lost from the 5th harmonic's resonance at 2.9363 Hz (brentq, above)
    ("spring_rate = 300.0\nspring_preload = 0.5\n", "found"),
    # a spring pulling the follower off its cam (x0 = -1 rad, lift 0.48 rad): lost at every speed
    ("spring_rate = 300.0\nspring_preload = -1.0\n", "lost_at_lowest_speed"),
    # a weak spring, lost at the cam speed 2.96 Hz, scanned only over 0.1 .. 1 Hz where it holds
    ("spring_rate = 100.0\nspring_preload = 0.5\njump_speed_range_hz = [0.1, 1.0]\n", "holds_in_range"),
])
@pytest.mark.slow
def test_jump_report_gives_the_speed_or_the_reason_it_has_none(closure, status):
    j = _jump_summary(closure)
    _assert_jump_consistent(j, 2.96)
    assert j["jump_speed_status"] == status
    # independent facts of each case: the NumPy force from the thesis series on the same grid
    ks, x0 = (float(line.split(" = ")[1]) for line in closure.splitlines()[:2])
    phi = 2 * np.pi * np.arange(128) / 128
    lo, hi = j["search_range_hz"]
    at_cam = _fmin_numpy([2.96], phi, ks, x0, 0.126)[0]
    assert j["contact_lost_at_cam_speed"] is bool(at_cam <= 0)
    if status == "found":
        assert j["jump_speed_hz"] == pytest.approx(2.9363, abs=1e-3)
        assert not j["contact_lost_at_cam_speed"]  # the window closes again below 2.96 Hz
    elif status == "lost_at_lowest_speed":
        assert _fmin_numpy([lo], phi, ks, x0, 0.126)[0] <= 0 and at_cam <= 0
        assert "lowest speed" in j["note"]
    else:
        # a 1 mHz scan of the range: contact holds throughout; it is lost at the cam speed
        assert _fmin_numpy(np.arange(lo, hi + 5e-4, 1e-3), phi, ks, x0, 0.126).min() > 0 and at_cam <= 0
        assert not j["cam_speed_in_range"] and "jump_speed_range_hz" in j["note"]


# --------------------------------------------------------------- drive and nonlinear FF


@pytest.mark.slow
def test_nonlinear_feedforward_removes_the_ripple_error(bench, bench_cam):
    """With drive flexibility, the linear cam still misses; the nonlinear one tracks.

    Shorter settling (1e-5) and M = 360 than the CLI to keep the test quick.
    """
    spec = bench.dynamics
    drive = d.drive_of(spec)
    cam = d.trim_harmonics(bench_cam)
    m, cycles = 360, d.settling_cycles(PLANT, W_BENCH, 1e-5, DynamicsSpec.max_cycles)
    target = d.evaluate_cam(cam, d.cam_grid(m)).f
    lin = d.compensate_linear(cam, PLANT, W_BENCH)
    nl = d.compensate_nonlinear(cam, drive, PLANT, W_BENCH, 60, cycles, m)
    assert float(nl.fit_rms) < 1e-12
    errs = {}
    for name, c in (("nominal", cam), ("linear", lin), ("nonlinear", nl.cam)):
        # each cam trimmed as `camjax dynamics` trims it (harmonics below 1e-13 of the largest):
        # the command's drive runs of the bench (the CLI test below) are then these programs
        r = d.simulate_drive(d.trim_harmonics(c), drive, PLANT, W_BENCH, cycles, m)
        errs[name] = float(jnp.max(jnp.abs(r.load - target)))
        ripple = float(jnp.max(jnp.abs(r.cam_speed - W_BENCH)) / W_BENCH)
        assert 0.01 < ripple < 0.1  # the cam speed does ripple, by a few percent
    # the linear cam ignores the speed ripple: it leaves a sizeable part of the error (measured 59 %)
    assert errs["linear"] > 0.25 * errs["nominal"]
    assert errs["nonlinear"] < 1e-4 * errs["nominal"]


@pytest.mark.slow
def test_drive_reduces_to_the_train_when_the_coupling_is_rigid(bench_cam):
    """Stiff, well-damped coupling: theta1 ~ Omega t and the load follows the rigid-drive train.

    Explicit RK4 needs sqrt(k01/I1) dt < ~2.8: k01 = 1e6 (110 Hz drive mode, zeta 0.5) with
    M = 720 gives 0.32. Both runs start alike, so transients cancel in the comparison.
    """
    drive = d.Drive(2.1, 0.126, 1e6, 1500.0)
    m = 720
    cam = d.trim_harmonics(bench_cam)
    r = d.simulate_drive(cam, drive, PLANT, W_BENCH, 30, m)
    assert float(jnp.max(jnp.abs(r.cam_speed - W_BENCH))) < 2e-3 * W_BENCH
    u = d.evaluate_cam(cam, d.cam_grid(2 * m)).f
    free = d.integrate_train(PLANT, u, W_BENCH, 30).angle
    assert float(jnp.max(jnp.abs(r.load - free))) < 1e-3 * float(jnp.max(jnp.abs(free - free.mean())))


# --------------------------------------------------------------------- gradients


def _central(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


def test_gradient_of_the_steady_state_error_matches_finite_differences(bench_cam):
    def ms(params):
        k23, c3, i3 = params
        return d.mean_square(d.tracking_error_harmonics(bench_cam, bench_cam, d.Plant(i3, c3, k23),
                                                        W_BENCH))

    x = jnp.array([3050.0, 0.205, 0.357])
    g = jax.jit(jax.grad(ms))(x)  # one program (eagerly: the forward and the backward pass)
    for i, h in enumerate((1e-2, 1e-6, 1e-6)):
        e = jnp.zeros(3).at[i].set(h)
        fd = (ms(x + e) - ms(x - e)) / (2 * h)
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-6)


@pytest.mark.slow
def test_gradient_through_rk4_scan_matches_finite_differences(bench_cam):
    u = d.evaluate_cam(bench_cam, d.cam_grid(180)).f

    def final(k23):
        return jnp.sum(d.integrate_train(d.Plant(0.357, 0.205, k23), u, W_BENCH, 3).angle ** 2)

    g = float(jax.jit(jax.grad(final))(3050.0))  # one program (eagerly: the forward and the backward pass)
    fd = float(_central(final, 3050.0, 1e-2))
    assert g == pytest.approx(fd, rel=1e-6)


@pytest.mark.slow
def test_gradient_of_the_jump_force_and_band_objective(bench, bench_cam):
    spec = bench.dynamics
    closure = d.closure_of(spec)
    phi = d.cam_grid(360)

    def mean_force(w):
        return jnp.mean(d.contact_force(bench_cam, PLANT, closure, w, phi) ** 2)

    assert float(jax.jit(jax.grad(mean_force))(W_BENCH)) == pytest.approx(
        float(_central(mean_force, W_BENCH, 1e-5)), rel=1e-6)
    band = W_BENCH * jnp.linspace(0.9, 1.1, 5)

    def band_obj(a5):
        cam = bench_cam._replace(cos=bench_cam.cos.at[5].set(a5))
        return d.band_tracking_ms(cam, PLANT, band)

    a5 = float(bench_cam.cos[5])
    assert float(jax.jit(jax.grad(band_obj))(a5)) == pytest.approx(float(_central(band_obj, a5, 1e-7)), rel=1e-6)


@pytest.mark.slow
def test_gradient_through_the_drive_model_matches_finite_differences(bench, bench_cam):
    cam = d.trim_harmonics(bench_cam)

    def ripple(k01):
        r = d.simulate_drive(cam, d.Drive(2.1, 0.126, k01, 10.0), PLANT, W_BENCH, 2, 90)
        return jnp.mean((r.cam_speed - W_BENCH) ** 2)

    g = float(jax.jit(jax.grad(ripple))(3000.0))  # one program (eagerly: the forward and the backward pass)
    assert g == pytest.approx(float(_central(ripple, 3000.0, 1e-2)), rel=1e-5)


@settings(max_examples=25, deadline=None)
@given(st.floats(0.05, 5.0), st.floats(0.0, 50.0), st.floats(1e2, 1e6), st.floats(0.5, 50.0),
       st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12))
def test_compensation_round_trips_for_any_plant_and_law(inertia, damping, stiffness, omega, coefs):
    """steady_state(compensate_linear(cam)) == cam for every plant, speed and law (relative 1e-13)."""
    a = jnp.asarray([0.3, *coefs[:5]])
    b = jnp.asarray([0.0, *coefs[6:11]])
    cam = d.CamHarmonics(a, b)
    plant = d.Plant(inertia, damping, stiffness)
    back = d.steady_state(d.compensate_linear(cam, plant, omega), plant, omega)
    scale = float(jnp.max(jnp.abs(a)) + jnp.max(jnp.abs(b)))
    # dividing by G and multiplying by the same G: a few ulps (measured <= 2e-16 relative)
    np.testing.assert_allclose(back.cos, a, atol=1e-13 * scale)
    np.testing.assert_allclose(back.sin, b, atol=1e-13 * scale)


def test_kernels_do_not_retrace_for_new_parameter_values(bench_cam):
    phi = d.cam_grid(360)
    d.max_abs(d.tracking_error_harmonics(bench_cam, bench_cam, PLANT, W_BENCH), phi)
    before = d.tracking_error_harmonics._cache_size(), d.max_abs._cache_size()
    for k in (2000.0, 2500.0, 4000.0):
        d.max_abs(d.tracking_error_harmonics(bench_cam, bench_cam, PLANT._replace(stiffness=k), 1.1 * k),
                  phi)
    assert (d.tracking_error_harmonics._cache_size(), d.max_abs._cache_size()) == before


@pytest.mark.slow
def test_law_shaping_lowers_band_vibration_and_keeps_the_lift(bench, bench_cam):
    c_phi, c_val = d.shaping_constraints(bench)
    lift = 2 * sum(h for _, h, _ in THESIS_NOMINAL.harmonics)  # S(2 pi) - S(pi), odd harmonics
    np.testing.assert_allclose(c_val, [0.0, lift], atol=1e-12)
    band = W_BENCH * jnp.linspace(0.9, 1.1, 9)
    cam0 = d.pad_harmonics(bench_cam, 15)
    res = d.shape_law(cam0, PLANT, band, jnp.asarray(c_phi), jnp.asarray(c_val), 0.48, steps=100)
    before = float(jnp.sqrt(d.band_tracking_ms(cam0, PLANT, band)))
    assert float(res.tracking_rms) < 0.6 * before  # measured 0.0073 vs 0.0158 rad
    assert float(res.constraint_max) < 1e-5  # quadratic penalty: ~1e-6 rad after 100 steps


# ------------------------------------------------------------------- scene and CLI


@pytest.mark.parametrize("extra, field", [
    ('bogus = 1', "dynamics.bogus"),
    ('I1 = 2.0', "dynamics.I1"),
    ('compute = ["jump"]', "dynamics.compute"),
    ('compute = ["drive"]', "dynamics.compute"),
    ('compute = ["everything"]', "dynamics.compute"),
    ('samples = 64\nharmonics = 40', "dynamics.harmonics"),
    ('I3 = 0.0', "dynamics.I3"),
])
def test_dynamics_section_errors_name_the_field(extra, field):
    base = {"follower": '"oscillating"', "I3": "0.3", "c3": "0.1", "k23": "1000.0"}
    key = extra.split(" = ")[0]
    lines = [f"{k} = {v}" for k, v in base.items() if k != key] + [extra]
    text = builtin_scene_text("default").replace("lift_mm = 5.0", "lift_mm = 0.5")  # rad
    text += "\n[dynamics]\n" + "\n".join(lines) + "\n"
    with pytest.raises(SceneError) as err:
        parse_scene(text)
    assert err.value.field == field


def test_oscillating_lift_beyond_pi_is_refused():
    text = builtin_scene_text("default").replace("lift_mm = 5.0", "lift_mm = 4.0")
    text += "[dynamics]\nfollower = \"oscillating\"\nI3 = 0.3\nc3 = 0.1\nk23 = 1000.0\n"
    with pytest.raises(SceneError, match="read as rad"):
        parse_scene(text)


def bench_with(dynamics: str) -> str:
    """The thesis-bench scene with ``dynamics`` (a [dynamics] section's text) for its own."""
    text = builtin_scene_text("thesis-bench")
    return text[: text.index("\n[dynamics]\n")] + dynamics


BENCH_TRAIN = """
[dynamics]
follower = "oscillating"
I3 = 0.357
c3 = 0.205
k23 = 3050.0
"""  # the bench's follower train; a test adds the rest of its [dynamics] section

BENCH_DRIVE = BENCH_TRAIN + """I2 = 0.126
I1 = 2.1
k01 = 3000.0
c01 = 10.0
spring_rate = 300.0
spring_preload = 0.5
"""  # and its drive and spring

SMALL_BENCH = BENCH_DRIVE + """steps_per_cycle = 360
transient_tolerance = 1e-5
shaping_steps = 100
compute = ["compensation", "robustness", "time_domain", "drive", "nonlinear", "jump", "shaping"]
speed_factors = [0.9, 1.0, 1.1]
wn_factors = [0.9, 1.0, 1.1]
damping_factors = [0.5, 1.0, 2.0]
"""


@pytest.mark.slow
def test_cli_dynamics_writes_json_and_figures(tmp_path):
    """The bench with a shorter settling; grid sizes match the tests above so kernels are reused."""
    text = bench_with(SMALL_BENCH)
    path = tmp_path / "bench.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert camjax.cli.main(["dynamics", str(path), "--out", str(out), "--dpi", "40"]) == 0
    data = json.loads((out / "dynamics.json").read_text())
    assert data["natural_frequency_hz"] == pytest.approx(14.71, abs=0.01)
    assert data["damping_ratio"] == pytest.approx(0.0031, abs=1e-4)
    assert data["compensated"]["max_tracking_error"] < 1e-15 < data["nominal"]["max_tracking_error"]
    assert len(data["robustness"]) == 27
    assert set(data["robustness"][0]) >= {"damping_factor", "speed_factor", "wn_factor", "max_tracking_error"}
    for key in ("time_domain", "drive", "nonlinear", "jump", "shaping", "speed_wn_equivalence"):
        assert key in data
    for name in ("motion", "compensated_cam", "robustness", "drive", "jump"):
        assert (out / f"dynamics_{name}.png").stat().st_size > 1000
    assert data["settling"]["settled"] is True
    assert data["settling"]["cycles"] == data["time_domain"]["cycles"] == data["drive"]["cycles"]


@pytest.mark.slow
def test_cli_dynamics_warns_when_max_cycles_stops_the_transient(tmp_path, capsys):
    """max_cycles = 3 on the bench (it needs 120 cycles for a tolerance of 1e-5): one warning
    line on stderr, dynamics.json says settled = false with the residual e^{-zeta wn 3 T}."""
    text = bench_with(BENCH_TRAIN + """samples = 128
harmonics = 20
steps_per_cycle = 64
transient_tolerance = 1e-5
max_cycles = 3
compute = ["time_domain"]
""")
    path = tmp_path / "bench.toml"
    path.write_text(text)
    assert camjax.cli.main(["dynamics", str(path), "--out", str(tmp_path / "out"), "--dpi", "30"]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "max_cycles = 3" in warnings[0]
    data = json.loads((tmp_path / "out" / "dynamics.json").read_text())
    decay = 0.205 / (2 * 0.357)  # zeta wn = c3 / (2 I3)
    assert data["settling"]["settled"] is False
    assert data["settling"]["cycles"] == data["time_domain"]["cycles"] == 3
    assert data["settling"]["cycles_needed"] == math.ceil(math.log(1e5) / (decay * 2 * math.pi / W_BENCH)) + 1
    assert data["settling"]["residual_factor"] == pytest.approx(math.exp(-decay * 3 * 2 * math.pi / W_BENCH),
                                                                rel=1e-12)


def test_cli_dynamics_refuses_a_scene_without_dynamics(tmp_path, capsys):
    assert camjax.cli.main(["dynamics", "default", "--out", str(tmp_path / "o")]) == 2
    assert "no [dynamics] section" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


BASE_KEYS = {"scene", "follower", "units", "cam_speed_hz", "natural_frequency_hz", "damping_ratio",
             "resonant_harmonic", "samples", "harmonics", "nominal"}


@pytest.mark.slow
@pytest.mark.parametrize("entry, keys", [
    ("compensation", {"compensated"}),
    ("robustness", {"compensated", "robustness", "speed_wn_equivalence"}),
    ("time_domain", {"time_domain", "settling"}),
    ("drive", {"drive", "settling"}),
    ("nonlinear", {"nonlinear", "drive", "settling"}),
    ("jump", {"jump"}),
    ("shaping", {"shaping"}),
])
def test_each_compute_entry_runs_alone_and_writes_only_its_keys(entry, keys):
    """compute = [entry]: the report holds that analysis (and what it needs), nothing else."""
    text = bench_with(BENCH_DRIVE + f"""samples = 128
harmonics = 20
steps_per_cycle = 64
transient_tolerance = 0.01
shaping_steps = 5
compute = ["{entry}"]
""")
    report = d.scene_dynamics(parse_scene(text, "bench"))
    assert set(report.summary) == BASE_KEYS | keys


@pytest.mark.slow
def test_the_design_path_does_not_even_import_the_dynamics_models(tmp_path):
    """In a fresh process, `camjax design` on the default scene leaves camjax.dynamics unloaded:
    a scene without [dynamics] cannot trace (or even import) any dynamics code."""
    import subprocess
    import sys

    code = ("import sys, camjax, camjax.cli\n"
            f"assert camjax.cli.main(['design', '--out', {str(tmp_path / 'd')!r}]) == 0\n"
            "assert 'dynamics' not in camjax.load_scene().needs()\n"
            "print('LOADED' if 'camjax.dynamics' in sys.modules else 'NOT LOADED')\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip().endswith("NOT LOADED")


@pytest.mark.slow
def test_meanwhile_sees_each_thread_but_the_last_as_it_finishes():
    """scene_dynamics calls ``meanwhile`` with this thread's analyses, then once per finished
    thread but the last (two threads here: time domain and jump): each report holds what the one
    before held and at least one more analysis, and the return value holds everything."""
    text = bench_with(BENCH_TRAIN + """spring_rate = 300.0
spring_preload = 0.5
samples = 128
harmonics = 20
steps_per_cycle = 64
transient_tolerance = 0.01
compute = ["compensation", "time_domain", "jump"]
""")
    seen = []
    final = d.scene_dynamics(parse_scene(text, "bench"), meanwhile=lambda r: seen.append(set(r.summary)))
    assert len(seen) == 2  # after this thread's compensation, then after the first thread finished
    assert seen[0] == BASE_KEYS | {"compensated", "settling"}  # settling is known before the runs
    assert seen[0] < seen[1] < set(final.summary) == BASE_KEYS | {"compensated", "time_domain", "settling", "jump"}


# ------------------------------------------------------------ work estimate and budget

# unit costs: one "second" per RK4 step of the train, nothing else, so the estimate is a count
COUNT_TRAIN_STEPS = budget.Costs(table_ns=0.0, batch_ns=0.0, train_step_ns=1e9, drive_step_us=(0, 0, 0, 0),
                                 nonlinear_step_us=(0, 0, 0, 0), lstsq_ns=0.0, shaping_step_us=(0, 0))
# and one "second" per batched table entry
COUNT_BATCHED = budget.Costs(table_ns=0.0, batch_ns=1e9, train_step_ns=0.0, drive_step_us=(0, 0, 0, 0),
                             nonlinear_step_us=(0, 0, 0, 0), lstsq_ns=0.0, shaping_step_us=(0, 0))


@pytest.mark.parametrize("steps_per_cycle, max_cycles", [(64, 3), (128, 3), (64, 100_000), (1000, 50)])
def test_work_estimate_counts_the_rk4_steps_the_fields_ask_for(steps_per_cycle, max_cycles):
    """time_domain runs 2 x cycles x steps_per_cycle RK4 steps; cycles = min(max_cycles, the cycles
    e^{-zeta wn t} needs to fall below transient_tolerance), counted here in closed form."""
    text = bench_with(BENCH_TRAIN + f"""steps_per_cycle = {steps_per_cycle}
max_cycles = {max_cycles}
transient_tolerance = 1e-5
compute = ["time_domain"]
""")
    scene = parse_scene(text, "bench")
    decay = 0.205 / (2 * 0.357)  # zeta wn = c3 / (2 I3)
    cycles = min(max_cycles, math.ceil(math.log(1e5) / (decay / 2.96)) + 1)
    work = budget.estimate_work(scene, COUNT_TRAIN_STEPS)
    # 1e9 ns x 1e-9 s/ns per step: exact up to a rounding of the product (1e-15)
    assert work.piece("time_domain").seconds == pytest.approx(2 * cycles * steps_per_cycle, rel=1e-12)
    assert work.seconds == pytest.approx(2 * cycles * steps_per_cycle, rel=1e-12)
    why = "max_cycles" if cycles == max_cycles else "transient_tolerance"
    assert work.piece("time_domain").fields == ("steps_per_cycle", why)


def test_work_estimate_grows_with_the_grids_as_the_fields_say():
    """robustness: (2 A B C + B C) plants (compensated and nominal over the grid, and the B C
    ratios) batched over the samples x (harmonics + 1) table; every grid analysis is linear in
    samples (a table per sample)."""
    base = BENCH_TRAIN + """spring_rate = 300.0
spring_preload = 0.5
samples = {n}
harmonics = 20
damping_factors = [0.5, 1.0]
speed_factors = [0.9, 1.0, 1.1]
wn_factors = [{kappa}]
compute = ["robustness", "jump", "compensation"]
"""
    for n, kappa, (a, b, c) in ((128, "1.0", (2, 3, 1)), (256, "0.9, 1.0, 1.1, 1.2", (2, 3, 4))):
        scene = parse_scene(bench_with(base.format(n=n, kappa=kappa)), "bench")
        rob = budget.estimate_work(scene, COUNT_BATCHED).piece("robustness")
        assert rob.seconds == pytest.approx((2 * a * b * c + b * c) * n * 21, rel=1e-12)
        assert {"damping_factors", "speed_factors", "wn_factors", "samples"} <= set(rob.fields)
    small, large = (budget.estimate_work(parse_scene(bench_with(base.format(n=n, kappa="1.0")), "bench"))
                    for n in (128, 1024))
    for name in ("nominal", "compensation", "jump", "robustness"):
        assert large.piece(name).seconds == pytest.approx(8 * small.piece(name).seconds, rel=1e-12)


def test_the_bench_and_small_scenes_are_under_the_budget(bench):
    for scene in (bench, parse_scene(bench_with(SMALL_BENCH), "bench")):
        work = budget.estimate_work(scene)
        assert 0 < work.seconds < budget.BUDGET_S
        assert budget.refusal(scene, work) is None
        assert {p.name for p in work.pieces} == {"nominal", *scene.dynamics.compute}


OVER_BUDGET = BENCH_TRAIN.replace("c3 = 0.205", "c3 = 0.0") + """steps_per_cycle = 100000
max_cycles = 100000
compute = ["time_domain"]
"""  # undamped: the transient never decays, every run takes max_cycles


def test_cli_dynamics_refuses_a_scene_over_the_budget_naming_the_fields(tmp_path, capsys):
    path = tmp_path / "big.toml"
    path.write_text(bench_with(OVER_BUDGET))
    out = tmp_path / "out"
    assert camjax.cli.main(["dynamics", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "dynamics.steps_per_cycle = 100000" in err and "dynamics.max_cycles = 100000" in err
    assert "2e+10 RK4 steps" in err  # 2 runs x 1e5 cycles x 1e5 steps
    assert "budget" in err and "--force" in err
    assert not out.exists()
    scene = parse_scene(bench_with(OVER_BUDGET), "big")
    work = budget.estimate_work(scene)
    assert work.seconds > budget.BUDGET_S and budget.refusal(scene, work) is not None
    assert budget.refusal(scene, work, force=True) is None  # --force: the run goes ahead


@pytest.mark.slow
def test_force_runs_a_scene_over_the_budget_and_a_terminal_gets_a_progress_bar(tmp_path, capsys, monkeypatch):
    """A budget of 1 ns puts a small scene over it: refused without --force (nothing written),
    run with it. With CAMJAX_PROGRESS=1 (as on a terminal) stderr gets the bar and its ETA; piped,
    none."""
    monkeypatch.setattr(budget, "BUDGET_S", 1e-9)
    path = tmp_path / "small.toml"
    path.write_text(bench_with(BENCH_TRAIN + 'samples = 128\nharmonics = 20\ncompute = ["compensation"]\n'))
    out = tmp_path / "out"
    assert camjax.cli.main(["dynamics", str(path), "--out", str(out), "--dpi", "30"]) == 2
    err = capsys.readouterr().err
    assert "dynamics.samples = 128" in err and "dynamics.harmonics = 20" in err and not out.exists()
    monkeypatch.setenv("CAMJAX_PROGRESS", "1")
    assert camjax.cli.main(["dynamics", str(path), "--out", str(out), "--dpi", "30", "--force"]) == 0
    assert "ETA" in capsys.readouterr().err and (out / "dynamics.json").exists()
    monkeypatch.delenv("CAMJAX_PROGRESS")
    assert camjax.cli.main(["dynamics", str(path), "--out", str(out), "--dpi", "30", "--force"]) == 0
    err = capsys.readouterr().err
    assert "ETA" not in err and "%|" not in err


def test_work_progress_credits_running_and_finished_analyses():
    import io
    import time

    work = budget.WorkEstimate((budget.Piece("nominal", 2.0, "", ()), budget.Piece("jump", 6.0, "", ())))
    stream = io.StringIO()
    bar = budget.WorkProgress(work, file=stream, interval_s=60.0)
    try:
        assert bar.credited() == 0.0
        bar.start("nominal")
        t0 = time.monotonic()
        assert bar.credited(t0 + 1.0) == pytest.approx(1.0, abs=0.1)  # running: its time so far
        assert bar.credited(t0 + 100.0) == pytest.approx(0.95 * 2.0)  # never past 95 % of its estimate
        bar.finish("nominal")
        assert bar.credited(t0 + 100.0) == pytest.approx(2.0)
        bar.start("jump")
        bar.finish("jump")
        assert bar.credited() == pytest.approx(8.0)
        bar.write("camjax dynamics: a line")
    finally:
        bar.close()
    text = stream.getvalue()
    assert "ETA" in text and "camjax dynamics: a line" in text
