"""Oscillating curved-face follower (SPEC 3): a crowned face of radius R_c on a swinging arm.

Layout and kinematic inversion: :mod:`camjax.followers._swing`. The face is an arc of a circle of
radius R_c, of chord W, whose centre C sits at the arm's end, l from the pivot:
C(psi) = (d - l cos psi, l sin psi), as the roller's centre of
:mod:`camjax.followers.oscillating_roller.geometry`. The arc is centred on the direction C moves
in (perpendicular to the arm, towards the cam): the face's axis. So the face's circle follows the
pitch curve of a roller of radius R_c, prime radius R_p = R_b + R_c, and the pressure angle, the
pitch curvature, the cam surface (the pitch curve moved inward by R_c, rho_c = rho_pitch - R_c),
the undercut and the contact force M / (l cos phi) are the oscillating roller's with R_f = R_c.
What differs:

- the face turns with the arm, not about C: the contact sits on the face at the angle phi from
  the face's axis (phi is the angle between the contact normal, which runs through C, and the
  path of C), R_c sin phi off the axis (:func:`face_travel`), which must stay within +-W/2. So
  ``|R_c sin phi| <= W/2`` is the pressure-angle limit ``|phi| <= asin(W / (2 R_c))``
  (:func:`face_travel_limit_rad`): the sizing is the roller's with the smaller of the two limits;
- the face slides on the cam (:func:`sliding_speed_m_s`). In the cam frame the cam stands still
  and the face moves: its centre along the pitch curve at T (per rad of cam angle; |T|^2 =
  l^2 Q^2 - 2 d l cos psi Q + d^2) and the face turns at -sigma Q (ccw positive; Q = 1 + sigma s',
  :func:`camjax.followers._swing.relative_rate`). The face's point at the contact,
  P = C - R_c n (n = sigma J T / |T| the outward normal), moves at
  T + (-sigma Q) J (P - C) = T (1 - Q R_c / |T|): the sliding speed is ``omega ||T| - Q R_c|``.
  On a dwell (s' = 0, |T| = R_p) it is omega R_b, the cam's surface speed under a still face;
- Hertz line contact of the cam surface and the crowned face, 1/rho_eq = 1/rho_c + 1/R_c: the
  roller's equivalent radius with R_f = R_c.

Every function here is pointwise in the kinematics (s, s', s'' at one angle, or a grid of them):
the closed forms take the arm angle psi, the rate Q and s''. All lengths in mm, angles in rad;
jit/vmap/grad-safe, with finite values and gradients for infeasible trial designs.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.followers._pitch import DEFAULT_ROTATION
from camjax.followers._swing import ArmTrig, arm_angle, of_angle, relative_rate
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.numerics import RHO_FLOOR_MM, floor_positive, safe_sqrt
from camjax.program import Kinematics

# Defaults of follower.max_pressure_angle_deg and min_curvature_radius_mm: the roller's
CURVED_MAX_PRESSURE_ANGLE_DEG = roller_geo.ROLLER_MAX_PRESSURE_ANGLE_DEG
CURVED_MIN_CURVATURE_RADIUS_MM = roller_geo.ROLLER_MIN_CURVATURE_RADIUS_MM


class Legs(NamedTuple):
    """The pitch curve's tangent at one arm angle (mm/rad): |T| cos phi and |T| sin phi."""

    across: jax.Array  # d sin psi: the component along the path of C (cos phi |T|)
    along: jax.Array  # l Q - d cos psi: the component along the arm, away from the pivot (sin phi |T|)


def legs(pivot_distance_mm, arm_length_mm, psi, rate) -> Legs:
    """(d sin psi, l Q - d cos psi): tan phi = along / across, |T|^2 = across^2 + along^2
    (:func:`camjax.followers.oscillating_roller.geometry.oscillating_roller_pressure_angle`)."""
    return arm_legs(pivot_distance_mm, arm_length_mm, of_angle(psi), rate)


def arm_legs(pivot_distance_mm, arm_length_mm, arm: ArmTrig, rate) -> Legs:
    """:func:`legs` in cos psi and sin psi (``arm``)."""
    d, l = pivot_distance_mm, arm_length_mm
    return Legs(d * arm.sn, l * rate - d * arm.c)


def face_travel_of(g: Legs, face_radius_mm) -> jax.Array:
    """R_c sin phi (mm) = R_c along / |T|: the contact's signed distance from the face's axis
    (positive towards the pivot; 0 where |T| = 0)."""
    norm = floor_positive(safe_sqrt(g.across**2 + g.along**2), RHO_FLOOR_MM)
    return face_radius_mm * g.along / norm


