"""What every problem family of :mod:`camjax.solvers.base` shares, written once.

The families (each follower folder's ``problem.py``, registered by :mod:`camjax.followers`, and the
robust wrapper of :mod:`camjax.robust.design`) differ in their design variables, physics and
constraints.
The pieces here reach a problem only through the fields every family's ``Problem`` has:
``theta_deg`` (n,), the box ``lower`` / ``upper`` (``Design`` pytrees, mm) and ``sigma_max_MPa``;
a design only as a pytree of named variables (mm), a violation only through its field names.
"""

from __future__ import annotations

import collections
import functools
import operator
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.numerics import finite_float, positive_part, safe_sqrt

# What the solvers see of a family (annotations): every family's own NamedTuple types, reached only
# through the family module (camjax.solvers.base.family_of) and as pytrees.
Problem = Any  # a family's Problem: the design-independent arrays on the angle grid
Design = Any  # a family's Design: NamedTuple of named variables, mm
Constraints = Any  # a family's Constraints: NamedTuple of (n,) arrays g <= 0, mm
Violation = Any  # a family's Violation: NamedTuple of worst violations, mm / MPa


class Weights(NamedTuple):
    """Objective weights (dimensionless, >= 0, not both 0); scalars or a batch."""

    alpha: jax.Array  # size
    gamma: jax.Array  # stress


def weights_of(alpha, gamma, dtype=None) -> Weights:
    """Weights as arrays (any matching shapes); alpha, gamma >= 0, not both 0."""
    dtype = dtype or jnp.result_type(float)
    return Weights(jnp.asarray(alpha, dtype), jnp.asarray(gamma, dtype))

# A design is feasible when every violation is below these (mm; MPa relative to sigma_max).
FEASIBILITY_TOL_MM = 1e-6
FEASIBILITY_RTOL_STRESS = 1e-6
# ... and |phi| exceeds its limit by at most this (rad): the pressure-angle constraint is met to
# FEASIBILITY_TOL_MM in mm, which is ~1e-8 rad at R_p ~ 50 mm.
FEASIBILITY_TOL_RAD = 1e-7

# ------------------------------------------------------------------------------ protocol


def twin_type(name: str, twin, doc: str, module: str, *, drop=(), add=(), before: str | None = None):
    """A family's own NamedTuple type ``name`` declared from its twin's (``twin``: a type of the
    family whose physics it reuses, e.g. the roller's for the curved face): the twin's fields in
    their order, less those named in ``drop``, with the names in ``add`` inserted before the field
    ``before`` (at the end without it); the twin's defaults for the fields it keeps. The type is
    distinct from the twin's (families are told apart by type) and belongs to ``module`` (the
    declaring module's ``__name__``, so that it pickles); the twin's declaration documents the
    fields."""
    fields = [field for field in twin._fields if field not in drop]
    at = fields.index(before) if before is not None else len(fields)
    fields[at:at] = list(add)
    defaults = [twin._field_defaults[f] for f in fields if f in twin._field_defaults]
    if fields[len(fields) - len(defaults):] != [f for f in fields if f in twin._field_defaults]:
        raise ValueError(f"{name}: the fields with defaults must come last")
    cls = collections.namedtuple(name, fields, defaults=defaults, module=module)
    cls.__doc__ = doc
    return cls


def design_arrays(scene, follower_type: str, what: str, arrays=None, **options):
    """A design problem's scene arrays and its dtype cast ``as_`` (Python, not traceable: reads the scene).

    Refuses a scene without [design] or with another follower (ValueError; ``what`` names the
    family's follower: "follower.type: 'x' is not <what>"). ``arrays``: the scene's
    :class:`camjax.evaluate.SceneArrays` if already computed, else computed here with ``options``
    (samples, dtype, extrema) passed to :func:`camjax.evaluate.scene_arrays`.
    """
    from camjax.evaluate import scene_arrays

    if scene.design is None:
        raise ValueError("scene has no [design] section: nothing to optimize")
    if scene.follower.type != follower_type:
        raise ValueError(f"follower.type: {scene.follower.type!r} is not {what}")
    if arrays is None:
        arrays = scene_arrays(scene, **options)
    dt = arrays.kin.s.dtype
    return arrays, lambda v: jnp.asarray(v, dt)


def design_box(design_section, design_type, as_):
    """(lower, upper): the [design] bounds of each field of ``design_type`` (a family's ``Design``),
    mm, cast by ``as_``."""
    box = [design_section.bounds(name) for name in design_type._fields]
    return design_type(*(as_(b[0]) for b in box)), design_type(*(as_(b[1]) for b in box))


