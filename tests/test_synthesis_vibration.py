"""The follower train's synthesis terms (camjax.synthesis.vibration): the exact linear maps against
SciPy's ODE solver and the project's own dynamics (RK4 of the train, the steady-state contact
force), the optimum against SciPy on the same discretization, the issue's residual-vibration
check against the best built-in law, and the scene's refusals."""

from __future__ import annotations

import json
import tomllib
from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import program as prog
from camjax.cli import main
from camjax.dynamics import ForceClosure, contact_force, harmonics_from_samples, integrate_train, plant_of
from camjax.dynamics.context import synthesis_train
from camjax.laws import LAWS
from camjax.laws.bspline import evaluate_derivatives
from camjax.scene import SceneError, builtin_scene_text, scene_from_dict
from camjax.scene.designed import starting_control
from camjax.synthesis import build_problem, make_basis
from camjax.synthesis.segments import builtin_q, meets_conditions, synthesize_segments
from camjax.synthesis.vibration import builtin_train_measures, force_matrix, state_maps, train_terms

# the built-in synthesis scene (rise and return designed between dwells, the reference follower
# train of mass, spring and damping) with a 60 Hz load train (k23 = I3 (2 pi 60)^2) at 240 rpm
# (r = omega_n beta / Omega = 23.6 on the rise) and the follower-train objective
BUILTIN = builtin_scene_text("synthesis")
SCENE = BUILTIN[: BUILTIN.index("[synthesis]")] + """
[dynamics]
follower = "translating"
I3 = 0.5
c3 = 18.85
k23 = 71061.3

[synthesis]
objective = { residual_vibration = 1e6, l2_jerk = 0.001 }
"""


def scene_data(**dynamics) -> dict:
    data = tomllib.loads(SCENE)
    data["dynamics"].update(dynamics)
    return data


@pytest.fixture(scope="module")
def scene():
    return scene_from_dict(scene_data())


# ------------------------------------------------------------------ the linear maps


