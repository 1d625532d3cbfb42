"""The roller follower's optimal-design problem: a problem family of :mod:`camjax.solvers.base`.

Design variables (:class:`Design`, mm): base radius R_b, roller radius R_f and offset e of a
translating roller follower; each is free between its bounds or fixed (lower == upper).

Objective, weights alpha (size) and gamma (stress), N = R_b,max + R_f,max:

    F = alpha (R_b + R_f) / N + gamma max_theta sigma(theta) / sigma_max,

with the roller's Hertz stress sigma = C sqrt(1 / (cos phi rho_eq)) (:func:`camjax.contact.roller_stress`:
C from the axial follower force, rho_eq = 1 / (1/rho_c + 1/R_f)). Without [contact] C = 0: no
stress term and no stress constraint. Constraints, one value per angle, ``g <= 0`` in mm
(:class:`Constraints`):

- pressure_angle: |s' - e~| - tan(phi_max) (d + s) <= 0, which is |phi| <= phi_max written
  without the arctan (d = sqrt(R_p^2 - e^2), e~ = e for ccw, -e for cw; finite everywhere);
- undercut: (R_f + rho_min) (kappa_pitch (R_f + rho_min) - 1) <= 0, i.e. rho_c >= rho_min where
  the pitch curve is convex (:func:`camjax.followers.roller.geometry.roller_undercut_constraint` times a length;
  concave parts satisfy it for every roller, as they must);
- stress: C^2 / (sigma_max^2 cos phi) - rho_eq <= 0, which is sigma <= sigma_max written on the
  equivalent radius so that it stays finite at and beyond an undercut (rho_eq <= 0 there);
- and the box bounds, which the solvers keep by projection. The scene checks that the bounds
  keep |e| < R_p (the follower axis cuts the prime circle) for every design in the box.

The solvers work in this family's own unit-box coordinates (:func:`to_unit`, :func:`from_unit`):
the prime radius R_b + R_f instead of R_b, floored at the closed-form smallest prime radius that
meets the pressure-angle limit at the design's offset, so that the optimum's flat valley
(R_b + R_f = const) and its curved valley along the pressure-angle limit lie along the axes.

Everything that does not depend on the design (s, s', s'', C) is computed once per scene by
:func:`problem_from_scene`. Modes are those of :mod:`camjax.followers.flat.problem`: :func:`per_angle` gives the
n one-angle problems; a pointwise solve is condensed into the design of its critical angle, the
one with the largest prime radius (with R_f and e fixed: the largest R_b, SPEC 5's rule).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import family
from camjax.contact import roller_stress

# re-exported: this family's protocol functions and tolerance, written once for every family
from camjax.family import FEASIBILITY_TOL_RAD as FEASIBILITY_TOL_RAD
from camjax.family import Weights
from camjax.family import bounds as bounds
from camjax.family import bounds_violation as bounds_violation
from camjax.family import size_norm as size_norm
from camjax.family import violated_constraints as violated_constraints
from camjax.followers import _closure_problem
from camjax.followers import _pitch as pitch
from camjax.followers.roller import geometry as roller_geo
from camjax.numerics import COS_FLOOR, RHO_FLOOR_MM, floor_positive, positive_part, safe_sqrt

CONSTRAINT_NAMES = ("pressure_angle", "undercut", "stress", "bounds")
# angles of the interior point's exchange rounds (camjax.solvers.exchange.exchange_angles): the
# roller's answers bind at more angles than the default's 16 take in one round (its 100-weighting
# sweep ran 1.4x slower at 16 than at 32, the same optima)
EXCHANGE_ANGLES = 32
VARIABLES = ("base_radius_mm", "roller_radius_mm", "offset_mm")


class Design(NamedTuple):
    """One roller-follower design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b, mm
    roller_radius_mm: jax.Array  # R_f, mm
    offset_mm: jax.Array  # e, mm (follower axis at x = e in the follower frame)


