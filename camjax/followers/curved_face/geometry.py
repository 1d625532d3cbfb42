"""Translating curved-face ("mushroom") follower (SPEC 3): one design (R_b, R_c, e), any grid.

The face is a circular arc of radius R_c (crowned), of width W, symmetric about the follower
axis, on a stem that slides along the axis x = e. The centre of the face's circle follows the
pitch curve of a roller of radius R_c: prime radius R_p = R_b + R_c, the centre at (e, w) in the
follower frame, w = sqrt(R_p^2 - e^2) + s. So the pressure angle phi, the pitch curvature, the cam
surface (the pitch curve moved inward by R_c, radius rho_c = rho_pitch - R_c) and the undercut
are the roller's with R_f = R_c (:mod:`camjax.followers.roller.geometry`). What differs:

- the face does not turn: the contact point sits on the face at the angle phi from its axis,
  R_c sin phi off the axis (:func:`face_travel`), which must stay within +-W/2. Since
  sin phi = u / r (u = s' - e~, r = sqrt(w^2 + u^2)), ``|R_c sin phi| <= W/2`` is the pressure-angle
  limit ``|phi| <= asin(W / (2 R_c))`` (:func:`face_travel_limit_rad`): the sizing is the roller's
  with the smaller of the two limits;
- the face slides on the cam: the cam moves relative to the follower as a rotation at omega about
  the instant centre I = (s', 0) (follower frame), and the contact point c lies on the normal
  through the pitch point at c - I = (1 - R_c / r) (-u, w), so the sliding speed is
  ``omega |r - R_c|`` (:func:`sliding_speed_m_s`);
- Hertz line contact of the cam surface and the crowned face, 1/rho_eq = 1/rho_c + 1/R_c: the
  roller's equivalent radius with R_f = R_c.

As R_c -> infinity (R_b fixed) phi -> 0 like u / R_c, the contact's offset from the cam's centre
line e + R_c sin phi -> s', rho_c -> R_b + s + s'', rho_eq -> rho_c and the sliding speed ->
omega (R_b + s): the flat face of :mod:`camjax.followers.flat.geometry`.

All lengths in mm, angles in rad; elementwise over the angle grid and jit/vmap/grad-safe in R_b,
R_c and e, for infeasible trial designs too. Frames and rotation: :mod:`camjax.followers._pitch`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.followers import _pitch as pitch
from camjax.followers._pitch import DEFAULT_ROTATION, rotation_sign
from camjax.followers.roller import geometry as roller_geo
from camjax.numerics import safe_divide, safe_sqrt
from camjax.program import Kinematics

# Defaults of the scene keys follower.max_pressure_angle_deg and min_curvature_radius_mm: the roller's
CURVED_MAX_PRESSURE_ANGLE_DEG = roller_geo.ROLLER_MAX_PRESSURE_ANGLE_DEG
CURVED_MIN_CURVATURE_RADIUS_MM = roller_geo.ROLLER_MIN_CURVATURE_RADIUS_MM


def _w_u(base_radius_mm, face_radius_mm, offset_mm, kin: Kinematics, rotation: str):
    """(w, u): the face centre's height d + s and u = s' - e~ (ccw formulas, e~ = sign e)."""
    e = rotation_sign(rotation) * offset_mm
    w = pitch.pitch_height(base_radius_mm + face_radius_mm, e, kin.s)
    return w, kin.ds - e


def face_travel_of(w, u, face_radius_mm) -> jax.Array:
    """R_c u / r (mm), r = sqrt(w^2 + u^2): the ccw contact offset on the face (0 where r = 0)."""
    r = safe_sqrt(w**2 + u**2)
    return face_radius_mm * safe_divide(u, r)


def face_travel(base_radius_mm, face_radius_mm, offset_mm, kin: Kinematics,
                rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """R_c sin phi (mm): where the contact sits on the face, off the follower axis (signed as
    :func:`camjax.followers._pitch.pressure_angle`: positive towards +x for ccw)."""
    w, u = _w_u(base_radius_mm, face_radius_mm, offset_mm, kin, rotation)
    return rotation_sign(rotation) * face_travel_of(w, u, face_radius_mm)


def sliding_speed_of(w, u, face_radius_mm, cam_speed_rad_s) -> jax.Array:
    """omega |r - R_c| / 1000 (m/s), r = sqrt(w^2 + u^2): the contact's distance from the instant
    centre of the cam's motion relative to the follower, times omega."""
    return cam_speed_rad_s * jnp.abs(safe_sqrt(w**2 + u**2) - face_radius_mm) * 1e-3


