"""Scene -> arrays -> curves: what a scene's models give, and what plots and export read.

:func:`scene_arrays` computes the design-independent arrays once per scene. Only what the scene
declares is computed: a scene without loads gets no force, one without [contact] no stress
coefficient. Everything downstream (geometry at a trial base radius, the objective, the report)
reads from :class:`SceneArrays`. :func:`evaluate_design` adds the geometry, stress and roller
quantities at one base radius as :class:`DesignCurves`, the NumPy arrays plots and export draw.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, loads, program, runtime
from camjax import extrema as extrema_mod
from camjax.contact import Material
from camjax.followers import _pitch as pitch
from camjax.followers.flat import geometry as flat_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.loads import FollowerTrain, Guide
from camjax.program import Kinematics, MotionProgram, TimeKinematics
from camjax.scene import Scene


class SceneModel(NamedTuple):
    """A scene's per-angle models in closed form (a pytree), for extrema refined off the grid.

    None where the scene does not declare the model (as in :class:`SceneArrays`).
    """

    program: MotionProgram
    cam_speed_rad_s: jax.Array
    train: FollowerTrain | None
    cam_width_mm: jax.Array | None  # [contact]
    cam: Material | None
    follower: Material | None


class PointValues(NamedTuple):
    """The scene's quantities at some cam angles of one segment (shapes of the angles)."""

    kin: Kinematics
    force_N: jax.Array | None
    torque_Nm: jax.Array | None
    stress_coefficient: jax.Array | None


def scene_model(scene: Scene, dtype=None) -> SceneModel:
    """The closed-form models a scene declares, as arrays of ``dtype`` (default float64)."""
    dtype = dtype or jnp.result_type(float)
    as_ = partial(jax.tree_util.tree_map, lambda x: jnp.asarray(x, dtype))
    c = scene.contact
    train = scene.follower.train
    return SceneModel(
        as_(scene.motion.program), jnp.asarray(program.rpm_to_rad_s(scene.motion.rpm), dtype),
        None if train is None else as_(train),
        None if c is None or train is None else jnp.asarray(c.cam_width_mm, dtype),
        None if c is None or train is None else as_(c.cam),
        None if c is None or train is None else as_(c.follower))


def model_at(model: SceneModel, segment: int, theta_deg: jax.Array) -> PointValues:
    """Kinematics, force, torque and stress coefficient on segment ``segment`` (Python int) at
    cam angles ``theta_deg`` (deg, inside the segment; its ends give one-sided limits)."""
    kin = program.segment_motion(model.program, segment, theta_deg)
    force = torque = coeff = None
    if model.train is not None:
        force = loads.kinetostatic_force(model.train, program.time_kinematics(kin, model.cam_speed_rad_s))
        torque = loads.cam_torque(force, kin.ds)
        if model.cam_width_mm is not None:
            coeff = contact.stress_coefficient(force, model.cam_width_mm, model.cam, model.follower)
    return PointValues(kin, force, torque, coeff)


class SceneArrays(NamedTuple):
    """Per-sample arrays of a scene (shape (N,) each; None where the scene does not ask)."""

    theta_deg: jax.Array  # cam angle, degrees
    kin: Kinematics  # s, s', s'', s''' (mm, per rad)
    motion: TimeKinematics  # y, y', y'', y''' (SI) at the scene's speed
    cam_speed_rad_s: jax.Array
    force_N: jax.Array | None  # kinetostatic contact force
    torque_Nm: jax.Array | None  # cam torque
    stress_coefficient: jax.Array | None  # C with sigma = C / sqrt(rho), MPa mm^0.5
    model: SceneModel | None = None  # closed forms behind the arrays; None: extrema on the grid


