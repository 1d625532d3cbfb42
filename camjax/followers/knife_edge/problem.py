"""The knife-edge follower's optimal-design problem: a problem family of :mod:`camjax.solvers.base`.

Design variables (:class:`Design`, mm): base radius R_b and offset e of a translating knife edge,
each free between its bounds or fixed (lower == upper). The knife edge is the roller of
:mod:`camjax.followers.roller.problem` with R_f = 0 (SPEC 3), and this family is that problem with
the roller's radius pinned at zero: every function below hands the roller's its design with
R_f = 0, so the knife edge and the roller agree wherever the roller's radius does not enter.

Objective, weight alpha (size): F = alpha R_b / R_b,max. No stress term: the Hertz stress of a
point contact is unbounded, so a knife edge takes no [contact] (the scene refuses one) and gamma is
0 (a sweep's gamma multiplies a zero term). Constraints, one value per angle, ``g <= 0`` in mm
(:class:`Constraints`):

- pressure_angle: |s' - e~| - tan(phi_max) (s + sqrt(R_b^2 - e^2)) <= 0, which is |phi| <= phi_max;
- curvature: rho_min (kappa rho_min - 1) <= 0, i.e. the profile's convex radius 1/kappa >= rho_min
  (concave parts hold it for every design; with rho_min = 0 it holds identically: a smooth motion
  gives no cusp);
- and the box bounds, kept by projection; the scene checks |e| < R_b in the box.

The solvers' unit-box coordinates, the polish of the prime circle onto the pressure-angle limit
between the samples, and the modes are the roller's (:func:`to_unit`, :func:`from_unit`,
:func:`polish`); a pointwise solve condenses into the design of the angle with the largest R_b.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import family

# re-exported: this family's protocol functions and tolerance, written once for every family
from camjax.family import FEASIBILITY_TOL_RAD as FEASIBILITY_TOL_RAD
from camjax.family import Weights, weighted_objective
from camjax.family import bounds as bounds
from camjax.family import bounds_violation as bounds_violation
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers import _pitch as pitch
from camjax.followers.roller import problem as roller

CONSTRAINT_NAMES = ("pressure_angle", "curvature", "bounds")
VARIABLES = ("base_radius_mm", "offset_mm")


class Design(NamedTuple):
    """One knife-edge design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b (= R_p), mm
    offset_mm: jax.Array  # e, mm (follower axis at x = e in the follower frame)


# the roller's Problem without a stress coefficient and a positive drive (no stress is modelled:
# sigma_max_MPa is 1, the objective's unused stress scale); the box is the knife edge's Design, the
# size norm N = R_b,max and min_curvature_radius_mm the smallest convex profile radius allowed
Problem = family.twin_type(
    "Problem", roller.Problem,
    "Design-independent data of one knife-edge design problem on an angle grid of n samples.", __name__,
    drop=("stress_coefficient", "closure"))


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    pressure_angle: jax.Array  # |s' - e~| - tan(phi_max) (d + s)
    curvature: jax.Array  # rho_min (kappa rho_min - 1)


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    pressure_angle: jax.Array  # rad: max |phi| - phi_max
    curvature: jax.Array  # mm: rho_min - the smallest convex profile radius
    bounds: jax.Array  # mm: largest distance outside the box


class Evaluation(NamedTuple):
    """A design judged on the whole grid (true maxima; shape () each)."""

    objective: jax.Array  # F
    size_mm: jax.Array  # R_b
    pressure_angle_max_deg: jax.Array  # max_theta |phi|
    pressure_angle_max_at_deg: jax.Array  # where it occurs
    profile_rho_min_mm: jax.Array  # smallest convex radius of the profile
    violation: Violation
    feasible: jax.Array  # bool
    # a sweep's record has a stress column (the Pareto front's second objective): 0, none modelled
    stress_max_MPa: jax.Array
    stress_max_deg: jax.Array


