"""Scene -> arrays -> curves: what a scene's models give, and what plots and export read.

:func:`scene_arrays` computes the design-independent arrays once per scene. Only what the scene
declares is computed: a scene without loads gets no force, one without [contact] no stress
coefficient. Everything downstream (geometry at a trial base radius, the objective, the report)
reads from :class:`SceneArrays`. :func:`evaluate_design` adds the geometry, stress and roller
quantities at one base radius as :class:`DesignCurves`, the NumPy arrays plots and export draw.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, geometry, loads, program
from camjax.program import Kinematics, TimeKinematics
from camjax.scene import Scene


class SceneArrays(NamedTuple):
    """Per-sample arrays of a scene (shape (N,) each; None where the scene does not ask)."""

    theta_deg: jax.Array  # cam angle, degrees
    kin: Kinematics  # s, s', s'', s''' (mm, per rad)
    motion: TimeKinematics  # y, y', y'', y''' (SI) at the scene's speed
    cam_speed_rad_s: jax.Array
    force_N: jax.Array | None  # kinetostatic contact force
    torque_Nm: jax.Array | None  # cam torque
    stress_coefficient: jax.Array | None  # C with sigma = C / sqrt(rho), MPa mm^0.5


def scene_arrays(scene: Scene, samples: int | None = None, dtype=None) -> SceneArrays:
    """Evaluate a scene's motion and, when declared, its loads and contact coefficient.

    Args:
      scene: a validated scene.
      samples: override the scene's grid size N.
      dtype: floating dtype (default: float64 when x64 is on). float32 halves memory and is
        about 3x faster with sin/cos, at ~1e-7 relative accuracy; see the README's limits.
    """
    dtype = dtype or jnp.result_type(float)
    n = scene.motion.samples if samples is None else int(samples)
    # one compiled call for the whole scene (the scene is closed over: its numbers are constants
    # of the program, so a fresh process finds it in the compilation cache) instead of a dozen
    # eager operations, each traced and looked up on its own
    return jax.jit(lambda: _scene_arrays(scene, n, dtype))()


def _scene_arrays(scene: Scene, n: int, dtype) -> SceneArrays:
    prog = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), scene.motion.program)
    kin = program.evaluate(prog, n)
    omega = jnp.asarray(program.rpm_to_rad_s(scene.motion.rpm), dtype)
    motion = program.time_kinematics(kin, omega)
    force = torque = coeff = None
    train = scene.follower.train
    if train is not None and not scene.follower.oscillating:  # a rocker's loads: camjax.rocker
        force = loads.kinetostatic_force(train, motion)
        torque = loads.cam_torque(force, kin.ds)
        if scene.contact is not None:
            c = scene.contact
            coeff = contact.stress_coefficient(force, c.cam_width_mm, c.cam, c.follower)
    theta_deg = program.sample_angles_deg(n, dtype)
    return SceneArrays(theta_deg, kin, motion, omega, force, torque, coeff)


class DesignCurves(NamedTuple):
    """Everything plots and export need at one design, as NumPy arrays of shape (N,) or scalars.

    Optional entries are None when the scene does not ask for the model.
    """

    theta_deg: np.ndarray  # cam angle, deg
    s_mm: np.ndarray
    ds_mm: np.ndarray  # mm/rad
    d2s_mm: np.ndarray  # mm/rad^2
    velocity_m_s: np.ndarray
    accel_m_s2: np.ndarray
    jerk_m_s3: np.ndarray
    segment_starts_deg: tuple[float, ...]
    follower_type: str  # "flat" or "roller"
    base_radius_mm: float
    face_width_mm: float | None  # flat face only
    profile_x_mm: np.ndarray  # cam outline, cam coordinates (geometry.py convention)
    profile_y_mm: np.ndarray
    rho_mm: np.ndarray | None  # flat face: radius of curvature of the cam profile
    force_N: np.ndarray | None
    torque_Nm: np.ndarray | None
    stress_MPa: np.ndarray | None
    sigma_max_MPa: float | None  # allowed stress of the [design], for plots
    roller_radius_mm: float | None
    offset_mm: float | None
    pitch_x_mm: np.ndarray | None  # roller: pitch curve
    pitch_y_mm: np.ndarray | None
    pressure_angle_deg: np.ndarray | None
    pitch_rho_mm: np.ndarray | None
    undercut_margin_mm: np.ndarray | None  # roller: rho_c - min radius on convex parts (float max on concave)
    pressure_angle_limit_deg: float | None = None  # roller: follower.max_pressure_angle_deg
    rotation: str = "ccw"  # the cam's turning direction (camjax.geometry.pitch)
    force_parts_N: dict[str, np.ndarray] | None = None  # {"inertia", "damping", "spring", "gravity"}


def _np(x):
    return None if x is None else np.asarray(x)


def _geometry_curves(f, rot: str, arrays: SceneArrays, base_radius_mm, rf, e):
    """Outline, curvature, stress, face width and roller quantities (None where not declared)."""
    kin = arrays.kin
    rho = stress = width = pitch_x = pitch_y = phi = pitch_rho = margin = None
    if f.type == "flat":
        x, y = geometry.flat_profile(base_radius_mm, kin, rot)
        rho = geometry.flat_radius_of_curvature(base_radius_mm, kin)
        if arrays.stress_coefficient is not None:
            stress = contact.stress_from_coefficient(arrays.stress_coefficient, rho)
        width = geometry.flat_face_width(kin, symmetric=True)
    else:
        x, y = geometry.roller_profile(base_radius_mm, rf, e, kin, rot)
        pitch_x, pitch_y = geometry.roller_pitch_curve(base_radius_mm, rf, e, kin, rot)
        g = geometry.roller_geometry(base_radius_mm, rf, e, kin, rot, f.min_curvature_radius_mm)
        phi, pitch_rho, margin = jnp.rad2deg(g.pressure_angle), g.pitch_radius_of_curvature, g.undercut_margin
        if arrays.stress_coefficient is not None:
            rho_eq = geometry.roller_equivalent_radius(g.pitch_curvature, rf)
            stress = contact.roller_stress(arrays.stress_coefficient, g.pressure_angle, rho_eq)
    return x, y, rho, stress, width, pitch_x, pitch_y, phi, pitch_rho, margin


def evaluate_design(scene: Scene, arrays: SceneArrays, base_radius_mm: float,
                    face_width_mm: float | None = None, *, roller_radius_mm: float | None = None,
                    offset_mm: float | None = None) -> DesignCurves:
    """Geometry, stress and roller quantities at one design (mm).

    ``roller_radius_mm``, ``offset_mm``: a roller's design values (default: the [follower]'s).
    Outlines follow the scene's ``motion.rotation`` (a cw cam is the mirror image of ccw).
    Roller stress: Hertz line contact of the cam surface (rho_c, concave parts included) and the
    roller under the normal force F / cos phi (:func:`camjax.contact.roller_stress`). The
    geometry is one compiled call (the scene's numbers are its constants).
    """
    kin, f, rot = arrays.kin, scene.follower, scene.motion.rotation
    rf = e = limit = None
    if f.type == "roller":
        rf = float(f.roller_radius_mm if roller_radius_mm is None else roller_radius_mm)
        e = float(f.offset_mm if offset_mm is None else offset_mm)
        limit = f.max_pressure_angle_deg
    x, y, rho, stress, width, pitch_x, pitch_y, phi, pitch_rho, margin = jax.jit(
        lambda a, r: _geometry_curves(f, rot, a, r, rf, e))(arrays, base_radius_mm)
    if f.type == "flat" and face_width_mm is None:
        face_width_mm = float(np.asarray(width))
    elif f.type != "flat":
        face_width_mm = None
    m = arrays.motion
    parts = None
    if f.train is not None and arrays.force_N is not None:
        numpy_motion = TimeKinematics(*(np.asarray(v) for v in m))
        parts = loads.force_parts(f.train, numpy_motion)._asdict()
    return DesignCurves(
        np.asarray(arrays.theta_deg), np.asarray(kin.s), np.asarray(kin.ds), np.asarray(kin.d2s),
        np.asarray(m.velocity), np.asarray(m.accel), np.asarray(m.jerk),
        scene.motion.program.start_deg, f.type, float(base_radius_mm),
        None if face_width_mm is None else float(face_width_mm),
        np.asarray(x), np.asarray(y), _np(rho), _np(arrays.force_N), _np(arrays.torque_Nm),
        _np(stress), None if scene.design is None else scene.design.sigma_max_MPa,
        rf, e, _np(pitch_x), _np(pitch_y), _np(phi), _np(pitch_rho), _np(margin), limit, rot, parts,
    )
