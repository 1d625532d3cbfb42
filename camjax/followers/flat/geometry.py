"""Translating flat-face follower, zero offset (SPEC section 3).

All lengths in mm, derivatives with respect to cam angle per radian. Every function is
elementwise over the angle grid and differentiable in the base radius, including trial radii far
below the feasible minimum (the curvature then comes out negative: a finite, penalty-ready
quantity). Frames and rotation: :mod:`camjax.followers._pitch`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.followers._pitch import DEFAULT_ROTATION, rotation_sign, to_cam_frame
from camjax.program import Kinematics

# Default smallest admissible radius of curvature (mm) of a flat-face cam: the strict "rho > 0"
# of SPEC 5 as a margin (scene key follower.min_curvature_radius_mm).
FLAT_MIN_CURVATURE_RADIUS_MM = 1e-3


def flat_radius_of_curvature(base_radius_mm: jax.Array, kin: Kinematics) -> jax.Array:
    """rho(theta) = R_b + s + s'' (mm); must stay > 0 (a flat face cannot follow a concavity)."""
    return base_radius_mm + kin.s + kin.d2s


def flat_min_base_radius(kin: Kinematics, min_curvature_radius_mm=0.0) -> tuple[jax.Array, jax.Array]:
    """Smallest R_b with rho >= rho_min everywhere, max_theta rho_min - (s + s''), and its index."""
    need = min_curvature_radius_mm - (kin.s + kin.d2s)
    i = jnp.argmax(need)
    return need[i], i


def flat_contact_offset(kin: Kinematics, rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Distance of the contact point from the follower axis, x = sign s' (mm; sign = side).

    ccw: x = s' (SPEC 3); a cw cam is the mirror image, x = -s'.
    """
    return rotation_sign(rotation) * kin.ds


def flat_face_width(kin: Kinematics, symmetric: bool = True) -> jax.Array:
    """Minimum face width (mm): 2 max|s'| for a symmetric face, max s' - min s' otherwise.

    Both are the same for either rotation (the mirror image swaps the sides of the face).
    """
    if symmetric:
        return 2.0 * jnp.max(jnp.abs(kin.ds))
    return jnp.max(kin.ds) - jnp.min(kin.ds)


def flat_profile(base_radius_mm: jax.Array, kin: Kinematics,
                 rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y) in mm: the contact point in cam coordinates at every sample.

    ccw: X = (R_b + s) sin theta + s' cos theta,  Y = (R_b + s) cos theta - s' sin theta: the
    contact point (s', R_b + s) of the follower frame seen from the cam. The follower face at
    angle theta is the line {P : P . (sin theta, cos theta) = R_b + s}. cw: mirrored in X.
    """
    return to_cam_frame(flat_contact_offset(kin, rotation), base_radius_mm + kin.s, kin.theta, rotation)