# ------------------------------------------------------------------------------ building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None,
                       extrema: str | None = None) -> Problem:
    """Problem of a knife-edge scene with a [design] section (Python, not traceable).

    Arguments as :func:`camjax.followers.roller.problem.problem_from_scene`.
    """
    arrays, as_ = family.design_arrays(scene, "knife_edge", "a knife-edge follower", arrays,
                                       samples=samples, dtype=dtype, extrema=extrema)
    d, f, kin = scene.design, scene.follower, arrays.kin
    lower, upper = family.design_box(d, Design, as_)
    return Problem(
        theta_deg=as_(arrays.theta_deg), s_mm=kin.s, ds_mm=kin.ds, d2s_mm=kin.d2s,
        lower=lower, upper=upper,
        sigma_max_MPa=as_(1.0), size_norm_mm=as_(d.bounds("base_radius_mm")[1]),
        tan_max_pressure_angle=as_(np.tan(np.radians(f.max_pressure_angle_deg))),
        max_pressure_angle_deg=as_(f.max_pressure_angle_deg),
        min_curvature_radius_mm=as_(f.min_curvature_radius_mm),
        rotation_sign=as_(pitch.rotation_sign(scene.motion.rotation)),
        model=arrays.model,
    )


def per_angle(problem: Problem) -> Problem:
    """The n pointwise problems: every grid leaf (n,) -> (n, 1), every scalar leaf -> (n,)."""
    return family.per_angle(problem._replace(model=None), {"theta_deg", "s_mm", "ds_mm", "d2s_mm"})


# ------------------------------------------------------------------- the roller at R_f = 0


def _zero(x) -> jax.Array:
    return jnp.zeros_like(jnp.asarray(x))


def _as_roller_design(design: Design) -> roller.Design:
    return roller.Design(design.base_radius_mm, _zero(design.base_radius_mm), design.offset_mm)


def _from_roller_design(design: roller.Design) -> Design:
    return Design(design.base_radius_mm, design.offset_mm)


def _as_roller(problem: Problem) -> roller.Problem:
    """The roller's problem with R_f pinned at 0 (no stress: its coefficient is 0)."""
    return roller.Problem(
        theta_deg=problem.theta_deg, s_mm=problem.s_mm, ds_mm=problem.ds_mm, d2s_mm=problem.d2s_mm,
        stress_coefficient=jnp.zeros_like(problem.s_mm), lower=_as_roller_design(problem.lower),
        upper=_as_roller_design(problem.upper), sigma_max_MPa=problem.sigma_max_MPa,
        size_norm_mm=problem.size_norm_mm, tan_max_pressure_angle=problem.tan_max_pressure_angle,
        max_pressure_angle_deg=problem.max_pressure_angle_deg,
        min_curvature_radius_mm=problem.min_curvature_radius_mm, rotation_sign=problem.rotation_sign,
        model=problem.model)


# ---------------------------------------------------------------------------- physics


def pressure_angle(problem: Problem, design: Design) -> jax.Array:
    """phi (rad) per angle, signed as :func:`camjax.followers._pitch.pressure_angle`."""
    return roller.pressure_angle(_as_roller(problem), _as_roller_design(design))


