"""Follower geometry: translating flat-face and translating roller followers (SPEC section 3).

All lengths in mm, angles in radians, derivatives with respect to cam angle per radian. Every
function is elementwise over the angle grid and differentiable in the base radius, including
trial radii far below the feasible minimum (the curvature then comes out negative: a finite,
penalty-ready quantity).

Profile convention: cam coordinates with the follower axis along +Y at theta = 0; the cam turns
so that the point of the profile in contact at cam angle theta lies at polar angle theta
measured clockwise from +Y (X = r sin theta, Y = r cos theta).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.numerics import capped_divide, safe_divide, safe_sqrt
from camjax.program import Kinematics

PRESSURE_ANGLE_LIMIT_DEG = 30.0  # rule of thumb for a translating roller follower (SPEC 3)

# ------------------------------------------------------------------------- flat face


def flat_radius_of_curvature(base_radius_mm: jax.Array, kin: Kinematics) -> jax.Array:
    """rho(theta) = R_b + s + s'' (mm); must stay > 0 (a flat face cannot follow a concavity)."""
    return base_radius_mm + kin.s + kin.d2s


def flat_min_base_radius(kin: Kinematics) -> tuple[jax.Array, jax.Array]:
    """Smallest R_b with rho >= 0 everywhere, max_theta -(s + s''), and the index where it binds."""
    need = -(kin.s + kin.d2s)
    i = jnp.argmax(need)
    return need[i], i


def flat_contact_offset(kin: Kinematics) -> jax.Array:
    """Distance of the contact point from the follower axis, x = s' (mm; sign = side)."""
    return kin.ds


def flat_face_width(kin: Kinematics, symmetric: bool = True) -> jax.Array:
    """Minimum face width (mm): 2 max|s'| for a symmetric face, max s' - min s' otherwise."""
    if symmetric:
        return 2.0 * jnp.max(jnp.abs(kin.ds))
    return jnp.max(kin.ds) - jnp.min(kin.ds)


def flat_profile(base_radius_mm: jax.Array, kin: Kinematics) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y) in mm: the contact point in cam coordinates at every sample.

    X = (R_b + s) sin theta + s' cos theta,  Y = (R_b + s) cos theta - s' sin theta.
    The follower face at angle theta is the line {P : P . (sin theta, cos theta) = R_b + s}.
    """
    r = base_radius_mm + kin.s
    c, s = jnp.cos(kin.theta), jnp.sin(kin.theta)
    return r * s + kin.ds * c, r * c - kin.ds * s


# ---------------------------------------------------------------------------- roller


class RollerGeometry(NamedTuple):
    """Translating roller follower, per sample (shape (N,) each)."""

    pressure_angle: jax.Array  # rad
    pitch_radius_of_curvature: jax.Array  # mm, signed: > 0 convex, < 0 concave
    undercut_margin: jax.Array  # |rho_pitch| - R_f, mm; <= 0 means undercut


def roller_geometry(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics) -> RollerGeometry:
    """Pressure angle, pitch-curve curvature and undercut margin of a translating roller follower.

    Prime-circle radius R_p = R_b + R_f; the pitch point sits at (offset, d + s) in the follower
    frame with d = sqrt(R_p^2 - offset^2). Pressure angle phi = atan((s' - e) / (s + d)).
    Pitch-curve radius of curvature (general offset; reduces to SPEC 3's formula for e = 0):
    rho = [w^2 + (s'-e)^2]^(3/2) / [w^2 + (s'-e)(2s'-e) - w s''],  w = d + s.
    The undercut check follows the source's conservative rule |rho| > R_f on both signs.
    """
    rp = base_radius_mm + roller_radius_mm
    d = safe_sqrt(rp**2 - offset_mm**2)
    w = d + kin.s
    u = kin.ds - offset_mm
    phi = jnp.arctan2(u, w)
    num = (w**2 + u**2) ** 1.5
    den = w**2 + u * (2.0 * kin.ds - offset_mm) - w * kin.d2s
    rho = capped_divide(num, den)
    return RollerGeometry(phi, rho, jnp.abs(rho) - roller_radius_mm)


def roller_pitch_curve(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics):
    """Pitch curve (X, Y) in cam coordinates, mm (same convention as :func:`flat_profile`)."""
    rp = base_radius_mm + roller_radius_mm
    w = safe_sqrt(rp**2 - offset_mm**2) + kin.s
    c, s = jnp.cos(kin.theta), jnp.sin(kin.theta)
    return w * s + offset_mm * c, w * c - offset_mm * s


def roller_profile(base_radius_mm, roller_radius_mm, offset_mm, kin: Kinematics):
    """Cam outline (X, Y), mm: the pitch curve moved inward by R_f along its normal."""
    rp = base_radius_mm + roller_radius_mm
    w = safe_sqrt(rp**2 - offset_mm**2) + kin.s
    u = kin.ds - offset_mm
    norm = safe_sqrt(w**2 + u**2)
    # the pitch curve's tangent in the follower frame is (w, u); its inward unit normal (towards
    # the cam centre) is (u, -w) / |(w, u)|
    nx, ny = safe_divide(u, norm), safe_divide(-w, norm)
    px, py = offset_mm + roller_radius_mm * nx, w + roller_radius_mm * ny
    c, s = jnp.cos(kin.theta), jnp.sin(kin.theta)
    return py * s + px * c, py * c - px * s
