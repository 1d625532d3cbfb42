"""Solvers of the optimal-design problem (:mod:`camjax.problem`).

- :mod:`~camjax.solvers.gradient`: augmented Lagrangian over optax Rprop, projected on the box,
  the whole loop in one ``jit`` (``solve_global``, ``solve_pointwise``, ``solve_sweep``);
- :mod:`~camjax.solvers.ga`: a real-coded GA whose population is evaluated in one vectorized
  call, batched over weightings (and angles in pointwise mode);
- :mod:`~camjax.solvers.sweep`: one entry point for every solver (gradient, ga, hybrid) and mode
  (global, pointwise): :func:`solve`, :func:`solve_batch`, ``sweep.sweep`` (``run_sweep``),
  :func:`plot_pareto`;
- :mod:`~camjax.solvers.scipy_baseline`: the same problems with ``scipy.optimize`` (SLSQP per
  angle, differential evolution), an independent check and the benchmarks' competitor.
"""

from camjax.solvers import ga, gradient
from camjax.solvers.ga import GASettings
from camjax.solvers.gradient import GradientSettings
from camjax.solvers.sweep import (
    MODES,
    SOLVERS,
    DesignResult,
    SweepResult,
    pareto_mask,
    plot_pareto,
    solve,
    solve_batch,
    weight_grid,
)

# ``camjax.solvers.sweep`` stays the module; its function is ``camjax.solvers.sweep.sweep``
# (also exported as ``run_sweep``).
from camjax.solvers.sweep import sweep as run_sweep  # noqa: E402

__all__ = [
    "MODES", "SOLVERS", "DesignResult", "GASettings", "GradientSettings", "SweepResult", "ga", "gradient",
    "pareto_mask", "plot_pareto", "run_sweep", "solve", "solve_batch", "weight_grid",
]