def scene_arrays(scene: Scene, samples: int | None = None, dtype=None, extrema: str | None = None
                 ) -> SceneArrays:
    """Evaluate a scene's motion and, when declared, its loads and contact coefficient.

    Args:
      scene: a validated scene.
      samples: override the scene's grid size N.
      dtype: floating dtype (default: float64 when x64 is on). float32 halves memory and is
        about 3x faster with sin/cos, at ~1e-7 relative accuracy; see the README's limits.
      extrema: "exact" (every max/min over the angle refined off the grid) or "grid" (the
        samples' own); default the scene's ``[motion] extrema``.
    """
    mode = scene.motion.extrema if extrema is None else extrema
    if mode not in extrema_mod.EXTREMA_MODES:
        raise ValueError(f"extrema: '{mode}' is not allowed; use {', '.join(extrema_mod.EXTREMA_MODES)}")
    dtype = dtype or jnp.result_type(float)
    n = scene.motion.samples if samples is None else int(samples)
    # one compiled call for the whole scene (the scene is closed over: its numbers are constants
    # of the program, so a fresh process finds it in the compilation cache) instead of a dozen
    # eager operations, each traced and looked up on its own
    arrays = jax.jit(lambda: _scene_arrays(scene, n, dtype))()
    # an oscillating follower's extrema stay on the grid (camjax.rocker evaluates its curves)
    model = scene_model(scene, dtype) if mode == "exact" and not scene.follower.oscillating else None
    return arrays._replace(model=model)


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
    rotation: str = "ccw"  # the cam's turning direction (camjax.followers._pitch)
    force_parts_N: dict[str, np.ndarray] | None = None  # {"inertia", "damping", "spring", "gravity"}


def _np(x):
    return None if x is None else np.asarray(x)


def _geometry_curves(f, rot: str, arrays: SceneArrays, base_radius_mm, rf, e):
    """Outline, curvature, stress, face width and roller quantities (None where not declared)."""
    kin = arrays.kin
    rho = stress = width = pitch_x = pitch_y = phi = pitch_rho = margin = None
    if f.type == "flat":
        x, y = flat_geo.flat_profile(base_radius_mm, kin, rot)
        rho = flat_geo.flat_radius_of_curvature(base_radius_mm, kin)
        if arrays.stress_coefficient is not None:
            stress = contact.stress_from_coefficient(arrays.stress_coefficient, rho)
        width = flat_geo.flat_face_width(kin, symmetric=True)
    else:
        x, y = roller_geo.roller_profile(base_radius_mm, rf, e, kin, rot)
        pitch_x, pitch_y = roller_geo.roller_pitch_curve(base_radius_mm, rf, e, kin, rot)
        g = roller_geo.roller_geometry(base_radius_mm, rf, e, kin, rot, f.min_curvature_radius_mm)
        phi, pitch_rho, margin = jnp.rad2deg(g.pressure_angle), g.pitch_radius_of_curvature, g.undercut_margin
        if arrays.stress_coefficient is not None:
            rho_eq = roller_geo.roller_equivalent_radius(g.pitch_curvature, rf)
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


# ------------------------------------------------------------------------------ extrema

KINEMATIC_CURVES = ("s", "ds", "d2s", "d3s")  # mm, mm/rad, mm/rad^2, mm/rad^3
LOAD_CURVES = ("force", "torque")  # N, N m
GUIDE_CURVES = ("cam_force", "reaction_1", "reaction_2", "gamma")  # N, N, N, mm (GuideReactions)
# translating roller at the base radius: pressure angle (rad), |pitch-curve rho| (mm), undercut
# margin rho_c - rho_min on convex parts (mm; the largest float on concave ones, as
# camjax.followers.roller.geometry.roller_undercut_margin)
ROLLER_CURVES = ("pressure_angle", "pitch_rho_abs", "undercut_margin")
# the roller's pressure-angle sizing: |s' - e~| / tan(limit) - s (mm), whose max is the smallest
# d = sqrt(R_p^2 - e^2) (camjax.followers.roller.geometry.roller_min_prime_radius_for_pressure_angle)
PRESSURE_NEED = "pressure_angle_need"