@pytest.mark.parametrize("zeta", [0.0, 0.05, 1.0, 2.5])
def test_state_maps_solve_the_train_equation(zeta):
    # y'' + 2 zeta r y' + r^2 y = r^2 q from rest, against SciPy's DOP853 at rtol 1e-12: the map
    # is exact up to its quadrature (~1e-23 relative per subinterval), so the gap is the ODE
    # solver's; 1e-9 on states of order 1. Critical damping (zeta = 1) takes the series branch.
    from scipy.integrate import solve_ivp

    r = 20.0
    q = lambda x: 10 * x**3 - 15 * x**4 + 6 * x**5  # noqa: E731
    sol = solve_ivp(lambda x, z: [r * z[1], -r * z[0] - 2 * zeta * r * z[1] + r * q(x)], (0.0, 1.0),
                    [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    edges = np.linspace(0.0, 1.0, 5)
    z = state_maps(r, zeta, edges, lambda x: q(x)[:, None], 5)[:, :, 0]
    assert np.max(np.abs(z - sol.sol(edges).T)) < 1e-9


def test_the_maps_fine_grid_is_each_subintervals_linspace_bit_for_bit():
    """The fine grid the maps integrate on (every subinterval split at once) holds the points of
    NumPy's linspace of each subinterval, exactly: the maps, and so every co-design's numbers,
    are those of the subinterval-by-subinterval construction. Uneven edges over six orders of
    magnitude, one to 300 pieces each."""
    from camjax.synthesis.vibration import _split

    rng = np.random.default_rng(0)
    for scale in (1e-3, 1.0, 7.3, 1e3):
        edges = np.unique(np.sort(rng.random(40)) * scale)
        pieces = rng.integers(1, 301, len(edges) - 1)
        expected = np.concatenate([edges[:1]] + [np.linspace(a, b, p + 1)[1:]
                                                 for a, b, p in zip(edges[:-1], edges[1:], pieces, strict=True)])
        assert np.array_equal(_split(edges, pieces), expected), scale


def _rk4_residual(scene, index, steps_per_cycle=14400):
    """The designed segment ``index`` run by the project's RK4 of the train (integrate_train), from
    rest at the dwell before it (the cycle rotated to start there): the normalized energy
    amplitude at its end, sqrt(e^2 + (e'/omega_n)^2) / |D|, and max |theta3 - theta2| / |D| over
    the dwell after it (the free vibration's measured amplitude)."""
    p = scene.motion.program
    spec = scene.dynamics
    m = steps_per_cycle
    start_deg = p.start_deg[index - 1]  # the dwell before: at rest
    shift = int(round(start_deg / 360.0 * 2 * m))
    u = np.roll(np.asarray(prog.evaluate(p, 2 * m).s) * 1e-3, -shift)
    omega = 2 * np.pi * spec.cam_speed_hz
    last = integrate_train(plant_of(spec), jnp.asarray(u), omega, 1)
    nxt = (index + 1) % len(p.kinds)  # the dwell after it
    end = int(round((p.start_deg[index] + p.angles_deg[index] - start_deg) % 360.0 / 360.0 * m))
    dwell_end = int(round((p.start_deg[nxt] + p.angles_deg[nxt] - start_deg) % 360.0 / 360.0 * m))
    theta2 = u[0::2]
    e = np.asarray(last.angle) - theta2
    wn = np.sqrt(spec.k23 / spec.I3)
    lift = abs(theta2[end] - theta2[0])
    amp = np.hypot(e[end], np.asarray(last.rate)[end] / wn) / lift
    return amp, np.max(np.abs(e[end:dwell_end])) / lift


@pytest.mark.slow
@pytest.mark.parametrize("index", [1, 3])
def test_the_residual_map_matches_the_dynamics_integration(scene, index):
    # the starting law (as the program plays it) through both: the map's amplitude against the
    # RK4 state at the segment's end. RK4 at 14400 steps per turn: omega_n dt = 6.5e-3, global
    # error ~ (omega_n dt)^4 ~ 2e-9 of the lift, i.e. ~1e-6 of the amplitude (~3e-3 of the lift):
    # tolerance 1e-5 relative
    ds = next(d for d in scene.motion.designed if d.index == index)
    train = synthesis_train(scene)
    terms = train_terms(ds.basis(), train, ds, 8)
    amp = float(np.linalg.norm(terms.residual_rows[0] @ starting_control(ds)))
    rk4, _ = _rk4_residual(scene, index)
    assert amp == pytest.approx(rk4, rel=1e-5)
    assert amp > 1e-4  # not a trivially small number


@pytest.mark.slow
def test_undamped_residual_is_the_free_vibrations_amplitude(scene):
    # c3 = 0: after the rise the error vibrates at constant amplitude A through the 90 deg dwell
    # (3.75 periods); its sampled maximum is within A (1 - cos(omega_n dt)) ~ 2e-5 A of it, plus
    # the RK4 error: tolerance 1e-4 relative
    s0 = scene_from_dict(scene_data(c3=0.0))
    ds = s0.motion.designed[0]
    terms = train_terms(ds.basis(), synthesis_train(s0), ds, 8)
    amp = float(np.linalg.norm(terms.residual_rows[0] @ starting_control(ds)))
    _, peak = _rk4_residual(s0, ds.index)
    assert amp == pytest.approx(peak, rel=1e-4)


@pytest.mark.slow
def test_the_force_map_matches_the_steady_state_contact_force():
    # a well-damped train (zeta = 0.3: the return's vibration decays to e^-7.9 ~ 4e-4 of itself in
    # the 100 deg dwell before the rise), so the steady state of camjax.dynamics.jump.contact_force
    # is the rise's response from rest. Its harmonic series converges slowly (the cubic's q'' has
    # kinks: the error of the truncated d2f falls as 1/H), so the check is the convergence: the
    # gap halves from H = 2000 to 4000 harmonics and is then below 2e-3 of the peak pointwise
    # (measured 0.22 N of 200 N at H = 4000, 0.11 N at 8000) and 5e-4 at the peak (2.5e-4)
    sc = scene_from_dict(scene_data(c3=113.1))
    spec = sc.dynamics
    ds = sc.motion.designed[0]
    train = synthesis_train(sc)
    x = np.linspace(0.0, 1.0, 91)
    ours = force_matrix(ds.basis(), train, ds, x) @ starting_control(ds)
    closure = ForceClosure(spec.I2, spec.spring_rate, spec.spring_preload, spec.follower_damping, spec.weight)
    samples = prog.evaluate(sc.motion.program, 16384).s * 1e-3
    gaps = []
    for h in (2000, 4000):
        theirs = np.asarray(contact_force(harmonics_from_samples(samples, h), plant_of(spec), closure,
                                          2 * np.pi * spec.cam_speed_hz, jnp.deg2rad(100.0 + 90.0 * x)))
        gaps.append(np.max(np.abs(ours - theirs)))
    peak = np.max(np.abs(ours))
    assert gaps[1] < 0.6 * gaps[0] and gaps[1] < 2e-3 * peak
    assert peak == pytest.approx(np.max(np.abs(theirs)), rel=5e-4)


# ------------------------------------------------------------------ the optimum


def _small_scene(objective: dict):
    data = scene_data()
    for i in (1, 3):
        data["motion"]["segments"][i]["control_count"] = 10
    data["synthesis"]["objective"] = objective
    sc = scene_from_dict(data)
    return sc, synthesis_train(sc)


@pytest.mark.slow
def test_the_quadratic_optimum_is_the_least_squares_solution():
    # residual_vibration + l2_jerk alone is an unconstrained QP in the free coordinates: its
    # optimum is the linear solve of the normal equations (NumPy, independent of the interior
    # point), to rounding: 1e-9 relative on the objective
    w = {"residual_vibration": 1e5, "l2_jerk": 1e-3}
    sc, train = _small_scene(w)
    r = synthesize_segments(sc.motion.designed, w, 8, train)[0]
    ds = r.segment
    basis = make_basis(ds.degree, ds.control_count)
    problem = build_problem(basis, ds.conditions, tuple(w), 8, train_terms(basis, train, ds, 8))
    cp = problem.A_pinv @ np.asarray(ds.values)[list(problem.kept)]
    Q = w["residual_vibration"] * problem.train.residual_gram + w["l2_jerk"] * problem.grams[3]
    N = problem.null
    z = np.linalg.solve(N.T @ Q @ N, -N.T @ Q @ cp)
    c = cp + N @ z
    assert r.model_objective == pytest.approx(float(c @ Q @ c), rel=1e-9)
    assert np.max(np.abs(r.control - c)) < 1e-6


@pytest.mark.slow
@pytest.mark.parametrize("w", [{"peak_force": 1.0},
                               {"peak_force": 1.0, "residual_vibration": 1e4, "l2_jerk": 1e-3}])
def test_the_peak_force_optimum_matches_scipy(w):
    # the same discretization (force rows at 9 points per span, residual and jerk quadratics) as an
    # epigraph problem in (z, t) for SciPy: HiGHS for peak_force alone (an LP), SLSQP for the mixed
    # QP. HiGHS solves the LP to ~1e-9: 1e-7 relative; SLSQP stops at ftol 1e-10 on a smooth
    # problem of 5 variables: 1e-6 relative (measured 1e-11 for both)
    from scipy.optimize import linprog, minimize

    sc, train = _small_scene(w)
    r = synthesize_segments(sc.motion.designed, w, 8, train)[0]
    ds = r.segment
    assert r.converged
    basis = make_basis(ds.degree, ds.control_count)
    problem = build_problem(basis, ds.conditions, tuple(w), 8, train_terms(basis, train, ds, 8))
    cp = problem.A_pinv @ np.asarray(ds.values)[list(problem.kept)]
    N, F = problem.null, problem.train.force_rows
    nz = N.shape[1]
    G = np.vstack([np.hstack([F @ N, -np.ones((len(F), 1))]), np.hstack([-F @ N, -np.ones((len(F), 1))])])
    h = np.concatenate([-F @ cp, F @ cp])
    if len(w) == 1:
        lp = linprog(np.r_[np.zeros(nz), 1.0], A_ub=G, b_ub=h, bounds=[(None, None)] * (nz + 1),
                     method="highs")
        assert r.model_objective == pytest.approx(lp.fun, rel=1e-7)
        return
    Q = w["residual_vibration"] * problem.train.residual_gram + w["l2_jerk"] * problem.grams[3]

    def f(x):
        c = cp + N @ x[:nz]
        return x[nz] + c @ Q @ c

    def grad(x):
        return np.r_[2.0 * N.T @ (Q @ (cp + N @ x[:nz])), 1.0]

    x0 = np.r_[np.zeros(nz), np.max(np.abs(F @ cp)) + 1.0]
    ineq = {"type": "ineq", "fun": lambda x: h - G @ x, "jac": lambda x: -G}
    res = minimize(f, x0, jac=grad, method="SLSQP", constraints=[ineq],
                   options={"ftol": 1e-10, "maxiter": 500})
    # status 8 (no descent along the line search) is SLSQP stopping at its precision, at the
    # optimum here: its point must be feasible and no better than ours
    assert res.status in (0, 8) and np.max(G @ res.x - h) < 1e-7  # N, on forces of ~100 N
    assert r.model_objective == pytest.approx(res.fun, rel=1e-6)
    assert r.model_objective <= res.fun * (1 + 1e-9)


# ------------------------------------------------------------------ the check


def _amplitudes(q_of, train, ds, band: float, count: int = 21):
    t = train._replace(speed_factors=tuple(1.0 + band * np.linspace(-1.0, 1.0, count)) if band else (1.0,))
    return np.asarray(builtin_train_measures(q_of, t, ds)["residual_vibration_by_speed"])


def _best_builtin_amplitude(train, ds, band):
    """The least (max over the band's speeds) residual amplitude of the built-in laws of the
    segment's joint class."""
    return min(float(np.max(_amplitudes(lambda x, law=law: builtin_q(law, ds.kind, x), train, ds, band)))
               for law in LAWS.values() if meets_conditions(law, ds))


_SPLINE_PROGRAMS: dict = {}


def _designed_q(result):
    """q, q', q'' of a designed segment's spline at x, in one compiled program of its knots and
    degree, shared by every design of that basis (called eagerly, the de Boor recursion dispatches
    ~100 single operations, each compiled for its shape)."""
    knots, degree = np.asarray(result.knots), result.segment.degree
    key = (knots.tobytes(), degree)
    if key not in _SPLINE_PROGRAMS:
        _SPLINE_PROGRAMS[key] = jax.jit(lambda c, x: evaluate_derivatives(knots, c, degree, x, 2))
    program = _SPLINE_PROGRAMS[key]
    return lambda x: program(result.control, x)


@pytest.mark.slow
@pytest.mark.parametrize("band, goal", [(0.0, 10.0), (0.1, 3.0)])
def test_residual_vibration_beats_the_best_built_in_law(scene, band, goal):
    # The check: at the design speed at least 10x below the best built-in law of the same
    # joint class, over a +-10 % band at least 3x below (the largest amplitude over 21 speeds of
    # the band, the design made on 5). Every figure from the same maps (checked above against the
    # dynamics integration). Measured: design speed 176x (rise), 303x (return); band 10.9x, 7.5x.
    w = {"residual_vibration": 1e6, "l2_jerk": 1e-3}
    sc = replace(scene, synthesis=replace(scene.synthesis, speed_band=band, speed_count=5 if band else 1))
    train = synthesis_train(sc)
    for r in synthesize_segments(sc.motion.designed, w, 8, train):
        ds = r.segment
        ours = np.max(_amplitudes(_designed_q(r), train, ds, band))
        best = _best_builtin_amplitude(train, ds, band)
        assert best / ours >= goal, (ds.index, best, ours)
        # the design's own figure is the same amplitude (designed on 5 speeds, reported RMS)
        if not band:
            assert r.measures["residual_vibration"] == pytest.approx(ours, rel=1e-6)


# ------------------------------------------------------------------ the scene and the command


@pytest.mark.parametrize("change, field", [
    (lambda d: d.pop("dynamics"), "dynamics"),
    (lambda d: d["synthesis"].update(objective={"peak_force": 1.0}) or d["follower"].pop("spring_N_per_m"),
     "dynamics.spring_rate"),
    (lambda d: d["synthesis"].update(objective={"residual_vibration": 1.0}), "synthesis.objective"),
    (lambda d: d["synthesis"].update(speed_band=0.1, speed_count=1), "synthesis.speed_count"),
    (lambda d: d["synthesis"].update(speed_band=-0.1), "synthesis.speed_band"),
    (lambda d: d["synthesis"]["objective"].update(residual_vibration=-1.0), "synthesis.objective.residual_vibration"),
    (lambda d: d["synthesis"].update(objective={"peak_force": 1.0}) or d["motion"]["segments"][1].update(
        degree=1, start={"v": "free", "a": "free"}, end={"v": "free", "a": "free"}),
     "motion.segments[1].degree"),
])
def test_a_train_term_without_its_data_is_refused_naming_the_field(change, field):
    data = scene_data()
    change(data)
    with pytest.raises(SceneError) as err:
        scene_from_dict(data)
    assert err.value.field == field
    assert "\n" not in str(err.value)


def test_the_command_refuses_without_dynamics_and_writes_nothing(tmp_path, capsys):
    data = tomllib.loads(SCENE)
    text = SCENE[: SCENE.index("[dynamics]")] + SCENE[SCENE.index("[synthesis]"):]
    assert "dynamics" not in tomllib.loads(text) and data["dynamics"]
    path = tmp_path / "s.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["synthesize", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "dynamics" in err and "residual_vibration" in err
    assert not out.exists()


@pytest.mark.slow
def test_result_json_reports_the_train_figures(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.replace("residual_vibration = 1e6", "residual_vibration = 1e6, peak_force = 1e-3"))
    out = tmp_path / "out"
    assert main(["synthesize", str(path), "--out", str(out)]) == 0
    res = json.loads((out / "result.json").read_text())["synthesis"]
    assert res["train"]["natural_frequency_hz"] == pytest.approx(60.0, rel=1e-5)
    assert res["train"]["speed_factors"] == [1.0]
    w = res["objective"]
    for s in res["segments"]:
        b = s["best_builtin"]
        for d in (s, b):
            assert {"residual_vibration", "residual_vibration_by_speed", "peak_force"} <= set(d)
        # objective = sum of weight x measure, the residual squared (its mean square)
        assert s["objective"] == pytest.approx(w["residual_vibration"] * s["residual_vibration"] ** 2
                                               + w["peak_force"] * s["peak_force"] + w["l2_jerk"] * s["l2_jerk"],
                                               rel=1e-9)
        assert b["objective"] == pytest.approx(w["residual_vibration"] * b["residual_vibration"] ** 2
                                               + w["peak_force"] * b["peak_force"] + w["l2_jerk"] * b["l2_jerk"],
                                               rel=1e-9)
        assert s["objective"] < b["objective"]
        # the contact force is above the spring's preload force at rest and of its size
        assert 30.0 < s["peak_force"] < 200.0


@pytest.mark.slow
def test_a_batch_with_the_train_terms_equals_one_at_a_time(scene):
    # the train terms are static matrices of the problem: the pure JAX solve vmaps over weights as
    # it does without them. A member that has converged keeps its iterate while the batch runs on,
    # so each equals its own solve up to the batched products' rounding: 1e-9 relative
    from camjax.synthesis import batch_synthesizer, kept_values, synthesizer

    ds = scene.motion.designed[0]
    basis = ds.basis()
    names = ("l2_jerk", "peak_force", "residual_vibration")
    problem = build_problem(basis, ds.conditions, names, 8, train_terms(basis, synthesis_train(scene), ds, 8))
    assert problem.objective == names
    values = kept_values(problem, np.asarray(ds.values))
    weights = np.asarray([[1e-3, 1e-2, 1e4], [1e-3, 1e-1, 1e6], [1e-2, 1e-3, 1e5]])
    batch = batch_synthesizer(problem)(np.tile(values, (3, 1)), weights)
    one = jax.jit(synthesizer(problem))
    for b in range(3):
        single = one(values, weights[b])
        assert bool(batch.converged[b]) and bool(single.converged)
        assert float(batch.objective[b]) == pytest.approx(float(single.objective), rel=1e-9)
        # the reported objective is the weighted sum of the measures, the residual squared
        m = single.measures
        expected = weights[b] @ np.asarray([m.l2_jerk, m.peak_force, m.residual_vibration**2])
        assert float(single.objective) == pytest.approx(float(expected), rel=1e-12)
