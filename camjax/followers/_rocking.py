"""The rocking family: an arm swinging about a pivot, lifts in deg (rad inside), loads about the pivot.

:class:`RockingFollower` runs a scene's design for every rocking follower type, and each type (a
folder of :mod:`camjax.followers`) fills in its hooks: its smallest admissible cam with the scene's
pivot and arm (or face), the radii at which it closes, and its geometry and contact at one base
radius. The run, step by step:

1. the scene's [design] solved, if it has one; the cam is then sized and drawn with the design's
   pivot, arm (or face) and roller (while it solves, the drawing for the scene's own follower runs
   in a second thread, :func:`camjax.runtime.ahead`: the drawing's programs take those dimensions
   and the base radius as data, so the design's drawing finds them compiled);
2. :meth:`RockingFollower.sizing` finds the smallest admissible cam (a SceneError when none exists);
3. :meth:`RockingFollower.drawing_radius` picks the base radius the cam is drawn at (the option
   ``--base-radius``, else the design's, else the smallest admissible + 1 mm rounded up) and checks
   that the geometry closes there;
4. :meth:`RockingFollower.evaluate` computes the curves there (:class:`RockerCurves`): outline,
   pitch curve, pressure angle, curvature, the torque about the pivot, contact force, cam torque
   and Hertz stress; :func:`rocker_violations` the constraints they break.

Units: the motion program of a rocking follower is in rad (the scene's ``lift_deg``); the report
gives angles in degrees, lengths in mm, loads in SI.
"""

from __future__ import annotations

import abc
import math
from dataclasses import replace
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import extrema as extrema_mod
from camjax import loads, runtime
from camjax import program as program_mod
from camjax.errors import SceneError
from camjax.evaluate import SceneArrays, scene_arrays
from camjax.followers import _checks
from camjax.followers._contract import Follower
from camjax.loads import RockerTrain
from camjax.program import Kinematics
from camjax.results import Extremes, GeometryViolation
from camjax.scene.reader import DEFAULT, TableReader, build

DRAWING_MARGIN_MM = 1.0  # drawn at the smallest admissible base radius + this, rounded up
# Without a [design], the drawing's programs (the base radius is data) compile beside the sizing's,
# run at this base radius (mm) before the smallest is known: any radius compiles them.
PROVISIONAL_RADIUS_MM = 50.0
TRAIN_KEYS = ("inertia_kg_m2", "spring_N_m_per_rad", "preload_rad", "damping_N_m_s_per_rad")


def read_train(r: TableReader) -> RockerTrain | None:
    """The train about the pivot of a rocking [follower] (None: no loads are modelled)."""
    if r.has("inertia_kg_m2") or r.has("spring_N_m_per_rad"):
        return build(RockerTrain, inertia_kg_m2=r.number("inertia_kg_m2", DEFAULT, low=0.0),
                     spring_N_m_per_rad=r.number("spring_N_m_per_rad", DEFAULT, low=0.0),
                     preload_rad=r.number("preload_rad", DEFAULT),
                     damping_N_m_s_per_rad=r.number("damping_N_m_s_per_rad", DEFAULT, low=0.0))
    for key in ("preload_rad", "damping_N_m_s_per_rad"):
        if r.has(key):
            raise r.error(key, r.table[key], "needs inertia_kg_m2 or spring_N_m_per_rad (loads are off)")
    return None


class RockerSizing(NamedTuple):
    """Smallest admissible cam of a rocker follower (Python floats)."""

    min_base_radius_mm: float  # R_b (roller: R_p - R_f)
    min_prime_radius_mm: float | None  # roller only: R_p
    angle_deg: float  # cam angle where the binding limit is reached
    binding: str  # "pressure_angle", "undercut", "curvature" ("none": an infeasible design's own radius)


