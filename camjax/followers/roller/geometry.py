"""Translating roller follower with offset (SPEC section 3): one design (R_b, R_f, e), any grid.

Prime-circle radius R_p = R_b + R_f; the roller centre (the pitch point) sits at (e, w) in the
follower frame, w = sqrt(R_p^2 - e^2) + s. The cam surface is the pitch curve moved inward by
R_f; its signed radius of curvature is rho_c = rho_pitch - R_f (convex > 0). Where the pitch
curve is convex the roller undercuts the cam unless rho_c >= the smallest radius allowed
(``min_curvature_radius_mm``, default 0); where it is concave the cam surface has radius
|rho_pitch| + R_f > R_f and cannot undercut.

All lengths in mm, angles in rad; every function is elementwise over the angle grid and
jit/vmap/grad-safe in R_b, R_f and e, for infeasible trial designs too (|e| >= R_p, undercut).
Frames and rotation: :mod:`camjax.followers._pitch`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.followers import _pitch as pitch
from camjax.followers._pitch import DEFAULT_ROTATION, rotation_sign
from camjax.program import Kinematics

# Defaults of the scene keys follower.max_pressure_angle_deg and min_curvature_radius_mm.
ROLLER_MAX_PRESSURE_ANGLE_DEG = 30.0  # rule of thumb (SPEC 3)
ROLLER_MIN_CURVATURE_RADIUS_MM = 0.0  # = no undercut


class RollerGeometry(NamedTuple):
    """Translating roller follower, per sample (shape (N,) each)."""

    pressure_angle: jax.Array  # rad
    pitch_curvature: jax.Array  # 1/mm, signed: > 0 convex, < 0 concave, 0 at an inflection
    pitch_radius_of_curvature: jax.Array  # mm, 1 / pitch_curvature (saturated at inflections)
    cam_radius_of_curvature: jax.Array  # rho_c = rho_pitch - R_f, mm (convex > 0)
    undercut_margin: jax.Array  # mm, rho_c - min radius where convex, float max where concave


def roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics) -> jax.Array:
    """w = sqrt(R_p^2 - e^2) + s (mm), the roller centre's height on the follower axis."""
    return pitch.pitch_height(base_radius_mm + roller_radius_mm, offset_mm, kin.s)