class CurveConstants(NamedTuple):
    """Scene constants the curves need besides the motion (a pytree; None where not declared).

    The roller's offset is stored times the rotation sign (a cw cam is the mirror image of the
    ccw one with e -> -e), so the curves are the ccw formulas of :mod:`camjax.followers._pitch`
    with the pressure angle's sign restored by ``rotation_sign``.
    """

    guide: Guide | None
    roller_radius_mm: jax.Array | None
    offset_mm: jax.Array | None  # rotation_sign * e
    rotation_sign: jax.Array | None  # +1 ccw, -1 cw
    min_curvature_radius_mm: jax.Array | None  # the undercut margin's rho_min
    tan_pressure_limit: jax.Array | None  # tan(follower.max_pressure_angle_deg)


def curve_constants(scene: Scene, roller_radius_mm: float | None = None,
                    offset_mm: float | None = None) -> CurveConstants:
    """The guide and roller constants of a scene (a roller design's R_f and e override the
    [follower]'s)."""
    f = scene.follower
    if f.type != "roller":
        return CurveConstants(scene.guide, None, None, None, None, None)
    sign = pitch.rotation_sign(scene.motion.rotation)
    rf = f.roller_radius_mm if roller_radius_mm is None else roller_radius_mm
    e = f.offset_mm if offset_mm is None else offset_mm
    return CurveConstants(scene.guide, float(rf), sign * float(e), sign, f.min_curvature_radius_mm,
                          math.tan(math.radians(f.max_pressure_angle_deg)))


class Extremes(NamedTuple):
    """Max and min of one curve over the cam angle and where they occur (Python floats, deg)."""

    max: float
    max_deg: float
    min: float
    min_deg: float


def _curve(name: str, p: PointValues, consts: CurveConstants, base_radius_mm) -> jax.Array:
    """One named curve from the point values (grid arrays or closed-form points alike)."""
    if name in KINEMATIC_CURVES:
        return getattr(p.kin, name)
    if name == "force":
        return p.force_N
    if name == "torque":
        return p.torque_Nm
    if name == "q":  # s + s'' (mm): the flat face's rho = R_b + q
        return p.kin.s + p.kin.d2s
    if name == "stress" and consts.roller_radius_mm is not None:  # roller contact stress, MPa
        g = roller_geo.roller_geometry(base_radius_mm, consts.roller_radius_mm, consts.offset_mm, p.kin)
        rho_eq = roller_geo.roller_equivalent_radius(g.pitch_curvature, consts.roller_radius_mm)
        return contact.roller_stress(p.stress_coefficient, g.pressure_angle, rho_eq)  # even in phi
    if name == "stress":  # flat-face contact stress at base_radius_mm, MPa
        return contact.stress_from_coefficient(p.stress_coefficient, base_radius_mm + p.kin.s + p.kin.d2s)
    if name in GUIDE_CURVES:
        offset = flat_geo.flat_contact_offset(p.kin)
        return getattr(loads.guide_reactions(consts.guide, p.force_N, offset), name)
    if name == PRESSURE_NEED:
        return roller_geo.roller_pressure_angle_need(p.kin.ds, p.kin.s, consts.offset_mm,
                                                   consts.tan_pressure_limit)
    if name in ROLLER_CURVES:
        g = roller_geo.roller_geometry(base_radius_mm, consts.roller_radius_mm, consts.offset_mm, p.kin,
                                     "ccw", consts.min_curvature_radius_mm)
        return {"pressure_angle": consts.rotation_sign * g.pressure_angle,
                "undercut_margin": g.undercut_margin,
                "pitch_rho_abs": jnp.abs(g.pitch_radius_of_curvature)}[name]
    raise ValueError(f"curve: unknown name '{name}'")


def curve_names(scene: Scene, arrays: SceneArrays, with_stress: bool = True) -> tuple[str, ...]:
    """The curves a scene's report takes extrema of (``q``: flat face only; ``stress`` with a
    contact model; the roller curves at the drawing base radius for a roller)."""
    names = list(KINEMATIC_CURVES)
    if arrays.force_N is not None:
        names += LOAD_CURVES
        if scene.guide is not None:
            names += GUIDE_CURVES
    if scene.follower.type == "roller":
        names += ROLLER_CURVES
    if scene.follower.type == "flat":
        names.append("q")
    if with_stress and arrays.stress_coefficient is not None:
        names.append("stress")
    return tuple(names)


