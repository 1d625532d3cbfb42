"""The unit box every solver works in, the objective they minimize and where they start.

Each design variable is mapped to the unit box, u = (x - lo) / (hi - lo) (:func:`to_unit`,
:func:`from_unit`; a variable fixed by lo == hi stays at 0, :func:`u_max_of`), so every variable has
the same scale whatever its bounds; a family may define its own map of the same box (``own``). The
solvers minimize F / (alpha + gamma) (:func:`solver_objective`: the same minimizer, O(1) for every
weighting), with a tie-break :data:`TIE_BREAK` (R_b + L) / N when alpha = 0, which picks the
smallest design of equal stress. They start from the family's ``start`` or the box's centre
(:func:`default_start`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.family import Design, Problem, Weights
from camjax.solvers.base import family_of

TIE_BREAK = 1e-9  # weight of the size term when alpha = 0


def span(problem: Problem) -> Design:
    """Each variable's range hi - lo (mm; 1 for a fixed variable)."""
    return jax.tree.map(lambda lo, hi: jnp.where(hi > lo, hi - lo, 1.0), *family_of(problem).bounds(problem))


def u_max_of(problem: Problem) -> Design:
    """1 for a variable with a proper range, 0 for one fixed by lo == hi."""
    return jax.tree.map(lambda lo, hi: jnp.where(hi > lo, 1.0, 0.0).astype(lo.dtype),
                        *family_of(problem).bounds(problem))


def to_unit(problem: Problem, design: Design, own: bool = True) -> Design:
    """Design (mm) -> unit box coordinates (not clipped).

    A family may define its own ``to_unit``/``from_unit`` (a bijection of the same unit box onto
    its bounds, one coordinate per variable, fixed where the variable is fixed) when the plain
    per-variable scaling is badly conditioned for its optimum; the first-order solvers then work
    in those (``own``). ``own=False``: the plain scaling, each variable over its bounds (what a
    second-order solver takes: a family's map may clip, which it cannot see).
    """
    family = family_of(problem)
    if own and hasattr(family, "to_unit"):
        return family.to_unit(problem, design)
    lower = family.bounds(problem)[0]
    return jax.tree.map(lambda x, lo, w: (x - lo) / w, design, lower, span(problem))


def from_unit(problem: Problem, u: Design, own: bool = True) -> Design:
    """Unit box coordinates -> design (mm) (a family's own ``from_unit`` if it has one and ``own``)."""
    family = family_of(problem)
    if own and hasattr(family, "from_unit"):
        return family.from_unit(problem, u)
    lower = family.bounds(problem)[0]
    return jax.tree.map(lambda v, lo, w: lo + v * w, u, lower, span(problem))


def clip_unit(problem: Problem, u: Design) -> Design:
    """``u`` clipped to the box (a fixed variable to 0)."""
    return jax.tree.map(lambda v, top: jnp.clip(v, 0.0, top), u, u_max_of(problem))


def midpoint(problem: Problem) -> Design:
    """Centre of the box."""
    return jax.tree.map(lambda lo, hi: 0.5 * (lo + hi), *family_of(problem).bounds(problem))


def default_start(problem: Problem) -> Design:
    """The solvers' default start (mm): the family's ``start(problem)`` where it has one, else
    :func:`midpoint`."""
    return getattr(family_of(problem), "start", midpoint)(problem)


def solver_objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F / (alpha + gamma) plus the alpha = 0 tie-break: what the solvers minimize (shape ())."""
    total = weights.alpha + weights.gamma
    scale = jnp.where(total > 0, total, 1.0)
    tie = jnp.where(weights.alpha > 0, 0.0, TIE_BREAK)
    family = family_of(problem)
    return family.objective(problem, weights, design) / scale + tie * family.size_term(problem, design)


def problem_dtype(problem) -> jnp.dtype:
    """Floating dtype of a problem (that of its bounds)."""
    return jax.tree.leaves(family_of(problem).bounds(problem)[0])[0].dtype
