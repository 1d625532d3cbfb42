"""Follower geometry, one module per follower type plus the shared pitch-curve maths.

- :mod:`camjax.geometry.pitch`: frames, cam rotation (ccw default, cw = mirror image), pressure
  angle and pitch-curve curvature of a translating follower's reference point;
- :mod:`camjax.geometry.flat`: translating flat-face follower;
- :mod:`camjax.geometry.roller`: translating roller follower with offset;
- :mod:`camjax.geometry.oscillating`: oscillating (rocker) roller and flat-face followers.

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
from camjax.geometry.oscillating import (
    OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM,
    OscillatingFlatGeometry,
    OscillatingFlatSizing,
    OscillatingRollerGeometry,
    OscillatingRollerSizing,
    arm_start_angle,
    face_start_angle,
    oscillating_flat_contact_distance,
    oscillating_flat_contact_point,
    oscillating_flat_face_extent,
    oscillating_flat_geometry,
    oscillating_flat_min_base_radius,
    oscillating_flat_profile,
    oscillating_flat_radius_of_curvature,
    oscillating_roller_geometry,
    oscillating_roller_min_prime_radius,
    oscillating_roller_pitch_curvature,
    oscillating_roller_pitch_curve,
    oscillating_roller_pressure_angle,
    oscillating_roller_profile,
    oscillating_roller_reach_constraint,
    oscillating_roller_tangent,
    swing_face_radius_of_curvature,
    swing_pitch_curvature,
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
    roller_pressure_angle_need,
    roller_profile,
    roller_reach_constraint,
    roller_undercut_constraint,
    roller_undercut_margin,
)

__all__ = [
    "DEFAULT_ROTATION", "FLAT_MIN_CURVATURE_RADIUS_MM", "OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM",
    "OscillatingFlatGeometry", "OscillatingFlatSizing", "OscillatingRollerGeometry",
    "OscillatingRollerSizing", "ROLLER_MAX_PRESSURE_ANGLE_DEG", "ROLLER_MIN_CURVATURE_RADIUS_MM",
    "ROTATIONS", "RollerGeometry", "RollerSizing", "arm_start_angle", "face_start_angle",
    "flat_contact_offset", "flat_face_width", "flat_min_base_radius", "flat_profile",
    "flat_radius_of_curvature", "inward_normal", "oscillating_flat_contact_distance",
    "oscillating_flat_contact_point", "oscillating_flat_face_extent", "oscillating_flat_geometry",
    "oscillating_flat_min_base_radius", "oscillating_flat_profile", "oscillating_flat_radius_of_curvature",
    "oscillating_roller_geometry", "oscillating_roller_min_prime_radius",
    "oscillating_roller_pitch_curvature", "oscillating_roller_pitch_curve",
    "oscillating_roller_pressure_angle", "oscillating_roller_profile",
    "oscillating_roller_reach_constraint", "oscillating_roller_tangent", "pitch_curvature", "pitch_height",
    "pressure_angle", "prime_radius", "radius_of_curvature", "roller_equivalent_radius", "roller_geometry",
    "roller_min_prime_radius", "roller_min_prime_radius_for_pressure_angle",
    "roller_min_prime_radius_for_undercut", "roller_pitch_curvature", "roller_pitch_curve",
    "roller_pitch_height", "roller_pressure_angle", "roller_pressure_angle_need", "roller_profile",
    "roller_reach_constraint",
    "roller_undercut_constraint", "roller_undercut_margin", "rotation_sign",
    "swing_face_radius_of_curvature", "swing_pitch_curvature", "to_cam_frame", "to_follower_frame",
]
