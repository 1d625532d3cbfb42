"""The roller design problem: physics against the independent NumPy/SciPy statement, gradients
against finite differences, the optimum against a dense scan over (R_b, R_f, e)."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax.family import Weights
from camjax.followers.roller import problem as R
from camjax.solvers import scipy_roller


@pytest.fixture(scope="module")
def roller_problem():
    return R.problem_from_scene(camjax.load_scene("roller"))


def designs():
    rng = np.random.default_rng(0)
    # inside the box and far outside it (undercut, |e| close to R_p, huge pressure angles)
    box = [R.Design(*x) for x in rng.uniform([2, 3, -4], [40, 12, 4], size=(20, 3))]
    return box + [R.Design(0.5, 12.0, 3.9), R.Design(2.0, 3.0, 4.9), R.Design(40.0, 3.0, -4.0)]


def test_objective_and_constraints_match_the_independent_numpy_statement(roller_problem):
    p = roller_problem
    d = scipy_roller._data(p)
    for alpha, gamma in [(1.0, 0.0), (0.3, 1.0), (0.0, 1.0)]:
        w = Weights(jnp.asarray(alpha), jnp.asarray(gamma))
        for x in designs():
            ours = float(R.objective(p, w, x))
            ref = scipy_roller.objective(d, alpha, gamma, np.array(x, float))
            # same formulas, different order of operations: float64 round-off of ~1e-15 relative
            assert ours == pytest.approx(ref, rel=1e-12), x
            rows = scipy_roller._rows(d, np.array(x, float))
            g = jnp.concatenate(jax.tree.leaves(R.constraints(p, x))) / p.size_norm_mm
            np.testing.assert_allclose(-np.asarray(g), rows, rtol=1e-10, atol=1e-13)


def test_stress_constraint_is_sigma_below_sigma_max(roller_problem):
    p = roller_problem
    for x in designs()[:20]:
        sigma = np.asarray(R.stress(p, x))
        g = np.asarray(R.constraints(p, x).stress)
        ok = np.asarray(R.constraints(p, x).undercut) < 0  # rho_eq > 0 there
        # g <= 0 <=> sigma <= sigma_max wherever the roller does not undercut
        assert np.array_equal((g <= 0)[ok], (sigma <= float(p.sigma_max_MPa))[ok])


def test_pressure_angle_constraint_is_the_pressure_angle_limit(roller_problem):
    p = roller_problem
    for x in designs()[:20]:
        phi = np.abs(np.asarray(R.pressure_angle(p, x)))
        g = np.asarray(R.constraints(p, x).pressure_angle)
        np.testing.assert_array_equal(g <= 0, phi <= math.radians(30.0))


@pytest.mark.slow
def test_gradients_match_finite_differences_and_stay_finite(roller_problem):
    p = roller_problem
    w = Weights(jnp.asarray(0.7), jnp.asarray(0.4))

    def f(x):
        d = R.Design(*x)
        c = R.constraints(p, d)
        return jnp.stack([R.objective(p, w, d), *(jnp.sum(jnp.tanh(v)) for v in c)])

    jac = jax.jit(jax.jacfwd(f))
    fj = jax.jit(f)
    for x0 in ([10.0, 6.0, 1.5], [25.0, 4.0, -2.0]):
        x0 = jnp.asarray(x0)
        got = jac(x0)
        for j in range(3):
            h = jnp.zeros(3).at[j].set(1e-4)
            fd = (fj(x0 + h) - fj(x0 - h)) / 2e-4
            # h = 1e-4: truncation h^2 |f'''| / 6 ~ 1e-9, round-off eps |sum over 360 angles| / h
            # ~ 1e-10 (h = 1e-6 measured 6e-8 of round-off); the objective's argmax is fixed in +-h
            np.testing.assert_allclose(got[:, j], fd, rtol=1e-6, atol=1e-8)
    for x in designs():
        g = jax.grad(lambda v: jnp.sum(f(v)))(jnp.asarray(x, float))
        assert np.all(np.isfinite(np.asarray(g))), x


def test_per_angle_problems_have_one_angle_each(roller_problem):
    per = R.per_angle(roller_problem)
    n = roller_problem.theta_deg.shape[0]
    assert per.s_mm.shape == (n, 1) and per.lower.offset_mm.shape == (n,)
    one = jax.tree.map(lambda x: x[17], per)
    x = R.Design(10.0, 5.0, 1.0)
    full = R.constraints(roller_problem, x)
    np.testing.assert_allclose(jnp.concatenate(jax.tree.leaves(R.constraints(one, x))),
                               [v[17] for v in full], rtol=1e-15)


@pytest.mark.slow
def test_solver_coordinates_invert_and_cover_the_box(roller_problem):
    from camjax.solvers.box import from_unit, to_unit

    p = roller_problem
    rng = np.random.default_rng(1)
    lo = np.array([float(x) for x in p.lower])
    hi = np.array([float(x) for x in p.upper])
    x = rng.uniform(lo, hi, size=(400, 3))
    d = R.Design(*(jnp.asarray(x[:, j]) for j in range(3)))
    phi_ok = np.asarray(jax.vmap(lambda d: jnp.max(jnp.abs(R.pressure_angle(p, d))))(d)) <= math.radians(30)
    u = to_unit(p, d)
    # every design of the box has coordinates in the unit box
    assert all(float(jnp.min(v)) >= -1e-12 and float(jnp.max(v)) <= 1 + 1e-12 for v in u)
    # a design within the pressure-angle limit maps back to itself (round-off: a few ulps of
    # the ~50 mm prime-radius range) ...
    back = from_unit(p, u)
    assert phi_ok.sum() > 100
    for a, b in zip(back, d, strict=True):
        np.testing.assert_allclose(np.asarray(a)[phi_ok], np.asarray(b)[phi_ok], rtol=0, atol=1e-12)
    # ... one beyond it keeps R_f and e and gets the smallest prime circle that meets the limit,
    # which the positions say is on the limit (|phi| = 30 deg at its worst angle)
    bad = ~phi_ok
    for name in ("roller_radius_mm", "offset_mm"):
        np.testing.assert_allclose(np.asarray(getattr(back, name))[bad], np.asarray(getattr(d, name))[bad],
                                   rtol=0, atol=1e-12)
    worst = jax.vmap(lambda d: jnp.max(jnp.abs(R.pressure_angle(p, d))))(back)
    np.testing.assert_allclose(np.degrees(np.asarray(worst)[bad]), 30.0, rtol=0, atol=1e-9)
    # the first coordinate is the prime radius alone: moving along the R_b + R_f = const valley
    # changes only the second
    v = from_unit(p, R.Design(jnp.full(50, 0.5), jnp.linspace(0, 1, 50), jnp.zeros(50)))
    rp = np.asarray(v.base_radius_mm + v.roller_radius_mm)
    np.testing.assert_allclose(rp, rp[0], rtol=0, atol=1e-12)
    # every unit-box point maps into the bounds (R_f is clipped to keep R_b inside its own)
    w = rng.uniform(0, 1, size=(500, 3))
    v = from_unit(p, R.Design(*(jnp.asarray(w[:, j]) for j in range(3))))
    for val, a, b in zip(v, lo, hi, strict=True):
        assert float(jnp.min(val)) >= a - 1e-12 and float(jnp.max(val)) <= b + 1e-12
    # and the map keeps finite gradients, also for a one-angle problem at e = 0 on a dwell
    one = jax.tree.map(lambda x: x[100], R.per_angle(p))  # 100 deg: a dwell, s' = 0
    for prob in (p, one):
        g = jax.grad(lambda u, prob=prob: sum(from_unit(prob, u)))(R.Design(*map(jnp.asarray, (0.0, 0.5, 0.5))))
        assert all(np.isfinite(float(x)) for x in g)


def test_solver_coordinates_are_the_plain_box_scaling_with_a_fixed_radius(roller_problem):
    from camjax.solvers.box import from_unit, to_unit

    # with R_f fixed the prime radius is R_b plus a constant: each variable keeps its own scaling
    p = roller_problem._replace(lower=roller_problem.lower._replace(roller_radius_mm=jnp.asarray(5.0)),
                                upper=roller_problem.upper._replace(roller_radius_mm=jnp.asarray(5.0)))
    d = R.Design(jnp.asarray(21.0), jnp.asarray(5.0), jnp.asarray(1.0))
    u = to_unit(p, d)
    assert float(u.base_radius_mm) == pytest.approx((21.0 - 2.0) / 38.0, abs=1e-15)
    assert float(u.offset_mm) == pytest.approx(5.0 / 8.0, abs=1e-15)
    assert float(from_unit(p, u).base_radius_mm) == pytest.approx(21.0, abs=1e-13)
