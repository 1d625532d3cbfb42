"""The oscillating roller follower's optimal-design problem: a problem family of :mod:`camjax.solvers.base`.

Design variables (:class:`Design`, mm): base radius R_b, roller radius R_f, pivot distance d and
arm length l of a rocker with a roller (:mod:`camjax.followers.oscillating_roller.geometry`); each is free between
its bounds or fixed (lower == upper). The prime radius is R_p = R_b + R_f and the arm starts at
psi0 with cos psi0 = (d^2 + l^2 - R_p^2) / (2 d l).

Objective, weights alpha (size) and gamma (stress), N = R_b,max + R_f,max:

    F = alpha (R_b + R_f) / N + gamma max_theta sigma(theta) / sigma_max,

with sigma the Hertz stress of the roller, P = M / (l cos phi) (M the torque about the pivot,
:func:`camjax.loads.rocker_torque`): sigma = C_M sqrt(1 / (l cos phi rho_eq)) with
C_M = 0.564 sqrt(M / (w K)) computed once per scene (l in m inside). Constraints, one value per
angle, ``g <= 0`` in mm (:class:`Constraints`):

- reach: max(|d - l| - R_p, R_p - (d + l)) (the roller reaches the prime circle), the same at
  every angle;
- pressure_angle: |l Q - d cos psi| - tan(phi_max) d sin psi <= 0, which is |phi| <= phi_max
  without the arctan (Q = 1 + sigma s');
- undercut: (R_f + rho_min) (kappa_pitch (R_f + rho_min) - 1) <= 0 (as the translating roller);
- stress: C_M^2 / (sigma_max^2 l cos phi) - rho_eq <= 0, sigma <= sigma_max on the equivalent
  radius (finite at and beyond an undercut);
- and the box bounds, which the solvers keep by projection.

Modes: :func:`per_angle` gives the n one-angle problems; a pointwise solve is condensed into the
design of the angle with the largest R_b + R_f.
"""

from __future__ import annotations

from typing import Any, NamedTuple

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
from camjax.followers import _closure_problem, _swing
from camjax.followers._swing import moment_coefficient as moment_coefficient
from camjax.followers._swing import per_angle as per_angle
from camjax.followers._swing import polish_design
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller.problem import record as record  # as the translating roller's
from camjax.followers.roller.problem import roller_evaluation, roller_figures
from camjax.followers.roller.problem import (
    row_labels as row_labels,  # a positive drive's, as the translating roller's
)
from camjax.followers.roller.problem import size_term as size_term  # the translating twin's size
from camjax.numerics import COS_FLOOR, RHO_FLOOR_MM, floor_positive, positive_part, safe_sqrt

CONSTRAINT_NAMES = ("reach", "pressure_angle", "undercut", "stress", "bounds")
VARIABLES = ("base_radius_mm", "roller_radius_mm", "pivot_distance_mm", "arm_length_mm")
# angles of the interior point's exchange rounds (camjax.solvers.exchange.exchange_angles): as the
# translating roller's, 32 (its 100-weighting sweep ran 1.1x slower at 16, the same optima)
EXCHANGE_ANGLES = 32