def size_term(problem: Problem, design: Design) -> jax.Array:
    """Normalized size R_b / N (dimensionless)."""
    return design.base_radius_mm / problem.size_norm_mm


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha R_b / N (dimensionless, shape ()); gamma multiplies a zero stress term."""
    return weighted_objective(weights, size_term(problem, design), jnp.zeros_like(design.base_radius_mm),
                              problem.sigma_max_MPa)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design."""
    g = roller.constraints(_as_roller(problem), _as_roller_design(design))
    # the roller's undercut constraint at R_f = 0 is the convex-radius limit
    return Constraints(pressure_angle=g.pressure_angle, curvature=g.undercut)


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint of :func:`constraints`, shape () each."""
    return family.stacked_maxima(constraints(problem, design))


# ------------------------------------------------------------------ solver coordinates


def to_unit(problem: Problem, design: Design) -> Design:
    """Design (mm) -> the solvers' unit-box coordinates: the roller's at R_f = 0
    (:func:`camjax.followers.roller.problem.to_unit`)."""
    return _from_roller_design(roller.to_unit(_as_roller(problem), _as_roller_design(design)))


def from_unit(problem: Problem, u: Design) -> Design:
    """The inverse of :func:`to_unit`, with R_b floored at the pressure-angle limit of the offset
    (:func:`camjax.followers.roller.problem.from_unit` at R_f = 0)."""
    return _from_roller_design(roller.from_unit(_as_roller(problem), _as_roller_design(u)))


def problem_at(problem: Problem, segment: int, theta_deg: jax.Array) -> Problem:
    """The problem at cam angles ``theta_deg`` (deg) of one segment of its model (needs
    ``problem.model``; :func:`camjax.followers.roller.problem.problem_at`)."""
    from camjax.evaluate import model_at

    kin = model_at(problem.model, segment, theta_deg).kin
    return problem._replace(theta_deg=theta_deg, s_mm=kin.s, ds_mm=kin.ds, d2s_mm=kin.d2s)


def exact_constraints(problem: Problem) -> tuple[str, ...]:
    """The constraints :func:`polish` keeps at every angle (static): all of them."""
    return CONSTRAINT_NAMES[:2]


def polish(problem: Problem, weights: Weights, design: Design) -> Design:
    """R_b and e moved the least that keeps the pressure angle and the convex-radius limit at every
    angle, not only at the samples (:func:`camjax.followers.roller.problem.polish` at R_f = 0)."""
    return _from_roller_design(roller.polish(_as_roller(problem), weights, _as_roller_design(design)))


def polish_pointwise(problem: Problem, weights: Weights, design: Design, extras: dict) -> tuple[Design, dict]:
    """The condensed pointwise design with R_b raised where a limit is passed between the samples
    (:func:`camjax.followers.roller.problem.polish_pointwise` at R_f = 0)."""
    out, extras = roller.polish_pointwise(_as_roller(problem), weights, _as_roller_design(design), extras)
    return _from_roller_design(out), extras


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, largest pressure angle (and its angle), smallest convex radius, violations."""
    ev = roller.evaluate(_as_roller(problem), weights, _as_roller_design(design))
    v = Violation(pressure_angle=ev.violation.pressure_angle, curvature=ev.violation.undercut,
                  bounds=bounds_violation(problem, design))
    zero = jnp.zeros_like(ev.objective)
    return Evaluation(
        objective=objective(problem, weights, design), size_mm=design.base_radius_mm,
        pressure_angle_max_deg=ev.pressure_angle_max_deg,
        pressure_angle_max_at_deg=ev.pressure_angle_max_at_deg,
        profile_rho_min_mm=ev.cam_rho_min_mm, violation=v, feasible=family.feasible(problem, v),
        stress_max_MPa=zero, stress_max_deg=zero)


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest R_b
    (SPEC 5's rule); extras: that angle (``base_radius_deg``) and the grid."""
    return family.condense_at_largest(problem, per_angle_design, per_angle_design.base_radius_mm,
                                      "base_radius_deg")


# ------------------------------------------------------------------------------- output


def solution_json(problem: Problem, solution) -> dict:
    """The knife edge's keys of result.json's design block, for one
    :class:`camjax.solvers.base.Solution` (no ``sigma_max_MPa``: no stress is modelled)."""
    ev = solution.evaluation
    out = family.solution_keys(
        problem, solution, VARIABLES, size_mm=solution.design.base_radius_mm,
        figures={"pressure_angle_max_deg": ev.pressure_angle_max_deg,
                 "pressure_angle_max_at_deg": ev.pressure_angle_max_at_deg,
                 "max_pressure_angle_deg": problem.max_pressure_angle_deg,
                 "profile_rho_min_mm": ev.profile_rho_min_mm},
        pointwise_angles=("base_radius_deg",))
    out.pop("sigma_max_MPa")
    return out


def record(solution) -> dict:
    """The knife edge's keys of a pareto.json row: the design, size R_b and a zero peak stress."""
    return family.record_json(solution, solution.design.base_radius_mm)


__all__ = [
    "CONSTRAINT_NAMES", "VARIABLES", "Constraints", "Design", "Evaluation", "Problem", "Violation",
    "condense_pointwise", "constraint_maxima", "constraints", "evaluate", "exact_constraints", "from_unit",
    "objective", "per_angle", "polish", "polish_pointwise", "pressure_angle", "problem_at",
    "problem_from_scene", "size_norm", "size_term", "to_unit", "violated_constraints",
]