@runtime.program_cache(static_argnames=("names",))
def _refined_extremes(model: SceneModel, consts: CurveConstants, grid: jax.Array, base_radius_mm,
                      names: tuple[str, ...]):
    """Max and min of every named curve, refined off the grid ``grid`` (Q, N), in one program.

    One refinement per (curve, sense): the function refined is w . curves with w = +-e_q, so a
    single :func:`camjax.extrema.refine_max`, mapped over the rows w, covers them all.
    """
    count = len(names)

    def fn(segment, theta_deg, params):
        m, c, radius, w = params
        p = model_at(m, segment, theta_deg)
        return jnp.tensordot(w, jnp.stack([_curve(n, p, c, radius) for n in names]), axes=1)

    bounds = program.segment_bounds_deg(model.program)
    weights = jnp.concatenate([jnp.eye(count, dtype=grid.dtype), -jnp.eye(count, dtype=grid.dtype)])
    dwells = extrema_mod.dwells(model.program)  # every curve here is a function of the motion
    # one row at a time (lax.map, not vmap): the refinement is traced once and not batched again,
    # which costs far more time than the rows' sequential run saves
    e = jax.lax.map(lambda w: extrema_mod.refine_max(fn, (model, consts, base_radius_mm, w), bounds, w @ grid,
                                                     constant=dwells), weights)
    return e.value[:count], e.angle_deg[:count], -e.value[count:], e.angle_deg[count:]


def refined_extremes(model: SceneModel, consts: CurveConstants, grid_point: PointValues, base_radius_mm,
                     names: tuple[str, ...]):
    """(max, max_deg, min, min_deg), arrays of shape (len(names),), refined off the grid values
    ``grid_point``; traceable (``names`` static)."""
    grid = jnp.stack([_curve(n, grid_point, consts, base_radius_mm) for n in names])
    return _refined_extremes(model, consts, grid, base_radius_mm, names)


def curve_extremes(scene: Scene, arrays: SceneArrays, names: tuple[str, ...],
                   base_radius_mm: float | None = None, *, roller_radius_mm: float | None = None,
                   offset_mm: float | None = None) -> dict[str, Extremes]:
    """Max and min over the cam angle of each named curve (see :func:`curve_names`).

    Exact (refined off the grid, :mod:`camjax.extrema`) when the arrays carry their
    :class:`SceneModel`, else the samples' own (the first sample wins on ties). ``base_radius_mm``
    is where ``stress`` and the roller curves are taken (with a roller design's
    ``roller_radius_mm`` and ``offset_mm``; default the [follower]'s). Python (returns floats);
    the refinement itself is one jitted call.
    """
    radius = 0.0 if base_radius_mm is None else float(base_radius_mm)
    model, consts = arrays.model, curve_constants(scene, roller_radius_mm, offset_mm)
    grid_point = PointValues(arrays.kin, arrays.force_N, arrays.torque_Nm, arrays.stress_coefficient)
    grid = jnp.stack([_curve(n, grid_point, consts, radius) for n in names])
    if model is None:
        g, t = np.asarray(grid), np.asarray(arrays.theta_deg)
        i, j = np.argmax(g, axis=1), np.argmin(g, axis=1)
        rows = np.arange(len(names))
        hi, hi_deg, lo, lo_deg = g[rows, i], t[i], g[rows, j], t[j]
    else:
        consts = jax.tree_util.tree_map(lambda x: jnp.asarray(x, grid.dtype), consts)
        refined = _refined_extremes(model, consts, grid, radius, names)
        hi, hi_deg, lo, lo_deg = (np.asarray(a) for a in refined)
    return {n: Extremes(float(hi[k]), float(hi_deg[k]), float(lo[k]), float(lo_deg[k]))
            for k, n in enumerate(names)}