class Problem(NamedTuple):
    """Design-independent data of one roller design problem on an angle grid of n samples."""

    theta_deg: jax.Array  # (n,) cam angle, degrees
    s_mm: jax.Array  # (n,) s, mm
    ds_mm: jax.Array  # (n,) s', mm/rad
    d2s_mm: jax.Array  # (n,) s'', mm/rad^2
    stress_coefficient: jax.Array  # (n,) C = 0.564 sqrt(F / (w K)), MPa mm^0.5 (0: no stress)
    lower: Design  # lower bounds, mm
    upper: Design  # upper bounds, mm
    sigma_max_MPa: jax.Array  # () allowable contact stress
    size_norm_mm: jax.Array  # () N = R_b,max + R_f,max
    tan_max_pressure_angle: jax.Array  # () tan(phi_max)
    max_pressure_angle_deg: jax.Array  # () phi_max, deg (as the scene gives it)
    min_curvature_radius_mm: jax.Array  # () smallest convex cam-surface radius allowed
    rotation_sign: jax.Array  # () +1 ccw, -1 cw (geometry.pitch): e~ = sign e
    # the scene's closed forms (camjax.evaluate.SceneModel) behind the grid when extrema are
    # exact: :func:`polish` keeps every constraint between the samples too; None: the grid's
    model: Any = None
    # a positive drive's second contact (camjax.followers._closure: GrooveTerms or YokeTerms), whose
    # constraints are rows of their own beside the first's (GrooveConstraints, YokeConstraints);
    # None: spring-closed
    closure: Any = None


class Constraints(NamedTuple):
    """Constraint functions g <= 0, mm, one value per angle (shape (n,) each)."""

    pressure_angle: jax.Array  # |s' - e~| - tan(phi_max) (d + s)
    undercut: jax.Array  # (R_f + rho_min) (kappa (R_f + rho_min) - 1)
    stress: jax.Array  # C^2 / (sigma_max^2 cos phi) - rho_eq


# a positive drive's constraints (camjax.followers._closure_problem.with_second_contact): the first contact's
# rows, the pressure angle as two, then the second contact's
GrooveConstraints = _closure_problem.positive_type("GrooveConstraints", Constraints, _closure_problem.GrooveTerms, __name__)
YokeConstraints = _closure_problem.positive_type("YokeConstraints", Constraints, _closure_problem.YokeTerms, __name__)
POSITIVE_CONSTRAINTS = {_closure_problem.GrooveTerms: GrooveConstraints, _closure_problem.YokeTerms: YokeConstraints}


class Violation(NamedTuple):
    """Worst violation of each constraint in physical units, 0 when satisfied (shape ())."""

    pressure_angle: jax.Array  # rad: max |phi| - phi_max
    undercut: jax.Array  # mm: rho_min - min rho_c over the convex parts
    stress: jax.Array  # MPa: max sigma - sigma_max
    bounds: jax.Array  # mm: largest distance outside the box


class Evaluation(NamedTuple):
    """A design judged on the whole grid (true maxima; shape () each)."""

    objective: jax.Array  # F
    size_mm: jax.Array  # R_b + R_f, the prime-circle radius
    stress_max_MPa: jax.Array  # max_theta sigma
    stress_max_deg: jax.Array  # where it occurs
    pressure_angle_max_deg: jax.Array  # max_theta |phi|
    pressure_angle_max_at_deg: jax.Array  # where it occurs
    cam_rho_min_mm: jax.Array  # smallest convex cam-surface radius rho_c (undercut at <= 0)
    violation: Violation
    feasible: jax.Array  # bool


# ------------------------------------------------------------------------------ building


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None,
                       extrema: str | None = None) -> Problem:
    """Problem of a roller scene with a [design] section (Python, not traceable: it reads the scene).

    Args:
      scene: a :class:`camjax.scene.Scene` with a roller follower and [design].
      arrays: its :class:`camjax.evaluate.SceneArrays` if already computed (else computed here).
      samples: grid size override (ignored when ``arrays`` is given).
      dtype: floating dtype of the arrays (default float64).
      extrema: "exact" or "grid" (ignored when ``arrays`` is given: theirs applies); default the
        scene's ``[motion] extrema``. Exact: the solvers' designs are polished so that every
        constraint holds between the samples too (:func:`polish`).
    """
    arrays, as_ = family.design_arrays(scene, "roller", "a roller follower", arrays,
                                       samples=samples, dtype=dtype, extrema=extrema)
    d, kin = scene.design, arrays.kin
    lower, upper = family.design_box(d, Design, as_)
    return Problem(
        **circle_scene_fields(scene, arrays, as_), lower=lower, upper=upper,
        size_norm_mm=as_(d.bounds("base_radius_mm")[1] + d.bounds("roller_radius_mm")[1]),
        closure=_closure_problem.design_terms(scene, arrays, _second_coefficient(scene.contact, arrays.force_N, kin.s)),
    )


