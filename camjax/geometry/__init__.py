"""Follower geometry, one module per follower type plus the shared pitch-curve maths.

- :mod:`camjax.geometry.pitch`: frames, cam rotation (ccw default, cw = mirror image), pressure
  angle and pitch-curve curvature of a translating follower's reference point;
- :mod:`camjax.geometry.flat`: translating flat-face follower;
- :mod:`camjax.geometry.roller`: translating roller follower with offset.

Everything public is re-exported here (``geometry.flat_profile``, ``geometry.roller_geometry``).
"""

from camjax.geometry.flat import (
    FLAT_MIN_CURVATURE_RADIUS_MM,
    flat_contact_offset,
    flat_face_width,
    flat_min_base_radius,
    flat_profile,
    flat_radius_of_curvature,
)
from camjax.geometry.pitch import (
    DEFAULT_ROTATION,
    ROTATIONS,
    inward_normal,
    pitch_curvature,
    pitch_height,
    pressure_angle,
    radius_of_curvature,
    rotation_sign,
    to_cam_frame,
    to_follower_frame,
)
from camjax.geometry.roller import (
    ROLLER_MAX_PRESSURE_ANGLE_DEG,
    ROLLER_MIN_CURVATURE_RADIUS_MM,
    RollerGeometry,
    RollerSizing,
    prime_radius,
    roller_equivalent_radius,
    roller_geometry,
    roller_min_prime_radius,
    roller_min_prime_radius_for_pressure_angle,
    roller_min_prime_radius_for_undercut,
    roller_pitch_curvature,
    roller_pitch_curve,
    roller_pitch_height,
    roller_pressure_angle,
    roller_profile,
    roller_reach_constraint,
    roller_undercut_constraint,
    roller_undercut_margin,
)

__all__ = [
    "DEFAULT_ROTATION", "FLAT_MIN_CURVATURE_RADIUS_MM", "ROLLER_MAX_PRESSURE_ANGLE_DEG",
    "ROLLER_MIN_CURVATURE_RADIUS_MM", "ROTATIONS", "RollerGeometry", "RollerSizing",
    "flat_contact_offset", "flat_face_width", "flat_min_base_radius", "flat_profile",
    "flat_radius_of_curvature", "inward_normal", "pitch_curvature", "pitch_height", "pressure_angle",
    "prime_radius", "radius_of_curvature", "roller_equivalent_radius", "roller_geometry",
    "roller_min_prime_radius", "roller_min_prime_radius_for_pressure_angle",
    "roller_min_prime_radius_for_undercut", "roller_pitch_curvature", "roller_pitch_curve",
    "roller_pitch_height", "roller_pressure_angle", "roller_profile", "roller_reach_constraint",
    "roller_undercut_constraint", "roller_undercut_margin", "rotation_sign", "to_cam_frame",
    "to_follower_frame",
]
