"""Any registered problem family solved with ``scipy.optimize``: the competitor of the rocker sweeps.

SciPy drives the optimizer; the functions it calls are the family's own JAX functions
(:func:`camjax.solvers.base.family_of`: ``objective``, ``constraints``, ``constraint_maxima``,
``per_angle``, ``bounds``, ``size_norm``), compiled once with ``jax.jit`` and differentiated with
``jax.jacfwd``. This is what a SciPy user with the camjax model would write; it is not an
independent check of the model (:mod:`camjax.solvers.scipy_roller` is one for the roller, written
in NumPy from SPEC 3), only of the solvers, whose optimum it must reach.

- :func:`slsqp`: SLSQP on one problem in epigraph form: variables the free design variables and t;
  minimize t subject to t >= f_i(x) at every angle i (f_i = alpha size / N + gamma sigma_i /
  sigma_max, the objective of the one-angle problem :func:`per_angle` gives) and -g(x) / N >= 0 for
  every constraint row; exact Jacobians from JAX. The start is the centre of the box.
- :func:`differential_evolution`: ``scipy.optimize.differential_evolution`` on the objective (the
  true max over the angles) with the largest constraint row as one ``NonlinearConstraint``,
  polished by SciPy (``trust-constr``, finite differences: SciPy's own hybrid).

Variables fixed by their bounds (lower == upper) are left out of the search. Python, not
traceable: call with a concrete problem; each call runs eagerly and returns floats. Requires scipy
(an optional dependency).
"""

from __future__ import annotations

import time
import warnings
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.family import Weights
from camjax.solvers.base import family_of

__all__ = ["FamilyBaselineResult", "differential_evolution", "slsqp"]


class FamilyBaselineResult(NamedTuple):
    """A design found by SciPy (floats) and what it took."""

    design: np.ndarray  # (m,) every design variable in the family's Design order, mm
    objective: float  # F with the true max over the problem's angles
    max_violation: float  # largest constraint row g / N > 0: 0 when feasible
    success: bool  # scipy's own flag
    iterations: int  # scipy's nit
    seconds: float  # wall time (SciPy and the compiled calls; compilation happens on the first call)


def _design(problem, x):
    """The family's Design from a flat (m,) vector in its field order."""
    lower, _ = family_of(problem).bounds(problem)
    return type(lower)(*(x[i] for i in range(len(lower))))


def _box(problem) -> tuple[np.ndarray, np.ndarray]:
    lower, upper = family_of(problem).bounds(problem)
    return (np.array([float(v) for v in lower]), np.array([float(v) for v in upper]))


@jax.jit
def _objective(problem, weights: Weights, x) -> jax.Array:
    return family_of(problem).objective(problem, weights, _design(problem, x))


def _rows(problem, x) -> jax.Array:
    """Every constraint row as g / N (<= 0 when satisfied), flattened."""
    fam = family_of(problem)
    g = fam.constraints(problem, _design(problem, x))
    return jnp.concatenate([jnp.ravel(v) for v in g]) / fam.size_norm(problem)


@jax.jit
def _max_row(problem, x) -> jax.Array:
    fam = family_of(problem)
    m = fam.constraint_maxima(problem, _design(problem, x))
    return jnp.max(jnp.stack(list(m))) / fam.size_norm(problem)


def _per_angle_objectives(problem, weights: Weights, x) -> jax.Array:
    """f_i(x): the objective of each one-angle problem, shape (n,)."""
    fam = family_of(problem)
    design = _design(problem, x)
    return jax.vmap(lambda p: fam.objective(p, weights, design))(fam.per_angle(problem))


@jax.jit
def _epigraph(problem, weights: Weights, x, t):
    """SLSQP's inequality rows h >= 0 (t - f_i, then -g / N) and their Jacobian in (x, t)."""

    def h(x):
        return jnp.concatenate([-_per_angle_objectives(problem, weights, x), -_rows(problem, x)])

    values, jac = h(x), jax.jacfwd(h)(x)
    n = problem.theta_deg.shape[-1]
    dt = jnp.concatenate([jnp.ones(n, values.dtype), jnp.zeros(values.shape[0] - n, values.dtype)])
    return values + t * dt, jnp.concatenate([jac, dt[:, None]], axis=1)