def circle_scene_fields(scene, arrays, as_) -> dict:
    """The Problem fields of a translating circle on the cam (the roller, the curved face's crown)
    that come from the scene alone: the grid (theta, s, s', s'', the Hertz coefficient C, zeros
    without [contact]), the limits (sigma_max, tan phi_max, phi_max, rho_min), the rotation's sign
    and the model behind the grid; ``as_`` casts to the problem's dtype (Python: reads the scene)."""
    d, f, kin = scene.design, scene.follower, arrays.kin
    coeff = arrays.stress_coefficient
    return dict(
        theta_deg=as_(arrays.theta_deg), s_mm=kin.s, ds_mm=kin.ds, d2s_mm=kin.d2s,
        stress_coefficient=jnp.zeros_like(kin.s) if coeff is None else as_(coeff),
        sigma_max_MPa=as_(d.sigma_max_MPa if d.sigma_max_MPa is not None else 1.0),
        tan_max_pressure_angle=as_(np.tan(np.radians(f.max_pressure_angle_deg))),
        max_pressure_angle_deg=as_(f.max_pressure_angle_deg),
        min_curvature_radius_mm=as_(f.min_curvature_radius_mm),
        rotation_sign=as_(pitch.rotation_sign(scene.motion.rotation)),
        model=arrays.model,
    )


def _second_coefficient(contact, force_N, like) -> jax.Array:
    """Hertz coefficient of the load a positive drive's second contact carries, max(-F, 0)."""
    if contact is None or force_N is None:
        return jnp.zeros_like(like)
    return _closure_problem.reversed_coefficient(force_N, contact.cam_width_mm, contact.cam, contact.follower)


def per_angle(problem: Problem) -> Problem:
    """The n pointwise problems: every grid leaf (n,) -> (n, 1), every scalar leaf -> (n,); one
    angle's problem has no model (its sample is all there is)."""
    return family.per_angle(problem._replace(model=None),
                            {"theta_deg", "s_mm", "ds_mm", "d2s_mm", "stress_coefficient"})


# ---------------------------------------------------------------------------- physics


class _Kin(NamedTuple):  # the geometry functions' view of the problem's grid (theta unused there)
    theta: jax.Array
    s: jax.Array
    ds: jax.Array
    d2s: jax.Array


class CircleTerms(NamedTuple):
    """Per-angle quantities of a circle whose centre runs on the pitch curve (the roller, the
    curved face's crown), which every function of a design shares (shape (n,) each)."""

    w: jax.Array  # d + s, mm: the circle centre's height on the follower axis
    u: jax.Array  # s' - e~, mm: tan phi = u / w (up to the rotation's sign)
    r: jax.Array  # sqrt(w^2 + u^2), mm: the circle centre's distance from the instant centre
    inv_cos: jax.Array  # 1 / cos phi = |(w, u)| / w, with cos phi floored at COS_FLOOR
    kappa: jax.Array  # pitch-curve curvature, 1/mm (convex > 0)
    rho_eq: jax.Array  # Hertz equivalent radius 1 / (1/rho_c + 1/R_f), mm


def circle_terms(problem: Problem, design: Design) -> CircleTerms:
    """The shared per-angle terms of a design (any problem with the roller's grid fields and
    ``rotation_sign``: the curved face passes its crown radius as R_f).

    The rotation enters only through e~ = sign e (geometry.pitch); with it every formula is the
    ccw one, and |phi|, cos phi and kappa are those of the true rotation. 1 / cos phi is written
    as r / w (r = |(w, u)|) to share the root with the curvature and avoid a cos(atan2(.)).
    """
    e = problem.rotation_sign * design.offset_mm
    kin = _Kin(problem.theta_deg, problem.s_mm, problem.ds_mm, problem.d2s_mm)
    w = roller_geo.roller_pitch_height(design.base_radius_mm, design.roller_radius_mm, e, kin)
    u = kin.ds - e
    r = jnp.sqrt(w**2 + u**2)
    kappa = pitch.pitch_curvature(w, kin.ds, kin.d2s, e)
    return CircleTerms(w, u, r, r / jnp.maximum(w, COS_FLOOR * r), kappa,
                       roller_geo.roller_equivalent_radius(kappa, design.roller_radius_mm))


