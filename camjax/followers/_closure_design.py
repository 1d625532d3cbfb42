"""A conjugate pair's free dimension: the yoke's span or the second arm's angle as a [design] variable.

A conjugate pair's second contact (:mod:`camjax.followers._closure`) depends on one dimension the
first does not: the span L between a translating yoke's two roller centres
(``yoke_span_mm``), or the angle beta between a rocker's two arms (``second_arm_angle_deg``). Either
may be a [design] variable like the others: a number fixes it (over the [follower]'s value), a
``[low, high]`` pair frees it (:func:`design_bounds`).

The objective (size and the first contact's stress) does not depend on it: it only moves the
second cam, whose limits (pressure angle, undercut, roller off the shaft, stress) are kept with the
first's. A free one is therefore chosen in two steps (:func:`solve_with_dimension`):

1. the design is solved for the first contact alone: no span or angle can give a smaller objective;
2. at that design the value is the smallest in its bounds at which the second cam holds its limits at
   every sample (a scan and a bisection, :func:`smallest_admissible`), and the design is judged again
   with it (:func:`evaluated_with`: the objective is the same, the second contact's figures are
   added). That design and value are an optimum of the whole problem. The smallest value is the
   smallest second cam: a yoke's second pitch circle sqrt(e^2 + (L - w)^2) grows with L, a second
   arm's largest reach |C2|^2 = d^2 + l2^2 - 2 d l2 cos(psi - beta) (psi - beta in (-180, 0) deg)
   grows with beta.

Where no value in the bounds lets the first contact's optimum keep the second cam, the design is
solved with both contacts at the most permissive value (:func:`camjax.followers._closure_problem.design_start`:
a yoke's largest span, a rocker's [follower] angle clipped into the bounds) and step 2 is taken at
that design; the objective is then that value's optimum, which another value may better.

result.json's design block holds the chosen value under its key, and the cam is drawn with it. A
solver's certificate (newton's) is that of the problem it solved: in the first case the first
contact's rows, whose optimum the chosen value keeps.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import jax
import jax.numpy as jnp

from camjax.followers._closure_problem import design_start, second_excess
from camjax.scene.reader import TableReader, fixed_or_free

# each free dimension: its [design] key, the design problem's closure field and the factor to it
YOKE_SPAN, ARM_ANGLE = "yoke_span_mm", "second_arm_angle_deg"
_TERMS_FIELD = {YOKE_SPAN: ("span_mm", 1.0), ARM_ANGLE: ("angle_rad", math.pi / 180.0)}
ADMISSIBLE_SCAN = 256  # steps of the scan over the bounds, before the refinements
ADMISSIBLE_HALVINGS = 80  # golden-section and bisection steps: below float64 resolution of the bounds
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


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


@partial(jax.jit, static_argnames=("key_field",))
def _smallest(problem, design, first, low, high, key_field: int):
    """Traced body of :func:`smallest_admissible` (``key_field``: the closure field's index)."""
    from camjax.family import FEASIBILITY_TOL_MM
    from camjax.solvers.base import family_of

    family = family_of(problem)

    def worst(value):  # the second contact's largest excess over what the first allows, mm
        terms = problem.closure
        moved = problem._replace(closure=terms._replace(**{terms._fields[key_field]: value}))
        return jnp.max(second_excess(family.constraints(moved, design), first))

    xs = low + (high - low) * jnp.linspace(0.0, 1.0, ADMISSIBLE_SCAN + 1)
    hs = jax.lax.map(worst, xs)
    ok = hs <= FEASIBILITY_TOL_MM
    # the least excess, refined between the scan's neighbours of its smallest (golden section): an
    # admissible range narrower than the scan's step (both contacts at their limit) is found there
    k = jnp.argmin(hs)
    a, b = xs[jnp.maximum(k - 1, 0)], xs[jnp.minimum(k + 1, ADMISSIBLE_SCAN)]

    def golden(_, bracket):
        a, b = bracket
        c, d = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
        lower = worst(c) <= worst(d)
        return jnp.where(lower, a, c), jnp.where(lower, d, b)

    a, b = jax.lax.fori_loop(0, ADMISSIBLE_HALVINGS, golden, (a, b))
    best = 0.5 * (a + b)
    # bisect between an inadmissible value and the first admissible one found
    j = jnp.argmax(ok)
    right = jnp.where(ok[j], xs[j], best)
    left = jnp.where(ok[j], xs[jnp.maximum(j - 1, 0)], xs[jnp.maximum(k - 1, 0)])

    def halve(_, bracket):
        a, b = bracket
        m = 0.5 * (a + b)
        bad = worst(m) > FEASIBILITY_TOL_MM
        return jnp.where(bad, m, a), jnp.where(bad, b, m)

    found = ok[j] | (worst(best) <= FEASIBILITY_TOL_MM)
    left_ok = worst(left) <= FEASIBILITY_TOL_MM
    _, right = jax.lax.fori_loop(0, ADMISSIBLE_HALVINGS, halve, (left, right))
    return jnp.where(left_ok, left, right), found


def smallest_admissible(problem, design, key: str, low: float, high: float) -> float | None:
    """The smallest yoke span (mm) or second arm angle (deg) in [low, high] at which ``design`` (the
    family's Design) keeps every second-contact limit at every sample where the first contact keeps
    its own (where the first is over, the second may be up to as far over), to the solvers'
    feasibility tolerance (:data:`camjax.family.FEASIBILITY_TOL_MM`); None where none does. A scan,
    a golden-section refinement of the least excess (a range narrower than the scan's step, as where
    both contacts reach their limit at once) and a bisection onto the first admissible value. One
    compiled program for every scene of a shape (the problem, design and bounds are its data)."""
    from camjax.solvers.base import family_of

    family = family_of(problem)
    field, factor = _TERMS_FIELD[key]
    first = family.constraints(problem._replace(closure=None), design)
    dtype = first[0].dtype
    index = problem.closure._fields.index(field)
    value, found = _smallest(problem, design, first, jnp.asarray(low * factor, dtype),
                             jnp.asarray(high * factor, dtype), key_field=index)
    return float(value) / factor if bool(found) else None


def evaluated_with(problem, solution):
    """A :class:`camjax.solvers.base.Solution` judged again on ``problem`` (the same design, its
    evaluation, violations and feasibility there; the objective does not depend on the conjugate
    pair's span or angle, the solver's iterations are those of its own solve; a certificate is
    rendered against the problem that solve had, see :func:`solve_with_dimension`)."""
    from camjax.family import weights_of

    weights = weights_of(solution.alpha, solution.gamma, problem.lower[0].dtype)
    ev = _evaluate(problem, weights, solution.design)
    return replace(solution, evaluation=ev, violation=ev.violation, feasible=ev.feasible)


@jax.jit
def _evaluate(problem, weights, design):
    """The design problem's family's ``evaluate`` (one compiled program per family and grid)."""
    from camjax.solvers.base import family_of

    return family_of(problem).evaluate(problem, weights, design)


def solve_with_dimension(scene, problem, free: tuple) -> tuple[dict, object]:
    """A scene's [design] with a conjugate pair's yoke span or second arm angle in it
    (``free`` = :func:`free_dimension`'s (key, low, high)): result.json's design block and the
    problem carrying the value, set (``low == high``) or chosen (free) as the module docstring says,
    and reported under its key. The scene's mode, weights, solver and seed
    (:func:`camjax.solvers.base.solve`); :func:`camjax.followers._design.design_block` dispatches here."""
    from camjax.solvers.base import solve
    from camjax.solvers.certificate import solution_json

    d = scene.design
    key, low, high = free
    solve_as_scene = partial(solve, weights=(d.alpha, d.gamma), mode=d.mode, solver=d.solver, seed=d.seed)
    value = design_start(scene, key)  # the problem's own
    if low == high:
        out = solution_json(problem, solve_as_scene(problem))
        out[key] = value
        return out, problem
    # the first contact alone: no value of the span or angle gives a smaller objective
    solved = problem._replace(closure=None)
    solution = solve_as_scene(solved)
    smallest = smallest_admissible(problem, solution.design, key, low, high)
    if smallest is None:  # the second cam binds there: solved at the most permissive value
        solved = problem
        solution = solve_as_scene(problem)
        smallest = smallest_admissible(problem, solution.design, key, low, high)
    value = value if smallest is None else smallest
    problem = with_dimension(problem, key, value)
    # a certificate is of the rows its own solve had
    out = solution_json(problem, evaluated_with(problem, solution), solved)
    out[key] = value
    return out, problem
