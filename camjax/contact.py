"""Hertz line contact between the cam and the follower face (SPEC section 4).

sigma = 0.564 sqrt(P' / (rho ((1 - nu1^2)/E1 + (1 - nu2^2)/E2))), P' = F / w.
Units: force N, width and rho mm, E in N/mm^2 (MPa) -> sigma in MPa.
The 0.564 factor (= sqrt(1/pi)) is applied everywhere; see the README on the source's
reference value of sigma_max.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.numerics import RHO_FLOOR_MM, floor_positive, safe_sqrt

HERTZ_FACTOR = 0.564


class Material(NamedTuple):
    """Elastic constants of one body."""

    E_MPa: float
    poisson: float


def compliance(cam: Material, follower: Material) -> jax.Array:
    """(1 - nu1^2)/E1 + (1 - nu2^2)/E2, in 1/MPa."""
    return (1.0 - cam.poisson**2) / cam.E_MPa + (1.0 - follower.poisson**2) / follower.E_MPa


def stress_coefficient(force_N, width_mm, cam: Material, follower: Material) -> jax.Array:
    """C with sigma = C / sqrt(rho): 0.564 sqrt(P' / K), MPa mm^0.5; 0 where the force is <= 0."""
    return HERTZ_FACTOR * safe_sqrt(force_N / (width_mm * compliance(cam, follower)))


def stress_from_coefficient(coefficient, rho_mm) -> jax.Array:
    """sigma = C / sqrt(rho) with rho floored at RHO_FLOOR_MM.

    For rho at or below the floor (a corner or a concavity: infeasible for a flat face) the
    stress saturates at C / sqrt(floor), finite, with zero gradient in rho; the curvature
    constraint carries the gradient there.
    """
    return coefficient / jnp.sqrt(floor_positive(rho_mm, RHO_FLOOR_MM))


def hertz_line_stress(force_N, rho_mm, width_mm, cam: Material, follower: Material) -> jax.Array:
    """Peak contact stress (MPa) of a line contact; 0 where the follower has lost contact."""
    return stress_from_coefficient(stress_coefficient(force_N, width_mm, cam, follower), rho_mm)
