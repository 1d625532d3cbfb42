"""Oscillating (rocker) flat-face follower (SPEC section 3): one design, any grid.

Layout and kinematic inversion: :mod:`camjax.followers._swing`. The face is a line at distance f
(``face_offset_mm``) from the pivot, parallel to the arm direction u and on the cam's side of it:
{X : m . X = p}, m(psi) = (sin psi, cos psi) its unit normal pointing away from the cam,
p(psi) = d sin psi - f its distance from O. The base radius is R_b = p(psi0),
sin psi0 = (R_b + f) / d; a rise lifts the face while psi < pi/2 (p grows), so psi0 + s must stay
in (0, pi/2).

Closed forms (:func:`oscillating_flat_radius_of_curvature`), c = cos psi, sn = sin psi,
Q = 1 + sigma s': the cam outline is the envelope of the face lines, radius of curvature
rho = d sn (1 - s'^2/Q^2) - f + d c s''/Q^3; the contact point lies on the face at xi = d c / Q
from the foot of the pivot (towards the cam centre), and the follower's pressure angle is
tan phi = f / xi.

All lengths mm, angles rad; elementwise over the angle grid and jit/vmap/grad-safe, with
finite values and gradients for infeasible trial designs (capped or floored divisions).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.followers import _pitch as pitch
from camjax.followers._pitch import DEFAULT_ROTATION
from camjax.followers._swing import arm_angle, first_admissible, relative_rate
from camjax.numerics import capped_divide
from camjax.program import Kinematics

# Default smallest admissible radius of curvature of an oscillating flat-face cam (mm), as for
# the translating flat face (camjax.followers.flat.geometry.FLAT_MIN_CURVATURE_RADIUS_MM).
OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM = 1e-3


def face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm) -> jax.Array:
    """psi0 (rad) of a flat face tangent to the base circle: sin psi0 = (R_b + f) / d, psi0 < pi/2."""
    r = (base_radius_mm + face_offset_mm) / pivot_distance_mm
    return jnp.arcsin(jnp.clip(r, -1.0 + 1e-15, 1.0 - 1e-15))


# --------------------------------------------------------------------------- flat face


class OscillatingFlatGeometry(NamedTuple):
    """Oscillating flat-face follower, per sample (shape (N,) each)."""

    arm_angle: jax.Array  # psi, rad
    radius_of_curvature: jax.Array  # rho of the cam outline, mm (must stay > 0)
    contact_distance: jax.Array  # xi, mm along the face from the foot of the pivot (> 0: cam side)
    pressure_angle: jax.Array  # rad, atan(f / xi)


def oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin: Kinematics,
                                      rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """xi = d cos psi / Q (mm): the contact point's distance along the face from the pivot's foot.

    Derivation: with alpha the polar angle of the face normal m in the cam frame,
    alpha = pi/2 - psi - sigma theta, so dalpha/dtheta = -sigma Q. The envelope of the lines
    m(alpha) . X = p touches each line at X = p m + (dp/dalpha) J m, J m = u, and
    dp/dalpha = (d c s') / (-sigma Q). The foot of the pivot on the face, A - f m, sits at
    coordinate A . u = -d c along u, so the contact point lies at dp/dalpha + d c
    = d c (1 - sigma s'/Q) = d c / Q from it (Q - sigma s' = 1), positive towards the cam centre.
    """
    psi = arm_angle(psi0, kin)
    q = relative_rate(kin, rotation)
    return capped_divide(pivot_distance_mm * jnp.cos(psi), q)


def oscillating_flat_radius_of_curvature(pivot_distance_mm, face_offset_mm, psi0, kin: Kinematics,
                                         rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """rho = d sn (1 - s'^2/Q^2) - f + d c s''/Q^3 (mm), the cam outline's radius of curvature.

    Derivation: the envelope of lines with support function p(alpha) has radius p + d^2p/dalpha^2.
    With p = d sn - f, dp/dalpha = -sigma d c s'/Q (see :func:`oscillating_flat_contact_distance`)
    and d/dalpha = (-sigma / Q) d/dtheta: d^2p/dalpha^2 = (1/Q) d/dtheta (d c s'/Q)
    = d [Q (c s'' - sn s'^2) - sigma c s' s''] / Q^3 = d (c s'' - sn s'^2 Q) / Q^3,
    using Q - sigma s' = 1. A dwell gives rho = p, the base circle.
    """
    return swing_face_radius_of_curvature(pivot_distance_mm, face_offset_mm, arm_angle(psi0, kin),
                                          relative_rate(kin, rotation), kin.ds, kin.d2s)


def swing_face_radius_of_curvature(pivot_distance_mm, face_offset_mm, psi, rate, ds, d2s) -> jax.Array:
    """The closed form of :func:`oscillating_flat_radius_of_curvature` in the arm angle psi (rad),
    Q = 1 + sigma s', s' and s'': for callers that hold sigma as data."""
    d, f = pivot_distance_mm, face_offset_mm
    c, sn = jnp.cos(psi), jnp.sin(psi)
    inv_q = capped_divide(jnp.ones_like(rate), rate)
    return d * sn * (1.0 - (ds * inv_q) ** 2) - f + d * c * d2s * inv_q**3


def oscillating_flat_geometry(pivot_distance_mm, face_offset_mm, base_radius_mm, kin: Kinematics,
                              rotation: str = DEFAULT_ROTATION) -> OscillatingFlatGeometry:
    """Arm angle, radius of curvature, contact distance and pressure angle per sample.

    The pressure angle is the angle between the face normal m and the path of the follower point
    in contact, perpendicular to A -> contact = -f m + xi u: cos phi = |xi| / sqrt(f^2 + xi^2),
    tan phi = f / xi (0 for a face through the pivot).
    """
    psi0 = face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm)
    xi = oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin, rotation)
    rho = oscillating_flat_radius_of_curvature(pivot_distance_mm, face_offset_mm, psi0, kin, rotation)
    return OscillatingFlatGeometry(arm_angle(psi0, kin), rho, xi, jnp.arctan2(face_offset_mm, xi))


def oscillating_flat_contact_point(pivot_distance_mm, face_offset_mm, psi0, kin: Kinematics,
                                   rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Contact point A - f m + xi u in the follower frame (mm), u = (-c, sn), m = (sn, c)."""
    psi = arm_angle(psi0, kin)
    c, sn = jnp.cos(psi), jnp.sin(psi)
    xi = oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin, rotation)
    return pivot_distance_mm - face_offset_mm * sn - xi * c, -face_offset_mm * c + xi * sn


def oscillating_flat_profile(pivot_distance_mm, face_offset_mm, base_radius_mm, kin: Kinematics,
                             rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y), mm, cam coordinates: the contact point seen from the cam."""
    psi0 = face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm)
    x, y = oscillating_flat_contact_point(pivot_distance_mm, face_offset_mm, psi0, kin, rotation)
    return pitch.to_cam_frame(x, y, kin.theta, rotation)


def oscillating_flat_face_extent(pivot_distance_mm, face_offset_mm, base_radius_mm, kin: Kinematics,
                                 rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """(min xi, max xi) (mm): the stretch of the face, from the pivot's foot, the contact sweeps.

    The face length needed is max xi - min xi (a face reaching from min xi to max xi).
    """
    psi0 = face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm)
    xi = oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin, rotation)
    return jnp.min(xi), jnp.max(xi)


class OscillatingFlatSizing(NamedTuple):
    """Smallest admissible base circle of an oscillating flat-face follower with d and f given."""

    base_radius_mm: jax.Array  # R_b, mm
    arm_start_angle: jax.Array  # psi0, rad
    found: jax.Array  # bool
    index: jax.Array  # int: the sample where rho is smallest at that radius
    face_min_mm: jax.Array  # min xi, mm from the pivot's foot
    face_max_mm: jax.Array  # max xi, mm
    face_length_mm: jax.Array  # max xi - min xi


def oscillating_flat_min_base_radius(kin: Kinematics, pivot_distance_mm, face_offset_mm,
                                     min_curvature_radius_mm=OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM,
                                     rotation: str = DEFAULT_ROTATION) -> OscillatingFlatSizing:
    """Smallest R_b (mm) with rho >= rho_min and R_b > 0, and the face the contact needs there.

    R_b = d sin psi0 - f grows with psi0 on (0, pi/2); the search runs over psi0 in
    (0, pi/2 - max s) (the face keeps rising), by :func:`first_admissible`.
    """
    d, f = pivot_distance_mm, face_offset_mm

    def bad_one(psi0):
        rho = oscillating_flat_radius_of_curvature(d, f, psi0, kin, rotation)
        return (jnp.min(rho) < min_curvature_radius_mm) | (d * jnp.sin(psi0) - f <= 0.0)

    psi_hi = 0.5 * math.pi - jnp.max(kin.s)
    psi0, found = first_admissible(bad_one, jnp.zeros_like(psi_hi), psi_hi, kin.s.shape[-1])
    rb = d * jnp.sin(psi0) - f
    rho = oscillating_flat_radius_of_curvature(d, f, psi0, kin, rotation)
    xi = oscillating_flat_contact_distance(d, psi0, kin, rotation)
    lo, hi = jnp.min(xi), jnp.max(xi)
    return OscillatingFlatSizing(rb, psi0, found, jnp.argmin(rho), lo, hi, hi - lo)


def sizing_limits(kin: Kinematics, psi0, params) -> jax.Array:
    """The sizing's limit at arm start angle psi0 (rad), <= 0 where admissible (shape
    (1, *kin.s.shape)): rho_min - rho. ``params``: (d, f, sigma, rho_min), arrays (the exact
    sizing, :func:`camjax.followers._sizing.exact_boundary`)."""
    d, f, sigma, rho_min = params
    rho = swing_face_radius_of_curvature(d, f, psi0 + kin.s, 1.0 + sigma * kin.ds, kin.ds, kin.d2s)
    return (rho_min - rho)[None]