def per_angle(problem, grid_fields):
    """The n pointwise problems: every leaf named in ``grid_fields`` (n,) -> (n, 1), every other
    leaf (scalars, the box) -> (n,).

    ``jax.vmap(f)(per_angle(p, ...), ...)`` solves the problem at each angle separately.
    """
    n = problem.theta_deg.shape[-1]
    scalar = lambda x: jnp.broadcast_to(x, (n,))  # noqa: E731
    return type(problem)(**{name: (value[:, None] if name in grid_fields else jax.tree.map(scalar, value))
                            for name, value in problem._asdict().items()})


def bounds(problem):
    """(lower, upper) box bounds of the design, mm."""
    return problem.lower, problem.upper


def bounds_violation(problem, design) -> jax.Array:
    """Largest distance (mm) of any design variable outside its box; 0 inside."""
    below = jax.tree.map(lambda x, lo: positive_part(lo - x), design, problem.lower)
    above = jax.tree.map(lambda x, hi: positive_part(x - hi), design, problem.upper)
    return jnp.max(jnp.stack(jax.tree.leaves(below) + jax.tree.leaves(above)))


def weighted_objective(weights, size_term, peak_stress_MPa, sigma_max_MPa) -> jax.Array:
    """F = alpha size_term + gamma peak_stress / sigma_max (dimensionless), ``weights`` a
    :class:`camjax.followers.flat.Weights`.

    The order a family computes the two terms in is part of its exact result: it fixes the order
    in which the gradient's contributions to a shared variable add up (float addition does not
    associate), so a family keeps the order it was written with.
    """
    return weights.alpha * size_term + weights.gamma * peak_stress_MPa / sigma_max_MPa


def through_twin(as_twin, *functions) -> tuple:
    """Each of a twin family's ``functions`` (``f(problem, design)``, e.g. the roller's pressure angle)
    for this family's designs, mapped onto the twin's by ``as_twin``: a family whose contact is its
    twin's (the curved face's is the roller's with R_f = R_c) takes them as they are. Each keeps
    the twin function's name and docstring."""
    def through(function):
        def of_design(problem, design):
            return function(problem, as_twin(design))

        of_design.__name__ = of_design.__qualname__ = function.__name__
        of_design.__doc__ = function.__doc__
        return of_design

    return tuple(through(f) for f in functions)


def sized_objective(size_term, peak_stress, problem, weights, design) -> jax.Array:
    """:func:`weighted_objective` of a family's ``size_term(problem, design)`` (dimensionless) and
    ``peak_stress(problem, design)`` (MPa), in that order."""
    return weighted_objective(weights, size_term(problem, design), peak_stress(problem, design),
                              problem.sigma_max_MPa)


def stress_pair(stress_squared) -> tuple:
    """(peak_stress, angle_stress) of a family whose stress is the root of ``stress_squared(problem,
    design) -> (n,)`` (sigma^2 per angle, MPa^2): the peak as one root of the largest (shape ()),
    and the stress per angle whose max it is (shape (n,): the optional ``angle_stress`` hook from
    which the interior point's epigraph rows come, :func:`camjax.solvers.epigraph.epigraph_form`)."""
    def peak_stress(problem, design) -> jax.Array:
        """max_theta sigma (MPa), shape (): one root of the largest sigma^2."""
        return safe_sqrt(jnp.max(stress_squared(problem, design)))

    def angle_stress(problem, design) -> jax.Array:
        """sigma (MPa) per angle, shape (n,), whose max is the peak stress (the epigraph's rows)."""
        return safe_sqrt(stress_squared(problem, design))

    return peak_stress, angle_stress


def excess(lean, reach, smooth: bool = False) -> jax.Array:
    """The row |lean| - reach <= 0 (mm; a pressure angle's |s' - e| - tan(phi_max) w, a face's
    travel less its half width), shape of the broadcast inputs.

    ``smooth``: the same row without the kink of |lean| at lean = 0 (a dwell, where s' = 0, with
    the offset near 0), as the interior point takes it (a family's ``smooth_constraints``):
    (lean^2 - reach |reach|) / (2 max(|lean|, |reach|)). It has the sign of |lean| - reach
    everywhere, and where that is 0 (|lean| = reach > 0: the row active) the same value and the
    same first derivatives (d/d lean = sign(lean), d/d reach = -1), so the optimum, its
    multipliers and its sensitivities are the same; it is smooth in lean wherever |lean| < reach.
    The roller's 100-weighting sweep (benchmarks/follower_sweep.py's problem) took at most 36
    Newton steps with it and 64 without, the steps zig-zagging across offset 0 at mu ~ 3e-3."""
    if not smooth:
        return jnp.abs(lean) - reach
    scale = jnp.maximum(jnp.abs(lean), jnp.abs(reach))
    nonzero = scale > 0
    safe_scale = jnp.where(nonzero, scale, 1.0)
    return jnp.where(nonzero, (lean**2 - reach * jnp.abs(reach)) / (2.0 * safe_scale), 0.0)


