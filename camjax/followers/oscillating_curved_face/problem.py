"""The oscillating curved-face follower's optimal-design problem (a family of :mod:`camjax.solvers.base`).

Design variables (:class:`Design`, mm): base radius R_b, face radius R_c, face width W, pivot
distance d and arm length l of a rocker with a crowned face
(:mod:`camjax.followers.oscillating_curved_face.geometry`); each is free between its bounds or
fixed (lower == upper). The prime radius is R_p = R_b + R_c and the arm starts at psi0 with
cos psi0 = (d^2 + l^2 - R_p^2) / (2 d l), as the oscillating roller's with R_f = R_c.

Objective, weights alpha (size) and gamma (stress), N = R_b,max + W_max:

    F = alpha (R_b + W) / N + gamma max_theta sigma(theta) / sigma_max,

the size of the translating curved face (:mod:`camjax.followers.curved_face.problem`: the cam's
base radius and the follower's face). The stress is the oscillating roller's with R_f = R_c
(P = M / (l cos phi), sigma = C_M sqrt(1 / (l cos phi rho_eq)), rho_eq = 1 / (1/rho_c + 1/R_c));
without [contact] C_M = 0: no stress term and no stress constraint. Constraints, one value per
angle, ``g <= 0`` in mm (:class:`Constraints`):

- reach: max(|d - l| - R_p, R_p - (d + l)) (the face's circle reaches the prime circle);
- pressure_angle: |l Q - d cos psi| - tan(phi_max) d sin psi <= 0 (as the oscillating roller's);
- undercut: (R_c + rho_min) (kappa_pitch (R_c + rho_min) - 1) <= 0;
- face_travel: R_c |sin phi| - W / 2 <= 0: the contact stays on the face;
- stress: C_M^2 / (sigma_max^2 l cos phi) - rho_eq <= 0;
- and the box bounds, kept by projection. The scene checks W <= 2 R_c in the box.

The solvers work in the plain unit box of the bounds, W a variable like the others: W enters the
objective and the face constraint only, so the optimum's W is the width the design needs
(:func:`face_width_need`, or W's lower bound). W is not eliminated as that need (a floor in the
solvers' coordinates, as the translating curved face's): the need is a max over angles whose
argmax jumps between the rise and the return, and the objective would get a kink there where
the optimum lies (the gradient solver then stalled at objective 1.044 against 0.969). As a
constraint per angle, each angle with its own multiplier in the gradient solver's refinement,
it is smooth.
With exact extrema, :func:`polish` moves the solved design the least that keeps every constraint
between the samples too (the rocking family's polish).

Modes: :func:`per_angle` gives the n one-angle problems; a pointwise solve is condensed into the
design of the angle with the largest R_b + R_c with the largest W over the angles.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import family
from camjax.contact import roller_stress
from camjax.family import (
    Weights,
    weighted_objective,
)

# re-exported: this family's protocol functions, written once for every family
from camjax.family import bounds as bounds
from camjax.family import bounds_violation as bounds_violation
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers import _pitch as pitch
from camjax.followers._swing import moment_model, polish_design
from camjax.followers.oscillating_curved_face import geometry as curved_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.oscillating_roller.problem import axial_coefficient, cos_phi, moment_coefficient
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller.problem import roller_figures
from camjax.numerics import RHO_FLOOR_MM, finite_float, floor_positive, positive_part, safe_sqrt

CONSTRAINT_NAMES = ("reach", "pressure_angle", "undercut", "face_travel", "stress", "bounds")
VARIABLES = ("base_radius_mm", "face_radius_mm", "face_width_mm", "pivot_distance_mm", "arm_length_mm")
GRID_FIELDS = frozenset({"theta_deg", "s_rad", "ds", "d2s", "moment_coefficient"})


class Design(NamedTuple):
    """One oscillating curved-face design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b, mm
    face_radius_mm: jax.Array  # R_c, mm: the crown's radius
    face_width_mm: jax.Array  # W, mm: the face's chord, symmetric about its axis
    pivot_distance_mm: jax.Array  # d, mm
    arm_length_mm: jax.Array  # l, mm: pivot to the centre of the face's circle


