"""Names of the design problems' modes, solvers and problem families: the one list everyone reads.

Scene parsing (:mod:`camjax.scene`), the CLI, the scale-out workers (:mod:`camjax.scaleout.blocks`,
which import this before JAX starts) and :func:`camjax.solvers.base.solve` validate against these
tuples with :func:`check_choice`. This module imports neither JAX nor NumPy, so reading the names
costs nothing.

Adding a solver: write a module with ``DEFAULT_SETTINGS`` and
``run_one(problem, weights, key, settings, init=None) -> camjax.solvers.base.Raw`` (see
:mod:`camjax.solvers.base`) and add ``name: "module.path"`` to :data:`SOLVER_MODULES`. Adding a
follower type: write a problem-family module (the protocol is in :mod:`camjax.solvers.base`) and
add ``name: "module.path"`` to :data:`FAMILY_MODULES`.
"""

from __future__ import annotations

MODES = ("global", "pointwise")

# solver name -> module providing DEFAULT_SETTINGS and run_one (imported on first use)
SOLVER_MODULES = {
    "gradient": "camjax.solvers.gradient",  # augmented Lagrangian over secant Rprop
    "ga": "camjax.solvers.ga",  # vectorized real-coded GA
    "hybrid": "camjax.solvers.hybrid",  # GA, then a gradient polish from its best design
}
SOLVERS = tuple(SOLVER_MODULES)

# problem family name -> module implementing the family protocol (its ``Problem`` type is the key
# the solvers dispatch on)
FAMILY_MODULES = {
    "flat_face": "camjax.followers.flat.problem",
    "roller": "camjax.followers.roller.problem",
    "oscillating_roller": "camjax.followers.oscillating_roller.problem",
    "oscillating_flat": "camjax.followers.oscillating_flat.problem",
}
# scene follower.type -> the problem family its [design] section builds (the family module's
# ``problem_from_scene(scene, arrays=None, *, samples=None, dtype=None)``)
FOLLOWER_FAMILIES = {"flat": "flat_face", "roller": "roller", "oscillating_roller": "oscillating_roller",
                     "oscillating_flat": "oscillating_flat"}

# Solution.status codes (int32 in the traced result) and their names
CONVERGED = 0  # the solver's stopping rule was met and the design is feasible
MAX_STEPS = 1  # feasible, but the step / generation budget ran out first (the GA's only stopping rule)
INFEASIBLE = 2  # the design violates a constraint beyond the feasibility tolerances
STATUS_NAMES = ("converged", "max_steps", "infeasible")


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


def status_name(code) -> str:
    """Name of a status code ("converged", "max_steps", "infeasible")."""
    return STATUS_NAMES[int(code)]
