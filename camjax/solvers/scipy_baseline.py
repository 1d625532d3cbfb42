"""The same design problems solved with ``scipy.optimize``: an independent check and a competitor.

As the source did (MATLAB fmincon per angle, and a GA), in NumPy/SciPy with no JAX in the loop:

- :func:`slsqp_pointwise`: SLSQP once per angle, looping over the angles in Python;
- :func:`slsqp_global`: SLSQP on the global problem in epigraph form (variables R_b, L and t,
  minimize alpha (R_b + L)/N + gamma t / sigma_max with t >= sigma(theta) at every angle: smooth,
  unlike the max over angles);
- :func:`differential_evolution_global` / :func:`differential_evolution_pointwise`:
  ``scipy.optimize.differential_evolution`` with the constraints as a ``NonlinearConstraint``
  (the GA-style competitor).

Objective and constraints follow :mod:`camjax.followers.flat.problem` exactly (same normalization N, same
rho_min margin, stress constraint as rho >= (C / sigma_max)^2), with analytic gradients for SLSQP.
Not traceable (SciPy): call with concrete arrays. Requires scipy (an optional dependency).
"""

from __future__ import annotations

import time
import warnings
from typing import NamedTuple

import numpy as np

from camjax.followers.flat.problem import Problem


class BaselineResult(NamedTuple):
    """Designs found by SciPy (NumPy arrays)."""

    base_radius_mm: np.ndarray  # () global, (n,) pointwise
    face_width_mm: np.ndarray
    objective: np.ndarray  # F (true max over the problem's angles)
    success: np.ndarray  # bool, scipy's own flag
    iterations: np.ndarray  # int, scipy's nit
    seconds: float  # wall time of the solves (Python loop included)


class _Data(NamedTuple):
    q: np.ndarray
    ds: np.ndarray
    c: np.ndarray
    theta: np.ndarray
    lo: np.ndarray  # (2,) bounds R, L
    hi: np.ndarray
    sigma_max: float
    norm: float
    rho_min: float


def _data(problem: Problem) -> _Data:
    f = lambda x: np.asarray(x, float)  # noqa: E731
    return _Data(f(problem.q_mm), f(problem.ds_mm), f(problem.stress_coefficient), f(problem.theta_deg),
                 np.array([float(problem.lower.base_radius_mm), float(problem.lower.face_width_mm)]),
                 np.array([float(problem.upper.base_radius_mm), float(problem.upper.face_width_mm)]),
                 float(problem.sigma_max_MPa), float(problem.size_norm_mm), float(problem.rho_min_mm))


def _at(d: _Data, k: int) -> _Data:
    """The one-angle problem at index k."""
    return d._replace(q=d.q[k:k + 1], ds=d.ds[k:k + 1], c=d.c[k:k + 1], theta=d.theta[k:k + 1])


def _stress(d: _Data, r: float) -> np.ndarray:
    rho = np.maximum(r + d.q, 1e-15)
    return d.c / np.sqrt(rho)


def objective(d: _Data, alpha: float, gamma: float, x) -> float:
    """F at x = (R_b, L) with the true max over angles."""
    return alpha * (x[0] + x[1]) / d.norm + gamma * float(np.max(_stress(d, x[0]))) / d.sigma_max


def _constraint_rows(d: _Data, x) -> np.ndarray:
    """Every constraint as h(x) >= 0 (scipy's convention), mm: (3n,)."""
    rho = x[0] + d.q
    return np.concatenate([rho - d.rho_min, rho - (d.c / d.sigma_max) ** 2, x[1] - 2.0 * np.abs(d.ds)])


def _constraint_jac(d: _Data, n_vars: int) -> np.ndarray:
    n = d.q.size
    jac = np.zeros((3 * n, n_vars))
    jac[: 2 * n, 0] = 1.0
    jac[2 * n:, 1] = 1.0
    return jac


def _slsqp_one(d: _Data, alpha: float, gamma: float, x0, ftol: float, maxiter: int):
    """SLSQP on (R_b, L, t) in epigraph form; on one angle t is just sigma there."""
    from scipy.optimize import minimize

    n = d.q.size
    scale = max(alpha + gamma, 1e-300)  # same minimizer, O(1) objective whatever the weights

    def f(z):
        return (alpha * (z[0] + z[1]) / d.norm + gamma * z[2] / d.sigma_max) / scale

    def df(z):
        return np.array([alpha / d.norm, alpha / d.norm, gamma / d.sigma_max]) / scale

    def h(z):  # t - sigma(theta) >= 0 and the design constraints >= 0
        return np.concatenate([z[2] - _stress(d, z[0]), _constraint_rows(d, z[:2])])

    def dh(z):
        rho = np.maximum(z[0] + d.q, 1e-15)
        top = np.zeros((n, 3))
        top[:, 0] = 0.5 * d.c * rho ** -1.5
        top[:, 2] = 1.0
        return np.vstack([top, _constraint_jac(d, 3)])

    x0 = np.clip(np.asarray(x0, float), d.lo, d.hi)
    t0 = float(np.max(_stress(d, x0[0])))
    bounds = [(d.lo[0], d.hi[0]), (d.lo[1], d.hi[1]), (0.0, None)]
    res = minimize(f, np.array([x0[0], x0[1], t0]), jac=df, method="SLSQP", bounds=bounds,
                   constraints=[{"type": "ineq", "fun": h, "jac": dh}],
                   options={"ftol": ftol, "maxiter": maxiter})
    return res.x[:2], bool(res.success), int(res.nit)


