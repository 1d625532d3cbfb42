"""SciPy baselines written the way a careful SciPy user would (fallback adapters).

Used by the pointwise and sweep benchmarks when ``camjax.solvers.scipy_baseline`` does not offer
the function needed. NumPy objective and constraints with analytic gradients (a stronger
baseline than finite differences), SciPy's own solvers.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from camjax.numerics import RHO_FLOOR_MM


class NumpyProblem:
    """The problem's arrays as NumPy (float64)."""

    def __init__(self, problem):
        self.q = np.asarray(problem.q_mm, float)
        self.ds = np.asarray(problem.ds_mm, float)
        self.c = np.asarray(problem.stress_coefficient, float)
        self.sigma_max = float(problem.sigma_max_MPa)
        self.norm = float(problem.size_norm_mm)
        self.rho_min = float(problem.rho_min_mm)
        self.lower = np.array([float(problem.lower.base_radius_mm), float(problem.lower.face_width_mm)])
        self.upper = np.array([float(problem.upper.base_radius_mm), float(problem.upper.face_width_mm)])
        self.c2 = (self.c / self.sigma_max) ** 2
        self.width = 2.0 * np.abs(self.ds)

    def bounds(self):
        return list(zip(self.lower, self.upper, strict=True))


def _stress_and_slope(np_p: NumpyProblem, r: float, idx=slice(None)):
    rho = np.maximum(r + np_p.q[idx], RHO_FLOOR_MM)
    sigma = np_p.c[idx] / np.sqrt(rho)
    slope = np.where(r + np_p.q[idx] > RHO_FLOOR_MM, -0.5 * sigma / rho, 0.0)
    return sigma, slope


def _objective(np_p: NumpyProblem, alpha: float, gamma: float, idx=slice(None)):
    """F(x) with the max over the angles ``idx`` and its (sub)gradient."""

    def fun(x):
        sigma, _ = _stress_and_slope(np_p, x[0], idx)
        return alpha * (x[0] + x[1]) / np_p.norm + gamma * np.max(sigma) / np_p.sigma_max

    def jac(x):
        sigma, slope = _stress_and_slope(np_p, x[0], idx)
        k = int(np.argmax(sigma))
        return np.array([alpha / np_p.norm + gamma * slope[k] / np_p.sigma_max, alpha / np_p.norm])

    return fun, jac


def _constraints(np_p: NumpyProblem, idx=slice(None)):
    """SLSQP inequality constraints c(x) >= 0, one per angle and kind, with constant Jacobian."""
    q, c2, width = np.atleast_1d(np_p.q[idx]), np.atleast_1d(np_p.c2[idx]), np.atleast_1d(np_p.width[idx])
    n = q.shape[0]
    jac = np.zeros((3 * n, 2))
    jac[: 2 * n, 0] = 1.0
    jac[2 * n :, 1] = 1.0
    need = np.concatenate([np_p.rho_min - q, c2 - q])

    def fun(x):
        return np.concatenate([x[0] - need, x[1] - width])

    return {"type": "ineq", "fun": fun, "jac": lambda x: jac}


def slsqp(
    np_p: NumpyProblem,
    alpha: float,
    gamma: float,
    x0,
    idx=slice(None),
    ftol: float = 1e-12,
    maxiter: int = 500,
):
    """One SLSQP solve (the angles ``idx``: one angle = pointwise, all = global)."""
    fun, jac = _objective(np_p, alpha, gamma, idx)
    return optimize.minimize(
        fun,
        np.asarray(x0, float),
        jac=jac,
        method="SLSQP",
        bounds=np_p.bounds(),
        constraints=[_constraints(np_p, idx)],
        options={"ftol": ftol, "maxiter": maxiter},
    )


def pointwise_slsqp(np_p: NumpyProblem, alpha: float, gamma: float, ftol: float = 1e-12) -> np.ndarray:
    """SLSQP looping over the angles, each from the box centre: (n, 2) designs (R_b, L) in mm."""
    x0 = 0.5 * (np_p.lower + np_p.upper)
    return np.array(
        [slsqp(np_p, alpha, gamma, x0, idx=slice(i, i + 1), ftol=ftol).x for i in range(np_p.q.size)]
    )


def global_slsqp(np_p: NumpyProblem, alpha: float, gamma: float, starts, ftol: float = 1e-12):
    """Global problem, SLSQP from each start; the best feasible result (x, F, solves)."""
    best = None
    for x0 in starts:
        res = slsqp(np_p, alpha, gamma, x0, ftol=ftol)
        if best is None or (violation(np_p, res.x) <= 1e-9, -res.fun) > (
            violation(np_p, best.x) <= 1e-9,
            -best.fun,
        ):
            best = res
    return best.x


def violation(np_p: NumpyProblem, x) -> float:
    """Largest constraint violation of a design, mm."""
    r, length = x
    return float(
        max(0.0, np.max(np_p.rho_min - np_p.q - r), np.max(np_p.c2 - np_p.q - r), np.max(np_p.width) - length)
    )


def global_de(
    np_p: NumpyProblem,
    alpha: float,
    gamma: float,
    seed: int,
    tol: float = 1e-8,
    maxiter: int = 1000,
    popsize: int = 15,
    polish: bool = True,
):
    """``differential_evolution`` (popsize 15 and local polish as SciPy's defaults; tol 1e-8 rather
    than 0.01, which stops ~1e-3 off the optimum on this problem), a vectorized NumPy objective
    and the constraints as a NonlinearConstraint (SciPy's feasibility rules); returns the design
    (R_b, L) and the number of function evaluations."""

    def fun(x):  # x: (2, S) with vectorized=True
        r, length = np.atleast_2d(x.T).T
        rho = np.maximum(r[None, :] + np_p.q[:, None], RHO_FLOOR_MM)
        peak = np.max(np_p.c[:, None] / np.sqrt(rho), axis=0)
        return alpha * (r + length) / np_p.norm + gamma * peak / np_p.sigma_max

    def cons(x):
        return np.array(
            [x[0] - (np_p.rho_min - np_p.q).max(), x[0] - (np_p.c2 - np_p.q).max(), x[1] - np_p.width.max()]
        )

    nlc = optimize.NonlinearConstraint(cons, 0.0, np.inf)
    res = optimize.differential_evolution(
        fun,
        np_p.bounds(),
        constraints=(nlc,),
        seed=seed,
        tol=tol,
        maxiter=maxiter,
        popsize=popsize,
        polish=polish,
        vectorized=True,
        updating="deferred",
    )
    return res.x, res.nfev
