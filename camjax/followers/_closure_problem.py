"""A positive drive's design problem: the second contact's constraint rows and the sizing's.

What the translating and the rocking roller's design problems share when a groove or a conjugate
cam holds the roller (:mod:`camjax.followers._closure` holds the closure's keys, geometry and
loads):

- the closure's terms of a design problem (:class:`GrooveTerms`, :class:`YokeTerms`,
  :class:`ArmTerms`, :func:`design_terms`) and the second contact's constraints, g <= 0 per angle
  (:func:`groove_second`, :func:`yoke_second`, :func:`arm_second`), each limit of each contact its
  own row beside the first contact's (:func:`with_second_contact`, :func:`row_labels` for the
  certificate);
- the sizing's: every limit of both contacts at every sample (:func:`second_limits`,
  :func:`first_admissible_size`).

Lengths mm, angles rad; every function is elementwise over the angle grid and jit/vmap/grad-safe.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.followers._closure import (
    outer_equivalent_radius,
    outer_flank_constraint,
    outer_flank_margin,
    point_pitch,
)
from camjax.scene.spec import ClosureSpec

# ------------------------------------------------------------------------------ design


class GrooveTerms(NamedTuple):
    """A groove in a design problem (a pytree: the problem's ``closure`` field)."""

    clearance_mm: jax.Array  # ()
    second_coefficient: jax.Array  # (n,) Hertz coefficient of the outer flank's load, from max(-F, 0)


class YokeTerms(NamedTuple):
    """A translating roller's yoke in a design problem."""

    span_mm: jax.Array  # () L, between the roller centres
    roller_radius_mm: jax.Array  # () the second roller's
    second_coefficient: jax.Array  # (n,) Hertz coefficient of the second cam's load, from max(-F, 0)


class ArmTerms(NamedTuple):
    """A rocker's second arm in a design problem."""

    arm_length_mm: jax.Array  # () l2
    angle_rad: jax.Array  # () beta, from the first arm to the second
    roller_radius_mm: jax.Array  # () the second roller's
    second_coefficient: jax.Array  # (n,) moment coefficient of the second cam's load, from max(-M, 0)


def design_terms(scene, arrays, second_coefficient):
    """The closure's terms of a design problem (None: spring-closed); ``second_coefficient`` the
    (n,) Hertz coefficient of the load the second contact carries (zeros without [contact])."""
    c = scene.follower.closure
    dt = arrays.kin.s.dtype
    as_ = lambda v: jnp.asarray(v, dt)  # noqa: E731
    if c.kind == "groove":
        return GrooveTerms(as_(c.clearance_mm), second_coefficient)
    if c.kind == "conjugate" and c.yoke_span_mm is not None:
        return YokeTerms(as_(design_start(scene, "yoke_span_mm")), as_(c.second_roller_radius_mm),
                         second_coefficient)
    if c.kind == "conjugate":
        angle = math.radians(design_start(scene, "second_arm_angle_deg"))
        return ArmTerms(as_(c.second_arm_length_mm), as_(angle), as_(c.second_roller_radius_mm),
                        second_coefficient)
    return None


def design_start(scene, key: str) -> float:
    """The yoke span (mm) or second arm angle (deg) a conjugate pair's design problem is solved at: the
    [follower]'s, or the [design]'s where it sets one; where [design] frees it, the most permissive
    value (:mod:`camjax.followers._closure_design`): a yoke's largest span, a rocker's [follower]
    angle clipped into the bounds."""
    value = getattr(scene.follower.closure, key)
    if scene.design is None or key not in dict(scene.design.variables):
        return value
    low, high = scene.design.bounds(key)
    return high if key == "yoke_span_mm" else min(max(value, low), high)


@jax.jit
def reversed_coefficient(force_N, cam_width_mm, cam, follower):
    """The Hertz coefficient of max(-F, 0): the second contact's (:func:`camjax.contact.stress_coefficient`);
    one compiled call where it is evaluated on a grid outside a program."""
    from camjax import contact

    return contact.stress_coefficient(jnp.maximum(-force_N, 0.0), cam_width_mm, cam, follower)


class SecondContact(NamedTuple):
    """The second contact's constraints of a design, g <= 0 per angle (mm), each its own row beside the
    first contact's (:func:`with_second_contact`), and what a report judges of it."""

    lean: jax.Array  # mm: its pressure-angle limit is |lean| - reach <= 0 (a groove's is the first's)
    reach: jax.Array  # mm
    undercut: jax.Array  # mm: the cut limit of its curvature
    stress: jax.Array  # mm (C^2 / (sigma_max^2 cos phi) - rho_eq)
    pressure_angle_rad: jax.Array  # |phi| of the second contact (the evaluation)
    margin_mm: jax.Array  # the second contact's cut margin (mm; <= rho_min: violated)
    stress_MPa: jax.Array  # the second contact's Hertz stress
    shaft: jax.Array | None = None  # mm: R2 - |C2| (conjugate): the second roller off the shaft
    side: jax.Array | None = None  # mm: l2 sin(psi - beta) (a second arm): across the line of centres


# A positive drive's constraint rows (its own NamedTuple per family and closure, declared with
# camjax.family.twin_type from the spring-closed Constraints): no max inside a row, so that the
# constraint set is smooth where two pieces cross. The pressure angle |lean| - reach <= 0 is two
# rows, lean - reach and -lean - reach (+phi_max and -phi_max: |s' - e~| is kinked at every
# dwell sample where s' = e~, and an interior-point path that crosses e~ = 0 over such rows
# oscillated there at the iteration cap); then each limit of the second contact on its own row.
# Each row names the spring-closed row of its limit (:data:`LIMIT_ROW`: what polish keeps and what
# the second contact is judged beside, :func:`second_excess`) and the SecondContact field it is.
PRESSURE_ROWS = ("pressure_angle_plus", "pressure_angle_minus")
GROOVE_ROWS = (*PRESSURE_ROWS, "outer_undercut", "outer_stress")  # one normal: one pressure angle
YOKE_ROWS = (*PRESSURE_ROWS, "second_pressure_angle_plus", "second_pressure_angle_minus", "second_undercut",
             "second_stress", "second_shaft")
ARM_ROWS = (*YOKE_ROWS, "second_side")
LIMIT_ROW = {"pressure_angle_plus": "pressure_angle", "pressure_angle_minus": "pressure_angle",
             "outer_undercut": "undercut", "outer_stress": "stress",
             "second_pressure_angle_plus": "pressure_angle", "second_pressure_angle_minus": "pressure_angle",
             "second_undercut": "undercut", "second_stress": "stress", "second_shaft": "undercut",
             "second_side": "pressure_angle"}
_SECOND_FIELD = {"outer_undercut": "undercut", "outer_stress": "stress", "second_undercut": "undercut",
                 "second_stress": "stress", "second_shaft": "shaft", "second_side": "side"}


_ROWS = {GrooveTerms: GROOVE_ROWS, YokeTerms: YOKE_ROWS, ArmTerms: ARM_ROWS}


def row_names(terms) -> tuple[str, ...]:
    """The rows a positive drive with closure ``terms`` adds to the spring-closed constraints, in
    place of their pressure angle (static)."""
    return _ROWS[type(terms)]


def with_second_contact(first, lean, reach, second: SecondContact, terms, types: dict):
    """A positive drive's constraints (g <= 0, mm, (n,) each), as ``types[type(terms)]`` (the family's
    NamedTuple, declared with :func:`positive_type`): the first contact's rows ``first`` (the
    family's spring-closed Constraints) less its pressure angle |lean| - reach, which is two rows
    (``lean`` and ``reach`` in mm), then the second contact's rows (:func:`row_names`)."""
    rows = {"pressure_angle_plus": lean - reach, "pressure_angle_minus": -lean - reach,
            "second_pressure_angle_plus": second.lean - second.reach,
            "second_pressure_angle_minus": -second.lean - second.reach}
    own = {name: rows[name] if name in rows else getattr(second, _SECOND_FIELD[name])
           for name in row_names(terms)}
    kept = {name: value for name, value in first._asdict().items() if name != "pressure_angle"}
    return types[type(terms)](**kept, **own)


def positive_type(name: str, constraints, terms_type, module: str):
    """A family's NamedTuple of a positive drive's constraints (:func:`with_second_contact`): its
    spring-closed ``constraints`` type without the pressure angle, then the rows of closure
    ``terms_type`` (:func:`camjax.family.twin_type`; ``module``: the declaring module's name)."""
    from camjax.family import twin_type

    return twin_type(name, constraints, f"{name}: g <= 0 (mm, (n,) each), the first contact's rows, the "
                     "pressure angle as two rows (+ and - the limit), then the second contact's.", module,
                     drop=("pressure_angle",), add=_ROWS[terms_type])


def second_excess(constraints, first) -> jax.Array:
    """Each second-contact row of a positive drive's ``constraints`` less what the spring-closed rows
    ``first`` of the same design allow there, max(that limit's row, 0) (mm, shape (rows, n)): <= 0
    where the second contact keeps every limit the first keeps, and is over by no more where the
    first is over."""
    names = [f for f in constraints._fields if f in LIMIT_ROW and f not in PRESSURE_ROWS]
    return jnp.stack([getattr(constraints, f) - jnp.maximum(getattr(first, LIMIT_ROW[f]), 0.0)
                      for f in names])


def exact_rows(names: tuple[str, ...], terms) -> tuple[str, ...]:
    """The rows a polish keeps at every angle (static): the spring-closed rows ``names`` and, with
    closure ``terms``, the rows of a positive drive of those limits (:data:`LIMIT_ROW`)."""
    if terms is None:
        return names
    kept = (f for f in names if f != "pressure_angle")
    return (*kept, *(f for f in row_names(terms) if LIMIT_ROW[f] in names))


_CONTACTS = {"groove": ("inner flank", "outer flank"), "conjugate": ("first cam", "second cam")}
_KINDS = {"second_shaft": "shaft_clearance", "second_side": "arm_side"}


def row_labels(terms) -> dict[str, tuple[str, str]]:
    """Row name -> (kind, contact) of a positive drive's constraint rows with closure ``terms`` (the
    certificate's labels): the kind of its limit (pressure_angle, undercut, stress, shaft_clearance,
    arm_side) and the contact ("inner flank", "outer flank", "inner and outer flanks": a groove's pressure
    angle; "first cam", "second cam"); {} for a spring-closed problem (``terms`` None)."""
    if terms is None:
        return {}
    groove = type(terms) is GrooveTerms
    first, second = _CONTACTS["groove" if groove else "conjugate"]
    labels = {"undercut": ("undercut", first), "stress": ("stress", first)}
    for name in row_names(terms):
        contact = ("inner and outer flanks" if groove else first) if name in PRESSURE_ROWS else second
        labels[name] = (_KINDS.get(name, LIMIT_ROW[name]), contact)
    return labels


def _second(sigma_max_MPa, coefficient, pressure, phi, undercut_g, margin, rho_eq,
            **clearances) -> SecondContact:
    """A second contact's constraints from its pressure-angle terms (lean, reach: |lean| - reach <= 0,
    mm), pressure angle (rad), cut constraint and margin (mm), Hertz equivalent radius (mm) and the
    coefficient of its load; ``clearances``: its ``shaft`` and ``side`` rows (mm) where it has them."""
    from camjax.contact import roller_stress
    from camjax.numerics import COS_FLOOR

    cos_phi = jnp.maximum(jnp.cos(phi), COS_FLOOR)
    need = coefficient**2 / (sigma_max_MPa**2 * cos_phi)
    return SecondContact(*pressure, undercut_g, need - rho_eq, jnp.abs(phi), margin,
                         roller_stress(coefficient, phi, rho_eq), **clearances)


def worst_of_both(sigma, phi, margin, second: SecondContact):
    """Per angle, the worse of the first contact's stress, |pressure angle| and undercut margin and the
    second contact's (:class:`SecondContact`): what a positive drive's report judges."""
    return (jnp.maximum(sigma, second.stress_MPa), jnp.maximum(phi, second.pressure_angle_rad),
            jnp.minimum(margin, second.margin_mm))


def groove_second(terms: GrooveTerms, kappa, roller_radius_mm, min_curvature_radius_mm, pressure, phi,
                  sigma_max_MPa, coefficient=None) -> SecondContact:
    """The outer flank: the first's pressure angle (shared normal: ``pressure`` = its (lean, reach), mm),
    its concavity limit and its stress (``coefficient``: the Hertz coefficient of the force along the
    roller's path, default the terms')."""
    c = terms.clearance_mm
    coefficient = terms.second_coefficient if coefficient is None else coefficient
    return _second(sigma_max_MPa, coefficient, pressure, phi,
                   outer_flank_constraint(kappa, roller_radius_mm + c, min_curvature_radius_mm),
                   outer_flank_margin(kappa, roller_radius_mm + c),
                   outer_equivalent_radius(kappa, roller_radius_mm, c))


def yoke_second(terms: YokeTerms, w, u, ds, d2s, signed_offset_mm, min_curvature_radius_mm, tan_limit,
                sigma_max_MPa) -> SecondContact:
    """The yoke's second cam (ccw formulas, e~ = sign e): its roller at depth D = L - w below the
    centre on the axis, tan phi2 = |s' - e~| / D; curvature of the pitch curve of (e~, w - L); the
    roller must stay off the shaft (D > R2: the ``shaft`` row). ``w``, ``u``: the first roller's
    height and s' - e~ (mm)."""
    from camjax.followers import _pitch as pitch
    from camjax.followers.roller.geometry import roller_undercut_margin

    r2, depth = terms.roller_radius_mm, terms.span_mm - w
    reach = r2 + min_curvature_radius_mm
    kappa2 = pitch.pitch_curvature(w - terms.span_mm, ds, d2s, signed_offset_mm)
    phi2 = jnp.arctan2(jnp.abs(u), depth)
    return _second(sigma_max_MPa, terms.second_coefficient, (u, tan_limit * depth), phi2,
                   reach * (kappa2 * reach - 1.0),
                   jnp.minimum(roller_undercut_margin(kappa2, r2), depth - r2),
                   r2 * (1.0 - r2 * kappa2), shaft=r2 - depth)


def arm_second(terms: ArmTerms, pivot_distance_mm, psi, ds, d2s, sign, min_curvature_radius_mm, tan_limit,
               sigma_max_MPa) -> SecondContact:
    """A rocker's second cam: its roller at C2 = (d - l2 cos(psi - beta), l2 sin(psi - beta)) driven
    along -dC2/dpsi (:func:`point_pitch`, :func:`path_pressure_angle`); the arm must stay across the
    line of centres (sin(psi - beta) < 0: the ``side`` row l2 sin(psi - beta)) and its roller off the
    shaft (|C2| > R2: the ``shaft`` row)."""
    from camjax.followers.roller.geometry import roller_undercut_margin

    l2, r2 = terms.arm_length_mm, terms.roller_radius_mm
    a = psi - terms.angle_rad
    c, sn = jnp.cos(a), jnp.sin(a)
    x, y = pivot_distance_mm - l2 * c, l2 * sn
    dcx, dcy, ddx, ddy = l2 * sn, l2 * c, l2 * c, -l2 * sn
    pp = point_pitch(x, y, ds * dcx, ds * dcy, d2s * dcx + ds**2 * ddx, d2s * dcy + ds**2 * ddy, sign)
    along = pp.normal_x * dcx + pp.normal_y * dcy  # -(n . m), m = -dC2/dpsi; |m| = l2
    across = -(pp.normal_x * dcy - pp.normal_y * dcx)
    phi2 = jnp.arctan2(across, along)
    reach = r2 + min_curvature_radius_mm
    coefficient = terms.second_coefficient * jax.lax.rsqrt(l2 * 1e-3)  # of the force -M / l2 on its path
    return _second(sigma_max_MPa, coefficient, (across, tan_limit * along), phi2,
                   reach * (pp.curvature * reach - 1.0),
                   jnp.minimum(roller_undercut_margin(pp.curvature, r2), jnp.hypot(x, y) - r2),
                   r2 * (1.0 - r2 * pp.curvature), shaft=r2 - jnp.hypot(x, y), side=y)


# ------------------------------------------------------------------------------ sizing


def second_limits(closure: ClosureSpec, kin, *, prime_radius_mm=None, signed_offset_mm=0.0, psi0=None,
                  pivot_distance_mm=None, arm_length_mm=None, sign=1.0, roller_radius_mm, min_curvature_radius_mm,
                  tan_limit):
    """The second contact's limits at one cam size, g <= 0 where admissible (shape (k, n): pressure
    angle, cut, and a conjugate cam's shaft clearance and a second arm's side), from the design
    problems' closed forms: a translating roller at prime radius
    ``prime_radius_mm`` (``signed_offset_mm``: sign e), a rocker at arm start angle ``psi0``."""
    from camjax.followers import _pitch as pitch

    zero = jnp.zeros_like(kin.s)
    if closure.kind == "groove":
        if psi0 is None:
            w = pitch.pitch_height(prime_radius_mm, signed_offset_mm, kin.s)
            kappa = pitch.pitch_curvature(w, kin.ds, kin.d2s, signed_offset_mm)
        else:
            from camjax.followers.oscillating_roller.geometry import swing_pitch_curvature

            kappa = swing_pitch_curvature(pivot_distance_mm, arm_length_mm, psi0 + kin.s, 1.0 + sign * kin.ds,
                                          kin.d2s)
        return jnp.stack([zero - 1.0, outer_flank_constraint(kappa, roller_radius_mm + closure.clearance_mm,
                                                             min_curvature_radius_mm)])
    if psi0 is None:
        terms = YokeTerms(closure.yoke_span_mm, closure.second_roller_radius_mm, zero)
        w = pitch.pitch_height(prime_radius_mm, signed_offset_mm, kin.s)
        second = yoke_second(terms, w, kin.ds - signed_offset_mm, kin.ds, kin.d2s, signed_offset_mm,
                             min_curvature_radius_mm, tan_limit, 1.0)
    else:
        terms = ArmTerms(closure.second_arm_length_mm, closure.second_arm_angle_deg * (math.pi / 180.0),
                         closure.second_roller_radius_mm, zero)
        second = arm_second(terms, pivot_distance_mm, psi0 + kin.s, kin.ds, kin.d2s, sign, min_curvature_radius_mm,
                            tan_limit, 1.0)
    pressure = jnp.abs(second.lean) - second.reach
    return jnp.stack([v for v in (pressure, second.undercut, second.shaft, second.side) if v is not None])


def first_admissible_size(bad, x0, hi, samples: int):
    """The smallest size x >= x0 (a prime radius, an arm start angle) where ``bad(x)`` is False:
    x0 itself where it is admissible, else the first admissible point of (x0, hi) by a scan and a
    bisection (:func:`camjax.followers._swing.first_admissible`). Returns (x, found)."""
    from camjax.followers._swing import first_admissible

    x, found = first_admissible(bad, x0, hi, samples)
    ok0 = ~bad(x0)
    return jnp.where(ok0, x0, x), ok0 | found
