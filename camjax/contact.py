"""Hertz line contact between the cam and the follower (SPEC sections 3 and 4).

Flat face: sigma = 0.564 sqrt(P' / (rho ((1 - nu1^2)/E1 + (1 - nu2^2)/E2))), P' = F / w.
Roller: sigma = 0.564 sqrt(P' (1/rho_c + 1/R_f) / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2)), the same
form with rho replaced by the equivalent radius 1 / (1/rho_c + 1/R_f) and P the normal force.
Units: force N, width and rho mm, E in N/mm^2 (MPa) -> sigma in MPa.
The 0.564 factor (= sqrt(1/pi)) is applied everywhere; see the README on the source's
reference value of sigma_max.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.numerics import COS_FLOOR, RHO_FLOOR_MM, capped_divide, floor_positive, safe_sqrt

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


def roller_stress(coefficient, pressure_angle_rad, equivalent_radius_mm) -> jax.Array:
    """Roller contact stress (MPa) from the axial-force coefficient C = 0.564 sqrt(F / (w K)).

    The normal force is P = F / cos phi (:func:`camjax.loads.normal_force`), so
    sigma = C sqrt(1 / cos phi) / sqrt(rho_eq), rho_eq = 1 / (1/rho_c + 1/R_f)
    (:func:`camjax.followers.roller.geometry.roller_equivalent_radius`). C depends on the scene only, phi and
    rho_eq on the design. Finite for every trial design: cos phi is floored like
    :func:`camjax.loads.normal_force` and rho_eq like :func:`stress_from_coefficient` (an
    undercut saturates the stress; the undercut constraint carries the gradient there).
    """
    inv_cos = 1.0 / floor_positive(jnp.cos(pressure_angle_rad), COS_FLOOR)
    return stress_from_coefficient(coefficient * jnp.sqrt(inv_cos), equivalent_radius_mm)


def roller_hertz_line_stress(force_N, pressure_angle_rad, cam_radius_mm, roller_radius_mm, width_mm,
                             cam: Material, follower: Material) -> jax.Array:
    """SPEC 3's roller stress written out (MPa), for one design; finite for every trial design.

    sigma = 0.564 sqrt((P / w) (1/rho_c + 1/R_f) / K), P = F / cos phi, with rho_c the signed
    cam-surface radius (convex > 0; concave parts included). Where 1/rho_c + 1/R_f <= 0 (an
    undercut) the stress saturates as in :func:`roller_stress`.
    """
    # 1/rho_c + 1/R_f = (rho_c + R_f) / (rho_c R_f); its inverse is the equivalent radius
    rho_eq = capped_divide(cam_radius_mm * roller_radius_mm, cam_radius_mm + roller_radius_mm)
    return roller_stress(stress_coefficient(force_N, width_mm, cam, follower), pressure_angle_rad, rho_eq)