def _whole(d: _Data, alpha: float, gamma: float, solve_one) -> BaselineResult:
    """Time ``solve_one() -> (x, ok, nit)`` on the whole problem; scalars in the result."""
    start = time.perf_counter()
    x, ok, nit = solve_one()
    seconds = time.perf_counter() - start
    return BaselineResult(np.asarray(x[0]), np.asarray(x[1]), np.asarray(objective(d, alpha, gamma, x)),
                          np.asarray(ok), np.asarray(nit), seconds)


def _per_angle(d: _Data, alpha: float, gamma: float, angles, solve_one) -> BaselineResult:
    """Time ``solve_one(d_k) -> (x, ok, nit)`` angle by angle (a Python loop, as the source did)."""
    idx = np.arange(d.q.size) if angles is None else np.asarray(angles, int)
    out = np.zeros((idx.size, 2))
    ok = np.zeros(idx.size, bool)
    nit = np.zeros(idx.size, int)
    obj = np.zeros(idx.size)
    start = time.perf_counter()
    for j, k in enumerate(idx):
        dk = _at(d, int(k))
        out[j], ok[j], nit[j] = solve_one(dk)
        obj[j] = objective(dk, alpha, gamma, out[j])
    seconds = time.perf_counter() - start
    return BaselineResult(out[:, 0], out[:, 1], obj, ok, nit, seconds)


def slsqp_pointwise(problem: Problem, alpha: float, gamma: float, angles=None, *, x0=None,
                    ftol: float = 1e-12, maxiter: int = 500) -> BaselineResult:
    """SLSQP separately at each angle (a Python loop, as the source's fmincon loop).

    Args:
      angles: indices of the angles to solve (default all n).
      x0: start (R_b, L) in mm, default the centre of the box.
    """
    d = _data(problem)
    x0 = 0.5 * (d.lo + d.hi) if x0 is None else np.asarray(x0, float)
    return _per_angle(d, alpha, gamma, angles, lambda dk: _slsqp_one(dk, alpha, gamma, x0, ftol, maxiter))


def slsqp_global(problem: Problem, alpha: float, gamma: float, *, x0=None, ftol: float = 1e-14,
                 maxiter: int = 500) -> BaselineResult:
    """SLSQP on the global problem (epigraph form: one t >= sigma(theta) row per angle)."""
    d = _data(problem)
    x0 = 0.5 * (d.lo + d.hi) if x0 is None else np.asarray(x0, float)
    return _whole(d, alpha, gamma, lambda: _slsqp_one(d, alpha, gamma, x0, ftol, maxiter))


def _de_one(d: _Data, alpha: float, gamma: float, seed: int, popsize: int, maxiter: int, tol: float):
    from scipy.optimize import NonlinearConstraint, differential_evolution

    def worst(x):  # min over every constraint row: >= 0 when feasible
        return float(np.min(_constraint_rows(d, x)))

    with warnings.catch_warnings():
        # the trust-constr polish warns that the (linear) constraint has a zero quasi-Newton update
        warnings.filterwarnings("ignore", message="delta_grad == 0.0", category=UserWarning)
        res = differential_evolution(lambda x: objective(d, alpha, gamma, x),
                                     list(zip(d.lo, d.hi, strict=True)),
                                     constraints=[NonlinearConstraint(worst, 0.0, np.inf)], seed=seed,
                                     popsize=popsize, maxiter=maxiter, tol=tol, polish=True)
    return res.x, bool(res.success), int(res.nit)


def differential_evolution_global(problem: Problem, alpha: float, gamma: float, *, seed: int = 0,
                                  popsize: int = 20, maxiter: int = 1000,
                                  tol: float = 1e-10) -> BaselineResult:
    """``scipy.optimize.differential_evolution`` on the global problem (true max over angles)."""
    d = _data(problem)
    return _whole(d, alpha, gamma, lambda: _de_one(d, alpha, gamma, seed, popsize, maxiter, tol))


def differential_evolution_pointwise(problem: Problem, alpha: float, gamma: float, angles=None, *,
                                     seed: int = 0, popsize: int = 20, maxiter: int = 1000,
                                     tol: float = 1e-10) -> BaselineResult:
    """Differential evolution separately at each angle (a Python loop; slow: seconds per angle)."""
    d = _data(problem)
    return _per_angle(d, alpha, gamma, angles,
                      lambda dk: _de_one(dk, alpha, gamma, seed, popsize, maxiter, tol))