class Design(NamedTuple):
    """One oscillating-roller design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b, mm
    roller_radius_mm: jax.Array  # R_f, mm
    pivot_distance_mm: jax.Array  # d, mm
    arm_length_mm: jax.Array  # l, mm


class Problem(NamedTuple):
    """Design-independent data of one oscillating-roller design problem on an angle grid of n samples."""

    theta_deg: jax.Array  # (n,) cam angle, degrees
    s_rad: jax.Array  # (n,) arm swing s, rad
    ds: jax.Array  # (n,) s', rad/rad
    d2s: jax.Array  # (n,) s'', rad/rad^2
    moment_coefficient: jax.Array  # (n,) C_M = 0.564 sqrt(M / (w K)), MPa mm^0.5 m^0.5 (0: no stress)
    lower: Design  # lower bounds, mm
    upper: Design  # upper bounds, mm
    sigma_max_MPa: jax.Array  # () allowable contact stress
    size_norm_mm: jax.Array  # () N = R_b,max + R_f,max
    tan_max_pressure_angle: jax.Array  # () tan(phi_max)
    min_curvature_radius_mm: jax.Array  # () smallest convex cam-surface radius allowed
    rotation_sign: jax.Array  # () +1 ccw, -1 cw
    # the motion program (as arrays) behind the grid when extrema are exact: :func:`polish`
    program: Any = None
    moment_model: Any = None  # camjax.followers._swing.MomentModel: C_M between the samples (the polish)
    # a positive drive's second contact (camjax.followers._closure: GrooveTerms or ArmTerms), whose
    # constraints are rows of their own beside the first's (GrooveConstraints, ArmConstraints);
    # None: spring-closed
    closure: Any = None


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    reach: jax.Array  # max(|d - l| - R_p, R_p - (d + l))
    pressure_angle: jax.Array  # |l Q - d c| - tan(phi_max) d sn
    undercut: jax.Array  # (R_f + rho_min) (kappa (R_f + rho_min) - 1)
    stress: jax.Array  # C_M^2 / (sigma_max^2 l cos phi) - rho_eq


# a positive drive's constraints (camjax.followers._closure_problem.with_second_contact): the first contact's
# rows, the pressure angle as two, then the second contact's
GrooveConstraints = _closure_problem.positive_type("GrooveConstraints", Constraints, _closure_problem.GrooveTerms, __name__)
ArmConstraints = _closure_problem.positive_type("ArmConstraints", Constraints, _closure_problem.ArmTerms, __name__)
POSITIVE_CONSTRAINTS = {_closure_problem.GrooveTerms: GrooveConstraints, _closure_problem.ArmTerms: ArmConstraints}


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    reach: jax.Array  # mm
    pressure_angle: jax.Array  # rad: max |phi| - phi_max
    undercut: jax.Array  # mm: rho_min - min rho_c over the convex parts
    stress: jax.Array  # MPa: max sigma - sigma_max
    bounds: jax.Array  # mm


class Evaluation(NamedTuple):
    """A design judged on the whole grid (true maxima; shape () each)."""

    objective: jax.Array
    size_mm: jax.Array  # R_b + R_f, the prime radius
    stress_max_MPa: jax.Array
    stress_max_deg: jax.Array
    pressure_angle_max_deg: jax.Array
    pressure_angle_max_at_deg: jax.Array
    cam_rho_min_mm: jax.Array  # smallest convex cam-surface radius
    violation: Violation
    feasible: jax.Array  # bool


# ------------------------------------------------------------------------------ building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None) -> Problem:
    """Problem of an oscillating-roller scene with a [design] section (Python: reads the scene)."""
    arrays, as_ = family.design_arrays(scene, "oscillating_roller", "an oscillating roller", arrays,
                                       samples=samples, dtype=dtype)
    d = scene.design
    lower, upper = family.design_box(d, Design, as_)
    return Problem(
        **_swing.scene_fields(scene, arrays, as_), lower=lower, upper=upper,
        size_norm_mm=as_(d.bounds("base_radius_mm")[1] + d.bounds("roller_radius_mm")[1]),
        tan_max_pressure_angle=as_(np.tan(np.radians(scene.follower.max_pressure_angle_deg))),
        closure=_closure_problem.design_terms(scene, arrays, _second_moment_coefficient(scene, arrays)),
    )


def _second_moment_coefficient(scene, arrays) -> jax.Array:
    """C_M of the pivot torque a positive drive's second contact carries, max(-M, 0) (as
    :func:`moment_coefficient`, zeros without loads or [contact])."""
    from camjax import loads
    from camjax.contact import HERTZ_FACTOR, compliance

    f, c, kin = scene.follower, scene.contact, arrays.kin
    if f.train is None or c is None:
        return jnp.zeros_like(kin.s)

    @jax.jit  # one compiled call, not operation by operation
    def reversed_coefficient(train, kin, speed, cam_width_mm, cam, follower):
        moment = loads.rocker_torque(train, kin, speed)
        return HERTZ_FACTOR * safe_sqrt(jnp.maximum(-moment, 0.0) / (cam_width_mm * compliance(cam, follower)))

    return reversed_coefficient(f.train, kin, arrays.cam_speed_rad_s, c.cam_width_mm, c.cam, c.follower)


# ---------------------------------------------------------------------------- physics


class _Geometry(NamedTuple):
    along: jax.Array  # l Q - d cos psi (mm): sin phi |T|
    across: jax.Array  # d sin psi (mm): cos phi |T|
    kappa: jax.Array  # pitch curvature, 1/mm
    reach: jax.Array  # () closure, mm


def _geometry(problem: Problem, design: Design) -> _Geometry:
    """Pressure-angle legs, pitch curvature and closure of a design (formulas of geometry.oscillating).

    The rotation enters through Q = 1 + sigma s' only; sigma is data here (a rotation string
    is static in camjax.geometry), so the closed forms are called with Q; cos psi and sin psi come
    from psi0's by angle addition (:func:`camjax.followers._swing.arm_trig`).
    """
    d, l = design.pivot_distance_mm, design.arm_length_mm
    rp = design.base_radius_mm + design.roller_radius_mm
    arm = rocker_roller_geo.arm_trig_of(rp, d, l, problem.s_rad)
    q = 1.0 + problem.rotation_sign * problem.ds
    kappa = rocker_roller_geo.arm_pitch_curvature(d, l, arm, q, problem.d2s)
    reach = rocker_roller_geo.oscillating_roller_reach_constraint(rp, d, l)
    return _Geometry(l * q - d * arm.c, d * arm.sn, kappa, reach)


def cos_phi(g) -> jax.Array:
    """cos phi of the pressure-angle legs ``g`` (``along``, ``across``, mm), floored at COS_FLOOR (both
    oscillating families)."""
    norm = floor_positive(g.along**2 + g.across**2, RHO_FLOOR_MM**2)
    return floor_positive(g.across * jax.lax.rsqrt(norm), COS_FLOOR)


def pressure_angle(problem: Problem, design: Design) -> jax.Array:
    """phi (rad) per angle, as :func:`camjax.followers.oscillating_roller.geometry.oscillating_roller_pressure_angle`."""
    g = _geometry(problem, design)
    return jnp.arctan2(g.along, g.across)


def axial_coefficient(problem: Problem, design: Design) -> jax.Array:
    """C = C_M / sqrt(l in m): the coefficient of the force along the path of the roller's (or the
    curved face's) centre, M / l."""
    return problem.moment_coefficient * jax.lax.rsqrt(design.arm_length_mm * 1e-3)


