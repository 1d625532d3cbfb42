"""A scene with an oscillating (rocker) follower: sizing, curves at one design, and its report block.

Data flows as for translating followers (:mod:`camjax.followers.oscillating_roller.geometry` for the maths):

1. :func:`rocker_sizing` finds the smallest admissible cam with the scene's pivot and arm (or
   face): roller -- the smallest prime radius with |phi| <= ``max_pressure_angle_deg`` and no
   undercut; flat face -- the smallest base radius with rho >= ``min_curvature_radius_mm``;
2. :func:`rocker_drawing_radius` picks the base radius the cam is evaluated and drawn at (the
   option ``--base-radius``, else the smallest admissible + 1 mm rounded up) and checks that the
   geometry closes there;
3. :func:`evaluate_rocker` computes the curves at that radius (:class:`RockerCurves`): outline,
   pitch curve, pressure angle, curvature, the torque about the pivot, contact force, cam torque
   and Hertz stress;
4. :func:`camjax.output.rocker.rocker_report` condenses them into ``result.json``.

Units: the motion program of an oscillating follower is in rad (the scene's ``lift_deg``); the
report gives angles in degrees, lengths in mm, loads in SI.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from camjax import contact, loads
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.program import Kinematics
from camjax.scene import SceneError

DRAWING_MARGIN_MM = 1.0  # drawn at the smallest admissible base radius + this, rounded up


class RockerSizing(NamedTuple):
    """Smallest admissible cam of a rocker follower (Python floats)."""

    min_base_radius_mm: float  # R_b (roller: R_p - R_f)
    min_prime_radius_mm: float | None  # roller only: R_p
    angle_deg: float  # cam angle where the binding limit is reached
    binding: str  # "pressure_angle", "undercut", "curvature" ("none": an infeasible design's own radius)


class RockerCurves(NamedTuple):
    """Everything plots and export need at one rocker design (NumPy arrays of shape (N,), scalars).

    Optional entries are None where the follower type or the scene does not have them.
    """

    theta_deg: np.ndarray  # cam angle, deg
    swing_deg: np.ndarray  # s, the arm's swing from its start, deg
    ds: np.ndarray  # s', rad/rad
    d2s: np.ndarray  # s'', rad/rad^2
    angular_velocity_rad_s: np.ndarray
    angular_accel_rad_s2: np.ndarray
    angular_jerk_rad_s3: np.ndarray
    segment_starts_deg: tuple[float, ...]
    follower_type: str  # "oscillating_roller" or "oscillating_flat"
    rotation: str  # "ccw" or "cw"
    pivot_distance_mm: float
    arm_length_mm: float | None  # roller
    roller_radius_mm: float | None  # roller
    face_offset_mm: float | None  # flat face
    base_radius_mm: float
    prime_radius_mm: float | None  # roller
    arm_start_angle_deg: float  # psi0, from the line of centres
    arm_angle_deg: np.ndarray  # psi = psi0 + s
    profile_x_mm: np.ndarray  # cam outline, cam coordinates (camjax.followers._pitch convention)
    profile_y_mm: np.ndarray
    pitch_x_mm: np.ndarray | None  # roller: pitch curve
    pitch_y_mm: np.ndarray | None
    pressure_angle_deg: np.ndarray
    rho_mm: np.ndarray  # radius of curvature of the cam surface (convex > 0)
    pitch_rho_mm: np.ndarray | None  # roller
    undercut_margin_mm: np.ndarray | None  # roller
    contact_distance_mm: np.ndarray | None  # flat: contact point along the face from the pivot's foot
    pivot_torque_Nm: np.ndarray | None  # torque the cam applies to the arm about the pivot
    contact_force_N: np.ndarray | None  # normal contact force
    torque_Nm: np.ndarray | None  # cam shaft torque
    stress_MPa: np.ndarray | None  # Hertz contact stress
    pressure_angle_limit_deg: float | None = None  # roller: follower.max_pressure_angle_deg


def _f(x) -> float:
    return float(np.asarray(x))


# -------------------------------------------------------------------------------- sizing


def rocker_sizing(scene, kin: Kinematics) -> RockerSizing:
    """Smallest admissible cam of the scene's rocker (Python; raises SceneError when none exists)."""
    f, rotation = scene.follower, scene.motion.rotation
    t = np.degrees(np.asarray(kin.theta))
    if f.type == "oscillating_roller":
        s = rocker_roller_geo.oscillating_roller_min_prime_radius(
            kin, f.pivot_distance_mm, f.arm_length_mm, f.roller_radius_mm,
            math.radians(f.max_pressure_angle_deg), f.min_curvature_radius_mm, rotation)
        if not bool(s.found):
            raise SceneError("follower.arm_length_mm", f.arm_length_mm,
                               f"with pivot_distance_mm = {f.pivot_distance_mm:g} no prime radius keeps "
                               f"|pressure angle| <= {f.max_pressure_angle_deg:g} deg without undercut",
                               "a longer arm, another pivot distance or a larger max_pressure_angle_deg")
        binding = "undercut" if bool(s.undercut_binds) else "pressure_angle"
        return RockerSizing(_f(s.base_radius_mm), _f(s.prime_radius_mm), _f(t[int(s.index)]), binding)
    s = rocker_flat_geo.oscillating_flat_min_base_radius(kin, f.pivot_distance_mm, f.face_offset_mm,
                                                  f.min_curvature_radius_mm, rotation)
    if not bool(s.found):
        raise SceneError("follower.pivot_distance_mm", f.pivot_distance_mm,
                           f"with face_offset_mm = {f.face_offset_mm:g} no base radius keeps the cam's "
                           f"radius of curvature >= {f.min_curvature_radius_mm:g} mm",
                           "a larger pivot distance")
    return RockerSizing(_f(s.base_radius_mm), None, _f(t[int(s.index)]), "curvature")


