"""Adapters: the SciPy baselines the benchmarks time, from ``camjax.solvers.scipy_baseline`` when it
offers them, else from :mod:`benchmarks.scipy_reference`. Each adapter prepares everything that is
not part of a solve (NumPy arrays, starts) up front, so that only solving is timed.
"""

from __future__ import annotations

from typing import NamedTuple

from benchmarks import scipy_reference as ref


class Loop(NamedTuple):
    """A prepared baseline: ``solve()`` runs it, ``source`` says whose code it is."""

    solve: object
    source: str


def pointwise_slsqp(problem, alpha: float, gamma: float) -> Loop:
    """SLSQP over every angle: solve() -> (n, 2) designs (R_b, L) in mm."""
    np_p = ref.NumpyProblem(problem)
    return Loop(lambda: ref.pointwise_slsqp(np_p, alpha, gamma), "benchmarks.scipy_reference.pointwise_slsqp")


def sweep_slsqp(problem, weightings, starts_per_weighting: int = 1) -> Loop:
    """Global SLSQP one weighting after another: solve() -> (w, 2) designs."""
    import numpy as np

    np_p = ref.NumpyProblem(problem)
    centre = 0.5 * (np_p.lower + np_p.upper)
    fracs = [0.5, 0.25, 0.75, 0.95][:starts_per_weighting]
    starts = (
        [np_p.lower + f * (np_p.upper - np_p.lower) for f in fracs] if starts_per_weighting > 1 else [centre]
    )

    def solve():
        return np.array([ref.global_slsqp(np_p, a, g, starts) for a, g in weightings])

    return Loop(solve, f"benchmarks.scipy_reference.global_slsqp ({len(starts)} start(s))")


def sweep_de(problem, weightings, seed: int = 0) -> Loop:
    """differential_evolution one weighting after another: solve() -> ((w, 2) designs, total nfev)."""
    import numpy as np

    np_p = ref.NumpyProblem(problem)

    def solve():
        out = [ref.global_de(np_p, a, g, seed=seed + i) for i, (a, g) in enumerate(weightings)]
        return np.array([x for x, _ in out]), int(sum(n for _, n in out))

    return Loop(solve, "benchmarks.scipy_reference.global_de (tol 1e-8, popsize 15, polish)")