class Problem(NamedTuple):
    """Design-independent data of one oscillating curved-face design problem on n samples."""

    theta_deg: jax.Array  # (n,) cam angle, degrees
    s_rad: jax.Array  # (n,) arm swing s, rad
    ds: jax.Array  # (n,) s', rad/rad
    d2s: jax.Array  # (n,) s'', rad/rad^2
    moment_coefficient: jax.Array  # (n,) C_M = 0.564 sqrt(M / (w K)), MPa mm^0.5 m^0.5 (0: no stress)
    lower: Design  # lower bounds, mm
    upper: Design  # upper bounds, mm
    sigma_max_MPa: jax.Array  # () allowable contact stress
    size_norm_mm: jax.Array  # () N = R_b,max + W_max
    tan_max_pressure_angle: jax.Array  # () tan(phi_max)
    min_curvature_radius_mm: jax.Array  # () smallest convex cam-surface radius allowed
    rotation_sign: jax.Array  # () +1 ccw, -1 cw
    # the motion program (as arrays) behind the grid when extrema are exact: :func:`polish`
    program: Any = None
    moment_model: Any = None  # camjax.followers._swing.MomentModel: C_M between the samples (the polish)


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    reach: jax.Array  # max(|d - l| - R_p, R_p - (d + l))
    pressure_angle: jax.Array  # |l Q - d c| - tan(phi_max) d sn
    undercut: jax.Array  # (R_c + rho_min) (kappa (R_c + rho_min) - 1)
    face_travel: jax.Array  # R_c |sin phi| - W / 2
    stress: jax.Array  # C_M^2 / (sigma_max^2 l cos phi) - rho_eq


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    reach: jax.Array  # mm
    pressure_angle: jax.Array  # rad: max |phi| - phi_max
    undercut: jax.Array  # mm: rho_min - min rho_c over the convex parts
    face_travel: jax.Array  # mm: max R_c |sin phi| - W / 2
    stress: jax.Array  # MPa: max sigma - sigma_max
    bounds: jax.Array  # mm


class Evaluation(NamedTuple):
    """A design judged on the whole grid (true maxima; shape () each)."""

    objective: jax.Array
    size_mm: jax.Array  # R_b + W
    stress_max_MPa: jax.Array
    stress_max_deg: jax.Array
    pressure_angle_max_deg: jax.Array
    pressure_angle_max_at_deg: jax.Array
    cam_rho_min_mm: jax.Array  # smallest convex cam-surface radius
    face_travel_max_mm: jax.Array  # max_theta R_c |sin phi|
    face_travel_max_deg: jax.Array  # where it occurs
    violation: Violation
    feasible: jax.Array  # bool


# ------------------------------------------------------------------------------ building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None) -> Problem:
    """Problem of an oscillating curved-face scene with a [design] section (Python: reads the scene)."""
    what = "an oscillating curved-face follower"
    arrays, as_ = family.design_arrays(scene, "oscillating_curved_face", what, arrays,
                                       samples=samples, dtype=dtype)
    d, f, kin = scene.design, scene.follower, arrays.kin
    lower, upper = family.design_box(d, Design, as_)
    return Problem(
        theta_deg=as_(arrays.theta_deg), s_rad=kin.s, ds=kin.ds, d2s=kin.d2s,
        moment_coefficient=as_(moment_coefficient(scene, arrays)),
        lower=lower, upper=upper,
        sigma_max_MPa=as_(d.sigma_max_MPa if d.sigma_max_MPa is not None else 1.0),
        size_norm_mm=as_(d.bounds("base_radius_mm")[1] + d.bounds("face_width_mm")[1]),
        tan_max_pressure_angle=as_(np.tan(np.radians(f.max_pressure_angle_deg))),
        min_curvature_radius_mm=as_(f.min_curvature_radius_mm),
        rotation_sign=as_(pitch.rotation_sign(scene.motion.rotation)),
        program=None if arrays.model is None else arrays.model.program,
        moment_model=None if arrays.model is None else moment_model(scene, arrays),
    )


def per_angle(problem: Problem) -> Problem:
    """The n pointwise problems: every grid leaf (n,) -> (n, 1), every scalar leaf -> (n,)."""
    return family.per_angle(problem._replace(program=None, moment_model=None), GRID_FIELDS)