def _result(problem, weights, x, success, nit, seconds) -> FamilyBaselineResult:
    lo, hi = _box(problem)
    x = np.clip(np.asarray(x, float), lo, hi)
    xj = jnp.asarray(x)
    return FamilyBaselineResult(x, float(_objective(problem, weights, xj)),
                                max(0.0, float(_max_row(problem, xj))), bool(success), int(nit), seconds)


def _weights(problem, alpha: float, gamma: float) -> Weights:
    dtype = problem.theta_deg.dtype
    return Weights(jnp.asarray(alpha, dtype), jnp.asarray(gamma, dtype))


def slsqp(problem, alpha: float, gamma: float, *, x0=None, ftol: float = 1e-12,
          maxiter: int = 500) -> FamilyBaselineResult:
    """SLSQP on the problem's angle grid in epigraph form (one t >= f_i row per angle).

    Args:
      problem: a registered family's problem (concrete arrays).
      alpha, gamma: the weighting.
      x0: start, every design variable in the family's order (mm); default the centre of the box.
    """
    from scipy.optimize import minimize

    weights = _weights(problem, alpha, gamma)
    lo, hi = _box(problem)
    free = hi > lo
    x_full = 0.5 * (lo + hi) if x0 is None else np.asarray(x0, float)

    def full(z):
        x = x_full.copy()
        x[free] = z[:-1]
        return jnp.asarray(x)

    cache: dict = {}

    def rows(z):  # SLSQP asks for the values and the Jacobian at the same point
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            v, j = _epigraph(problem, weights, full(z), jnp.asarray(z[-1]))
            cache[key] = (np.asarray(v), np.asarray(j)[:, np.append(free, True)])
        return cache[key]

    t0 = float(np.max(np.asarray(_per_angle_objectives(problem, weights, jnp.asarray(x_full)))))
    grad_t = np.zeros(int(free.sum()) + 1)
    grad_t[-1] = 1.0
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = minimize(lambda z: z[-1], np.append(x_full[free], t0), jac=lambda z: grad_t, method="SLSQP",
                       bounds=[*zip(lo[free], hi[free], strict=True), (None, None)],
                       constraints=[{"type": "ineq", "fun": lambda z: rows(z)[0],
                                     "jac": lambda z: rows(z)[1]}],
                       options={"ftol": ftol, "maxiter": maxiter})
    x = x_full.copy()
    x[free] = res.x[:-1]
    return _result(problem, weights, x, res.success, res.nit, time.perf_counter() - start)


def differential_evolution(problem, alpha: float, gamma: float, *, seed: int = 0, popsize: int = 20,
                           maxiter: int = 1000, tol: float = 1e-10,
                           polish: bool = True) -> FamilyBaselineResult:
    """``scipy.optimize.differential_evolution`` on the problem (true max over the angles), the
    largest constraint row <= 0 as a ``NonlinearConstraint``."""
    from scipy.optimize import NonlinearConstraint
    from scipy.optimize import differential_evolution as de

    weights = _weights(problem, alpha, gamma)
    lo, hi = _box(problem)
    free = hi > lo

    def full(z):
        x = lo.copy()
        x[free] = z
        return jnp.asarray(x)

    objective = partial(_objective, problem, weights)
    max_row = partial(_max_row, problem)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.filterwarnings("ignore", message="delta_grad == 0.0", category=UserWarning)
        res = de(lambda z: float(objective(full(z))), list(zip(lo[free], hi[free], strict=True)),
                 constraints=[NonlinearConstraint(lambda z: float(max_row(full(z))), -np.inf, 0.0)],
                 seed=seed, popsize=popsize, maxiter=maxiter, tol=tol, polish=polish)
    x = lo.copy()
    x[free] = res.x
    return _result(problem, weights, x, res.success, res.nit, time.perf_counter() - start)
