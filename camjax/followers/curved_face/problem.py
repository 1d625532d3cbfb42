"""The curved-face follower's optimal-design problem: a problem family of :mod:`camjax.solvers.base`.

Design variables (:class:`Design`, mm): base radius R_b, face radius R_c, face width W and offset
e of a translating curved-face (mushroom) follower; each is free between its bounds or fixed
(lower == upper).

Objective, weights alpha (size) and gamma (stress), N = R_b,max + W_max:

    F = alpha (R_b + W) / N + gamma max_theta sigma(theta) / sigma_max,

the flat face's size (SPEC 5: the cam's base radius and the follower's face), which this problem
becomes as R_c -> infinity. The stress is the roller's with R_f = R_c
(:func:`camjax.contact.roller_stress`: sigma = C sqrt(1 / (cos phi rho_eq)),
rho_eq = 1 / (1/rho_c + 1/R_c)); without [contact] C = 0: no stress term and no stress
constraint. Constraints, one value per angle, ``g <= 0`` in mm (:class:`Constraints`):

- pressure_angle: |s' - e~| - tan(phi_max) (d + s) <= 0 (as the roller's);
- undercut: (R_c + rho_min) (kappa_pitch (R_c + rho_min) - 1) <= 0 (as the roller's);
- face_travel: R_c |s' - e~| / r - W / 2 <= 0, r = sqrt((d + s)^2 + (s' - e~)^2): the contact,
  R_c |sin phi| off the axis, stays on the face;
- stress: C^2 / (sigma_max^2 cos phi) - rho_eq <= 0 (as the roller's);
- and the box bounds, kept by projection. The scene checks |e| < R_b + R_c and W <= 2 R_c in the box.

The solvers work in the unit box of the bounds, with the face width floored at the width the
design needs on the samples (:func:`from_unit`): W enters the objective and the face constraint
only, so the optimum's W is that need (or its lower bound), and every design the solvers see
keeps its contact on the face. :func:`polish` keeps every constraint between the samples too
(exact extrema).

Modes: :func:`per_angle` gives the n one-angle problems; a pointwise solve is condensed into the
design of the angle with the largest R_b (SPEC 5's rule) with the largest W over the angles (the
flat face's rule for L).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax import family

# re-exported: this family's protocol functions and tolerance, written once for every family
from camjax.family import FEASIBILITY_TOL_RAD as FEASIBILITY_TOL_RAD
from camjax.family import Weights
from camjax.family import bounds as bounds
from camjax.family import bounds_violation as bounds_violation
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller import problem as roller
from camjax.numerics import RHO_FLOOR_MM, floor_positive, positive_part

CONSTRAINT_NAMES = ("pressure_angle", "undercut", "face_travel", "stress", "bounds")
VARIABLES = ("base_radius_mm", "face_radius_mm", "face_width_mm", "offset_mm")
GRID_FIELDS = frozenset({"theta_deg", "s_mm", "ds_mm", "d2s_mm", "stress_coefficient"})


class Design(NamedTuple):
    """One curved-face design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b, mm
    face_radius_mm: jax.Array  # R_c, mm: the crown's radius
    face_width_mm: jax.Array  # W, mm: the face's chord, symmetric about the axis
    offset_mm: jax.Array  # e, mm (follower axis at x = e in the follower frame)


# the roller's Problem without a positive drive: the circle's grid, limits and model; here the
# box is the curved face's Design and the size norm N = R_b,max + W_max
Problem = family.twin_type(
    "Problem", roller.Problem,
    "Design-independent data of one curved-face design problem on an angle grid of n samples.", __name__,
    drop=("closure",))


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    pressure_angle: jax.Array  # |s' - e~| - tan(phi_max) (d + s)
    undercut: jax.Array  # (R_c + rho_min) (kappa (R_c + rho_min) - 1)
    face_travel: jax.Array  # R_c |sin phi| - W / 2
    stress: jax.Array  # C^2 / (sigma_max^2 cos phi) - rho_eq


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    pressure_angle: jax.Array  # rad: max |phi| - phi_max
    undercut: jax.Array  # mm: rho_min - min rho_c over the convex parts
    face_travel: jax.Array  # mm: max R_c |sin phi| - W / 2
    stress: jax.Array  # MPa: max sigma - sigma_max
    bounds: jax.Array  # mm: largest distance outside the box


# the roller's Evaluation (size_mm: R_b + W) and the contact's largest travel off the face's axis,
# max_theta R_c |sin phi| (mm), and where it occurs (deg)
Evaluation = family.twin_type(
    "Evaluation", roller.Evaluation, "A design judged on the whole grid (true maxima; shape () each).",
    __name__, add=("face_travel_max_mm", "face_travel_max_deg"), before="violation")


