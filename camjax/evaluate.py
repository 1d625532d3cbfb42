"""Scene -> arrays -> curves: what a scene's models give, and what plots and export read.

:func:`scene_arrays` computes the design-independent arrays once per scene. Only what the scene
declares is computed: a scene without loads gets no force, one without [contact] no stress
coefficient. Everything downstream (geometry at a trial base radius, the objective, the report)
reads from :class:`SceneArrays`; each follower type adds its geometry at one design
(:mod:`camjax.followers`). :func:`curve_extremes` takes the max and min over the cam angle of the
motion's, the loads' and the follower's curves, refined off the grid.
"""

from __future__ import annotations

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, followers, loads, program, runtime
from camjax import extrema as extrema_mod
from camjax.contact import Material
from camjax.loads import FollowerTrain, Guide
from camjax.program import Kinematics, MotionProgram, TimeKinematics
from camjax.results import Extremes
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
    # a rocker's loads are its follower's (camjax.followers._rocking), not a translating train's
    train = None if followers.of(scene).rocking else scene.follower.train
    return SceneModel(
        as_(scene.motion.program), jnp.asarray(program.rpm_to_rad_s(scene.motion.rpm), dtype),
        None if train is None else as_(train),
        None if c is None or train is None else jnp.asarray(c.cam_width_mm, dtype),
        None if c is None or train is None else as_(c.cam),
        None if c is None or train is None else as_(c.follower))


def model_at(model: SceneModel, segment, theta_deg: jax.Array) -> PointValues:
    """Kinematics, force, torque and stress coefficient on segment ``segment`` (an int, or an
    integer array of shape (): :func:`camjax.program.segment_motion`) at cam angles ``theta_deg``
    (deg, inside the segment; its ends give one-sided limits)."""
    kin = program.segment_motion(model.program, segment, theta_deg)
    return PointValues(kin, *_loads(model, kin, program.time_kinematics(kin, model.cam_speed_rad_s)))


def _loads(model: SceneModel, kin: Kinematics, motion: TimeKinematics):
    """(force N, cam torque N m, stress coefficient) of the model's train and [contact] at the
    kinematics ``kin`` (any shape; ``motion``: at the model's speed), None where not declared."""
    force = torque = coeff = None
    if model.train is not None:
        force = loads.kinetostatic_force(model.train, motion)
        torque = loads.cam_torque(force, kin.ds)
        if model.cam_width_mm is not None:
            coeff = contact.stress_coefficient(force, model.cam_width_mm, model.cam, model.follower)
    return force, torque, coeff


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
    # one compiled call for the whole grid, the scene's numbers its data (:func:`scene_model`): one
    # program for every scene of the same laws, declared models and grid size
    model = scene_model(scene, dtype)
    arrays = _grid_arrays(model, n)
    return arrays._replace(model=model if mode == "exact" else None)


@partial(jax.jit, static_argnames="n")
def _grid_arrays(model: SceneModel, n: int) -> SceneArrays:
    return _arrays_of(model, program.evaluate(model.program, n))


def arrays_from_kinematics(scene: Scene, kin: Kinematics) -> SceneArrays:
    """The scene's arrays (loads, contact coefficient) for the kinematics ``kin`` on the grid of
    ``len(kin.s)`` samples instead of its program's: traceable in ``kin`` (law co-design builds
    them from kinematics linear in a law's control values). Extrema on the grid (no model)."""
    return _arrays_of(scene_model(scene, kin.s.dtype), kin)


def _arrays_of(model: SceneModel, kin: Kinematics) -> SceneArrays:
    """The grid arrays of the model's loads and contact at the kinematics ``kin`` (shape (N,))."""
    motion = program.time_kinematics(kin, model.cam_speed_rad_s)
    theta_deg = program.sample_angles_deg(kin.s.shape[-1], kin.s.dtype)
    return SceneArrays(theta_deg, kin, motion, model.cam_speed_rad_s, *_loads(model, kin, motion))


# ------------------------------------------------------------------------------ extrema

KINEMATIC_CURVES = ("s", "ds", "d2s", "d3s")  # mm, mm/rad, mm/rad^2, mm/rad^3
LOAD_CURVES = ("force", "torque")  # N, N m


class CurveConstants(NamedTuple):
    """Scene constants the curves need besides the motion (a pytree; None where not declared)."""

    guide: Guide | None
    follower: Any  # the follower's own (its curve_constants), e.g. a roller's R_f and offset


def curve_constants(scene: Scene, follower=None) -> CurveConstants:
    """The guide and the follower's constants of a scene; ``follower``: the [follower] spec the cam
    is drawn with (a design's dimensions; default the scene's)."""
    spec = scene.follower if follower is None else follower
    return CurveConstants(scene.guide, followers.of(scene).curve_constants(scene, spec))


