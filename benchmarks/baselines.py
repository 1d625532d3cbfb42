"""Adapters from the benchmarks to ``camjax.solvers.scipy_baseline`` (the SciPy competitor).

Each adapter prepares what is not part of a solve, and returns a :class:`Loop` whose ``solve()``
runs the SciPy solves one after another (what a SciPy user does) and returns (k, 2) designs.
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from camjax.solvers import scipy_baseline as sb


class Loop(NamedTuple):
    """A prepared baseline: ``solve()`` runs it, ``source`` says what it calls."""

    solve: object
    source: str


def _quiet(fn):
    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return fn()

    return run


def pointwise_slsqp(problem, alpha: float, gamma: float) -> Loop:
    """SLSQP at every angle (Python loop): solve() -> (n, 2) designs (R_b, L) in mm."""

    def solve():
        res = sb.slsqp_pointwise(problem, alpha, gamma)
        return np.stack([res.base_radius_mm, res.face_width_mm], axis=-1)

    return Loop(_quiet(solve), "camjax.solvers.scipy_baseline.slsqp_pointwise (ftol 1e-12)")


def _box_starts(problem, count: int) -> list[np.ndarray]:
    lo = np.array([float(problem.lower.base_radius_mm), float(problem.lower.face_width_mm)])
    hi = np.array([float(problem.upper.base_radius_mm), float(problem.upper.face_width_mm)])
    return [lo + f * (hi - lo) for f in (0.5, 0.25, 0.75, 0.95)[:count]]


def sweep_slsqp(problem, weightings, starts_per_weighting: int = 1) -> Loop:
    """Global SLSQP, weighting after weighting (best of ``starts_per_weighting`` box starts)."""
    starts = _box_starts(problem, starts_per_weighting)

    def one(alpha, gamma):
        runs = [sb.slsqp_global(problem, alpha, gamma, x0=x0) for x0 in starts]
        best = min(runs, key=lambda r: float(r.objective))
        return [float(best.base_radius_mm), float(best.face_width_mm)]

    def solve():
        return np.array([one(a, g) for a, g in weightings])

    return Loop(
        _quiet(solve), f"camjax.solvers.scipy_baseline.slsqp_global ({len(starts)} start(s), ftol 1e-14)"
    )


def sweep_de(problem, weightings, seed: int = 0) -> Loop:
    """differential_evolution, weighting after weighting (its defaults here: popsize 20,
    tol 1e-10, trust-constr polish)."""

    def solve():
        out = [
            sb.differential_evolution_global(problem, a, g, seed=seed + i)
            for i, (a, g) in enumerate(weightings)
        ]
        return np.array([[float(r.base_radius_mm), float(r.face_width_mm)] for r in out])

    return Loop(
        _quiet(solve), "camjax.solvers.scipy_baseline.differential_evolution_global (popsize 20, tol 1e-10)"
    )
