"""Names of the design problems' modes, solvers and problem families: the one list everyone reads.

Scene parsing (:mod:`camjax.scene`), the CLI, the scale-out workers (:mod:`camjax.scaleout.blocks`,
which import this before JAX starts) and :func:`camjax.solvers.base.solve` validate against these
tuples with :func:`check_choice`. This module imports neither JAX nor NumPy, so reading the names
costs nothing.

Adding a solver: write a module with ``DEFAULT_SETTINGS`` and
``run_one(problem, weights, key, settings, init=None) -> camjax.solvers.base.Raw`` (see
:mod:`camjax.solvers.base`) and add ``name: "module.path"`` to :data:`SOLVER_MODULES`. A follower
type's problem family is its folder's ``problem.py`` (:mod:`camjax.followers`), found there.
"""

from __future__ import annotations

MODES = ("global", "pointwise")

# solver name -> module providing DEFAULT_SETTINGS and run_one (imported on first use)
SOLVER_MODULES = {
    "gradient": "camjax.solvers.gradient",  # augmented Lagrangian over secant Rprop
    "ga": "camjax.solvers.ga",  # vectorized real-coded GA
    "hybrid": "camjax.solvers.hybrid",  # GA, then newton from its best design
    "newton": "camjax.solvers.newton",  # primal-dual interior point on the epigraph form
}
SOLVERS = tuple(SOLVER_MODULES)
# the solver a problem gets when none is named (a scene's [design] without ``solver``, the library's
# solve and sweep functions): the interior point, which stops on its KKT residual and certifies
# its answer; a robust design's too (:mod:`camjax.robust.design` solves its rounds on the samples
# nearest to breaking a limit, few enough for the interior point's path: SOLVER_SUBSET)
DEFAULT_SOLVER = "newton"

def check_choice(field: str, value, allowed) -> None:
    """Raise ValueError naming ``field`` when ``value`` is not one of ``allowed``."""
    allowed = tuple(allowed)
    if value not in allowed:
        raise ValueError(f"{field}: {value!r} is not allowed; use {', '.join(map(str, allowed))}")


def check_weights(alphas, gammas) -> None:
    """Objective weights: finite, >= 0, not both 0 in any pair (sequences of floats); ValueError otherwise."""
    pairs = list(zip(map(float, alphas), map(float, gammas), strict=True))
    if any(not (a == a and g == g and abs(a) < float("inf") and abs(g) < float("inf")) for a, g in pairs):
        raise ValueError("alpha, gamma: weights must be finite")
    if any(a < 0 or g < 0 for a, g in pairs):
        raise ValueError("alpha, gamma: weights must be >= 0")
    if any(a == 0 and g == 0 for a, g in pairs):
        raise ValueError("alpha, gamma: a weighting with alpha = gamma = 0 has nothing to minimize")