def pressure_angle(problem: Problem, design: Design) -> jax.Array:
    """phi (rad) per angle, signed as :func:`camjax.followers._pitch.pressure_angle`."""
    x = circle_terms(problem, design)
    return problem.rotation_sign * jnp.arctan2(x.u, x.w)


def stress(problem: Problem, design: Design) -> jax.Array:
    """Hertz contact stress sigma(theta) (MPa), shape (n,); finite (saturated) at an undercut."""
    x = circle_terms(problem, design)
    return roller_stress(problem.stress_coefficient, jnp.arctan2(x.u, x.w), x.rho_eq)


def _stress_squared(problem: Problem, design: Design) -> jax.Array:
    """sigma^2 (MPa^2) per angle as C^2 / (cos phi rho_eq), rho_eq floored: finite at an undercut."""
    x = circle_terms(problem, design)
    return problem.stress_coefficient**2 * x.inv_cos / floor_positive(x.rho_eq, RHO_FLOOR_MM)


peak_stress, angle_stress = family.stress_pair(_stress_squared)


def size_term(problem: Problem, design: Design) -> jax.Array:
    """Normalized size (R_b + R_f) / N (dimensionless)."""
    return (design.base_radius_mm + design.roller_radius_mm) / problem.size_norm_mm


def objective(problem: Problem, weights: Weights, design: Design) -> jax.Array:
    """F = alpha (R_b + R_f) / N + gamma max_theta sigma / sigma_max (dimensionless, shape ())."""
    return family.sized_objective(size_term, peak_stress, problem, weights, design)


def constraints(problem: Problem, design: Design) -> Constraints:
    """Every angle's constraints as g <= 0 (mm), shape (n,) each; finite for every design. A positive
    drive's are a :data:`GrooveConstraints` or :data:`YokeConstraints`: the second contact's rows after
    the first's."""
    return _constraints(problem, design, smooth=False)


def smooth_constraints(problem: Problem, design: Design) -> Constraints:
    """:func:`constraints` as the interior point takes them: the pressure angle's row without the
    kink of |s' - e~| where s' = e~ (:func:`camjax.family.excess`; the same sign, and the same value
    and gradient where the row is 0). A positive drive's rows have no such kink (its pressure angle
    is two rows): :func:`constraints`."""
    return _constraints(problem, design, smooth=True)


def _constraints(problem: Problem, design: Design, smooth: bool) -> Constraints:
    x = circle_terms(problem, design)
    first = circle_constraints(problem, design, x, smooth)  # a positive drive drops its pressure row
    if problem.closure is None:
        return first
    return _closure_problem.with_second_contact(first, x.u, problem.tan_max_pressure_angle * x.w,
                                        _second_contact(problem, design, x), problem.closure,
                                        POSITIVE_CONSTRAINTS)


def row_labels(problem: Problem) -> dict:
    """Each constraint row's (kind, contact) where the problem has two contacts (the certificate's
    labels, :func:`camjax.followers._closure_problem.row_labels`)."""
    return _closure_problem.row_labels(problem.closure)


def circle_constraints(problem: Problem, design: Design, x: CircleTerms, smooth: bool = False) -> Constraints:
    """The circle's own constraints as g <= 0 (mm), shape (n,) each, from its terms ``x``
    (:func:`circle_terms`): the pressure angle (``smooth``: without its kink,
    :func:`camjax.family.excess`), the undercut and the stress."""
    reach = design.roller_radius_mm + problem.min_curvature_radius_mm
    need = problem.stress_coefficient**2 * x.inv_cos / problem.sigma_max_MPa**2
    return Constraints(
        pressure_angle=family.excess(x.u, problem.tan_max_pressure_angle * x.w, smooth),
        undercut=reach * roller_geo.roller_undercut_constraint(x.kappa, design.roller_radius_mm,
                                                             problem.min_curvature_radius_mm),
        stress=need - x.rho_eq,
    )


