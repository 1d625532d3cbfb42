"""The roller design problem solved with ``scipy.optimize``: an independent check and a competitor.

NumPy/SciPy with no JAX in the loop, written from SPEC 3 separately from
:mod:`camjax.followers.roller.problem` (same objective, normalization and constraints, so the optima agree):

- :func:`slsqp`: SLSQP on one problem in epigraph form (variables R_b, R_f, e and t; minimize
  alpha (R_b + R_f)/N + gamma t / sigma_max with t >= sigma(theta) at every angle), Jacobians by
  SciPy's finite differences (what a user of SciPy would write for these curvature formulas);
  with a one-angle problem (:func:`camjax.followers.roller.problem.per_angle`) it is the pointwise solve;
- :func:`differential_evolution`: ``scipy.optimize.differential_evolution`` with the constraint
  maxima as one ``NonlinearConstraint`` (the GA-style competitor), polished by SciPy.

Fixed variables (lower == upper) are kept fixed by their bounds. Not traceable (SciPy): call with
concrete arrays. Requires scipy (an optional dependency).
"""

from __future__ import annotations

import time
import warnings
from typing import NamedTuple

import numpy as np

from camjax.followers.roller.problem import Problem


class RollerBaselineResult(NamedTuple):
    """A design found by SciPy (floats) and what it took."""

    design: np.ndarray  # (3,) R_b, R_f, e in mm
    objective: float  # F with the true max over the problem's angles
    max_violation: float  # largest constraint row < 0 (scaled by N): 0 when feasible
    success: bool  # scipy's own flag
    iterations: int  # scipy's nit
    seconds: float  # wall time


class _Data(NamedTuple):
    s: np.ndarray
    ds: np.ndarray
    d2s: np.ndarray
    c: np.ndarray
    lo: np.ndarray  # (3,)
    hi: np.ndarray
    sigma_max: float
    norm: float
    tan_limit: float
    rho_min: float
    sign: float


def _data(problem: Problem) -> _Data:
    f = lambda x: np.asarray(x, float)  # noqa: E731
    return _Data(f(problem.s_mm), f(problem.ds_mm), f(problem.d2s_mm), f(problem.stress_coefficient),
                 np.array([float(v) for v in problem.lower]), np.array([float(v) for v in problem.upper]),
                 float(problem.sigma_max_MPa), float(problem.size_norm_mm),
                 float(problem.tan_max_pressure_angle), float(problem.min_curvature_radius_mm),
                 float(problem.rotation_sign))


def _physics(d: _Data, x):
    """(w, u, kappa, rho_eq, cos phi) at every angle for design x = (R_b, R_f, e)."""
    rb, rf, e = x[0], x[1], d.sign * x[2]
    w = np.sqrt(max((rb + rf) ** 2 - e**2, 0.0)) + d.s
    u = d.ds - e
    kappa = (w**2 + u * (2 * d.ds - e) - w * d.d2s) / (w**2 + u**2) ** 1.5
    rho_eq = rf * (1.0 - rf * kappa)  # 1 / (1/rho_c + 1/R_f)
    cos_phi = w / np.sqrt(w**2 + u**2)
    return w, u, kappa, rho_eq, cos_phi


def _stress(d: _Data, x) -> np.ndarray:
    _, _, _, rho_eq, cos_phi = _physics(d, x)
    return d.c / np.sqrt(np.maximum(cos_phi, 1e-12) * np.maximum(rho_eq, 1e-15))


def objective(d: _Data, alpha: float, gamma: float, x) -> float:
    """F = alpha (R_b + R_f)/N + gamma max sigma / sigma_max (true max over angles)."""
    return alpha * (x[0] + x[1]) / d.norm + gamma * float(np.max(_stress(d, x))) / d.sigma_max


def _rows(d: _Data, x) -> np.ndarray:
    """Every constraint row as h >= 0, dimensionless (lengths divided by N)."""
    w, u, kappa, rho_eq, cos_phi = _physics(d, x)
    need = d.c**2 / (d.sigma_max**2 * np.maximum(cos_phi, 1e-12))
    reach = x[1] + d.rho_min
    rows = [d.tan_limit * w - np.abs(u), reach * (1.0 - kappa * reach), rho_eq - need]
    return np.concatenate(rows) / d.norm


def _result(d, alpha, gamma, x, success, nit, seconds) -> RollerBaselineResult:
    x = np.clip(np.asarray(x, float)[:3], d.lo, d.hi)
    viol = max(0.0, -float(np.min(_rows(d, x))))
    return RollerBaselineResult(x, objective(d, alpha, gamma, x), viol, bool(success), int(nit), seconds)


def slsqp(problem: Problem, alpha: float, gamma: float, *, x0=None, ftol: float = 1e-12,
          maxiter: int = 500) -> RollerBaselineResult:
    """SLSQP on the problem's angle grid (epigraph form: one t >= sigma(theta) row per angle).

    Args:
      x0: start (R_b, R_f, e) in mm, default the centre of the box.
    """
    from scipy.optimize import minimize

    d = _data(problem)
    x = 0.5 * (d.lo + d.hi) if x0 is None else np.asarray(x0, float)
    t0 = float(np.max(_stress(d, x)))

    def f(z):
        return alpha * (z[0] + z[1]) / d.norm + gamma * z[3] / d.sigma_max

    def h(z):
        return np.concatenate([(z[3] - _stress(d, z[:3])) / d.sigma_max, _rows(d, z[:3])])

    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # trial steps outside the feasible region
        res = minimize(f, np.append(x, t0), method="SLSQP",
                       bounds=[*zip(d.lo, d.hi, strict=True), (0.0, None)],
                       constraints=[{"type": "ineq", "fun": h}], options={"ftol": ftol, "maxiter": maxiter})
    return _result(d, alpha, gamma, res.x, res.success, res.nit, time.perf_counter() - start)


def differential_evolution(problem: Problem, alpha: float, gamma: float, *, seed: int = 0,
                           popsize: int = 20, maxiter: int = 1000, tol: float = 1e-10,
                           polish: bool = True) -> RollerBaselineResult:
    """``scipy.optimize.differential_evolution`` on the problem (true max over angles)."""
    from scipy.optimize import NonlinearConstraint
    from scipy.optimize import differential_evolution as de

    d = _data(problem)
    free = d.hi > d.lo  # DE needs a non-empty interval per variable: fixed ones are inserted

    def full(z):
        x = d.lo.copy()
        x[free] = z
        return x

    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.filterwarnings("ignore", message="delta_grad == 0.0", category=UserWarning)
        res = de(lambda z: objective(d, alpha, gamma, full(z)),
                 list(zip(d.lo[free], d.hi[free], strict=True)),
                 constraints=[NonlinearConstraint(lambda z: float(np.min(_rows(d, full(z)))), 0.0, np.inf)],
                 seed=seed, popsize=popsize, maxiter=maxiter, tol=tol, polish=polish)
    return _result(d, alpha, gamma, full(res.x), res.success, res.nit, time.perf_counter() - start)