# ------------------------------------------------------------------------------ building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None,
                       extrema: str | None = None) -> Problem:
    """Problem of a curved-face scene with a [design] section (Python, not traceable).

    Arguments as :func:`camjax.followers.roller.problem.problem_from_scene`.
    """
    arrays, as_ = family.design_arrays(scene, "curved_face", "a curved-face follower", arrays,
                                       samples=samples, dtype=dtype, extrema=extrema)
    d = scene.design
    lower, upper = family.design_box(d, Design, as_)
    return Problem(**roller.circle_scene_fields(scene, arrays, as_), lower=lower, upper=upper,
                   size_norm_mm=as_(d.bounds("base_radius_mm")[1] + d.bounds("face_width_mm")[1]))


def per_angle(problem: Problem) -> Problem:
    """The n pointwise problems: every grid leaf (n,) -> (n, 1), every scalar leaf -> (n,)."""
    return family.per_angle(problem._replace(model=None), GRID_FIELDS)


# ---------------------------------------------------------------------------- physics


def _as_roller(design: Design) -> roller.Design:
    """The roller with the crown's radius: the curved face's contact is the roller's circle on the
    pitch curve of R_p = R_b + R_c (its terms, pressure angle, stress and circle constraints)."""
    return roller.Design(design.base_radius_mm, design.face_radius_mm, design.offset_mm)


def _terms(problem: Problem, design: Design) -> roller.CircleTerms:
    return roller.circle_terms(problem, _as_roller(design))


def _travel(x: roller.CircleTerms, design: Design) -> jax.Array:
    """R_c |u| / r (mm): the contact's distance from the face's axis, per angle."""
    return design.face_radius_mm * jnp.abs(x.u) / floor_positive(x.r, RHO_FLOOR_MM)


# the roller's at R_f = R_c: phi (rad) and sigma (MPa) per angle, and max_theta sigma (MPa)
pressure_angle, stress, peak_stress, angle_stress = family.through_twin(
    _as_roller, roller.pressure_angle, roller.stress, roller.peak_stress, roller.angle_stress)


def face_width_need(problem: Problem, design: Design) -> jax.Array:
    """2 max_theta R_c |sin phi| (mm), the narrowest face that keeps the contact on it, shape ()
    (batched designs: over the last axis)."""
    return width_need(lambda p, d: _travel(_terms(p, d), d), problem, design)


def width_need(travel, problem, design) -> jax.Array:
    """2 max_theta ``travel(problem, design)`` (mm) of a curved face (either family; ``travel`` its
    contact's distance from the face's axis per angle), shape () (batched designs: over the last
    axis)."""
    column = jax.tree.map(lambda x: jnp.expand_dims(x, -1), design)  # (..., 1) against the grid (n,)
    return 2.0 * jnp.max(travel(problem, column), axis=-1)


def size_term(problem: Problem, design: Design) -> jax.Array:
    """Normalized size (R_b + W) / N (dimensionless)."""
    return (design.base_radius_mm + design.face_width_mm) / problem.size_norm_mm


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha (R_b + W) / N + gamma max_theta sigma / sigma_max (dimensionless, shape ())."""
    return family.sized_objective(size_term, peak_stress, problem, weights, design)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design."""
    x = _terms(problem, design)
    circle = roller.circle_constraints(problem, _as_roller(design), x)
    return Constraints(pressure_angle=circle.pressure_angle, undercut=circle.undercut,
                       face_travel=_travel(x, design) - 0.5 * design.face_width_mm, stress=circle.stress)


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint of :func:`constraints`, shape () each (one stacked reduction)."""
    return family.stacked_maxima(constraints(problem, design))


# ------------------------------------------------------------------ solver coordinates


def to_unit(problem: Problem, design: Design) -> Design:
    """Design (mm) -> the solvers' unit-box coordinates: each variable over its bounds."""
    return family.to_unit_box(problem, design)


def from_unit(problem: Problem, u: Design) -> Design:
    """The unit box -> design (mm), with the face width floored at the need of the design's
    R_b, R_c and e on the samples (:func:`face_width_need`, at most W_max).

    Below the floor W takes the floor's value and keeps the gradient of its own coordinate too
    (straight-through), so a weighting never finds a flat, zero-gradient stretch there.
    """
    plain = family.from_unit_box(problem, u)
    floor = jnp.minimum(face_width_need(problem, plain), problem.upper.face_width_mm)
    raw = plain.face_width_mm
    height = raw - jax.lax.stop_gradient(floor)
    width = jnp.where(height > 0, raw, floor + height - jax.lax.stop_gradient(height))
    return plain._replace(face_width_mm=width)


def problem_at(problem: Problem, segment: int, theta_deg: jax.Array) -> Problem:
    """The problem at cam angles ``theta_deg`` (deg) of one segment of its model, its grid fields
    taken from the closed forms (:func:`camjax.evaluate.model_at`; needs ``problem.model``)."""
    from camjax.evaluate import model_at

    p = model_at(problem.model, segment, theta_deg)
    coefficient = jnp.zeros_like(p.kin.s) if p.stress_coefficient is None else p.stress_coefficient
    return problem._replace(theta_deg=theta_deg, s_mm=p.kin.s, ds_mm=p.kin.ds, d2s_mm=p.kin.d2s,
                            stress_coefficient=coefficient)