def condense_at_largest(problem, per_angle_design, size_mm, angle_key: str):
    """The whole-cam design of a pointwise solve: the design of the angle where ``size_mm`` (n,)
    is largest (the first on ties); extras: that angle under ``angle_key`` and the grid."""
    i = jnp.argmax(size_mm)
    design = jax.tree.map(lambda x: x[i], per_angle_design)
    return design, {angle_key: problem.theta_deg[i], "theta_deg": problem.theta_deg}


def all_within(violation, tolerances: dict) -> jax.Array:
    """Whether every violation named in ``tolerances`` is within its tolerance (bool, traceable)."""
    within = (getattr(violation, name) <= tol for name, tol in tolerances.items())
    return functools.reduce(operator.and_, within)


def violated(names, violation, tolerances: dict) -> list[str]:
    """The names (in the order of ``names``) whose violation exceeds its tolerance (Python)."""
    return [name for name in names if float(getattr(violation, name)) > tolerances[name]]


def size_norm(problem) -> jax.Array:
    """N (mm), shape (): the length the constraints are divided by (the family's ``size_norm_mm``,
    the largest size its box allows)."""
    return problem.size_norm_mm


def stacked_maxima(constraints):
    """max_theta of each per-angle constraint (a family's ``Constraints`` of (n,) arrays), shape ()
    each, as one reduction over the stacked constraints: XLA then evaluates the shared terms once
    per angle instead of once per constraint."""
    return type(constraints)(*jnp.max(jnp.stack(constraints), axis=-1))


def tolerances(names, sigma_max_MPa=None) -> dict:
    """Each named constraint's feasibility tolerance: the pressure angle's in rad
    (:data:`FEASIBILITY_TOL_RAD`), the stress's in MPa (:data:`FEASIBILITY_RTOL_STRESS` times
    ``sigma_max_MPa``), every other's in mm (:data:`FEASIBILITY_TOL_MM`)."""
    def one(name):
        if name == "pressure_angle":
            return FEASIBILITY_TOL_RAD
        if name == "stress":
            return FEASIBILITY_RTOL_STRESS * sigma_max_MPa
        return FEASIBILITY_TOL_MM

    return {name: one(name) for name in names}


def feasible(problem, violation) -> jax.Array:
    """Whether every violation (a family's ``Violation``, one field per constraint) is within its
    :func:`tolerances` (bool, traceable; the stress's relative to ``problem.sigma_max_MPa``)."""
    return all_within(violation, tolerances(violation._fields, problem.sigma_max_MPa))


def violated_constraints(problem, violation) -> list[str]:
    """Names of the violated constraints, in the order of the ``Violation``'s fields, each judged by
    its :func:`tolerances` (Python; needs concrete values)."""
    names = violation._fields
    sigma_max = float(problem.sigma_max_MPa) if "stress" in names else None
    return violated(names, violation, tolerances(names, sigma_max))


def worst_contact(problem, design, sigma, phi, margin, limit_rad) -> tuple[dict, dict]:
    """The worst of a circle's contact on the cam over the grid, and what it violates (traceable).

    ``sigma`` the Hertz stress (MPa), ``phi`` the |pressure angle| (rad) and ``margin`` the convex
    cam-surface radius rho_c (mm) per angle, shape (n,) each; ``limit_rad`` phi_max. Returns
    (figures, violations): the Evaluation fields ``stress_max_MPa``, ``stress_max_deg``,
    ``pressure_angle_max_deg``, ``pressure_angle_max_at_deg`` (the first angle on ties) and
    ``cam_rho_min_mm``; the Violation fields ``pressure_angle`` (rad), ``undercut`` (mm, rho_min -
    min rho_c against ``problem.min_curvature_radius_mm``), ``stress`` (MPa) and ``bounds`` (mm).
    """
    i, j = jnp.argmax(sigma), jnp.argmax(phi)
    rho_c_min = jnp.min(margin)
    figures = dict(stress_max_MPa=sigma[i], stress_max_deg=problem.theta_deg[i],
                   pressure_angle_max_deg=jnp.rad2deg(phi[j]), pressure_angle_max_at_deg=problem.theta_deg[j],
                   cam_rho_min_mm=rho_c_min)
    violations = dict(pressure_angle=positive_part(phi[j] - limit_rad),
                      undercut=positive_part(problem.min_curvature_radius_mm - rho_c_min),
                      stress=positive_part(sigma[i] - problem.sigma_max_MPa),
                      bounds=bounds_violation(problem, design))
    return figures, violations


