"""The design problem: closed-form pointwise optimum, exact global reference, safe numerics.

Independent references: a bounded scalar minimization per angle (SciPy) for the closed form, a
dense NumPy scan over R_b for the global problem, finite differences for gradients.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import numpy_reference_optimum

import camjax
from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import gradient as G

WEIGHTINGS = [(1.0, 1.0), (10.0, 1.0), (1.0, 10.0), (1.0, 0.0), (0.0, 1.0), (1e-6, 1.0), (1e6, 1.0)]


@pytest.fixture(scope="module")
def problem(default_scene):
    """The grid problem (extrema = "grid"): these tests check it against NumPy on the same grid;
    the exact one is checked in test_exact_design.py."""
    return P.problem_from_scene(default_scene, camjax.scene_arrays(default_scene, extrema="grid"))


def _numpy(problem):
    return {k: np.asarray(getattr(problem, k), float) for k in ("q_mm", "ds_mm", "stress_coefficient")}


def _dense_scan_global(problem, alpha, gamma, step=1e-3, refine=1e-6):
    """argmin over R_b of alpha R/N + gamma max_theta sigma / sigma_max, feasible R only, NumPy."""
    a = _numpy(problem)
    q, c = a["q_mm"], a["stress_coefficient"]
    smax, norm = float(problem.sigma_max_MPa), float(problem.size_norm_mm)
    need = max(float(problem.lower.base_radius_mm),
               float(np.max(np.maximum(float(problem.rho_min_mm), (c / smax) ** 2) - q)))
    hi = float(problem.upper.base_radius_mm)

    def g(r):
        rho = r[:, None] + q[None, :]
        return alpha * r / norm + gamma * np.max(c / np.sqrt(rho), axis=1) / smax

    r = np.arange(need, hi + step, step)
    r = np.clip(r, need, hi)
    best = r[np.argmin(g(r))]
    fine = np.clip(np.arange(best - 2 * step, best + 2 * step, refine), need, hi)
    return fine[np.argmin(g(fine))]


def test_closed_form_matches_scalar_minimization_at_every_angle(problem):
    from scipy.optimize import minimize_scalar

    a = _numpy(problem)
    smax, norm = float(problem.sigma_max_MPa), float(problem.size_norm_mm)
    lo, hi = float(problem.lower.base_radius_mm), float(problem.upper.base_radius_mm)
    for alpha, gamma in [(1.0, 1.0), (10.0, 1.0), (1.0, 10.0)]:
        d = optimum.pointwise_optimum(problem, weights_of(alpha, gamma))
        r_cf = np.asarray(d.base_radius_mm)
        for k in range(0, a["q_mm"].size, 7):
            q, c = a["q_mm"][k], a["stress_coefficient"][k]
            need = max(lo, max(float(problem.rho_min_mm), (c / smax) ** 2) - q)

            def f(r, q=q, c=c, alpha=alpha, gamma=gamma):
                return alpha * r / norm + gamma * c / (smax * np.sqrt(r + q))

            res = minimize_scalar(f, bounds=(need, hi), method="bounded", options={"xatol": 1e-10})
            best = min([res.x, need, hi], key=f)  # Brent stops short of an optimal end point
            assert abs(best - r_cf[k]) < 1e-6, (alpha, gamma, k)
        # L: the smallest feasible face width at every angle
        expect = np.clip(np.maximum(2 * np.abs(a["ds_mm"]), float(problem.lower.face_width_mm)), None,
                         float(problem.upper.face_width_mm))
        np.testing.assert_allclose(np.asarray(d.face_width_mm), expect, atol=1e-12)


def test_reference_case_reproduces_source_figures(problem):
    """SPEC 5: alpha = gamma = 1 -> R_b 28.3-28.4 mm at 315 deg, L 19.1 mm at 330 deg; ..."""
    def largest(alpha, gamma):
        d = optimum.pointwise_optimum(problem, weights_of(alpha, gamma))
        i, j = int(jnp.argmax(d.base_radius_mm)), int(jnp.argmax(d.face_width_mm))
        return (float(d.base_radius_mm[i]), float(problem.theta_deg[i]), float(d.face_width_mm[j]),
                float(problem.theta_deg[j]))

    r, r_deg, length, l_deg = largest(1.0, 1.0)
    ref = numpy_reference_optimum(1.0, 1.0)  # independent NumPy closed form (tests/reference.py)
    assert 28.3 <= r <= 28.4 and r == pytest.approx(ref[0], abs=1e-9) and r_deg == ref[1] == 315.0
    assert length == pytest.approx(ref[2], abs=1e-12) and l_deg == ref[3] == 330.0
    assert largest(10.0, 1.0)[0] == pytest.approx(numpy_reference_optimum(10.0, 1.0)[0], abs=1e-9)
    assert largest(10.0, 1.0)[0] == pytest.approx(25.0, abs=0.05)  # SPEC: about 25 mm
    assert largest(1.0, 10.0)[0] == 40.0  # upper bound
    for alpha, gamma in WEIGHTINGS:
        assert largest(alpha, gamma)[2] == pytest.approx(length, abs=1e-12)  # L independent of weights


@pytest.mark.parametrize("alpha,gamma", [(1.0, 1.0), (10.0, 1.0), (1.0, 10.0), (1.0, 0.0), (3.0, 0.7)])
def test_global_optimum_matches_dense_scan(problem, alpha, gamma):
    d = optimum.global_optimum(problem, weights_of(alpha, gamma))
    scan = _dense_scan_global(problem, alpha, gamma)
    # the scan is refined to 1e-6 mm: its argmin is within a refine step or two of the true one
    assert float(d.base_radius_mm) == pytest.approx(scan, abs=2e-6)
    solved = G.solve_global(problem, weights_of(alpha, gamma))  # the gradient solver, directly
    assert float(solved.design.base_radius_mm) == pytest.approx(scan, abs=2e-6)
    assert float(d.face_width_mm) == pytest.approx(2 * float(jnp.max(jnp.abs(problem.ds_mm))), abs=1e-12)


def test_single_angle_global_equals_pointwise(problem):
    per = P.per_angle(problem)
    w = weights_of(1.0, 1.0)
    glob = jax.jit(jax.vmap(optimum.global_optimum, in_axes=(0, None)))(per, w)
    pw = optimum.pointwise_optimum(problem, w)
    np.testing.assert_allclose(np.asarray(glob.base_radius_mm), np.asarray(pw.base_radius_mm), atol=1e-9)
    np.testing.assert_allclose(np.asarray(glob.face_width_mm), np.asarray(pw.face_width_mm), atol=1e-12)


def test_infeasible_bounds_name_the_constraint(problem):
    tight = P.with_bounds(problem, base_radius_mm=(5.0, 20.0), face_width_mm=(5.0, 10.0))
    w = weights_of(1.0, 1.0)
    d = optimum.global_optimum(tight, w)
    ev = P.evaluate(tight, w, d)
    assert not bool(ev.feasible)
    assert np.isfinite(float(ev.objective))
    assert P.violated_constraints(tight, ev.violation) == ["curvature", "stress", "face_width"]
    # a radius that gives rho > 0 but too much stress violates only the stress
    stress_only = P.with_bounds(problem, base_radius_mm=(5.0, 24.15))
    ev = P.evaluate(stress_only, w, optimum.global_optimum(stress_only, w))
    assert P.violated_constraints(stress_only, ev.violation) == ["stress"]


def test_objective_gradient_matches_finite_differences(problem):
    w = weights_of(1.0, 1.0)
    x = P.Design(jnp.asarray(30.0), jnp.asarray(20.0))
    grad = jax.grad(lambda d: P.objective(problem, w, d))(x)
    h = 1e-6
    for name in P.Design._fields:
        up = x._replace(**{name: getattr(x, name) + h})
        dn = x._replace(**{name: getattr(x, name) - h})
        fd = (P.objective(problem, w, up) - P.objective(problem, w, dn)) / (2 * h)
        assert float(getattr(grad, name)) == pytest.approx(float(fd), rel=1e-6)


@settings(max_examples=40, deadline=None)
@given(r=st.floats(-100.0, 100.0), length=st.floats(-10.0, 50.0), alpha=st.sampled_from([0.0, 1e-6, 1.0, 1e6]))
def test_gradients_finite_for_any_design(problem, r, length, alpha):
    """Feasible or not (rho <= 0 included), the solver's function and gradient stay finite."""
    val, grad, ev = _lagrangian_grad_eval(problem, weights_of(alpha, 1.0), jnp.asarray(r), jnp.asarray(length))
    assert np.isfinite(float(val))
    assert all(np.isfinite(float(g)) for g in jax.tree.leaves(grad))
    assert all(np.isfinite(float(v)) for v in jax.tree.leaves(ev))


@jax.jit
def _lagrangian_grad_eval(problem, w, r, length):
    u = G.to_unit(problem, P.Design(r, length))
    lam = jax.tree.map(jnp.ones_like, P.constraints(problem, G.from_unit(problem, u)))
    val, grad = jax.value_and_grad(lambda v: G.augmented_lagrangian(v, problem, w, lam, 1e3)[0])(u)
    return val, grad, P.evaluate(problem, w, G.from_unit(problem, u))


def test_fast_reductions_equal_the_per_angle_definitions(problem):
    """peak_stress and constraint_maxima (the GA's one-pass fitness) = max of the per-angle curves."""
    for r in (3.0, 24.0, 28.4, 40.0):  # infeasible (rho < 0 somewhere) to comfortable
        x = P.Design(jnp.asarray(r), jnp.asarray(15.0))
        assert float(P.peak_stress(problem, x)) == pytest.approx(float(jnp.max(P.stress(problem, x))), rel=1e-14)
        full = P.constraints(problem, x)
        fast = P.constraint_maxima(problem, x)
        for a, b in zip(jax.tree.leaves(full), jax.tree.leaves(fast), strict=True):
            assert float(b) == pytest.approx(float(jnp.max(a)), abs=1e-12)
