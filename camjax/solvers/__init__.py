"""Solvers of the optimal-design problems (every follower folder's ``problem.py``, :mod:`camjax.followers`).

- :mod:`~camjax.solvers.registry`: the names of modes, solvers and problem families, and the one
  validator :func:`~camjax.solvers.registry.check_choice` (imports neither JAX nor NumPy);
- :mod:`~camjax.solvers.base`: one result type (:class:`~camjax.solvers.base.Solution`) and one
  entry point (:func:`~camjax.solvers.base.solve`, :func:`~camjax.solvers.base.solve_batch`)
  for every solver and mode; the solver and problem-family protocols;
- :mod:`~camjax.solvers.gradient`: augmented Lagrangian over optax Rprop, projected on the box,
  the whole loop in one ``jit``;
- :mod:`~camjax.solvers.ga`: a real-coded GA whose population is evaluated in one vectorized call;
- :mod:`~camjax.solvers.hybrid`: the GA, then the interior point's polish (:mod:`~camjax.solvers.newton`);
- :mod:`~camjax.solvers.sweep`: many weightings in chunks and their Pareto front
  (``sweep.sweep``, also ``run_sweep``), :func:`~camjax.solvers.sweep.plot_pareto`;
- :mod:`~camjax.solvers.scipy_baseline`: the same problems with ``scipy.optimize`` (SLSQP per
  angle, differential evolution), an independent check and the benchmarks' competitor.

Attributes are imported on first use (module ``__getattr__``), so ``camjax.solvers.registry``
can be read without starting JAX.
"""

from __future__ import annotations

import importlib

from camjax.solvers.registry import MODES, SOLVERS

_LAZY = {
    "Solution": "camjax.solvers.base", "Settings": "camjax.solvers.base", "solve": "camjax.solvers.base",
    "solve_batch": "camjax.solvers.base", "GASettings": "camjax.solvers.ga",
    "GradientSettings": "camjax.solvers.gradient", "SweepResult": "camjax.solvers.sweep",
    "pareto_mask": "camjax.solvers.sweep", "plot_pareto": "camjax.solvers.sweep",
    "weight_grid": "camjax.solvers.sweep",
}
_SUBMODULES = ("base", "ga", "gradient", "hybrid", "registry", "scipy_baseline", "sweep")

__all__ = ["MODES", "SOLVERS", *_LAZY, "run_sweep", *_SUBMODULES]


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    if name == "run_sweep":  # the function ``camjax.solvers.sweep.sweep`` (the module keeps its name)
        return importlib.import_module("camjax.solvers.sweep").sweep
    if name in _SUBMODULES:
        return importlib.import_module(f"camjax.solvers.{name}")
    raise AttributeError(f"module 'camjax.solvers' has no attribute {name!r}")
