"""The quasi-Newton arithmetic both BFGS loops share (camjax.solvers.quasi_newton): the update
meets the secant condition and, on a quadratic, builds the inverse Hessian; the backtracking step
is the quadratic's minimizer, clipped; NumPy and jax.numpy give the same numbers."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax.solvers import quasi_newton as qn

RNG = np.random.default_rng(7)
A = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])  # SPD Hessian of a quadratic


def test_update_meets_the_secant_condition_and_stays_symmetric_positive_definite():
    """h+ y = s (to 1e-14 relative: a few roundings of O(1) numbers), h+ symmetric, eigenvalues > 0,
    from the scaled identity of the first step."""
    s, y = RNG.normal(size=3), None
    y = A @ s  # the gradient change of the quadratic along s: s.y = s^T A s > 0
    sy = float(s @ y)
    assert qn.curvature_ok(sy, np.linalg.norm(s), np.linalg.norm(y))
    eye = np.eye(3)
    h0 = qn.first_scaling(sy, float(y @ y), eye)
    h = qn.inverse_hessian_update(h0, s, y, sy, eye, np)
    np.testing.assert_allclose(h @ y, s, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(h, h.T, rtol=0, atol=1e-15)
    assert np.all(np.linalg.eigvalsh(h) > 0)


def test_updates_along_conjugate_steps_give_the_inverse_hessian():
    """BFGS with exact line searches on f = x^T A x / 2 ends, after n = 3 steps, at A^-1 (a classic
    property: the steps are A-conjugate and each update keeps every earlier secant condition);
    checked against numpy.linalg.inv to 1e-12 relative."""
    x = np.array([1.0, -2.0, 0.5])
    g = A @ x
    h = np.eye(3)
    for _ in range(3):
        p = -h @ g
        t = -float(g @ p) / float(p @ A @ p)  # the exact minimizer along p
        s = t * p
        y = A @ s
        h = qn.inverse_hessian_update(h, s, y, float(s @ y), np.eye(3), np)
        x, g = x + s, g + y
    np.testing.assert_allclose(h, np.linalg.inv(A), rtol=1e-12, atol=1e-13)
    assert np.linalg.norm(g) < 1e-12  # and the minimum is reached


def test_backtrack_is_the_minimizer_of_the_quadratic_clipped():
    """f(t) = 1 - 2 t + c t^2: the quadratic through f(0), f'(0) = -2 and f(step) has its minimum at
    1 / c. Inside [0.1, 0.5] x step that value (1e-15 relative); outside, the nearer end; an
    infinite f(step) or a concave fit gives the fallback x step."""
    step, slope, f = 1.0, -2.0, 1.0
    for c, expected in ((4.0, 0.25), (1.5, 0.5), (50.0, 0.1)):
        f_step = f + slope * step + c * step**2
        assert float(qn.backtrack(step, slope, f, f_step, 0.5, np)) == pytest.approx(expected, rel=1e-15)
    assert float(qn.backtrack(step, slope, f, np.inf, 0.5, np)) == 0.5
    assert float(qn.backtrack(step, slope, f, np.nan, 0.1, np)) == 0.1
    assert float(qn.backtrack(2.0, slope, f, f + slope * 2.0 - 1.0, 0.1, np)) == 0.2  # concave: no minimum


def test_numpy_and_jax_numpy_give_the_same_numbers():
    """The shared functions are one formula in both loops: the co-design's NumPy search and the
    gradient solver's traced refinement (here under jit, float64) agree to 1e-15 relative (XLA and
    NumPy's BLAS may sum a matrix product in another order: a rounding or two of O(1) numbers)."""
    s, y = RNG.normal(size=4), RNG.normal(size=4)
    y = y if float(s @ y) > 0 else -y
    h = np.diag(RNG.uniform(0.5, 2.0, size=4))
    eye = np.eye(4)
    sy = float(s @ y)
    by_numpy = qn.inverse_hessian_update(h, s, y, sy, eye, np)
    by_jax = jax.jit(lambda *a: qn.inverse_hessian_update(*a, jnp))(h, s, y, sy, eye)
    np.testing.assert_allclose(np.asarray(by_jax), by_numpy, rtol=1e-15, atol=1e-15)
    args = (0.7, -1.3, 2.0, 1.6)
    by_jax = float(jax.jit(lambda *a: qn.backtrack(*a, 0.1, jnp))(*args))
    assert by_jax == pytest.approx(float(qn.backtrack(*args, 0.1, np)), rel=1e-15)