def sliding_speed_m_s(base_radius_mm, face_radius_mm, offset_mm, kin: Kinematics, cam_speed_rad_s,
                      rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Relative tangential speed of cam and face at the contact (m/s), >= 0 (the same for either
    rotation: a mirror image)."""
    w, u = _w_u(base_radius_mm, face_radius_mm, offset_mm, kin, rotation)
    return sliding_speed_of(w, u, face_radius_mm, cam_speed_rad_s)


def face_travel_limit_rad(face_radius_mm, face_width_mm) -> jax.Array:
    """asin(min(W / (2 R_c), 1)) (rad): the pressure angle at which the contact reaches the face's
    edge (pi/2: a face as wide as its circle, no limit)."""
    return jnp.arcsin(jnp.clip(face_width_mm / (2.0 * face_radius_mm), 0.0, 1.0))


def contact_point(base_radius_mm, face_radius_mm, offset_mm, kin: Kinematics,
                  rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """The contact point in the follower frame (x, y), mm: the face centre (e, w) moved towards the
    cam centre by R_c along the pitch curve's normal."""
    w = roller_geo.roller_pitch_height(base_radius_mm, face_radius_mm, offset_mm, kin)
    nx, ny = pitch.inward_normal(w, kin.ds, offset_mm, rotation)
    return offset_mm + face_radius_mm * nx, w + face_radius_mm * ny


def profile(base_radius_mm, face_radius_mm, offset_mm, kin: Kinematics,
            rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y) in cam coordinates, mm: the roller's with R_f = R_c."""
    return roller_geo.roller_profile(base_radius_mm, face_radius_mm, offset_mm, kin, rotation)


def geometry(base_radius_mm, face_radius_mm, offset_mm, kin: Kinematics, rotation: str = DEFAULT_ROTATION,
             min_curvature_radius_mm=CURVED_MIN_CURVATURE_RADIUS_MM) -> roller_geo.RollerGeometry:
    """Pressure angle, pitch and cam-surface curvature, undercut margin: the roller's with R_f = R_c."""
    return roller_geo.roller_geometry(base_radius_mm, face_radius_mm, offset_mm, kin, rotation,
                                      min_curvature_radius_mm)


def min_prime_radius(kin: Kinematics, face_radius_mm, face_width_mm, offset_mm, max_pressure_angle_rad,
                     min_curvature_radius_mm=CURVED_MIN_CURVATURE_RADIUS_MM,
                     rotation: str = DEFAULT_ROTATION) -> tuple[roller_geo.RollerSizing, jax.Array]:
    """Smallest R_p = R_b + R_c (mm) with |phi| <= the limit, the contact on the face and no
    undercut at every sample; and whether the face (rather than the pressure angle) sets the
    angle limit (bool). The roller's sizing with the limit min(phi_max, asin(W / (2 R_c)))."""
    face = face_travel_limit_rad(face_radius_mm, face_width_mm)
    limit = jnp.minimum(max_pressure_angle_rad, face)
    sizing = roller_geo.roller_min_prime_radius(kin, face_radius_mm, offset_mm, limit,
                                                min_curvature_radius_mm, rotation)
    return sizing, face < max_pressure_angle_rad


__all__ = [
    "CURVED_MAX_PRESSURE_ANGLE_DEG", "CURVED_MIN_CURVATURE_RADIUS_MM", "contact_point", "face_travel",
    "face_travel_limit_rad", "face_travel_of", "geometry", "min_prime_radius", "profile",
    "sliding_speed_m_s", "sliding_speed_of",
]