def exact_constraints(problem: Problem) -> tuple[str, ...]:
    """The constraints :func:`polish` keeps at every angle (static): pressure angle, undercut,
    face travel, and the stress with a contact model."""
    has_stress = problem.model is not None and problem.model.cam_width_mm is not None
    return ("pressure_angle", "undercut", "face_travel", *(("stress",) if has_stress else ()))


def polish(problem: Problem, weights: Weights, design: Design, free: tuple[str, ...] | None = None) -> Design:
    """The solver's design moved, where it is short, the least distance that keeps the pressure
    angle, the undercut, the contact on the face and the stress within their limits at every
    angle, not only at the samples (:func:`camjax.followers._polish.polish_design`: each
    constraint's max over every segment refined off the grid, minimum-norm Newton steps of the
    free variables onto the short ones). Without a model (grid extrema) the design is returned
    unchanged. ``free``: the fields that may move (default all free in the box). Traceable."""
    if problem.model is None:
        return design
    from camjax.followers._polish import polish_design

    return polish_design(problem, design, constraints, exact_constraints(problem),
                         program=problem.model.program, at=lambda j, t: problem_at(problem, j, t), free=free)


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, peak stress, pressure angle and face travel (and their angles), violations and
    feasibility."""
    x = _terms(problem, design)
    phi = jnp.abs(jnp.arctan2(x.u, x.w))
    return judged_on_face(Evaluation, Violation, problem, design, objective(problem, weights, design),
                          stress(problem, design), phi, x.kappa, _travel(x, design),
                          jnp.deg2rad(problem.max_pressure_angle_deg))


def judged_on_face(evaluation_type, violation_type, problem, design, objective, sigma, phi, kappa, travel,
                   limit_rad, **violations):
    """The ``Evaluation`` of a curved face (translating or oscillating) from its per-angle curves
    (n,): the stress ``sigma`` (MPa), ``phi`` the |pressure angle| (rad), the pitch curvature
    ``kappa`` (1/mm) and ``travel`` the contact's distance from the face's axis (mm); the circle's
    worst contact (:func:`camjax.family.worst_contact`, the cam radius that of the crown's pitch
    curve), the largest travel and its angle, the ``face_travel`` violation against W / 2 and the
    family's own ``violations``; size R_b + W."""
    margin = roller_geo.roller_undercut_margin(kappa, design.face_radius_mm, 0.0)
    figures, circle = family.worst_contact(problem, design, sigma, phi, margin, limit_rad)
    k = jnp.argmax(travel)
    off_face = positive_part(travel[k] - 0.5 * design.face_width_mm)
    return family.judged(
        evaluation_type, violation_type, problem, objective=objective,
        size_mm=design.base_radius_mm + design.face_width_mm,
        figures=dict(**figures, face_travel_max_mm=travel[k], face_travel_max_deg=problem.theta_deg[k]),
        violations=dict(**violations, **circle, face_travel=off_face))


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest R_b
    (SPEC 5's rule; R_c and e are that angle's) with the largest W over the angles (the flat
    face's rule for L). Judged on the whole grid, its violations, if any, are reported. Extras:
    the critical angle (``base_radius_deg``) and the grid."""
    design, extras = family.condense_at_largest(problem, per_angle_design, per_angle_design.base_radius_mm,
                                                "base_radius_deg")
    return design._replace(face_width_mm=jnp.max(per_angle_design.face_width_mm)), extras


def polish_pointwise(problem: Problem, weights: Weights, design: Design, extras: dict) -> tuple[Design, dict]:
    """The condensed pointwise design with R_b and W, the variables condensed by the largest-value
    rules, moved where a limit is passed between the samples (:func:`polish` with R_c and e held)."""
    return polish(problem, weights, design, free=("base_radius_mm", "face_width_mm")), extras


# ------------------------------------------------------------------------------- output

def solution_json(problem: Problem, solution) -> dict:
    """The curved-face keys of result.json's design block, for one :class:`camjax.solvers.base.Solution`."""
    d = solution.design
    return family.solution_keys(problem, solution, VARIABLES, size_mm=d.base_radius_mm + d.face_width_mm,
                                prime_radius_mm=d.base_radius_mm + d.face_radius_mm,
                                figures=face_figures(solution.evaluation, problem.max_pressure_angle_deg),
                                pointwise_angles=("base_radius_deg",))


def face_figures(evaluation, max_pressure_angle_deg) -> dict:
    """result.json's figures of a curved face (either curved-face family's ``Evaluation``): the
    roller's (:func:`camjax.followers.roller.problem.roller_figures`) and the contact's largest
    travel off the face's axis (mm) and its angle (deg)."""
    ev = evaluation
    return {**roller.roller_figures(ev, max_pressure_angle_deg),
            "face_travel_max_mm": ev.face_travel_max_mm, "face_travel_max_deg": ev.face_travel_max_deg}


def record(solution) -> dict:
    """The keys of a pareto.json row of a curved face (translating or oscillating): the design, its
    prime radius R_b + R_c, the size R_b + W and the peak stress."""
    d = solution.design
    return family.record_json(solution, d.base_radius_mm + d.face_width_mm,
                              prime_radius_mm=d.base_radius_mm + d.face_radius_mm)