class RockerGeometry(NamedTuple):
    """A rocking follower's geometry at one base radius (per sample (N,) arrays, or scalars), and
    the dimensions :class:`RockerCurves` reports (None where the type has none; scalars, traced
    where the follower's dimensions are)."""

    profile_x_mm: Any  # cam outline, cam coordinates
    profile_y_mm: Any
    arm_angle: Any  # psi, rad
    arm_start_angle: Any  # psi0, rad
    pressure_angle: Any  # rad
    rho_mm: Any  # radius of curvature of the cam surface (convex > 0)
    pitch_x_mm: Any = None  # roller: pitch curve
    pitch_y_mm: Any = None
    pitch_rho_mm: Any = None
    pitch_curvature: Any = None  # 1/mm (the roller's contact stress)
    undercut_margin_mm: Any = None
    contact_distance_mm: Any = None  # flat face: contact point along the face from the pivot's foot
    arm_length_mm: float | None = None
    roller_radius_mm: float | None = None
    face_offset_mm: float | None = None
    prime_radius_mm: float | None = None
    pressure_angle_limit_deg: float | None = None


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
    follower_type: str  # the registered type (camjax.followers)
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
    # the follower's own per-sample curves, name -> (N,) (profile.csv columns after the shared ones):
    # a positive-drive closure's flanks or second cam, margins and loads (camjax.followers._closure)
    own_curves: dict[str, np.ndarray] | None = None
    closure: str = "spring"  # [follower] closure


class RockerRun(NamedTuple):
    """A rocker scene's run: its arrays, sizing, solved design, drawing radius, curves and the
    constraints the drawn geometry breaks."""

    sizing: RockerSizing
    base_radius_mm: float
    base_radius_source: str
    curves: RockerCurves
    arrays: SceneArrays | None = None
    design: dict[str, Any] | None = None  # the solver's JSON of the [design] (None without one)
    violations: tuple[GeometryViolation, ...] = ()
    # max/min of each of RockingFollower.point_curves at base_radius_mm (exact unless the scene
    # asks for grid extrema)
    extremes: dict[str, Extremes] | None = None


def _f(x) -> float:
    return float(np.asarray(x))


def rocker_violations(curves: RockerCurves, scene, extremes: dict[str, Extremes] | None = None
                      ) -> list[GeometryViolation]:
    """Constraints broken by a rocking follower's evaluated geometry (empty: usable geometry).

    Whatever curves the follower has are judged: |pressure angle| > its limit and undercut (a
    roller), cam-surface radius < ``follower.min_curvature_radius_mm`` (a face); with loads,
    contact force < 0; with a [design], peak stress > sigma_max. Tolerances are the solvers'
    (:mod:`camjax.followers._checks`). ``extremes`` (:meth:`RockingFollower.curve_extremes` at the
    curves' design): judged on them where they have the curve (exact extrema: the continuous ones,
    as the report states them), else on the samples.
    """
    t, out, ex = curves.theta_deg, [], extremes or {}
    at = _checks.worst_of(t, ex)

    if curves.undercut_margin_mm is not None:
        if "pressure_angle" in ex:  # rad in the extremes, deg in the checks
            e = ex["pressure_angle"]
            phi = max((math.degrees(e.max), e.max_deg), (-math.degrees(e.min), e.min_deg))
        else:
            phi = at(np.abs(curves.pressure_angle_deg), np.argmax)
        out += _checks.pressure_angle(*phi, curves.pressure_angle_limit_deg)
        out += _checks.undercut(*at(curves.undercut_margin_mm, np.argmin, "undercut_margin"))
    else:
        out += _checks.curvature(*at(curves.rho_mm, np.argmin, "rho"), scene.follower.min_curvature_radius_mm)
    if curves.stress_MPa is not None and scene.design is not None and scene.design.sigma_max_MPa:
        out += _checks.stress(*at(curves.stress_MPa, np.argmax, "stress", "max"), scene.design.sigma_max_MPa)
    # a positive drive's second contact (sampled): outer flank, or second cam
    out += _checks.closure(curves.own_curves or {}, t, curves.pressure_angle_limit_deg)
    if curves.contact_force_N is not None and curves.closure == "spring":  # positive drive: no spring to lose
        force, deg = at(curves.contact_force_N, np.argmin, "contact_force")
        if force < 0:
            out.append(GeometryViolation(
                "contact", f"contact force {force:.4g} N at {deg:g} deg < 0: the follower leaves the cam"))
    return out