def sliding_speed_of(g: Legs, rate, face_radius_mm, cam_speed_rad_s) -> jax.Array:
    """omega ||T| - Q R_c| / 1000 (m/s): the relative tangential speed of cam and face at the contact."""
    return cam_speed_rad_s * jnp.abs(safe_sqrt(g.across**2 + g.along**2) - rate * face_radius_mm) * 1e-3


def _legs(pivot_distance_mm, arm_length_mm, prime_radius_mm, kin: Kinematics, rotation: str):
    psi0 = rocker_roller_geo.arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    rate = relative_rate(kin, rotation)
    return legs(pivot_distance_mm, arm_length_mm, arm_angle(psi0, kin), rate), rate


def face_travel(pivot_distance_mm, arm_length_mm, face_radius_mm, prime_radius_mm, kin: Kinematics,
                rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """R_c sin phi (mm) per sample: where the contact sits on the face, off its axis."""
    g, _ = _legs(pivot_distance_mm, arm_length_mm, prime_radius_mm, kin, rotation)
    return face_travel_of(g, face_radius_mm)


def sliding_speed_m_s(pivot_distance_mm, arm_length_mm, face_radius_mm, prime_radius_mm, kin: Kinematics,
                      cam_speed_rad_s, rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Relative tangential speed of cam and face at the contact (m/s), >= 0, per sample."""
    g, rate = _legs(pivot_distance_mm, arm_length_mm, prime_radius_mm, kin, rotation)
    return sliding_speed_of(g, rate, face_radius_mm, cam_speed_rad_s)


def face_travel_limit_rad(face_radius_mm, face_width_mm) -> jax.Array:
    """asin(min(W / (2 R_c), 1)) (rad): the pressure angle at which the contact reaches the face's
    edge (pi/2: a face as wide as its circle, no limit)."""
    return jnp.arcsin(jnp.clip(face_width_mm / (2.0 * face_radius_mm), 0.0, 1.0))


def geometry(pivot_distance_mm, arm_length_mm, face_radius_mm, prime_radius_mm, kin: Kinematics,
             rotation: str = DEFAULT_ROTATION,
             min_curvature_radius_mm=CURVED_MIN_CURVATURE_RADIUS_MM):
    """Arm angle, pressure angle, pitch and cam-surface curvature, undercut margin: the oscillating
    roller's with R_f = R_c."""
    return rocker_roller_geo.oscillating_roller_geometry(pivot_distance_mm, arm_length_mm, face_radius_mm,
                                                         prime_radius_mm, kin, rotation,
                                                         min_curvature_radius_mm)


def profile(pivot_distance_mm, arm_length_mm, face_radius_mm, prime_radius_mm, kin: Kinematics,
            rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y) in cam coordinates, mm: the oscillating roller's with R_f = R_c."""
    return rocker_roller_geo.oscillating_roller_profile(pivot_distance_mm, arm_length_mm, face_radius_mm,
                                                        prime_radius_mm, kin, rotation)


def min_prime_radius(kin: Kinematics, pivot_distance_mm, arm_length_mm, face_radius_mm, face_width_mm,
                     max_pressure_angle_rad, min_curvature_radius_mm=CURVED_MIN_CURVATURE_RADIUS_MM,
                     rotation: str = DEFAULT_ROTATION):
    """Smallest R_p = R_b + R_c with |phi| <= the limit, the contact on the face and no undercut at
    every sample, d and l given; and whether the face (rather than the pressure angle) sets the
    angle limit (bool). The oscillating roller's sizing with the limit min(phi_max, asin(W / 2 R_c))."""
    face = face_travel_limit_rad(face_radius_mm, face_width_mm)
    limit = jnp.minimum(max_pressure_angle_rad, face)
    sizing = rocker_roller_geo.oscillating_roller_min_prime_radius(
        kin, pivot_distance_mm, arm_length_mm, face_radius_mm, limit, min_curvature_radius_mm, rotation)
    return sizing, face < max_pressure_angle_rad


__all__ = [
    "CURVED_MAX_PRESSURE_ANGLE_DEG", "CURVED_MIN_CURVATURE_RADIUS_MM", "Legs", "face_travel",
    "face_travel_limit_rad", "face_travel_of", "geometry", "legs", "min_prime_radius", "profile",
    "sliding_speed_m_s", "sliding_speed_of",
]
