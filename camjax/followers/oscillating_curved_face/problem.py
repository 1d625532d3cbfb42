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

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import family
from camjax.contact import roller_stress
from camjax.family import Weights

# re-exported: this family's protocol functions, written once for every family
from camjax.family import bounds as bounds
from camjax.family import bounds_violation as bounds_violation
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers import _swing
from camjax.followers._swing import per_angle as per_angle
from camjax.followers._swing import polish_design
from camjax.followers.curved_face.problem import face_figures, judged_on_face, width_need
from camjax.followers.curved_face.problem import record as record  # as the translating face's
from camjax.followers.curved_face.problem import size_term as size_term  # the translating twin's size
from camjax.followers.oscillating_curved_face import geometry as curved_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.oscillating_roller import problem as rocker
from camjax.followers.oscillating_roller.problem import axial_coefficient, cos_phi
from camjax.followers.roller import geometry as roller_geo
from camjax.numerics import RHO_FLOOR_MM, floor_positive, positive_part

CONSTRAINT_NAMES = ("reach", "pressure_angle", "undercut", "face_travel", "stress", "bounds")
VARIABLES = ("base_radius_mm", "face_radius_mm", "face_width_mm", "pivot_distance_mm", "arm_length_mm")
# angles of the interior point's exchange rounds (camjax.solvers.exchange.exchange_angles): 32, its
# fastest 100-weighting sweep since its pressure angle's row is smooth (smooth_constraints): 0.19-0.26 s
# against 0.31-0.43 s at 24 (its slowest weighting 43 Newton steps, not 56), 0.26-0.28 s at 40 or 48,
# 0.30 s at the default 16 (49 steps at the median, not 34.5: more rounds)
EXCHANGE_ANGLES = 32


class Design(NamedTuple):
    """One oscillating curved-face design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b, mm
    face_radius_mm: jax.Array  # R_c, mm: the crown's radius
    face_width_mm: jax.Array  # W, mm: the face's chord, symmetric about its axis
    pivot_distance_mm: jax.Array  # d, mm
    arm_length_mm: jax.Array  # l, mm: pivot to the centre of the face's circle


# the oscillating roller's Problem without a positive drive: the grid, limits, program and moment
# model; here the box is the curved face's Design and the size norm N = R_b,max + W_max
Problem = family.twin_type(
    "Problem", rocker.Problem,
    "Design-independent data of one oscillating curved-face design problem on n samples.", __name__,
    drop=("closure",))


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


# the oscillating roller's Evaluation (size_mm: R_b + W) and the contact's largest travel off the
# face's axis, max_theta R_c |sin phi| (mm), and where it occurs (deg)
Evaluation = family.twin_type(
    "Evaluation", rocker.Evaluation, "A design judged on the whole grid (true maxima; shape () each).",
    __name__, add=("face_travel_max_mm", "face_travel_max_deg"), before="violation")


# ------------------------------------------------------------------------------ building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None) -> Problem:
    """Problem of an oscillating curved-face scene with a [design] section (Python: reads the scene)."""
    what = "an oscillating curved-face follower"
    arrays, as_ = family.design_arrays(scene, "oscillating_curved_face", what, arrays,
                                       samples=samples, dtype=dtype)
    d = scene.design
    lower, upper = family.design_box(d, Design, as_)
    return Problem(
        **_swing.scene_fields(scene, arrays, as_), lower=lower, upper=upper,
        size_norm_mm=as_(d.bounds("base_radius_mm")[1] + d.bounds("face_width_mm")[1]),
        tan_max_pressure_angle=as_(np.tan(np.radians(scene.follower.max_pressure_angle_deg))),
    )


# ---------------------------------------------------------------------------- physics


# The oscillating roller's circle terms at R_f = R_c give the same values, but a gradient through
# them adds its terms in another order (the solved design would move by ~1e-9 mm): the face keeps
# its own, in the order its results were established with.
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
    arm = rocker_roller_geo.arm_trig_of(rp, d, l, problem.s_rad)
    q = 1.0 + problem.rotation_sign * problem.ds
    kappa = rocker_roller_geo.arm_pitch_curvature(d, l, arm, q, problem.d2s)
    return _Terms(curved_geo.arm_legs(d, l, arm, q), kappa,
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
    (batched designs: over the last axis; :func:`camjax.followers.curved_face.problem.width_need`)."""
    return width_need(lambda p, d: _travel(_terms(p, d), d), problem, design)


