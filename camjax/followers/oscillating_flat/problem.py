"""The oscillating flat face's optimal-design problem: a problem family of :mod:`camjax.solvers.base`.

Design variables (:class:`Design`, mm): base radius R_b, pivot distance d and face offset f of a
rocker with a flat face (:mod:`camjax.followers.oscillating_roller.geometry`); each is free between its bounds or
fixed (lower == upper). The face starts at psi0 with sin psi0 = (R_b + f) / d.

Objective, weights alpha (size) and gamma (stress):

    F = alpha R_b / R_b,max + gamma max_theta sigma(theta) / sigma_max,

sigma the Hertz stress of the face on the cam, P = M / xi (M the torque about the pivot, xi the
contact point's distance along the face): sigma = C_M / sqrt(xi rho) with C_M = 0.564 sqrt(M / (w K))
computed once per scene (xi in m inside). Constraints, one value per angle, ``g <= 0`` in mm:

- reach: (R_b + f) - d and -(R_b + f) (the face touches the base circle: 0 < sin psi0 < 1), the
  larger of the two, the same at every angle;
- swing: d (psi0 + s - pi/2) (the face keeps rising: psi < 90 deg, which also keeps xi > 0);
- curvature: rho_min - rho (a flat face cannot follow a concave cam);
- stress: C_M^2 / (sigma_max^2 xi) - rho, sigma <= sigma_max written on rho (finite where rho <= 0);
- and the box bounds, which the solvers keep by projection.

The face length the contact needs (max xi - min xi) is reported with the design.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax import family
from camjax.contact import stress_from_coefficient
from camjax.family import Weights

# re-exported: this family's protocol functions, written once for every family
from camjax.family import bounds as bounds
from camjax.family import bounds_violation as bounds_violation
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers import _swing
from camjax.followers._swing import per_angle as per_angle
from camjax.followers._swing import polish_design
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import problem as rocker_roller
from camjax.numerics import RHO_FLOOR_MM, capped_divide, finite_float, floor_positive, positive_part

CONSTRAINT_NAMES = ("reach", "swing", "curvature", "stress", "bounds")
VARIABLES = ("base_radius_mm", "pivot_distance_mm", "face_offset_mm")


class Design(NamedTuple):
    """One oscillating flat-face design (scalars), or a batch of them."""

    base_radius_mm: jax.Array  # R_b, mm
    pivot_distance_mm: jax.Array  # d, mm
    face_offset_mm: jax.Array  # f, mm


# the rocking grid, limits, program and moment model as the oscillating roller's Problem has them
# (:func:`camjax.followers._swing.scene_fields`), without its pressure-angle limit and positive
# drive; the box is the flat face's Design and the size norm N = R_b,max
Problem = family.twin_type(
    "Problem", rocker_roller.Problem,
    "Design-independent data of one oscillating flat-face design problem on n angles.", __name__,
    drop=("tan_max_pressure_angle", "closure"))


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    reach: jax.Array
    swing: jax.Array
    curvature: jax.Array
    stress: jax.Array


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    reach: jax.Array  # mm
    swing: jax.Array  # mm (d times the excess angle)
    curvature: jax.Array  # mm: rho_min - min rho
    stress: jax.Array  # MPa
    bounds: jax.Array  # mm


class Evaluation(NamedTuple):
    """A design judged on the whole grid (shape () each)."""

    objective: jax.Array
    size_mm: jax.Array  # R_b
    stress_max_MPa: jax.Array
    stress_max_deg: jax.Array
    rho_min_mm: jax.Array
    rho_min_deg: jax.Array
    face_length_mm: jax.Array  # max xi - min xi
    violation: Violation
    feasible: jax.Array


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None) -> Problem:
    """Problem of an oscillating flat-face scene with a [design] section (Python: reads the scene)."""
    arrays, as_ = family.design_arrays(scene, "oscillating_flat", "an oscillating flat face", arrays,
                                       samples=samples, dtype=dtype)
    lower, upper = family.design_box(scene.design, Design, as_)
    return Problem(**_swing.scene_fields(scene, arrays, as_), lower=lower, upper=upper,
                   size_norm_mm=as_(scene.design.bounds("base_radius_mm")[1]))


class _Geometry(NamedTuple):
    psi: jax.Array  # (n,) arm angle, rad
    rho: jax.Array  # (n,) cam radius of curvature, mm
    xi: jax.Array  # (n,) contact distance along the face, mm
    reach: jax.Array  # () mm


def _geometry(problem: Problem, design: Design) -> _Geometry:
    """The closed forms of camjax.followers.oscillating_roller.geometry with the rotation as data (Q = 1 + sigma s')."""
    d, f = design.pivot_distance_mm, design.face_offset_mm
    psi = rocker_flat_geo.face_start_angle(design.base_radius_mm, d, f) + problem.s_rad
    q = 1.0 + problem.rotation_sign * problem.ds
    rho = rocker_flat_geo.swing_face_radius_of_curvature(d, f, psi, q, problem.ds, problem.d2s)
    reach = jnp.maximum(design.base_radius_mm + f - d, -(design.base_radius_mm + f))
    return _Geometry(psi, rho, capped_divide(d * jnp.cos(psi), q), reach)


def stress(problem: Problem, design: Design) -> jax.Array:
    """Hertz contact stress sigma(theta) (MPa), shape (n,); saturated where rho <= 0."""
    g = _geometry(problem, design)
    coeff = problem.moment_coefficient * jax.lax.rsqrt(floor_positive(g.xi * 1e-3, RHO_FLOOR_MM))
    return stress_from_coefficient(coeff, g.rho)


def peak_stress(problem: Problem, design: Design) -> jax.Array:
    """max_theta sigma (MPa), shape ()."""
    return jnp.max(stress(problem, design))


def size_term(problem: Problem, design: Design) -> jax.Array:
    """Normalized size R_b / R_b,max."""
    return design.base_radius_mm / problem.size_norm_mm


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha R_b / R_b,max + gamma max_theta sigma / sigma_max (shape ())."""
    return family.sized_objective(size_term, peak_stress, problem, weights, design)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design."""
    g = _geometry(problem, design)
    xi_m = floor_positive(g.xi * 1e-3, RHO_FLOOR_MM)
    need = problem.moment_coefficient**2 / (problem.sigma_max_MPa**2 * xi_m)
    return Constraints(
        reach=jnp.broadcast_to(g.reach, g.rho.shape),
        swing=design.pivot_distance_mm * (g.psi - 0.5 * math.pi),
        curvature=problem.min_curvature_radius_mm - g.rho,
        stress=need - g.rho,
    )


def polish(problem: Problem, weights: Weights, design: Design) -> Design:
    """The solver's design moved, where it is short, the least that keeps the curvature and the stress at every
    cam angle, not only at the samples (:func:`camjax.followers._swing.polish_design`; needs
    ``problem.program``, i.e. exact extrema)."""
    return polish_design(problem, design, constraints, ("curvature", "stress"))


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint, shape () each."""
    return jax.tree.map(jnp.max, constraints(problem, design))


def start(problem: Problem, steps: int = 60) -> Design:
    """The gradient solver's start: the box's centre, its base radius raised to the smallest one in
    the box whose cam keeps rho >= rho_min at every sample there (bisection; R_b's upper bound if
    none does, its centre if the centre already does).

    From the centre a stress-weighted solve starts where rho < 0: there the stress is saturated
    (its gradient zero), and on the built-in scene 2 of 10 weightings gamma/alpha in 1e-2 .. 1e2
    ended at the box's edge, infeasible (9 of 10 without the BFGS refinement), where the hybrid
    finds feasible optima for all 10. rho grows with R_b at a fixed pivot (the face starts further
    from the pivot), so the feasible base radii lie above a threshold. The gradient solver starts
    from here and from the centre and keeps the better (:func:`camjax.solvers.gradient.minimize`):
    from here alone, one weighting settled in a worse local optimum (0.93 against 0.60).
    """
    centre = jax.tree.map(lambda lo, hi: 0.5 * (lo + hi), problem.lower, problem.upper)

    def curved_ok(rb):
        return jnp.max(constraints(problem, centre._replace(base_radius_mm=rb)).curvature) <= 0.0

    def halve(_, bounds):
        lo, hi = bounds
        mid = 0.5 * (lo + hi)
        ok = curved_ok(mid)
        return jnp.where(ok, lo, mid), jnp.where(ok, mid, hi)

    lo, hi = problem.lower.base_radius_mm, problem.upper.base_radius_mm
    _, first = jax.lax.fori_loop(0, steps, halve, (lo, hi))
    rb = jnp.where(curved_ok(centre.base_radius_mm), centre.base_radius_mm, jnp.where(curved_ok(hi), first, hi))
    return centre._replace(base_radius_mm=rb)


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, peak stress, smallest curvature radius, face length, violations and feasibility."""
    g = _geometry(problem, design)
    sigma = stress(problem, design)
    i, j = jnp.argmax(sigma), jnp.argmin(g.rho)
    c = constraint_maxima(problem, design)
    v = Violation(reach=positive_part(c.reach), swing=positive_part(c.swing),
                  curvature=positive_part(c.curvature),
                  stress=positive_part(sigma[i] - problem.sigma_max_MPa),
                  bounds=bounds_violation(problem, design))
    feasible = family.feasible(problem, v)
    return Evaluation(
        objective=objective(problem, weights, design), size_mm=design.base_radius_mm,
        stress_max_MPa=sigma[i], stress_max_deg=problem.theta_deg[i], rho_min_mm=g.rho[j],
        rho_min_deg=problem.theta_deg[j], face_length_mm=jnp.max(g.xi) - jnp.min(g.xi),
        violation=v, feasible=feasible,
    )


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest R_b."""
    return family.condense_at_largest(problem, per_angle_design, per_angle_design.base_radius_mm,
                                      "base_radius_deg")


_f = finite_float


def solution_json(problem: Problem, solution) -> dict:
    """The oscillating flat-face keys of result.json's design block, for one Solution."""
    ev = solution.evaluation
    figures = {"stress_max_MPa": ev.stress_max_MPa, "stress_max_deg": ev.stress_max_deg,
               "rho_min_mm": ev.rho_min_mm, "rho_min_deg": ev.rho_min_deg,
               "face_length_mm": ev.face_length_mm}
    return family.solution_keys(problem, solution, VARIABLES, size_mm=solution.design.base_radius_mm,
                                figures=figures, pointwise_angles=("base_radius_deg",))


def record(solution) -> dict:
    """The oscillating flat-face keys of a pareto.json row: the design, size R_b and peak stress."""
    return family.record_json(solution, solution.design.base_radius_mm)