def _second_contact(problem: Problem, design: Design, x: CircleTerms) -> _closure_problem.SecondContact:
    """The positive drive's second contact (the groove's outer flank, the yoke's second cam)."""
    t = problem.closure
    if isinstance(t, _closure_problem.GrooveTerms):
        return _closure_problem.groove_second(t, x.kappa, design.roller_radius_mm, problem.min_curvature_radius_mm,
                                      (x.u, problem.tan_max_pressure_angle * x.w), jnp.arctan2(x.u, x.w),
                                      problem.sigma_max_MPa)
    return _closure_problem.yoke_second(t, x.w, x.u, problem.ds_mm, problem.d2s_mm, problem.rotation_sign * design.offset_mm,
                                problem.min_curvature_radius_mm, problem.tan_max_pressure_angle, problem.sigma_max_MPa)


def constraint_maxima(problem: Problem, design: Design) -> Constraints:
    """max_theta of each constraint of :func:`constraints`, shape () each.

    One reduction over the stacked constraints: XLA then evaluates the shared terms once per
    angle instead of once per constraint.
    """
    return family.stacked_maxima(constraints(problem, design))


# ------------------------------------------------------------------ solver coordinates


def _straight_through(x, clipped):
    """``clipped`` in value, the gradient of ``x``: a variable pushed past a moving limit is still
    drawn back by the objective instead of sitting where a clip would give it a zero gradient."""
    return x + jax.lax.stop_gradient(clipped - x)