def circle_arm_closure_problem(scene, kin, base_radius_mm: float, circle_radius_mm: float,
                               cannot_reach: str) -> str | None:
    """Why an arm carrying a circle of radius R (mm; the roller, the curved face's crown) cannot
    drive the cam at base radius R_b (mm), or None: the prime radius R_p = R_b + R must lie
    strictly between |d - l| and d + l (the circle reaches the prime circle) and the arm must stay
    off the line of centres while it swings (psi0 + max s < pi). ``cannot_reach`` opens the first
    message (e.g. "the roller cannot reach the prime circle R_p")."""
    f = scene.follower
    swing = float(np.max(np.asarray(kin.s)))
    if base_radius_mm <= 0:
        return "the base radius must be > 0"
    d, l, rp = f.pivot_distance_mm, f.arm_length_mm, base_radius_mm + circle_radius_mm
    if not abs(d - l) < rp < d + l:
        return (f"{cannot_reach} = {rp:g} mm: needs |d - l| = "
                f"{abs(d - l):g} < R_p < d + l = {d + l:g}")
    psi0 = math.acos((d * d + l * l - rp * rp) / (2 * d * l))
    if psi0 + swing >= math.pi:
        return (f"the arm starts {math.degrees(psi0):g} deg from the line of centres and the lift "
                f"({math.degrees(swing):g} deg) swings it through that line")
    return None


class _Motion(NamedTuple):
    rotation: str


class CurveScene(NamedTuple):
    """What :meth:`RockingFollower.point_curves` reads of a scene (its follower spec, [contact] and
    the cam's rotation), without the numbers a design varies: hashable and picklable, so that it
    keys a saved program that serves every design of the scene's follower."""

    follower: Any
    contact: Any
    motion: _Motion

    @classmethod
    def of(cls, scene, follower) -> CurveScene:
        """The scene's contact and rotation with ``follower`` (a spec whose design numbers are 0:
        :meth:`camjax.followers._contract.Follower.without_design_numbers`)."""
        return cls(follower, scene.contact, _Motion(scene.motion.rotation))


def _designed(drawn: CurveScene, numbers):
    """(the rocker type, ``drawn`` with the design's ``numbers`` (name -> value, traced or not))."""
    from camjax import followers

    return followers.get(drawn.follower.type), drawn._replace(follower=replace(drawn.follower, **numbers))


def _grid_curves(kin: Kinematics, speed, numbers, base_radius_mm, drawn: CurveScene, names: tuple[str, ...]):
    """(the rocker type, ``drawn`` with the design's ``numbers``, the named point curves on the grid
    of ``kin``, shape (Q, N))."""
    kind, drawn = _designed(drawn, numbers)
    curves = kind.point_curves(drawn, kin, speed, base_radius_mm)
    return kind, drawn, jnp.stack([curves[n] for n in names])


@partial(jax.jit, static_argnames=("drawn", "names"))
def _curve_grid_program(kin: Kinematics, speed, numbers, base_radius_mm, drawn: CurveScene,
                        names: tuple[str, ...]):
    """The named point curves on the grid of ``kin`` (Q, N) in one compiled call (see
    :func:`_refined_curves`; evaluated operation by operation, they compiled some fifty
    one-operation programs)."""
    return _grid_curves(kin, speed, numbers, base_radius_mm, drawn, names)[2]


# RockerGeometry's scalar fields (floats in RockerCurves)
_SCALARS = ("arm_length_mm", "roller_radius_mm", "face_offset_mm", "prime_radius_mm",
            "pressure_angle_limit_deg")