def roller_pressure_angle(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics,
                          rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """phi (rad): ccw atan((s' - e) / (s + sqrt(R_p^2 - e^2))) (SPEC 3); see :func:`pitch.pressure_angle`."""
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    return pitch.pressure_angle(w, kin.ds, offset_mm, rotation)


def roller_pitch_curvature(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics,
                           rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Signed curvature of the pitch curve (1/mm, convex > 0).

    For e = 0 its inverse is SPEC 3's [(R_p+s)^2 + s'^2]^(3/2) / [(R_p+s)^2 + 2s'^2 - s''(R_p+s)].
    """
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    return pitch.pitch_curvature(w, kin.ds, kin.d2s, offset_mm, rotation)


def roller_undercut_constraint(pitch_curvature, roller_radius_mm, min_curvature_radius_mm=0.0) -> jax.Array:
    """g = kappa_pitch (R_f + rho_min) - 1 (dimensionless); g <= 0 means no undercut.

    Where the pitch curve is convex (kappa > 0) this is rho_pitch >= R_f + rho_min, i.e.
    rho_c = rho_pitch - R_f >= rho_min; where it is concave (kappa <= 0) it holds for every
    roller, as it must. Written on the curvature so that it is finite and smooth through the
    inflections where rho_pitch is infinite: the form solvers use.
    """
    return pitch_curvature * (roller_radius_mm + min_curvature_radius_mm) - 1.0


def roller_undercut_margin(pitch_curvature, roller_radius_mm, min_curvature_radius_mm=0.0) -> jax.Array:
    """rho_c - rho_min (mm) where the pitch curve is convex; the largest float where concave.

    <= 0 means undercut. Concave parts cannot undercut: they get a margin no minimum picks.
    """
    cap = jnp.finfo(jnp.result_type(pitch_curvature, float)).max
    rho = pitch.radius_of_curvature(pitch_curvature)
    return jnp.where(pitch_curvature > 0, rho - roller_radius_mm - min_curvature_radius_mm, cap)


def roller_equivalent_radius(pitch_curvature, roller_radius_mm) -> jax.Array:
    """1 / (1/rho_c + 1/R_f) = R_f (1 - R_f kappa_pitch) (mm), the Hertz equivalent radius.

    From 1/(rho_p - R_f) + 1/R_f = rho_p / (R_f (rho_p - R_f)) = 1 / (R_f (1 - R_f kappa_p)).
    Positive on concave parts (> R_f) and on convex parts without undercut; R_f at an
    inflection (a flat cam surface); 0 at the undercut limit and negative beyond it. Finite for
    every design, unlike 1/rho_c.
    """
    return roller_radius_mm * (1.0 - roller_radius_mm * pitch_curvature)


def roller_contact_stress(coefficient, pitch_curvature, pressure_angle_rad,
                          roller_radius_mm) -> jax.Array | None:
    """Hertz stress (MPa) of a circle of radius R_f (a roller, a curved face's crown) on the cam
    per angle: :func:`camjax.contact.roller_stress` of the axial-force coefficient C on the
    :func:`roller_equivalent_radius`; None where there is no coefficient (no [contact])."""
    from camjax.contact import roller_stress

    if coefficient is None:
        return None
    rho_eq = roller_equivalent_radius(pitch_curvature, roller_radius_mm)
    return roller_stress(coefficient, pressure_angle_rad, rho_eq)


def roller_geometry(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics,
                    rotation: str = DEFAULT_ROTATION,
                    min_curvature_radius_mm=ROLLER_MIN_CURVATURE_RADIUS_MM) -> RollerGeometry:
    """Pressure angle, pitch-curve and cam-surface curvature and undercut margin at every sample.

    Pressure angle phi = atan((s' - e)/(s + d)), d = sqrt(R_p^2 - e^2) (ccw). Pitch-curve radius
    of curvature (general offset; SPEC 3's formula for e = 0):
    rho = [w^2 + (s'-e)^2]^(3/2) / [w^2 + (s'-e)(2s'-e) - w s''],  w = d + s.
    """
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    phi = pitch.pressure_angle(w, kin.ds, offset_mm, rotation)
    kappa = pitch.pitch_curvature(w, kin.ds, kin.d2s, offset_mm, rotation)
    rho = pitch.radius_of_curvature(kappa)
    # rho_c where rho_pitch is saturated stays saturated (a flat stretch), not cap - R_f
    rho_c = jnp.where(jnp.abs(rho) < jnp.finfo(rho.dtype).max, rho - roller_radius_mm, rho)
    margin = roller_undercut_margin(kappa, roller_radius_mm, min_curvature_radius_mm)
    return RollerGeometry(phi, kappa, rho, rho_c, margin)


def roller_pitch_curve(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics,
                       rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Pitch curve (X, Y) in cam coordinates, mm: the roller centre (e, w) seen from the cam."""
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    return pitch.to_cam_frame(offset_mm, w, kin.theta, rotation)


def roller_profile(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics,
                   rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y), mm: the pitch curve moved inward (towards the cam centre) by R_f."""
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    nx, ny = pitch.inward_normal(w, kin.ds, offset_mm, rotation)
    return pitch.to_cam_frame(offset_mm + roller_radius_mm * nx, w + roller_radius_mm * ny,
                              kin.theta, rotation)


def roller_reach_constraint(base_radius_mm, roller_radius_mm, offset_mm) -> jax.Array:
    """g = |e| - R_p (mm); the follower axis must cut the prime circle, g < 0."""
    return jnp.abs(offset_mm) - (base_radius_mm + roller_radius_mm)


def roller_pressure_angle_need(ds, s, signed_offset_mm, tan_max_pressure_angle) -> jax.Array:
    """The d = sqrt(R_p^2 - e^2) (mm) at which |phi| reaches its limit at each angle:
    |s' - e~| / tan(phi_max) - s, elementwise (e~ = the offset times the rotation sign,
    :func:`camjax.followers._pitch.rotation_sign`). Its max over the angle is the smallest d."""
    return jnp.abs(ds - signed_offset_mm) / tan_max_pressure_angle - s


def roller_min_prime_radius_for_pressure_angle(kin: Kinematics, offset_mm, max_pressure_angle_rad,
                                               rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Smallest R_p (mm) with |phi| <= the limit at every sample, in closed form.

    |phi| <= lim  <=>  |sign s' - e| <= tan(lim) (d + s)  <=>  d >= |s' - sign e| / tan(lim) - s
    (for d + s > 0), so d_min = max(0, max_theta(|s' - sign e| / tan lim - s)) and
    R_p = sqrt(e^2 + d_min^2). Exact on the grid (no bisection); the pressure angle does not
    depend on R_f for a given R_p.
    """
    e = rotation_sign(rotation) * offset_mm
    d_min = jnp.max(roller_pressure_angle_need(kin.ds, kin.s, e, jnp.tan(max_pressure_angle_rad)))
    return jnp.sqrt(offset_mm**2 + jnp.maximum(d_min, 0.0) ** 2)


def roller_min_prime_radius_for_undercut(kin: Kinematics, roller_radius_mm, offset_mm,
                                         min_curvature_radius_mm=ROLLER_MIN_CURVATURE_RADIUS_MM,
                                         rotation: str = DEFAULT_ROTATION, lower_mm=0.0,
                                         bisections: int = 200) -> jax.Array:
    """Smallest R_p >= ``lower_mm`` (mm) with no undercut at any sample, by bisection.

    No undercut is max_theta kappa_pitch(R_p) (R_f + rho_min) <= 1; growing the prime circle
    flattens the convex parts of the pitch curve, so the admissible R_p form an interval
    [R_min, inf) (the result is a bracket end on the admissible side). The bracket's upper end
    doubles until admissible (``lax.while_loop``), then ``bisections`` halvings (200: to the last
    bit in float64). jit/vmap-safe; not reverse-differentiable (a while loop), nor meant to be.
    """
    e = rotation_sign(rotation) * offset_mm
    reach = roller_radius_mm + min_curvature_radius_mm

    def bad(rp):
        w = pitch.pitch_height(rp, e, kin.s)
        return jnp.max(pitch.pitch_curvature(w, kin.ds, kin.d2s, e)) * reach > 1.0

    lo = jnp.maximum(jnp.asarray(lower_mm, kin.s.dtype), jnp.abs(e))
    hi0 = jnp.maximum(2.0 * lo, reach + jnp.abs(e) + 1.0)
    lo, hi = jax.lax.while_loop(lambda b: bad(b[1]), lambda b: (b[1], 2.0 * b[1]), (lo, hi0))

    def halve(_, bracket):
        a, b = bracket
        m = 0.5 * (a + b)
        return jnp.where(bad(m), m, a), jnp.where(bad(m), b, m)

    lo, hi = jax.lax.fori_loop(0, bisections, halve, (lo, hi))
    lower = jnp.maximum(jnp.asarray(lower_mm, kin.s.dtype), jnp.abs(e))
    return jnp.where(bad(lower), hi, lower)


class RollerSizing(NamedTuple):
    """Smallest admissible prime circle of a roller follower and the limit that sets it."""

    prime_radius_mm: jax.Array  # R_p = R_b + R_f, mm
    undercut_binds: jax.Array  # bool: the undercut limit (else the pressure angle) sets R_p
    index: jax.Array  # int: the sample where the binding limit is reached


def roller_min_prime_radius(kin: Kinematics, roller_radius_mm, offset_mm, max_pressure_angle_rad,
                            min_curvature_radius_mm=ROLLER_MIN_CURVATURE_RADIUS_MM,
                            rotation: str = DEFAULT_ROTATION) -> RollerSizing:
    """Smallest R_p (mm) with |phi| <= the limit and no undercut at every sample.

    The pressure angle gives R_p in closed form
    (:func:`roller_min_prime_radius_for_pressure_angle`); if the roller undercuts there, the
    undercut limit is found by bisection above it (:func:`roller_min_prime_radius_for_undercut`).
    The index is where |phi| peaks (pressure angle) or where the pitch curve is most convex
    (undercut) at that radius. jit/vmap-safe.
    """
    r_phi = roller_min_prime_radius_for_pressure_angle(kin, offset_mm, max_pressure_angle_rad, rotation)
    r = roller_min_prime_radius_for_undercut(kin, roller_radius_mm, offset_mm, min_curvature_radius_mm,
                                             rotation, lower_mm=r_phi)
    undercut = r > r_phi
    base = r - roller_radius_mm
    phi = roller_pressure_angle(base, roller_radius_mm, offset_mm, kin, rotation)
    kappa = roller_pitch_curvature(base, roller_radius_mm, offset_mm, kin, rotation)
    return RollerSizing(r, undercut, jnp.where(undercut, jnp.argmax(kappa), jnp.argmax(jnp.abs(phi))))


def prime_radius(base_radius_mm, roller_radius_mm) -> jax.Array:
    """R_p = R_b + R_f (mm), the prime circle catalogues and textbooks quote."""
    return base_radius_mm + roller_radius_mm


def undercut_limits(kin: Kinematics, prime_radius_mm, params) -> jax.Array:
    """The undercut limit at prime radius R_p (mm), <= 0 where admissible (shape
    (1, *kin.s.shape)): kappa_pitch (R_f + rho_min) - 1. ``params``: (sign e, R_f + rho_min),
    arrays (the exact sizing, :func:`camjax.followers._sizing.exact_boundary`)."""
    e, reach = params
    w = pitch.pitch_height(prime_radius_mm, e, kin.s)
    return (pitch.pitch_curvature(w, kin.ds, kin.d2s, e) * reach - 1.0)[None]


__all__ = [
    "ROLLER_MAX_PRESSURE_ANGLE_DEG", "ROLLER_MIN_CURVATURE_RADIUS_MM", "RollerGeometry", "RollerSizing",
    "prime_radius", "roller_equivalent_radius", "roller_geometry", "roller_min_prime_radius",
    "roller_min_prime_radius_for_pressure_angle", "roller_pitch_curvature", "roller_pitch_curve",
    "roller_pressure_angle_need",
    "roller_pitch_height", "roller_pressure_angle", "roller_profile", "roller_reach_constraint",
    "roller_undercut_constraint", "roller_undercut_margin", "undercut_limits",
]
