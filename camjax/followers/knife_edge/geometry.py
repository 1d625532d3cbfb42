"""Translating knife-edge follower with offset (SPEC section 3): the roller with R_f = 0.

The edge's tip rides the cam at the pitch point (e, w) of the follower frame,
w = sqrt(R_b^2 - e^2) + s: the pitch curve *is* the cam profile and the prime circle is the base
circle (R_p = R_b). Pressure angle and curvature are the roller's closed forms
(:mod:`camjax.followers.roller.geometry`) at R_f = 0:

- phi = atan((s' - e) / (s + sqrt(R_b^2 - e^2)))  (ccw; cw mirrors, :mod:`camjax.followers._pitch`);
- kappa = [w^2 + u (2 s' - e) - w s''] / [w^2 + u^2]^(3/2), u = s' - e, the profile's signed
  curvature (convex > 0); rho = 1 / kappa.

There is no undercut (nothing is offset from the pitch curve): a smooth motion gives a smooth
profile wherever w > 0, since its tangent (w, u) never vanishes. The limit is the profile's convex
radius of curvature, rho >= ``min_curvature_radius_mm`` (a sharp crest wears the edge; 0 = no
limit); concave parts are followed by the edge at any radius. No Hertz stress: at a point contact
of zero radius it is unbounded (SPEC 3), so the follower takes no [contact] section.

All lengths in mm, angles in rad; every function is elementwise over the angle grid and
jit/vmap/grad-safe in R_b and e (for infeasible trial designs too, |e| >= R_b included).
"""

from __future__ import annotations

from typing import NamedTuple

import jax

from camjax.followers._pitch import DEFAULT_ROTATION
from camjax.followers.roller import geometry as roller_geo
from camjax.program import Kinematics

# Defaults of the scene keys follower.max_pressure_angle_deg and min_curvature_radius_mm.
KNIFE_EDGE_MAX_PRESSURE_ANGLE_DEG = 30.0  # rule of thumb (SPEC 3), as the roller's
KNIFE_EDGE_MIN_CURVATURE_RADIUS_MM = 0.0  # = no limit on the profile's convex radius


class KnifeEdgeGeometry(NamedTuple):
    """Translating knife-edge follower, per sample (shape (N,) each)."""

    pressure_angle: jax.Array  # rad
    curvature: jax.Array  # 1/mm, signed: > 0 convex, < 0 concave, 0 at an inflection
    radius_of_curvature: jax.Array  # mm, 1 / curvature (saturated at inflections)
    curvature_margin: jax.Array  # mm, rho - min radius where convex, float max where concave


def knife_edge_tip_height(base_radius_mm, offset_mm, kin: Kinematics) -> jax.Array:
    """w = sqrt(R_b^2 - e^2) + s (mm), the tip's height on the follower axis."""
    return roller_geo.roller_pitch_height(base_radius_mm, 0.0, offset_mm, kin)


def knife_edge_profile(base_radius_mm, offset_mm, kin: Kinematics,
                       rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y), mm: the tip (e, w) seen from the cam (the pitch curve itself)."""
    return roller_geo.roller_pitch_curve(base_radius_mm, 0.0, offset_mm, kin, rotation)


def knife_edge_geometry(base_radius_mm, offset_mm, kin: Kinematics, rotation: str = DEFAULT_ROTATION,
                        min_curvature_radius_mm=KNIFE_EDGE_MIN_CURVATURE_RADIUS_MM) -> KnifeEdgeGeometry:
    """Pressure angle, profile curvature and the convex-radius margin at every sample."""
    g = roller_geo.roller_geometry(base_radius_mm, 0.0, offset_mm, kin, rotation, min_curvature_radius_mm)
    return KnifeEdgeGeometry(g.pressure_angle, g.pitch_curvature, g.pitch_radius_of_curvature,
                             g.undercut_margin)


def knife_edge_min_base_radius(kin: Kinematics, offset_mm, max_pressure_angle_rad,
                               min_curvature_radius_mm=KNIFE_EDGE_MIN_CURVATURE_RADIUS_MM,
                               rotation: str = DEFAULT_ROTATION) -> roller_geo.RollerSizing:
    """Smallest R_b (= R_p, mm) with |phi| <= the limit and a convex radius >= the minimum at every
    sample: the pressure angle in closed form, the curvature by bisection above it (a larger base
    circle flattens the convex parts), :func:`camjax.followers.roller.geometry.roller_min_prime_radius`
    at R_f = 0. ``undercut_binds`` there reads: the curvature limit binds. jit/vmap-safe."""
    return roller_geo.roller_min_prime_radius(kin, 0.0, offset_mm, max_pressure_angle_rad,
                                              min_curvature_radius_mm, rotation)


__all__ = [
    "KNIFE_EDGE_MAX_PRESSURE_ANGLE_DEG", "KNIFE_EDGE_MIN_CURVATURE_RADIUS_MM", "KnifeEdgeGeometry",
    "knife_edge_geometry", "knife_edge_min_base_radius", "knife_edge_profile", "knife_edge_tip_height",
]