@partial(jax.jit, static_argnames="drawn")
def _drawing_arrays(kin: Kinematics, speed, numbers, base_radius_mm, drawn: CurveScene):
    """(geometry, pivot torque, cam torque, contact force, stress) of ``drawn``'s rocker with the
    design's ``numbers`` at one base radius, on the grid of ``kin``:
    :meth:`RockingFollower.evaluate`'s arrays in one compiled call (operation by operation they
    compiled some forty one-operation programs); None where the scene has no such curve."""
    kind, drawn = _designed(drawn, numbers)
    f = drawn.follower
    g = kind.geometry(drawn, kin, base_radius_mm)
    moment = force = torque = stress = None
    if f.train is not None:
        moment = loads.rocker_torque(f.train, kin, speed)
        torque = loads.rocker_cam_torque(moment, kin.ds)
        force, stress = kind.contact(drawn, moment, g)
    return g, moment, torque, force, stress


@runtime.program_cache(static_argnames=("drawn", "names"))
def _refined_curves(prog, speed, kin, numbers, base_radius_mm, drawn: CurveScene, names: tuple[str, ...]):
    """Max and min of the named point curves of ``drawn``'s rocker at one base radius (mm), refined
    off their values on the grid of the kinematics ``kin`` (computed here too) in one program
    (:func:`camjax.extrema.refine_curves`). ``numbers``: the follower's dimensions a design varies
    (name -> scalar array, :meth:`RockingFollower.design_numbers`), data like the base radius, so
    that one compiled program (and a saved one, :func:`camjax.runtime.program_cache`) serves every
    design of a scene's follower with the same curves."""
    kind, drawn, grid = _grid_curves(kin, speed, numbers, base_radius_mm, drawn, names)

    def stacked(segment, theta_deg, params):
        p, w = params
        c = kind.point_curves(drawn, program_mod.segment_motion(p, segment, theta_deg), w, base_radius_mm)
        return jnp.stack([c[n] for n in names])

    # every curve is a function of the motion: dwells are constant
    return extrema_mod.refine_curves(stacked, (prog, speed), program_mod.segment_bounds_deg(prog), grid,
                                     constant=extrema_mod.dwells(prog))


