"""A conjugate pair's free dimension: the yoke's span or the second arm's angle as a [design] variable.

A conjugate pair's second contact (:mod:`camjax.followers._closure`) depends on one dimension the
first does not: the span L between a translating yoke's two roller centres
(``yoke_span_mm``), or the angle beta between a rocker's two arms (``second_arm_angle_deg``). Either
may be a [design] variable like the others: a number fixes it (over the [follower]'s value), a
``[low, high]`` pair frees it (:func:`design_bounds`).

The objective (size and the first contact's stress) does not depend on it: it only moves the
second cam, whose limits (pressure angle, undercut, roller off the shaft, stress) are kept with the
first's. A free one is therefore chosen in two steps (:func:`solve_scene_design`):

1. the design is solved with it at its most permissive value: a yoke's largest span (the second
   roller deepest below the shaft: its cam's pressure angle and its distance from the shaft ease as
   L grows), a rocker's [follower] angle clipped into the bounds;
2. at that design it is moved to the smallest value in its bounds at which the second cam still holds
   its limits at every sample (a scan and a bisection, :func:`smallest_admissible`), and the design
   is judged again there (:func:`evaluated_with`): the objective does not change, the second
   contact's figures do. The smallest value is the smallest second cam: a yoke's second pitch
   circle sqrt(e^2 + (L - w)^2) grows with L, a second arm's largest reach
   |C2|^2 = d^2 + l2^2 - 2 d l2 cos(psi - beta) (psi - beta in (-180, 0) deg) grows with beta.

The design is not solved again at the chosen value (a solve from scratch there can start where the
second roller meets the shaft and not recover); where a rocker's second cam binds its design at the
[follower]'s angle, another angle may allow a smaller cam, which this choice does not look for.

result.json's design block holds the chosen value under its key, and the cam is drawn with it.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import jax
import jax.numpy as jnp

from camjax.errors import SceneError
from camjax.followers._closure import design_start
from camjax.scene.reader import TableReader, fixed_or_free

# each free dimension: its [design] key, the design problem's closure field and the factor to it
YOKE_SPAN, ARM_ANGLE = "yoke_span_mm", "second_arm_angle_deg"
_TERMS_FIELD = {YOKE_SPAN: ("span_mm", 1.0), ARM_ANGLE: ("angle_rad", math.pi / 180.0)}
ADMISSIBLE_SCAN = 256  # values scanned in the bounds before the bisection onto the first admissible one


def design_bounds(r: TableReader, follower, rocking: bool,
                  smallest_roller_mm: float) -> dict[str, tuple[float, float]]:
    """The [design] table's ``yoke_span_mm`` (translating) or ``second_arm_angle_deg`` (rocking) as
    (low, high), or {} without it; a SceneError naming the key where the [follower] is not a
    conjugate pair or the bounds cannot hold one (``smallest_roller_mm``: the design's smallest R_f)."""
    key = ARM_ANGLE if rocking else YOKE_SPAN
    if not r.has(key):
        return {}
    closure = follower.closure
    if closure.kind != "conjugate":
        raise r.error(key, r.table[key], f"is a design variable of a conjugate pair only (the [follower] has "
                      f"closure = {closure.kind!r})", "closure = 'conjugate' in [follower], or no such key")
    lo, hi = fixed_or_free(r, key)
    if rocking and hi >= 360.0:
        raise r.error(key, r.table[key], "puts the second arm on the first", "bounds > 0 and < 360")
    overlap = smallest_roller_mm + closure.second_roller_radius_mm
    if not rocking and lo <= overlap:
        raise r.error(key, r.table[key], "lets the second roller overlap the first: the span must exceed "
                      "R_f + the second roller's radius", f"low > {overlap:g}")
    return {key: (lo, hi)}


def free_dimension(design_spec) -> tuple[str, float, float] | None:
    """(key, low, high) of the [design]'s yoke span or second arm angle; None without one."""
    bounds = dict(design_spec.variables)
    for key in _TERMS_FIELD:
        if key in bounds:
            return (key, *bounds[key])
    return None


def with_dimension(problem, key: str, value):
    """The design problem with its conjugate pair's span (mm) or second arm angle (deg) set to ``value``."""
    field, factor = _TERMS_FIELD[key]
    terms = problem.closure
    value = jnp.asarray(value * factor, getattr(terms, field).dtype)
    return problem._replace(closure=terms._replace(**{field: value}))


def _design_of(problem, result: dict):
    from camjax.solvers.base import family_of

    family = family_of(problem)
    dtype = problem.lower[0].dtype
    return family, family.Design(*(jnp.asarray(result[name], dtype) for name in family.Design._fields))


@partial(jax.jit, static_argnames=("key_field",))
def _smallest(problem, design, allowed, low, high, key_field: int):
    """Traced body of :func:`smallest_admissible` (``key_field``: the closure field's index)."""
    from camjax.followers._swing import first_admissible
    from camjax.solvers.base import family_of

    family = family_of(problem)

    def bad(value):
        terms = problem.closure
        moved = problem._replace(closure=terms._replace(**{terms._fields[key_field]: value}))
        g = jnp.stack(family.constraints(moved, design))
        return jnp.any(g > allowed)

    n = problem.theta_deg.shape[-1]
    ok_low = ~bad(low)
    value, found = first_admissible(bad, low, high, n, scan=ADMISSIBLE_SCAN)
    return jnp.where(ok_low, low, value), ok_low | found


def smallest_admissible(problem, result: dict, key: str, low: float, high: float) -> float | None:
    """The smallest yoke span (mm) or second arm angle (deg) in [low, high] at which the design of
    ``result`` keeps every second-contact limit at every sample where the first contact keeps its
    own (where the first is over, the second may be up to as far over); None where none does.
    One compiled program for every scene of a shape (the problem, design and bounds are its data)."""
    family, design = _design_of(problem, result)
    field, factor = _TERMS_FIELD[key]
    first = jnp.stack(family.constraints(problem._replace(closure=None), design))
    dtype = first.dtype
    index = problem.closure._fields.index(field)
    value, found = _smallest(problem, design, jnp.maximum(first, 0.0), jnp.asarray(low * factor, dtype),
                             jnp.asarray(high * factor, dtype), key_field=index)
    return float(value) / factor if bool(found) else None


def evaluated_with(problem, solution):
    """A :class:`camjax.solvers.base.Solution` judged again on ``problem`` (the same design, its
    evaluation, violations and feasibility there; the objective does not depend on the conjugate
    pair's span or angle, the solver's iterations and certificate are those of its own solve)."""
    from camjax.family import weights_of
    from camjax.solvers.base import family_of

    weights = weights_of(solution.alpha, solution.gamma, problem.lower[0].dtype)
    ev = jax.jit(family_of(problem).evaluate)(problem, weights, solution.design)
    return replace(solution, evaluation=ev, violation=ev.violation, feasible=ev.feasible)


def solve_scene_design(scene, arrays) -> tuple[dict, object]:
    """A scene's [design] solved: (result.json's design block, the design problem it is judged on).

    The scene's mode, weights, solver and seed (:func:`camjax.solvers.base.solve`); a robust design's
    over its samples (:func:`camjax.robust.design.design_json`). A conjugate pair's yoke span or
    second arm angle in [design] is set (fixed) or chosen (free) as the module docstring says, and
    reported under its key."""
    from camjax.solvers.base import problem_from_scene, solve
    from camjax.solvers.newton import design_json

    d = scene.design
    problem = problem_from_scene(scene, arrays)
    free = free_dimension(d)
    if d.robust is not None:
        if free is not None:
            raise SceneError(f"design.{free[0]}", list(free[1:]), "cannot be set in a robust design (its "
                             "samples hold the [follower]'s)", "the value in [follower] only")
        from camjax.robust.design import design_json as robust_design_json

        return robust_design_json(scene, problem), problem
    if free is None:
        return design_json(problem, d), problem
    key, low, high = free
    value = design_start(scene, key)  # the problem's own
    solution = solve(problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver, seed=d.seed)
    out = solution.to_json(problem)
    smallest = None if low == high else smallest_admissible(problem, out, key, low, high)
    if smallest is not None and smallest != value:
        problem, value = with_dimension(problem, key, smallest), smallest
        out = evaluated_with(problem, solution).to_json(problem)
    out[key] = value
    return out, problem