def stress(problem: Problem, design: Design) -> jax.Array:
    """Hertz contact stress sigma(theta) (MPa), shape (n,); finite (saturated) at an undercut."""
    x = _terms(problem, design)
    phi = jnp.arctan2(x.legs.along, x.legs.across)
    return roller_stress(axial_coefficient(problem, design), phi, x.rho_eq)


def _stress_squared(problem: Problem, design: Design) -> jax.Array:
    """sigma^2 (MPa^2) per angle as C^2 / (cos phi rho_eq), rho_eq floored: finite at an undercut."""
    x = _terms(problem, design)
    coefficient = axial_coefficient(problem, design)
    return coefficient**2 / (cos_phi(x.legs) * floor_positive(x.rho_eq, RHO_FLOOR_MM))


peak_stress, angle_stress = family.stress_pair(_stress_squared)


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha (R_b + W) / N + gamma max_theta sigma / sigma_max (dimensionless, shape ())."""
    return family.sized_objective(size_term, peak_stress, problem, weights, design)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design."""
    return _constraints(problem, design, smooth=False)


def smooth_constraints(problem: Problem, design: Design) -> Constraints:
    """:func:`constraints` as the interior point takes them: the pressure angle's row without the
    kink of its |lean| (:func:`camjax.family.excess`; the same sign, and the same value and
    gradient where the row is 0)."""
    return _constraints(problem, design, smooth=True)


def _constraints(problem: Problem, design: Design, smooth: bool) -> Constraints:
    x = _terms(problem, design)
    reach_r = design.face_radius_mm + problem.min_curvature_radius_mm
    need = axial_coefficient(problem, design) ** 2 / (problem.sigma_max_MPa**2 * cos_phi(x.legs))
    return Constraints(
        reach=jnp.broadcast_to(x.reach, x.kappa.shape),
        pressure_angle=family.excess(x.legs.along, problem.tan_max_pressure_angle * x.legs.across, smooth),
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
    return judged_on_face(Evaluation, Violation, problem, design, objective(problem, weights, design),
                          stress(problem, design), jnp.abs(jnp.arctan2(x.legs.along, x.legs.across)), x.kappa,
                          _travel(x, design), jnp.arctan(problem.tan_max_pressure_angle),
                          reach=positive_part(x.reach))


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest
    R_b + R_c (the oscillating roller's rule), with the largest W over the angles (the curved
    face's). Judged on the whole grid, its violations, if any, are reported."""
    size = per_angle_design.base_radius_mm + per_angle_design.face_radius_mm
    design, extras = family.condense_at_largest(problem, per_angle_design, size, "prime_radius_deg")
    return design._replace(face_width_mm=jnp.max(per_angle_design.face_width_mm)), extras


# ------------------------------------------------------------------------------- output

def solution_json(problem: Problem, solution) -> dict:
    """The oscillating curved-face keys of result.json's design block, for one Solution."""
    d, limit_deg = solution.design, np.degrees(np.arctan(problem.tan_max_pressure_angle))
    return family.solution_keys(problem, solution, VARIABLES, size_mm=d.base_radius_mm + d.face_width_mm,
                                prime_radius_mm=d.base_radius_mm + d.face_radius_mm,
                                figures=face_figures(solution.evaluation, limit_deg),
                                pointwise_angles=("prime_radius_deg",))