def judged(evaluation_type, violation_type, problem, *, objective, size_mm, figures: dict, violations: dict):
    """A family's ``Evaluation`` (``evaluation_type``) of one design: its ``objective`` and
    ``size_mm``, the Evaluation ``figures``, the ``Violation`` of the ``violations`` (by field name)
    and whether it is :func:`feasible`."""
    v = violation_type(**violations)
    return evaluation_type(objective=objective, size_mm=size_mm, **figures, violation=v,
                           feasible=feasible(problem, v))


def unit_coordinate(x, lo, hi):
    """(x - lo) / (hi - lo): a variable over its bounds (x - lo for a fixed one, lo == hi)."""
    return (x - lo) / jnp.where(hi > lo, hi - lo, 1.0)


def from_unit_coordinate(v, lo, hi):
    """lo + v (hi - lo): the inverse of :func:`unit_coordinate`."""
    return lo + v * jnp.where(hi > lo, hi - lo, 1.0)


def to_unit_box(problem, design):
    """Design (mm) -> each variable over its bounds (:func:`unit_coordinate`; not clipped)."""
    return jax.tree.map(unit_coordinate, design, problem.lower, problem.upper)


def from_unit_box(problem, u):
    """Unit-box coordinates -> design (mm): the inverse of :func:`to_unit_box`."""
    return jax.tree.map(from_unit_coordinate, u, problem.lower, problem.upper)


# -------------------------------------------------------------------------------- output


def design_json(design, variables, **derived) -> dict:
    """Each design variable's value (mm), in the order of ``variables``, then each ``derived``
    length (mm, e.g. ``prime_radius_mm``)."""
    return {**{name: finite_float(getattr(design, name)) for name in variables},
            **{name: finite_float(v) for name, v in derived.items()}}


def violation_json(violation) -> dict:
    """result.json's ``constraint_violation``: each field of a family's ``Violation`` in the order of
    its fields, named with its unit: ``pressure_angle_deg`` (converted from rad), ``stress_MPa``,
    every other ``<name>_mm``."""
    units = {"pressure_angle": "deg", "stress": "MPa"}
    return {f"{name}_{units.get(name, 'mm')}": finite_float(np.degrees(v) if name == "pressure_angle" else v)
            for name, v in zip(violation._fields, violation, strict=True)}


def bounds_json(problem, variables) -> dict:
    """result.json's ``<variable>_bounds_mm``: [low, high] of each design variable (``..._mm`` name)."""
    return {f"{name[:-3]}_bounds_mm": [finite_float(getattr(problem.lower, name)),
                                       finite_float(getattr(problem.upper, name))]
            for name in variables}


def pointwise_json(solution, variables) -> dict:
    """result.json's ``pointwise`` block: the grid and every variable's per-angle optimum (lists)."""
    return {"theta_deg": np.asarray(solution.extras["theta_deg"], float).tolist(),
            **{name: np.asarray(getattr(solution.pointwise, name), float).tolist() for name in variables}}


def solution_keys(problem, solution, variables, *, size_mm, figures: dict, pointwise_angles=(),
                  **derived) -> dict:
    """A family's keys of result.json's design block, in the order every family writes them.

    The design (:func:`design_json` of ``variables`` and the ``derived`` lengths), then
    ``size_mm``, ``constraint_violation`` (:func:`violation_json` of the solution's violation), the
    evaluation ``figures``, ``sigma_max_MPa`` and each variable's bounds; for a pointwise
    ``solution`` also the extras named in ``pointwise_angles`` (deg) and the ``pointwise`` block.
    Every number is checked finite (:func:`camjax.numerics.finite_float`).
    """
    out = {
        **design_json(solution.design, variables, **derived),
        "size_mm": finite_float(size_mm),
        "constraint_violation": violation_json(solution.violation),
        **{name: finite_float(v) for name, v in figures.items()},
        "sigma_max_MPa": finite_float(problem.sigma_max_MPa),
        **bounds_json(problem, variables),
    }
    if solution.mode == "pointwise":
        out.update({name: finite_float(solution.extras[name]) for name in pointwise_angles})
        out["pointwise"] = pointwise_json(solution, variables)
    return out


def record_json(solution, size_mm, **derived) -> dict:
    """A pareto.json row's family keys: the solution's design (every field of its ``Design``, then
    the ``derived`` lengths, :func:`design_json`), its size (mm) and the peak stress and its angle."""
    d, evaluation = solution.design, solution.evaluation
    return {**design_json(d, d._fields, **derived), "size_mm": finite_float(size_mm),
            "stress_max_MPa": finite_float(evaluation.stress_max_MPa),
            "stress_max_deg": finite_float(evaluation.stress_max_deg)}