class RockingFollower(Follower):
    """An arm swinging about a pivot: the run every such type shares, and its hooks."""

    rocking = True

    # ---- hooks: the follower's physics

    @abc.abstractmethod
    def sizing(self, scene, kin: Kinematics, program=None) -> RockerSizing:
        """Smallest admissible cam of the scene's rocker (Python; SceneError when none exists): with
        ``program`` (the :class:`camjax.program.MotionProgram` behind ``kin``; exact extrema) its
        limits hold at every cam angle, else at the samples of ``kin``."""

    @abc.abstractmethod
    def closure_problem(self, scene, kin: Kinematics, base_radius_mm: float) -> str | None:
        """Why the rocker cannot run on a cam of this base radius (mm), or None when it can."""

    @abc.abstractmethod
    def geometry(self, scene, kin: Kinematics, base_radius_mm: float) -> RockerGeometry:
        """The geometry at one base radius with the scene's pivot and arm (or face)."""

    @abc.abstractmethod
    def contact(self, scene, moment, g: RockerGeometry) -> tuple[Any, Any]:
        """(normal contact force (N), Hertz stress (MPa) or None without [contact]) from the torque
        ``moment`` (N m) the cam applies about the pivot."""

    def closure_curves(self, scene, kin: Kinematics, base_radius_mm: float, g: RockerGeometry, moment):
        """The curves of a positive-drive closure (:mod:`camjax.followers._closure`) at one base radius,
        named as profile.csv's columns (``moment``: the pivot torque the follower needs, N m, or
        None); only called for a follower whose ``closures`` has one."""
        raise NotImplementedError(f"a {self.title} follower has no positive-drive closure")

    def drawn_follower(self, scene, result: dict):
        """The [follower] spec with a solved design's pivot, arm (or face) and roller (those the cam
        is drawn with; ``result``: the solver's JSON, empty without a design)."""
        dims = {k: result[k] for k in self.variables if k != "base_radius_mm" and k in result}
        closure = scene.follower.closure.designed(result)
        if closure is not scene.follower.closure:
            dims["closure"] = closure
        return replace(scene.follower, **dims) if dims else scene.follower

    # ---- the curves the report takes extrema of

    def point_curves(self, scene, kin: Kinematics, cam_speed_rad_s, base_radius_mm: float) -> dict[str, Any]:
        """The curves whose max and min the report states, at the angles of ``kin`` (any angles:
        grid samples or one segment's points), keyed by name.

        Functions of the motion (s, s', s'', s''') alone and pointwise, so that the same closed
        forms give the samples and the refined extrema: the motion (``s``, ``ds``, ``d2s``,
        ``d3s``; rad per rad^k), ``arm_angle`` and ``pressure_angle`` (rad), ``rho`` (cam surface,
        mm; none where the type has an undercut margin: a roller's cam radius has poles), what the
        type's geometry has of ``pitch_curvature`` (the pitch curve's, 1/mm),
        ``undercut_margin`` (mm) and ``contact_distance`` (along a face, mm), and with loads
        ``pivot_torque`` (N m), ``torque`` (cam shaft, N m), ``contact_force`` (N) and, with a
        [contact] section, ``stress`` (MPa).
        """
        g = self.geometry(scene, kin, base_radius_mm)
        out = {"s": kin.s, "ds": kin.ds, "d2s": kin.d2s, "d3s": kin.d3s, "arm_angle": g.arm_angle,
               "pressure_angle": g.pressure_angle}
        if g.undercut_margin_mm is None:
            out["rho"] = g.rho_mm
        else:  # a roller's cam radius passes through infinity at an inflection: its margin instead
            out["undercut_margin"] = g.undercut_margin_mm
        if g.pitch_curvature is not None:  # 1 / pitch-curve radius: finite where the radius is not
            out["pitch_curvature"] = g.pitch_curvature
        if g.contact_distance_mm is not None:
            out["contact_distance"] = g.contact_distance_mm
        if scene.follower.train is not None:
            moment = loads.rocker_torque(scene.follower.train, kin, cam_speed_rad_s)
            force, stress = self.contact(scene, moment, g)
            out.update(pivot_torque=moment, torque=loads.rocker_cam_torque(moment, kin.ds), contact_force=force)
            if stress is not None:
                out["stress"] = stress
        return {k: jnp.broadcast_to(v, jnp.shape(kin.s)) for k, v in out.items()}

    def curve_extremes(self, scene, arrays: SceneArrays, names: tuple[str, ...] | None,
                       base_radius_mm: float, follower=None) -> dict[str, Extremes]:
        """Max and min over the cam angle of each named curve of :meth:`point_curves` (all of them
        when ``names`` is None) at one base radius (mm), with ``follower`` (the [follower] spec the
        cam is drawn with; default the scene's).

        Exact (refined off the grid by :mod:`camjax.extrema`, in one compiled call) when the
        arrays carry their closed forms (``[motion] extrema = "exact"``), else the samples' own
        (the first sample wins on ties). Python: returns floats.
        """
        drawn = scene if follower is None or follower is scene.follower else replace(scene, follower=follower)
        radius, speed = float(base_radius_mm), arrays.cam_speed_rad_s
        if names is None:  # every curve: their names without computing them
            names = tuple(jax.eval_shape(lambda k: self.point_curves(drawn, k, speed, radius), arrays.kin))
        names = tuple(names)
        as_ = lambda v: jnp.asarray(v, arrays.kin.s.dtype)  # noqa: E731
        static, numbers = self.without_design_numbers(drawn.follower)
        numbers = {k: as_(v) for k, v in numbers.items()}
        curve_scene = CurveScene.of(drawn, static)
        if arrays.model is None:
            grid = _curve_grid_program(arrays.kin, as_(speed), numbers, as_(radius), drawn=curve_scene, names=names)
            extremes = extrema_mod.sampled_extremes(grid, arrays.theta_deg)
        else:
            extremes = _refined_curves(arrays.model.program, as_(speed), arrays.kin, numbers, as_(radius),
                                       drawn=curve_scene, names=names)
        hi, hi_deg, lo, lo_deg = (np.asarray(a) for a in extremes)
        return {n: Extremes(float(hi[k]), float(hi_deg[k]), float(lo[k]), float(lo_deg[k]))
                for k, n in enumerate(names)}

    # ---- the run

    def drawing_radius(self, scene, kin: Kinematics, sizing: RockerSizing,
                       override_mm: float | None = None) -> tuple[float, str]:
        """Base radius (mm) the rocker cam is evaluated and drawn at, and where it comes from.

        The option wins (and must close, else a SceneError naming ``--base-radius``); otherwise the
        smallest admissible + 1 mm rounded up, or the smallest itself where that would not close.
        """
        if override_mm is not None:
            why = self.closure_problem(scene, kin, float(override_mm))
            if why is not None:
                raise SceneError("--base-radius", float(override_mm), why)
            return float(override_mm), "option --base-radius"
        r = float(math.ceil(max(sizing.min_base_radius_mm, 0.0) + DRAWING_MARGIN_MM))
        if self.closure_problem(scene, kin, r) is None:
            return r, f"smallest admissible + {DRAWING_MARGIN_MM:g} mm, rounded up to whole mm"
        return sizing.min_base_radius_mm, "smallest admissible"

    def evaluate(self, scene, kin: Kinematics, cam_speed_rad_s, base_radius_mm: float) -> RockerCurves:
        """Outline, pressure angle, curvature, loads and stress of the scene's rocker at one base radius."""
        f, rotation, w = scene.follower, scene.motion.rotation, cam_speed_rad_s
        as_ = lambda v: jnp.asarray(v, kin.s.dtype)  # noqa: E731
        static, numbers = self.without_design_numbers(f)
        g, moment, torque, force, stress = jax.device_get(_drawing_arrays(
            kin, as_(w), {k: as_(v) for k, v in numbers.items()}, as_(base_radius_mm),
            drawn=CurveScene.of(scene, static)))
        g = g._replace(**{k: None if v is None else float(v) for k, v in g._asdict().items() if k in _SCALARS})
        own = None
        if f.closure.positive:  # (NumPy inside: not traceable)
            own = {k: np.asarray(v) for k, v in self.closure_curves(scene, kin, base_radius_mm, g, moment).items()}
        arr = lambda v: None if v is None else np.asarray(v)  # noqa: E731
        num = lambda v: None if v is None else _f(v)  # noqa: E731
        wf = float(w)  # the rates in NumPy (w^2, w^3 multiplied out as XLA's integer powers are)
        return RockerCurves(
            theta_deg=np.degrees(np.asarray(kin.theta)), swing_deg=np.degrees(np.asarray(kin.s)),
            ds=np.asarray(kin.ds), d2s=np.asarray(kin.d2s),
            angular_velocity_rad_s=np.asarray(kin.ds) * wf,
            angular_accel_rad_s2=np.asarray(kin.d2s) * (wf * wf),
            angular_jerk_rad_s3=np.asarray(kin.d3s) * (wf * (wf * wf)),
            segment_starts_deg=scene.motion.program.start_deg, follower_type=self.name, rotation=rotation,
            pivot_distance_mm=f.pivot_distance_mm, arm_length_mm=g.arm_length_mm,
            roller_radius_mm=g.roller_radius_mm, face_offset_mm=g.face_offset_mm,
            base_radius_mm=float(base_radius_mm), prime_radius_mm=num(g.prime_radius_mm),
            arm_start_angle_deg=_f(np.degrees(g.arm_start_angle)),
            arm_angle_deg=np.degrees(np.asarray(g.arm_angle)), profile_x_mm=np.asarray(g.profile_x_mm),
            profile_y_mm=np.asarray(g.profile_y_mm), pitch_x_mm=arr(g.pitch_x_mm), pitch_y_mm=arr(g.pitch_y_mm),
            pressure_angle_deg=np.degrees(np.asarray(g.pressure_angle)), rho_mm=np.asarray(g.rho_mm),
            pitch_rho_mm=arr(g.pitch_rho_mm), undercut_margin_mm=arr(g.undercut_margin_mm),
            contact_distance_mm=arr(g.contact_distance_mm), pivot_torque_Nm=arr(moment),
            contact_force_N=arr(force), torque_Nm=arr(torque), stress_MPa=arr(stress),
            pressure_angle_limit_deg=g.pressure_angle_limit_deg, own_curves=own, closure=f.closure.kind,
        )

    def run(self, scene, arrays: SceneArrays | None = None, *, base_radius_mm: float | None = None,
            dtype=None) -> RockerRun:
        """Design, sizing, drawing radius, curves and violations of a rocker scene (see the module
        docstring; Python: may raise SceneError)."""
        arrays = scene_arrays(scene, dtype=dtype) if arrays is None else arrays
        if scene.design is None:
            return self._drawn_run(scene, arrays, None, base_radius_mm)
        from camjax.followers._design import design_block
        from camjax.solvers.base import problem_from_scene

        # the drawing's programs compiled beside the solver's, for the scene's own follower: they
        # take the design's dimensions and base radius as data (:meth:`design_numbers`)
        with runtime.ahead(lambda: self._drawn_run(scene, arrays, None, base_radius_mm)):
            design, _ = design_block(scene, problem_from_scene(scene, arrays))
        return self._drawn_run(scene, arrays, design, base_radius_mm)

    def _drawn_run(self, scene, arrays: SceneArrays, design: dict | None,
                   base_radius_mm: float | None) -> RockerRun:
        """The run's sizing, drawing radius, curves and violations for a solved ``design`` (the
        solver's JSON), or None: the scene's follower, drawn at ``base_radius_mm`` or its smallest
        cam + 1 mm."""
        kin, drawn = arrays.kin, scene
        program = None if arrays.model is None else arrays.model.program
        if design is not None:
            # the cam is sized and drawn with the design's pivot, arm (or face) and roller
            drawn = replace(scene, follower=self.drawn_follower(scene, design))
            try:
                sizing = self.sizing(drawn, kin, program)
            except SceneError:  # an infeasible design: its own radius is all there is to report
                sizing = RockerSizing(design["base_radius_mm"], design.get("prime_radius_mm"), 0.0, "none")
            if base_radius_mm is None:
                radius, source = design["base_radius_mm"], "design"
            else:
                radius, source = self.drawing_radius(drawn, kin, sizing, base_radius_mm)
        else:
            # the drawing's programs compiled beside the sizing's (:func:`camjax.runtime.ahead`)
            with runtime.ahead(lambda: self._at_radius(scene, arrays, PROVISIONAL_RADIUS_MM)):
                sizing = self.sizing(scene, kin, program)
            radius, source = self.drawing_radius(scene, kin, sizing, base_radius_mm)
        curves, extremes = self._at_radius(drawn, arrays, radius)
        return RockerRun(sizing, radius, source, curves, arrays, design,
                         tuple(rocker_violations(curves, scene, extremes)), extremes)

    def _at_radius(self, drawn, arrays: SceneArrays, radius: float):
        """(curves, extremes) of the cam of the scene ``drawn`` (its follower the one the cam is
        drawn with) at base radius ``radius`` (mm)."""
        return (self.evaluate(drawn, arrays.kin, arrays.cam_speed_rad_s, radius),
                self.curve_extremes(drawn, arrays, None, radius))
