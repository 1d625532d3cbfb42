"""The optimal-design problem of SPEC section 5: design pytree, objective, constraints, references.

Design variables (a pytree, :class:`Design`): base radius R_b and face width L of a flat-face
follower, in mm. More fields (offset, roller radius, law parameters) can be added to
:class:`Design` and to the bounds; the solvers only ever ``tree_map`` over it.

Objective, weights alpha (size) and gamma (stress), N = R_b,max + L_max:

    F = alpha (R_b + L) / N + gamma max_theta sigma(theta) / sigma_max,

with sigma(theta) = C(theta) / sqrt(rho(theta)), rho = R_b + q, q = s + s''. Constraints, all
written ``g <= 0`` in mm (:class:`Constraints`, one value per angle):

- curvature:  rho_min - rho <= 0      (rho > 0: a flat face cannot follow a concavity; rho_min
  is the scene's follower.min_curvature_radius_mm, 1 um by default, so that "> 0" has a minimum);
- stress:     (C / sigma_max)^2 - rho <= 0, which is sigma <= sigma_max for C >= 0 written so that
  it is linear in R_b and stays finite where rho <= 0 (sigma itself saturates there);
- face_width: 2 |s'| - L <= 0         (symmetric face);
- and the box bounds of the scene, which the solvers keep by projection.

Everything that does not depend on the design (q, s', C) is computed once per scene by
:func:`problem_from_scene`; the objective is then a few flops per design and angle.

Modes. **global** (the real design): one R_b and L for the whole cam, max over theta of the
stress and every angle's constraints. **pointwise** (the source's method): the problem solved
separately at each angle; :func:`per_angle` turns a problem on an N-angle grid into N problems on
a one-angle grid, stacked along a leading axis, so that the same solver code ``vmap``s over
them. On a one-angle grid the global and pointwise problems coincide.

This module is the flat-face *problem family* of :mod:`camjax.solvers.base` (the protocol the
solvers reach a problem through): :func:`bounds`, :func:`size_norm`, :func:`objective`,
:func:`size_term`, :func:`constraints`, :func:`constraint_maxima`, :func:`evaluate`,
:func:`per_angle`, :func:`condense_pointwise`, :func:`violated_constraints`,
:func:`solution_json` and :func:`record`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import family, runtime
from camjax.family import (
    Weights,
    bounds_violation,
    weighted_objective,
)

# re-exported: this family's protocol functions, written once for every family
from camjax.family import bounds as bounds
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers.flat import optimum
from camjax.followers.flat.needs import (  # noqa: F401  (the family's pytrees and per-angle needs, re-exported)
    Design,
    ExactExtrema,
    Problem,
    curvature_radius,
    exact_peak_stress,
    face_width_need,
    required_base_radius,
    required_face_width,
    rho_need,
    stress,
    stress_rho_need,
)
from camjax.numerics import RHO_FLOOR_MM, finite_float, max_over_angles, positive_part, safe_sqrt

CONSTRAINT_NAMES = ("curvature", "stress", "face_width", "bounds")


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    curvature: jax.Array  # rho_min - rho
    stress: jax.Array  # (C / sigma_max)^2 - rho
    face_width: jax.Array  # 2 |s'| - L


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    curvature: jax.Array  # mm: rho_min - min rho
    stress: jax.Array  # MPa: max sigma - sigma_max
    face_width: jax.Array  # mm: 2 max|s'| - L
    bounds: jax.Array  # mm: largest distance outside the box


class Evaluation(NamedTuple):
    """A design judged on the whole grid (true maxima; shape () each)."""

    objective: jax.Array  # F
    size_mm: jax.Array  # R_b + L
    stress_max_MPa: jax.Array  # max_theta sigma
    stress_max_deg: jax.Array  # where it occurs
    rho_min_mm: jax.Array  # min_theta rho
    violation: Violation
    feasible: jax.Array  # bool


# ----------------------------------------------------------------------------- building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None,
                       rho_min_mm: float | None = None, extrema: str | None = None) -> Problem:
    """Problem of a scene with a [design] section (Python, not traceable: it reads the scene).

    Args:
      scene: a :class:`camjax.scene.Scene` with [contact] and [design].
      arrays: its :class:`camjax.evaluate.SceneArrays` if already computed (else computed here).
      samples: grid size override (ignored when ``arrays`` is given).
      dtype: floating dtype of the arrays (default float64).
      rho_min_mm: the curvature margin of the constraint rho > 0 (default: the scene's
        follower.min_curvature_radius_mm).
      extrema: "exact" or "grid" (ignored when ``arrays`` is given: theirs applies); default
        the scene's ``[motion] extrema``. Exact: the constraint maxima and the peak stress are
        refined off the grid and the solvers' designs polished (:class:`ExactExtrema`).
    """
    from camjax.evaluate import scene_arrays

    if scene.design is None:
        raise ValueError("scene has no [design] section: nothing to optimize")
    if scene.follower.type != "flat":
        raise ValueError(f"follower.type: {scene.follower.type!r} is not a flat face; use "
                         "camjax.solvers.base.problem_from_scene (it picks the follower's family)")
    if arrays is None:
        arrays = scene_arrays(scene, samples=samples, dtype=dtype, extrema=extrema)
    if arrays.stress_coefficient is None:
        raise ValueError("scene has no contact stress: the objective needs [contact] and loads")
    d = scene.design
    kin = arrays.kin
    dt = kin.s.dtype
    as_ = lambda v: jnp.asarray(v, dt)  # noqa: E731
    return Problem(
        theta_deg=as_(arrays.theta_deg),
        q_mm=kin.s + kin.d2s,
        ds_mm=kin.ds,
        stress_coefficient=as_(arrays.stress_coefficient),
        lower=Design(as_(d.bounds("base_radius_mm")[0]), as_(d.bounds("face_width_mm")[0])),
        upper=Design(as_(d.bounds("base_radius_mm")[1]), as_(d.bounds("face_width_mm")[1])),
        sigma_max_MPa=as_(d.sigma_max_MPa),
        size_norm_mm=as_(d.bounds("base_radius_mm")[1] + d.bounds("face_width_mm")[1]),
        rho_min_mm=as_(scene.follower.min_curvature_radius_mm if rho_min_mm is None else rho_min_mm),
        exact=None if arrays.model is None else _exact_extrema(arrays, as_(d.sigma_max_MPa)),
    )


def _problem_curves(p, sigma_max_MPa) -> jax.Array:
    """(-q, stress need (C / sigma_max)^2 - q, s') stacked, from point or grid values (mm)."""
    q = p.kin.s + p.kin.d2s
    return jnp.stack([-q, (p.stress_coefficient / sigma_max_MPa) ** 2 - q, p.kin.ds])


@runtime.program_cache
def _exact_maxima(model, sigma_max_MPa, grid_point):
    """max -q, max stress need, the face width 2 max |s'| and where each occurs, refined off their
    values at the grid's point values ``grid_point`` (computed here too: one program, nothing
    operation by operation)."""
    from camjax import extrema
    from camjax.evaluate import model_at
    from camjax.program import segment_bounds_deg

    grid = _problem_curves(grid_point, sigma_max_MPa)

    def fn(segment, theta_deg, params):
        m, sigma, w = params
        return jnp.tensordot(w, _problem_curves(model_at(m, segment, theta_deg), sigma), axes=1)

    eye = jnp.eye(3, dtype=grid.dtype)
    rows = jnp.concatenate([eye, -eye[2:]])
    segments, dwells = segment_bounds_deg(model.program), extrema.dwells(model.program)
    # mapped, not vmapped: traced once and not batched again (see evaluate._refined_extremes)
    e, at = jax.lax.map(lambda w: extrema.refine_max(fn, (model, sigma_max_MPa, w), segments, w @ grid,
                                                     constant=dwells), rows)
    width = 2.0 * jnp.maximum(jnp.maximum(e[2], e[3]), 0.0)
    return -e[0], e[1], width, at[0], at[1], jnp.where(e[2] >= e[3], at[2], at[3])


def _exact_extrema(arrays, sigma_max_MPa) -> ExactExtrema:
    """The design-independent maxima of the problem, refined off the grid (one jitted call)."""
    from camjax.evaluate import PointValues

    grid_point = PointValues(arrays.kin, None, None, arrays.stress_coefficient)
    return ExactExtrema(arrays.model, *_exact_maxima(arrays.model, sigma_max_MPa, grid_point))


def per_angle(problem: Problem) -> Problem:
    """The n pointwise problems: every grid leaf (n,) -> (n, 1), every scalar leaf -> (n,).

    ``jax.vmap(f)(per_angle(p), ...)`` solves the problem at each angle separately.
    """
    n = problem.theta_deg.shape[-1]
    grid = lambda x: x[:, None]  # noqa: E731
    scalar = lambda x: jnp.broadcast_to(x, (n,))  # noqa: E731
    return Problem(
        grid(problem.theta_deg), grid(problem.q_mm), grid(problem.ds_mm),
        grid(problem.stress_coefficient),
        jax.tree.map(scalar, problem.lower), jax.tree.map(scalar, problem.upper),
        scalar(problem.sigma_max_MPa), scalar(problem.size_norm_mm), scalar(problem.rho_min_mm),
    )


def with_bounds(problem: Problem, base_radius_mm=None, face_width_mm=None) -> Problem:
    """The same problem with other (low, high) bounds; the normalization N is kept."""
    lower, upper = problem.lower, problem.upper
    if base_radius_mm is not None:
        lower = lower._replace(base_radius_mm=jnp.asarray(base_radius_mm[0], problem.q_mm.dtype))
        upper = upper._replace(base_radius_mm=jnp.asarray(base_radius_mm[1], problem.q_mm.dtype))
    if face_width_mm is not None:
        lower = lower._replace(face_width_mm=jnp.asarray(face_width_mm[0], problem.q_mm.dtype))
        upper = upper._replace(face_width_mm=jnp.asarray(face_width_mm[1], problem.q_mm.dtype))
    return problem._replace(lower=lower, upper=upper)


# ---------------------------------------------------------------------------- physics


def peak_stress(problem: Problem, design: Design) -> jax.Array:
    """max_theta sigma (MPa), shape (), computed as sqrt(max_theta C^2 / rho).

    sqrt is monotone, so this is the max of :func:`stress` (to rounding) with one division per
    angle and a single square root: the inner loop of a population's fitness. Its gradient is
    that of the argmax angle, -C / (2 rho^(3/2)).
    """
    def ratio(c, q):  # C^2 / rho; padding (C = 0) gives 0 <= the max
        return c**2 / jnp.maximum(design.base_radius_mm + q, RHO_FLOOR_MM)

    return safe_sqrt(max_over_angles(ratio, problem.stress_coefficient, problem.q_mm))


def size_term(problem: Problem, design: Design) -> jax.Array:
    """Normalized size (R_b + L) / N (dimensionless)."""
    return (design.base_radius_mm + design.face_width_mm) / problem.size_norm_mm


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha (R_b + L) / N + gamma max_theta sigma / sigma_max (dimensionless, shape ()), true max."""
    peak = peak_stress(problem, design)
    return weighted_objective(weights, size_term(problem, design), peak, problem.sigma_max_MPa)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each. Linear in the design."""
    rho = curvature_radius(problem, design)
    return Constraints(
        curvature=problem.rho_min_mm - rho,
        stress=stress_rho_need(problem) - rho,
        face_width=face_width_need(problem) - design.face_width_mm,
    )


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint of :func:`constraints`, shape () each, in O(1) per design.

    Every constraint is (design-independent per-angle term) - (one design variable), so its
    max over angles is the max of the first term (computed once; XLA hoists it out of a batch
    of designs) minus the variable. This is what keeps a population's fitness one pass over the
    angles (for the peak stress) instead of four.
    """
    return Constraints(
        curvature=problem.rho_min_mm - design.base_radius_mm - q_min(problem),
        stress=stress_need_max(problem) - design.base_radius_mm,
        face_width=required_face_width(problem) - design.face_width_mm,
    )


def q_min(problem: Problem) -> jax.Array:
    """min_theta (s + s'') (mm), exact when the problem carries :class:`ExactExtrema`, shape ()."""
    return jnp.min(problem.q_mm) if problem.exact is None else problem.exact.q_min_mm


def stress_need_max(problem: Problem) -> jax.Array:
    """max_theta ((C / sigma_max)^2 - q) (mm): the R_b the stress limit needs; exact likewise."""
    if problem.exact is None:
        return jnp.max(stress_rho_need(problem) - problem.q_mm)
    return problem.exact.stress_need_mm


def violation(problem: Problem, design: Design, peak_stress_MPa: jax.Array | None = None) -> Violation:
    """Worst violation of each constraint in physical units (mm, MPa); zeros when feasible.

    ``peak_stress_MPa``: the design's peak stress if already known (else computed here).
    """
    g = constraint_maxima(problem, design)
    if peak_stress_MPa is not None:
        peak = peak_stress_MPa
    elif problem.exact is None:
        peak = jnp.max(stress(problem, design))
    else:
        peak = exact_peak_stress(problem, design).value
    return Violation(
        curvature=positive_part(g.curvature),
        stress=positive_part(peak - problem.sigma_max_MPa),  # in MPa
        face_width=positive_part(g.face_width),
        bounds=bounds_violation(problem, design),
    )


def is_feasible(problem: Problem, v: Violation) -> jax.Array:
    """All violations within the tolerances (FEASIBILITY_TOL_MM; stress relative to sigma_max)."""
    return family.feasible(problem, v)


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, peak stress (and its angle), smallest rho, violations and feasibility.

    Exact (refined off the grid) when the problem carries :class:`ExactExtrema`.
    """
    if problem.exact is None:
        sigma = stress(problem, design)
        i = jnp.argmax(sigma)
        peak, peak_deg = sigma[i], problem.theta_deg[i]
        f = objective(problem, weights, design)
    else:
        peak, peak_deg = exact_peak_stress(problem, design)
        f = weighted_objective(weights, size_term(problem, design), peak, problem.sigma_max_MPa)
    v = violation(problem, design, peak)
    return Evaluation(
        objective=f,
        size_mm=design.base_radius_mm + design.face_width_mm,
        stress_max_MPa=peak,
        stress_max_deg=peak_deg,
        rho_min_mm=design.base_radius_mm + q_min(problem),
        violation=v,
        feasible=is_feasible(problem, v),
    )


# ------------------------------------------------------------------------- references


# Secant steps of :func:`polish` (superlinear from the solver's design: ~1e-3 -> 1e-15 in ~6),
# and its second start point, beside the solver's R, as a fraction of the R_b interval.
# ------------------------------------------------------------------- family protocol


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the largest R_b and the largest L over angles.

    SPEC 5: reported with the angles where they occur (the first such angle on ties).
    ``per_angle_design`` has leaves (n,); returns scalars and the extras
    {base_radius_deg, face_width_deg, theta_deg}.
    """
    i = jnp.argmax(per_angle_design.base_radius_mm)
    j = jnp.argmax(per_angle_design.face_width_mm)
    design = Design(per_angle_design.base_radius_mm[i], per_angle_design.face_width_mm[j])
    extras = {"base_radius_deg": problem.theta_deg[i], "face_width_deg": problem.theta_deg[j],
              "theta_deg": problem.theta_deg}
    return design, extras


# the family's optional hooks: the exact optimum near a solver's design (exact extrema)
polish = optimum.polish
polish_pointwise = optimum.polish_pointwise


def _f(x) -> float:
    return finite_float(x)


def solution_json(problem: Problem, solution) -> dict:
    """The flat-face keys of result.json's design block, for one :class:`camjax.solvers.base.Solution`."""
    d, ev, v = solution.design, solution.evaluation, solution.violation
    out = {
        "base_radius_mm": _f(d.base_radius_mm),
        "face_width_mm": _f(d.face_width_mm),
        "size_mm": _f(d.base_radius_mm + d.face_width_mm),
        "constraint_violation": {"curvature_mm": _f(v.curvature), "stress_MPa": _f(v.stress),
                                 "face_width_mm": _f(v.face_width), "bounds_mm": _f(v.bounds)},
        "stress_max_MPa": _f(ev.stress_max_MPa),
        "stress_max_deg": _f(ev.stress_max_deg),
        "rho_min_mm": _f(ev.rho_min_mm),
        "sigma_max_MPa": _f(problem.sigma_max_MPa),
        "base_radius_bounds_mm": [_f(problem.lower.base_radius_mm), _f(problem.upper.base_radius_mm)],
        "face_width_bounds_mm": [_f(problem.lower.face_width_mm), _f(problem.upper.face_width_mm)],
    }
    if solution.mode == "pointwise":
        out["base_radius_deg"] = _f(solution.extras["base_radius_deg"])
        out["face_width_deg"] = _f(solution.extras["face_width_deg"])
        out["pointwise"] = {
            "theta_deg": np.asarray(solution.extras["theta_deg"], float).tolist(),
            "base_radius_mm": np.asarray(solution.pointwise.base_radius_mm, float).tolist(),
            "face_width_mm": np.asarray(solution.pointwise.face_width_mm, float).tolist(),
        }
    return out


def record(solution) -> dict:
    """The flat-face keys of a pareto.json row (one solution): the design, size and peak stress."""
    d, ev = solution.design, solution.evaluation
    return {"base_radius_mm": _f(d.base_radius_mm), "face_width_mm": _f(d.face_width_mm),
            "size_mm": _f(d.base_radius_mm + d.face_width_mm),
            "stress_max_MPa": _f(ev.stress_max_MPa), "stress_max_deg": _f(ev.stress_max_deg)}