def _curve(name: str, p: PointValues, consts: CurveConstants, base_radius_mm, follower: str) -> jax.Array:
    """One named curve from the point values (grid arrays or closed-form points alike): the motion's
    and the loads' here, the follower type's own (and ``stress``) from its follower."""
    if name in KINEMATIC_CURVES:
        return getattr(p.kin, name)
    if name == "force":
        return p.force_N
    if name == "torque":
        return p.torque_Nm
    return followers.get(follower).curve(name, p, consts, base_radius_mm)


def curve_names(scene: Scene, arrays: SceneArrays, with_stress: bool = True) -> tuple[str, ...]:
    """The curves a scene's report takes extrema of: the motion's, the loads' when declared, the
    follower's own (a flat face's guide reactions among them), and ``stress`` with a contact
    model (unless ``with_stress`` is False)."""
    names = list(KINEMATIC_CURVES)
    if arrays.force_N is not None:
        names += LOAD_CURVES
    names += followers.of(scene).curve_names(scene, arrays)
    if with_stress and arrays.stress_coefficient is not None:
        names.append("stress")
    return tuple(names)


def _curve_grid(grid_point: PointValues, consts: CurveConstants, base_radius_mm, names: tuple[str, ...],
                follower: str) -> jax.Array:
    """The named curves on the grid, shape (len(names), N)."""
    return jnp.stack([_curve(n, grid_point, consts, base_radius_mm, follower) for n in names])


# the grid's curves in one compiled call (operation by operation, a report's curves compiled some
# thirty one-operation programs)
_curve_grid_program = jax.jit(_curve_grid, static_argnames=("names", "follower"))


@runtime.program_cache(static_argnames=("names", "follower"))
def _refined_extremes(model: SceneModel, consts: CurveConstants, grid_point: PointValues, base_radius_mm,
                      names: tuple[str, ...], follower: str):
    """Max and min of every named curve, refined off its values at the grid's point values
    ``grid_point`` (the curves computed here too: one program, no operation by operation), in one
    program (:func:`camjax.extrema.refine_curves`)."""
    grid = _curve_grid(grid_point, consts, base_radius_mm, names, follower)

    def curves(segment, theta_deg, params):
        m, c, radius = params
        p = model_at(m, segment, theta_deg)
        return jnp.stack([_curve(n, p, c, radius, follower) for n in names])

    # every curve here is a function of the motion: dwells are constant
    return extrema_mod.refine_curves(curves, (model, consts, base_radius_mm), program.segment_bounds_deg(model.program),
                                     grid, constant=extrema_mod.dwells(model.program))


def refined_extremes(model: SceneModel, consts: CurveConstants, grid_point: PointValues, base_radius_mm,
                     names: tuple[str, ...], follower: str):
    """(max, max_deg, min, min_deg), arrays of shape (len(names),), refined off the grid values
    ``grid_point``; traceable (``names`` and the follower type ``follower`` static)."""
    return _refined_extremes(model, consts, grid_point, base_radius_mm, names, follower)


def curve_extremes(scene: Scene, arrays: SceneArrays, names: tuple[str, ...],
                   base_radius_mm: float | None = None, *, follower=None) -> dict[str, Extremes]:
    """Max and min over the cam angle of each named curve (see :func:`curve_names`).

    Exact (refined off the grid, :mod:`camjax.extrema`) when the arrays carry their
    :class:`SceneModel`, else the samples' own (the first sample wins on ties). ``base_radius_mm``
    is where ``stress`` and the follower's curves are taken, with ``follower`` (the [follower]
    spec the cam is drawn with: a design's dimensions; default the scene's). Python (returns
    floats); the refinement itself is one jitted call.
    """
    radius = 0.0 if base_radius_mm is None else float(base_radius_mm)
    kind = followers.of(scene)
    if kind.rocking:  # its curves are its geometry's and its loads' about the pivot
        return kind.curve_extremes(scene, arrays, names, radius, follower)
    model, consts = arrays.model, curve_constants(scene, follower)
    grid_point = PointValues(arrays.kin, arrays.force_N, arrays.torque_Nm, arrays.stress_coefficient)
    if model is None:
        grid = _curve_grid_program(grid_point, consts, radius, tuple(names), scene.follower.type)
        hi, hi_deg, lo, lo_deg = extrema_mod.sampled_extremes(grid, arrays.theta_deg)
        rows = range(len(names))
    else:
        # the report's curves and the follower's sizing curves are refined in one program (a
        # row of it is that curve's own refinement): one compile per run, not one per set
        report = curve_names(scene, arrays)
        shared = tuple(names) == report or set(names) <= set(kind.sizing_curves)
        program_names = (*report, *kind.sizing_curves) if shared else names
        dtype = arrays.kin.s.dtype
        consts = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), consts)
        refined = _refined_extremes(model, consts, grid_point, jnp.asarray(radius, dtype), program_names,
                                    scene.follower.type)
        hi, hi_deg, lo, lo_deg = (np.asarray(a) for a in refined)
        rows = [program_names.index(n) for n in names]
    return {n: Extremes(float(hi[k]), float(hi_deg[k]), float(lo[k]), float(lo_deg[k]))
            for k, n in zip(rows, names, strict=True)}