def closure_problem(scene, kin: Kinematics, base_radius_mm: float) -> str | None:
    """Why the rocker cannot run on a cam of this base radius (mm), or None when it can.

    Roller: the prime radius R_p = R_b + R_f must lie strictly between |d - l| and d + l (the
    roller reaches the prime circle) and the arm must stay off the line of centres while it
    swings (psi0 + max s < pi). Flat face: 0 < R_b + f < d and the face keeps rising
    (psi0 + max s < pi/2).
    """
    f = scene.follower
    swing = float(np.max(np.asarray(kin.s)))
    if base_radius_mm <= 0:
        return "the base radius must be > 0"
    if f.type == "oscillating_roller":
        d, l, rp = f.pivot_distance_mm, f.arm_length_mm, base_radius_mm + f.roller_radius_mm
        if not abs(d - l) < rp < d + l:
            return (f"the roller cannot reach the prime circle R_p = {rp:g} mm: needs |d - l| = "
                    f"{abs(d - l):g} < R_p < d + l = {d + l:g}")
        psi0 = math.acos((d * d + l * l - rp * rp) / (2 * d * l))
        if psi0 + swing >= math.pi:
            return (f"the arm starts {math.degrees(psi0):g} deg from the line of centres and the lift "
                    f"({math.degrees(swing):g} deg) swings it through that line")
        return None
    d, off = f.pivot_distance_mm, f.face_offset_mm
    if not 0 < base_radius_mm + off < d:
        return (f"the face cannot touch the base circle: needs 0 < R_b + face_offset = "
                f"{base_radius_mm + off:g} < d = {d:g}")
    psi0 = math.asin((base_radius_mm + off) / d)
    if psi0 + swing >= 0.5 * math.pi:
        return (f"the face starts {math.degrees(psi0):g} deg from the line of centres and the lift "
                f"({math.degrees(swing):g} deg) turns it past 90 deg, where a rise no longer lifts it")
    return None


def rocker_drawing_radius(scene, kin: Kinematics, sizing: RockerSizing,
                          override_mm: float | None = None) -> tuple[float, str]:
    """Base radius (mm) the rocker cam is evaluated and drawn at, and where it comes from.

    The option wins (and must close, else a SceneError naming ``--base-radius``); otherwise the
    smallest admissible + 1 mm rounded up, or the smallest itself where that would not close.
    """
    if override_mm is not None:
        why = closure_problem(scene, kin, float(override_mm))
        if why is not None:
            raise SceneError("--base-radius", float(override_mm), why)
        return float(override_mm), "option --base-radius"
    r = float(math.ceil(max(sizing.min_base_radius_mm, 0.0) + DRAWING_MARGIN_MM))
    if closure_problem(scene, kin, r) is None:
        return r, f"smallest admissible + {DRAWING_MARGIN_MM:g} mm, rounded up to whole mm"
    return sizing.min_base_radius_mm, "smallest admissible"


# ----------------------------------------------------------------------------- curves