def stress(problem: Problem, design: Design) -> jax.Array:
    """Hertz contact stress sigma(theta) (MPa), shape (n,); finite (saturated) at an undercut."""
    g = _geometry(problem, design)
    rho_eq = roller_geo.roller_equivalent_radius(g.kappa, design.roller_radius_mm)
    return roller_stress(axial_coefficient(problem, design), jnp.arctan2(g.along, g.across), rho_eq)


def _stress_squared(problem: Problem, design: Design) -> jax.Array:
    """sigma^2 (MPa^2) per angle as C^2 / (cos phi rho_eq), rho_eq floored: finite at an undercut."""
    g = _geometry(problem, design)
    rho_eq = roller_geo.roller_equivalent_radius(g.kappa, design.roller_radius_mm)
    return axial_coefficient(problem, design) ** 2 / (cos_phi(g) * floor_positive(rho_eq, RHO_FLOOR_MM))


peak_stress, angle_stress = family.stress_pair(_stress_squared)


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha (R_b + R_f) / N + gamma max_theta sigma / sigma_max (dimensionless, shape ())."""
    return family.sized_objective(size_term, peak_stress, problem, weights, design)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design."""
    return _constraints(problem, design, smooth=False)


def smooth_constraints(problem: Problem, design: Design) -> Constraints:
    """:func:`constraints` as the interior point takes them: the pressure angle's row without the
    kink of its |lean| (:func:`camjax.family.excess`; the same sign, and the same value and
    gradient where the row is 0). A positive drive's pressure angle is two rows already."""
    return _constraints(problem, design, smooth=True)