# ---------------------------------------------------------------------------- physics


class _Terms(NamedTuple):
    """Per-angle quantities every function of a design shares (shape (n,) each)."""

    legs: curved_geo.Legs  # d sin psi, l Q - d cos psi (mm): |T| cos phi, |T| sin phi
    kappa: jax.Array  # pitch curvature, 1/mm
    rho_eq: jax.Array  # Hertz equivalent radius 1 / (1/rho_c + 1/R_c), mm
    reach: jax.Array  # () closure, mm


def _terms(problem: Problem, design: Design) -> _Terms:
    """The closed forms of :mod:`camjax.followers.oscillating_curved_face.geometry` with the
    rotation as data: it enters through Q = 1 + sigma s' only."""
    d, l = design.pivot_distance_mm, design.arm_length_mm
    rp = design.base_radius_mm + design.face_radius_mm
    psi = rocker_roller_geo.arm_start_angle(rp, d, l) + problem.s_rad
    q = 1.0 + problem.rotation_sign * problem.ds
    kappa = rocker_roller_geo.swing_pitch_curvature(d, l, psi, q, problem.d2s)
    return _Terms(curved_geo.legs(d, l, psi, q), kappa,
                  roller_geo.roller_equivalent_radius(kappa, design.face_radius_mm),
                  rocker_roller_geo.oscillating_roller_reach_constraint(rp, d, l))


def _travel(x: _Terms, design: Design) -> jax.Array:
    """R_c |sin phi| (mm): the contact's distance from the face's axis, per angle."""
    return jnp.abs(curved_geo.face_travel_of(x.legs, design.face_radius_mm))


def pressure_angle(problem: Problem, design: Design) -> jax.Array:
    """phi (rad) per angle, as
    :func:`camjax.followers.oscillating_roller.geometry.oscillating_roller_pressure_angle`."""
    g = _terms(problem, design).legs
    return jnp.arctan2(g.along, g.across)


def face_width_need(problem: Problem, design: Design) -> jax.Array:
    """2 max_theta R_c |sin phi| (mm), the narrowest face that keeps the contact on it, shape ()
    (batched designs: over the last axis)."""
    column = jax.tree.map(lambda x: jnp.expand_dims(x, -1), design)  # (..., 1) against the grid (n,)
    return 2.0 * jnp.max(_travel(_terms(problem, column), column), axis=-1)


def stress(problem: Problem, design: Design) -> jax.Array:
    """Hertz contact stress sigma(theta) (MPa), shape (n,); finite (saturated) at an undercut."""
    x = _terms(problem, design)
    phi = jnp.arctan2(x.legs.along, x.legs.across)
    return roller_stress(axial_coefficient(problem, design), phi, x.rho_eq)


def peak_stress(problem: Problem, design: Design) -> jax.Array:
    """max_theta sigma (MPa), shape ()."""
    x = _terms(problem, design)
    coefficient = axial_coefficient(problem, design)
    ratio = coefficient**2 / (cos_phi(x.legs) * floor_positive(x.rho_eq, RHO_FLOOR_MM))
    return safe_sqrt(jnp.max(ratio))


def size_term(problem: Problem, design: Design) -> jax.Array:
    """Normalized size (R_b + W) / N (dimensionless)."""
    return (design.base_radius_mm + design.face_width_mm) / problem.size_norm_mm


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha (R_b + W) / N + gamma max_theta sigma / sigma_max (dimensionless, shape ())."""
    return weighted_objective(weights, size_term(problem, design), peak_stress(problem, design),
                              problem.sigma_max_MPa)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design."""
    x = _terms(problem, design)
    reach_r = design.face_radius_mm + problem.min_curvature_radius_mm
    need = axial_coefficient(problem, design) ** 2 / (problem.sigma_max_MPa**2 * cos_phi(x.legs))
    return Constraints(
        reach=jnp.broadcast_to(x.reach, x.kappa.shape),
        pressure_angle=jnp.abs(x.legs.along) - problem.tan_max_pressure_angle * x.legs.across,
        undercut=reach_r * roller_geo.roller_undercut_constraint(x.kappa, design.face_radius_mm,
                                                               problem.min_curvature_radius_mm),
        face_travel=_travel(x, design) - 0.5 * design.face_width_mm,
        stress=need - x.rho_eq,
    )