def evaluate_rocker(scene, kin: Kinematics, cam_speed_rad_s, base_radius_mm: float) -> RockerCurves:
    """Outline, pressure angle, curvature, loads and stress of the scene's rocker at one base radius."""
    f, rotation = scene.follower, scene.motion.rotation
    d, w = f.pivot_distance_mm, cam_speed_rad_s
    pitch_x = pitch_y = pitch_rho = margin = xi = None
    if f.type == "oscillating_roller":
        rf, l = f.roller_radius_mm, f.arm_length_mm
        rp = base_radius_mm + rf
        g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, rp, kin, rotation, f.min_curvature_radius_mm)
        x, y = rocker_roller_geo.oscillating_roller_profile(d, l, rf, rp, kin, rotation)
        pitch_x, pitch_y = rocker_roller_geo.oscillating_roller_pitch_curve(d, l, rp, kin, rotation)
        psi, phi, rho = g.arm_angle, g.pressure_angle, g.cam_radius_of_curvature
        pitch_rho, margin = g.pitch_radius_of_curvature, g.undercut_margin
        psi0 = rocker_roller_geo.arm_start_angle(rp, d, l)
    else:
        rp, l = None, None
        g = rocker_flat_geo.oscillating_flat_geometry(d, f.face_offset_mm, base_radius_mm, kin, rotation)
        x, y = rocker_flat_geo.oscillating_flat_profile(d, f.face_offset_mm, base_radius_mm, kin, rotation)
        psi, phi, rho, xi = g.arm_angle, g.pressure_angle, g.radius_of_curvature, g.contact_distance
        psi0 = rocker_flat_geo.face_start_angle(base_radius_mm, d, f.face_offset_mm)
    moment = force = torque = stress = None
    if f.train is not None:
        moment = loads.rocker_torque(f.train, kin, w)
        torque = loads.rocker_cam_torque(moment, kin.ds)
        if f.type == "oscillating_roller":
            force = loads.rocker_roller_contact_force(moment, l, phi)
        else:
            force = loads.rocker_flat_contact_force(moment, xi)
        if scene.contact is not None:
            c = scene.contact
            if f.type == "oscillating_roller":
                # the force along the roller's path, M / l, is the roller formula's "axial" force
                coeff = contact.stress_coefficient(moment / (l * 1e-3), c.cam_width_mm, c.cam, c.follower)
                rho_eq = roller_geo.roller_equivalent_radius(g.pitch_curvature, f.roller_radius_mm)
                stress = contact.roller_stress(coeff, phi, rho_eq)
            else:
                stress = contact.hertz_line_stress(force, rho, c.cam_width_mm, c.cam, c.follower)
    arr = lambda v: None if v is None else np.asarray(v)  # noqa: E731
    return RockerCurves(
        theta_deg=np.degrees(np.asarray(kin.theta)), swing_deg=np.degrees(np.asarray(kin.s)),
        ds=np.asarray(kin.ds), d2s=np.asarray(kin.d2s),
        angular_velocity_rad_s=np.asarray(kin.ds * w), angular_accel_rad_s2=np.asarray(kin.d2s * w**2),
        angular_jerk_rad_s3=np.asarray(kin.d3s * w**3),
        segment_starts_deg=scene.motion.program.start_deg, follower_type=f.type, rotation=rotation,
        pivot_distance_mm=d, arm_length_mm=l, roller_radius_mm=f.roller_radius_mm if rp is not None else None,
        face_offset_mm=None if rp is not None else f.face_offset_mm, base_radius_mm=float(base_radius_mm),
        prime_radius_mm=None if rp is None else float(rp), arm_start_angle_deg=_f(jnp.degrees(psi0)),
        arm_angle_deg=np.degrees(np.asarray(psi)), profile_x_mm=np.asarray(x), profile_y_mm=np.asarray(y),
        pitch_x_mm=arr(pitch_x), pitch_y_mm=arr(pitch_y), pressure_angle_deg=np.degrees(np.asarray(phi)),
        rho_mm=np.asarray(rho), pitch_rho_mm=arr(pitch_rho), undercut_margin_mm=arr(margin),
        contact_distance_mm=arr(xi), pivot_torque_Nm=arr(moment), contact_force_N=arr(force),
        torque_Nm=arr(torque), stress_MPa=arr(stress),
        pressure_angle_limit_deg=None if rp is None else float(f.max_pressure_angle_deg),
    )


class RockerRun(NamedTuple):
    """A rocker scene's sizing, drawing radius and curves."""

    sizing: RockerSizing
    base_radius_mm: float
    base_radius_source: str
    curves: RockerCurves


def run_rocker(scene, kin: Kinematics, cam_speed_rad_s, base_radius_mm: float | None = None,
               design: dict | None = None) -> RockerRun:
    """Sizing, drawing radius and curves of a rocker scene (Python: reads the scene, may raise SceneError).

    ``design``: the solved [design] (:meth:`camjax.solvers.base.Solution.to_json` keys of the
    oscillating families): the cam is sized and drawn with its roller, pivot and arm (or face
    offset), at its base radius unless ``base_radius_mm`` (the option) is given.
    """
    if design is not None:
        geometry_keys = ("roller_radius_mm", "pivot_distance_mm", "arm_length_mm", "face_offset_mm")
        follower = replace(scene.follower, **{k: design[k] for k in geometry_keys if k in design})
        scene = replace(scene, follower=follower)
        try:
            sizing = rocker_sizing(scene, kin)
        except SceneError:  # an infeasible design: its own radius is all there is to report
            sizing = RockerSizing(design["base_radius_mm"], design.get("prime_radius_mm"), 0.0, "none")
        if base_radius_mm is None:
            radius = design["base_radius_mm"]
            return RockerRun(sizing, radius, "design", evaluate_rocker(scene, kin, cam_speed_rad_s, radius))
    else:
        sizing = rocker_sizing(scene, kin)
    radius, source = rocker_drawing_radius(scene, kin, sizing, base_radius_mm)
    return RockerRun(sizing, radius, source, evaluate_rocker(scene, kin, cam_speed_rad_s, radius))