def _constraints(problem: Problem, design: Design, smooth: bool) -> Constraints:
    g = _geometry(problem, design)
    reach_r = design.roller_radius_mm + problem.min_curvature_radius_mm
    rho_eq = roller_geo.roller_equivalent_radius(g.kappa, design.roller_radius_mm)
    need = axial_coefficient(problem, design) ** 2 / (problem.sigma_max_MPa**2 * cos_phi(g))
    first = Constraints(
        reach=jnp.broadcast_to(g.reach, g.kappa.shape),
        pressure_angle=family.excess(g.along, problem.tan_max_pressure_angle * g.across, smooth),
        undercut=reach_r * roller_geo.roller_undercut_constraint(g.kappa, design.roller_radius_mm,
                                                               problem.min_curvature_radius_mm),
        stress=need - rho_eq,
    )
    if problem.closure is None:
        return first
    return _closure_problem.with_second_contact(first, g.along, problem.tan_max_pressure_angle * g.across,
                                        _second_contact(problem, design, g), problem.closure,
                                        POSITIVE_CONSTRAINTS)


def _second_contact(problem: Problem, design: Design, g: _Geometry) -> _closure_problem.SecondContact:
    """The positive drive's second contact (the groove's outer flank, the second arm's cam)."""
    t = problem.closure
    if isinstance(t, _closure_problem.GrooveTerms):
        coefficient = t.second_coefficient * jax.lax.rsqrt(design.arm_length_mm * 1e-3)
        return _closure_problem.groove_second(t, g.kappa, design.roller_radius_mm, problem.min_curvature_radius_mm,
                                      (g.along, problem.tan_max_pressure_angle * g.across),
                                      jnp.arctan2(g.along, g.across), problem.sigma_max_MPa, coefficient)
    rp = design.base_radius_mm + design.roller_radius_mm
    psi = rocker_roller_geo.arm_start_angle(rp, design.pivot_distance_mm, design.arm_length_mm) + problem.s_rad
    return _closure_problem.arm_second(t, design.pivot_distance_mm, psi, problem.ds, problem.d2s, problem.rotation_sign,
                               problem.min_curvature_radius_mm, problem.tan_max_pressure_angle, problem.sigma_max_MPa)


def polish(problem: Problem, weights: Weights, design: Design) -> Design:
    """The solver's design moved, where it is short, the least that keeps the pressure angle, the undercut and the stress at every
    cam angle, not only at the samples (:func:`camjax.followers._swing.polish_design`; needs
    ``problem.program``, i.e. exact extrema)."""
    return polish_design(problem, design, constraints,
                         _closure_problem.exact_rows(("pressure_angle", "undercut", "stress"), problem.closure))


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint of :func:`constraints`, shape () each."""
    return jax.tree.map(jnp.max, constraints(problem, design))


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, peak stress and pressure angle (and their angles), violations and feasibility."""
    g = _geometry(problem, design)
    return roller_evaluation((Evaluation, Violation), problem, objective(problem, weights, design), design,
                             stress(problem, design),
                             jnp.abs(jnp.arctan2(g.along, g.across)), g.kappa,
                             lambda: _second_contact(problem, design, g), jnp.arctan(problem.tan_max_pressure_angle),
                             reach=positive_part(g.reach))


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest R_b + R_f."""
    size = per_angle_design.base_radius_mm + per_angle_design.roller_radius_mm
    return family.condense_at_largest(problem, per_angle_design, size, "prime_radius_deg")


# ------------------------------------------------------------------------------- output

def solution_json(problem: Problem, solution) -> dict:
    """The oscillating-roller keys of result.json's design block, for one Solution."""
    limit_deg = np.degrees(np.arctan(problem.tan_max_pressure_angle))
    prime = solution.design.base_radius_mm + solution.design.roller_radius_mm
    return family.solution_keys(problem, solution, VARIABLES, size_mm=prime, prime_radius_mm=prime,
                                figures=roller_figures(solution.evaluation, limit_deg),
                                pointwise_angles=("prime_radius_deg",))