def polish(problem: Problem, weights: Weights, design: Design) -> Design:
    """The solver's design moved, where it is short, the least that keeps the pressure angle, the
    undercut, the contact on the face and the stress at every cam angle, not only at the samples
    (:func:`camjax.followers._swing.polish_design`; needs ``problem.program``, i.e. exact extrema)."""
    names = ("pressure_angle", "undercut", "face_travel", "stress")
    return polish_design(problem, design, constraints, names)


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint of :func:`constraints`, shape () each (one stacked reduction)."""
    return family.stacked_maxima(constraints(problem, design))


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, peak stress, pressure angle and face travel (and their angles), violations and
    feasibility."""
    x = _terms(problem, design)
    sigma = stress(problem, design)
    phi = jnp.abs(jnp.arctan2(x.legs.along, x.legs.across))
    travel = _travel(x, design)
    i, j, k = jnp.argmax(sigma), jnp.argmax(phi), jnp.argmax(travel)
    rho_c_min = jnp.min(roller_geo.roller_undercut_margin(x.kappa, design.face_radius_mm, 0.0))
    v = Violation(
        reach=positive_part(x.reach),
        pressure_angle=positive_part(phi[j] - jnp.arctan(problem.tan_max_pressure_angle)),
        undercut=positive_part(problem.min_curvature_radius_mm - rho_c_min),
        face_travel=positive_part(travel[k] - 0.5 * design.face_width_mm),
        stress=positive_part(sigma[i] - problem.sigma_max_MPa),
        bounds=bounds_violation(problem, design),
    )
    return Evaluation(
        objective=objective(problem, weights, design),
        size_mm=design.base_radius_mm + design.face_width_mm,
        stress_max_MPa=sigma[i], stress_max_deg=problem.theta_deg[i],
        pressure_angle_max_deg=jnp.rad2deg(phi[j]), pressure_angle_max_at_deg=problem.theta_deg[j],
        cam_rho_min_mm=rho_c_min, face_travel_max_mm=travel[k], face_travel_max_deg=problem.theta_deg[k],
        violation=v, feasible=family.feasible(problem, v),
    )


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest
    R_b + R_c (the oscillating roller's rule), with the largest W over the angles (the curved
    face's). Judged on the whole grid, its violations, if any, are reported."""
    size = per_angle_design.base_radius_mm + per_angle_design.face_radius_mm
    design, extras = family.condense_at_largest(problem, per_angle_design, size, "prime_radius_deg")
    return design._replace(face_width_mm=jnp.max(per_angle_design.face_width_mm)), extras


# ------------------------------------------------------------------------------- output

_f = finite_float


def _design_keys(d: Design) -> dict:
    return {**family.design_json(d, VARIABLES), "prime_radius_mm": _f(d.base_radius_mm + d.face_radius_mm)}


def solution_json(problem: Problem, solution) -> dict:
    """The oscillating curved-face keys of result.json's design block, for one Solution."""
    d, v, ev = solution.design, solution.violation, solution.evaluation
    limit_deg = np.degrees(np.arctan(problem.tan_max_pressure_angle))
    return family.solution_keys(
        problem, solution, VARIABLES, design_keys=_design_keys(d),
        size_mm=d.base_radius_mm + d.face_width_mm,
        violation={"reach_mm": v.reach, "pressure_angle_deg": np.degrees(v.pressure_angle),
                   "undercut_mm": v.undercut, "face_travel_mm": v.face_travel, "stress_MPa": v.stress,
                   "bounds_mm": v.bounds},
        figures={**roller_figures(ev, limit_deg),
                 "face_travel_max_mm": ev.face_travel_max_mm, "face_travel_max_deg": ev.face_travel_max_deg},
        pointwise_angles=("prime_radius_deg",))


def record(solution) -> dict:
    """The oscillating curved-face keys of a pareto.json row: the design, size R_b + W and peak stress."""
    d = solution.design
    return family.record_json(_design_keys(d), d.base_radius_mm + d.face_width_mm, solution.evaluation)