def _prime_box(problem: Problem) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(smallest and largest prime radius in the box, whether R_b is free)."""
    lo, hi = problem.lower, problem.upper
    return (lo.base_radius_mm + lo.roller_radius_mm, hi.base_radius_mm + hi.roller_radius_mm,
            hi.base_radius_mm > lo.base_radius_mm)


def to_unit(problem: Problem, design: Design) -> Design:
    """Design (mm) -> the solvers' unit-box coordinates (not clipped); :func:`from_unit` inverts it.

    With R_b free the first coordinate is the prime radius R_p = R_b + R_f over its range in the
    box, the second R_f over its bounds and the third e over its bounds. The size, the pressure
    angle and the pitch-curve curvature depend on R_p and e only, so trading R_f between stress
    and undercut at a fixed size (the optimum's flat valley R_b + R_f = const) moves one
    coordinate instead of the diagonal of (R_b, R_f). With R_b fixed each variable is scaled by
    its own bounds (as for every family).
    """
    p_lo, p_hi, rb_free = _prime_box(problem)
    plain = family.to_unit_box(problem, design)
    prime = family.unit_coordinate(design.base_radius_mm + design.roller_radius_mm, p_lo, p_hi)
    return plain._replace(base_radius_mm=jnp.where(rb_free, prime, plain.base_radius_mm))


def from_unit(problem: Problem, u: Design) -> Design:
    """The solvers' unit-box coordinates -> design (mm): the inverse of :func:`to_unit` on the box,
    with the prime circle floored at the pressure-angle limit.

    With R_b free, R_p from the first coordinate is raised where it is below the smallest prime
    radius that meets the pressure-angle limit at the offset e (closed form,
    :func:`min_prime_radius_for_pressure_angle`). There R_p follows e along the limit exactly: the
    curved valley where the optimum rides that limit (R_p falling as e moves towards the
    balance of rise and return) becomes a problem in e and R_f alone, and every design the
    solvers see meets the limit. Below the floor the first coordinate keeps the gradient of R_p
    (straight-through), so a weighting that wants a larger prime circle lifts it off the limit.
    R_f (second coordinate) is then clipped to the roller radii that keep R_b = R_p - R_f within
    its bounds, also straight-through. Every unit-box point maps into the box (unless the limit
    itself needs a prime circle larger than the box allows).
    """
    lo, hi = problem.lower, problem.upper
    p_lo, p_hi, rb_free = _prime_box(problem)
    plain = family.from_unit_box(problem, u)
    raw = family.from_unit_coordinate(u.base_radius_mm, p_lo, p_hi)
    floor = jnp.minimum(min_prime_radius_for_pressure_angle(problem, plain.offset_mm), p_hi)
    height = raw - jax.lax.stop_gradient(floor)  # the gradient of R_p in the first coordinate only
    prime = jnp.where(height > 0, raw, floor + _straight_through(height, jnp.zeros_like(height)))
    rf = plain.roller_radius_mm
    rf = _straight_through(rf, jnp.clip(rf, jnp.maximum(lo.roller_radius_mm, prime - hi.base_radius_mm),
                                        jnp.minimum(hi.roller_radius_mm, prime - lo.base_radius_mm)))
    return plain._replace(base_radius_mm=jnp.where(rb_free, prime - rf, plain.base_radius_mm),
                          roller_radius_mm=jnp.where(rb_free, rf, plain.roller_radius_mm))


def min_prime_radius_for_pressure_angle(problem: Problem, offset_mm: jax.Array) -> jax.Array:
    """Smallest R_p (mm) with |phi| <= the limit at every angle for offset e, in closed form.

    |s' - e~| <= tan(phi_max) (d + s) at every angle  <=>  d >= max(|s' - e~| / tan(phi_max) - s),
    and R_p = sqrt(e^2 + d^2) (as :func:`camjax.followers.roller.geometry.roller_min_prime_radius_for_pressure_angle`).
    """
    e = jnp.expand_dims(problem.rotation_sign * offset_mm, -1)  # (..., 1) against the grid (n,)
    need = roller_geo.roller_pressure_angle_need(problem.ds_mm, problem.s_mm, e, problem.tan_max_pressure_angle)
    d_min = jnp.max(need, axis=-1)
    return safe_sqrt(offset_mm**2 + positive_part(d_min) ** 2)  # 0 (finite gradient) at e = 0 = d_min


def problem_at(problem: Problem, segment: int, theta_deg: jax.Array) -> Problem:
    """The problem at cam angles ``theta_deg`` (deg) of one segment of its model, its grid fields
    taken from the closed forms (:func:`camjax.evaluate.model_at`; needs ``problem.model``)."""
    from camjax.evaluate import model_at

    p = model_at(problem.model, segment, theta_deg)
    coefficient = jnp.zeros_like(p.kin.s) if p.stress_coefficient is None else p.stress_coefficient
    closure = problem.closure
    if closure is not None:
        m = problem.model
        second = (jnp.zeros_like(p.kin.s) if m.cam_width_mm is None or p.force_N is None else
                  _closure_problem.reversed_coefficient(p.force_N, m.cam_width_mm, m.cam, m.follower))
        closure = closure._replace(second_coefficient=second)
    return problem._replace(theta_deg=theta_deg, s_mm=p.kin.s, ds_mm=p.kin.ds, d2s_mm=p.kin.d2s,
                            stress_coefficient=coefficient, closure=closure)


def exact_constraints(problem: Problem) -> tuple[str, ...]:
    """The constraints :func:`polish` keeps at every angle (static): the pressure angle and the
    undercut, and the stress with a contact model; a positive drive's second contact's too."""
    has_stress = problem.model is not None and problem.model.cam_width_mm is not None
    return _closure_problem.exact_rows(("pressure_angle", "undercut", *(("stress",) if has_stress else ())),
                               problem.closure)


def polish(problem: Problem, weights: Weights, design: Design, free: tuple[str, ...] | None = None) -> Design:
    """The solver's design moved, where it is short, the least distance that keeps the pressure
    angle, the undercut and the stress within their limits at every angle, not only at the samples.

    The solvers keep the constraints on the samples (R_p floored at the closed-form
    pressure-angle limit there, :func:`from_unit`); between two samples a constraint can pass its
    limit by ~1e-6 relative. With ``problem.model`` each constraint's max over every segment is
    refined off the grid and the free variables take minimum-norm Newton steps onto the short
    ones (:func:`camjax.followers._polish.polish_design`; the undercut is written on the
    pitch-curve curvature, finite through the inflections where the radius is infinite). The
    objective changes by the same ~1e-6. Without a model the design is returned unchanged.
    ``free``: the fields that may move (default all free in the box). Traceable and vmappable.
    """
    if problem.model is None:
        return design
    from camjax.followers._polish import polish_design

    return polish_design(problem, design, constraints, exact_constraints(problem),
                         program=problem.model.program, at=lambda j, t: problem_at(problem, j, t), free=free)


def polish_pointwise(problem: Problem, weights: Weights, design: Design, extras: dict) -> tuple[Design, dict]:
    """The condensed pointwise design with R_b, the variable condensed by the largest-R_p rule,
    raised where a constraint passes its limit between the samples (:func:`polish` with R_f and
    e held: the pointwise rule's R_b taken as the continuous max over the angles)."""
    return polish(problem, weights, design, free=("base_radius_mm",)), extras


def evaluate(problem: Problem, weights: Weights, design: Design) -> Evaluation:
    """Objective, peak stress and pressure angle (and their angles), violations and feasibility."""
    x = circle_terms(problem, design)
    return roller_evaluation((Evaluation, Violation), problem, objective(problem, weights, design), design,
                             stress(problem, design), jnp.abs(jnp.arctan2(x.u, x.w)), x.kappa,
                             lambda: _second_contact(problem, design, x),
                             jnp.deg2rad(problem.max_pressure_angle_deg))


def roller_evaluation(types, problem, objective_value, design, sigma, phi, kappa, second_contact,
                      max_pressure_angle_rad, **violations):
    """Either roller family's :class:`Evaluation` (``types``: its (Evaluation, Violation)) at its
    ``objective_value``, from its contact stress (MPa), pressure angle (rad) and pitch-curve
    curvature (1/mm) per angle: the undercut margin of the convex parts, with a positive drive the worse of both contacts
    (``second_contact()``, called only then), the worst contact and the size R_b + R_f;
    ``violations``: the family's own beside the contact's."""
    margin = roller_geo.roller_undercut_margin(kappa, design.roller_radius_mm, 0.0)  # rho_c, convex parts
    if problem.closure is not None:  # a positive drive: the second contact's limits too
        sigma, phi, margin = _closure_problem.worst_of_both(sigma, phi, margin, second_contact())
    figures, contact = family.worst_contact(problem, design, sigma, phi, margin, max_pressure_angle_rad)
    evaluation, violation = types
    return family.judged(evaluation, violation, problem, objective=objective_value,
                         size_mm=design.base_radius_mm + design.roller_radius_mm, figures=figures,
                         violations=dict(**violations, **contact))


def condense_pointwise(problem: Problem, per_angle_design: Design) -> tuple[Design, dict]:
    """The whole-cam design of a pointwise solve: the design of the angle with the largest R_b + R_f.

    With R_f and e fixed that is the largest R_b over the angles (SPEC 5's rule). With R_f or e
    free every angle picks its own; the critical angle's design is reported and judged on the
    whole grid (its violations, if any, are reported, not hidden). Extras: the critical angle
    (``prime_radius_deg``) and the grid.
    """
    size = per_angle_design.base_radius_mm + per_angle_design.roller_radius_mm
    return family.condense_at_largest(problem, per_angle_design, size, "prime_radius_deg")


# ------------------------------------------------------------------------------- output

def solution_json(problem: Problem, solution) -> dict:
    """The roller keys of result.json's design block, for one :class:`camjax.solvers.base.Solution`."""
    d = solution.design
    prime = d.base_radius_mm + d.roller_radius_mm
    return family.solution_keys(problem, solution, VARIABLES, size_mm=prime, prime_radius_mm=prime,
                                figures=roller_figures(solution.evaluation, problem.max_pressure_angle_deg),
                                pointwise_angles=("prime_radius_deg",))


def roller_figures(evaluation, max_pressure_angle_deg) -> dict:
    """result.json's figures of a roller on a cam (either roller family's :class:`Evaluation`): peak
    stress (MPa) and pressure angle (deg), their angles (deg), the limit (deg), the smallest convex
    cam radius (mm)."""
    ev = evaluation
    return {"stress_max_MPa": ev.stress_max_MPa, "stress_max_deg": ev.stress_max_deg,
            "pressure_angle_max_deg": ev.pressure_angle_max_deg,
            "pressure_angle_max_at_deg": ev.pressure_angle_max_at_deg,
            "max_pressure_angle_deg": max_pressure_angle_deg, "cam_rho_min_mm": ev.cam_rho_min_mm}


def record(solution) -> dict:
    """The keys of a pareto.json row of a roller (translating or oscillating): the design, its prime
    radius, the size R_b + R_f and the peak stress."""
    d = solution.design
    prime = d.base_radius_mm + d.roller_radius_mm
    return family.record_json(solution, prime, prime_radius_mm=prime)
