"""The translating family: a follower sliding along its axis, lifts in mm, loads of a lumped train.

:class:`TranslatingFollower` runs a scene's design for every translating follower type, and each
type (a folder of :mod:`camjax.followers`) fills in its hooks: its smallest admissible cam, the
figures its solved design reports, its geometry at one base radius and the curves its report takes
the extrema of. The run, step by step:

1. the scene's [design] solved (:meth:`TranslatingFollower.solve_design`), if it has one;
2. the smallest admissible base radius for the follower the cam is drawn with (a design's
   dimensions, else the [follower]'s; :meth:`TranslatingFollower.min_base_radius`);
3. the drawing radius (:func:`drawing_base_radius`), the extrema of every curve there
   (:func:`camjax.evaluate.curve_extremes`, exact unless the scene asks for the samples'), and the
   curves (:meth:`TranslatingFollower.curves`, a :class:`DesignCurves`);
4. the constraints the drawn geometry breaks (:func:`geometry_violations`).
"""

from __future__ import annotations

import abc
import functools
import math
from dataclasses import replace
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import loads, runtime
from camjax.evaluate import SceneArrays, curve_extremes, curve_names, scene_arrays
from camjax.family import FEASIBILITY_TOL_MM
from camjax.followers import _checks
from camjax.followers._checks import least_abs_offset as least_abs_offset  # re-exported
from camjax.followers._contract import Follower
from camjax.loads import FollowerTrain
from camjax.program import TimeKinematics
from camjax.results import Extremes, GeometryViolation, MinBaseRadius
from camjax.scene.reader import DEFAULT, TableReader, build

DRAWING_MARGIN_MM = 1.0  # without a [design], draw at the smallest admissible R_b + this, rounded up
# Without a [design], the drawing's programs (the base radius is data) compile beside the smallest
# cam's, run at this base radius (mm) before the smallest is known: any radius compiles them.
PROVISIONAL_RADIUS_MM = 50.0
TRAIN_KEYS = ("mass_kg", "spring_N_per_m", "preload_mm", "damping_Ns_per_m", "gravity_m_s2")


def _f(x) -> float:
    """A scalar as a Python float (JSON)."""
    return float(np.asarray(x))


def read_train(r: TableReader) -> FollowerTrain | None:
    """The lumped follower train of a translating [follower] (None: no loads are modelled)."""
    if r.has("mass_kg") or r.has("spring_N_per_m"):
        return build(
            FollowerTrain,
            mass_kg=r.number("mass_kg", DEFAULT, low=0.0),
            spring_N_per_m=r.number("spring_N_per_m", DEFAULT, low=0.0),
            preload_mm=r.number("preload_mm", DEFAULT),
            damping_Ns_per_m=r.number("damping_Ns_per_m", DEFAULT, low=0.0),
            gravity_m_s2=r.number("gravity_m_s2", DEFAULT),
        )
    for key in ("preload_mm", "damping_Ns_per_m", "gravity_m_s2"):
        if r.has(key):
            raise r.error(key, r.table[key], "needs mass_kg or spring_N_per_m (loads are off)")
    return None


# ------------------------------------------------------------------------------ curves


class GeometryCurves(NamedTuple):
    """A follower's geometry at one base radius, per sample (None where the type has none)."""

    profile_x_mm: jax.Array  # cam outline, cam coordinates
    profile_y_mm: jax.Array
    rho_mm: jax.Array | None = None  # flat face: radius of curvature of the cam profile
    stress_MPa: jax.Array | None = None  # Hertz contact stress (with [contact])
    face_width_mm: jax.Array | None = None  # flat face: 2 max|s'| on the samples
    pitch_x_mm: jax.Array | None = None  # pitch curve (the roller's centre)
    pitch_y_mm: jax.Array | None = None
    pressure_angle_deg: jax.Array | None = None
    pitch_rho_mm: jax.Array | None = None
    undercut_margin_mm: jax.Array | None = None  # rho_c - min radius on convex parts (float max on concave)
    own_curves: dict[str, jax.Array] | None = None  # the follower's own curves (see DesignCurves)


class DesignCurves(NamedTuple):
    """Everything plots and export need at one design, as NumPy arrays of shape (N,) or scalars.

    Optional entries are None when the scene does not ask for the model or the follower type has
    none.
    """

    theta_deg: np.ndarray  # cam angle, deg
    s_mm: np.ndarray
    ds_mm: np.ndarray  # mm/rad
    d2s_mm: np.ndarray  # mm/rad^2
    velocity_m_s: np.ndarray
    accel_m_s2: np.ndarray
    jerk_m_s3: np.ndarray
    segment_starts_deg: tuple[float, ...]
    follower_type: str  # the registered type (camjax.followers)
    base_radius_mm: float
    face_width_mm: float | None  # flat face only
    profile_x_mm: np.ndarray  # cam outline, cam coordinates (camjax.followers._pitch convention)
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
    # the follower's own per-sample curves, name -> (N,) (profile.csv columns after the shared ones);
    # "face_travel_mm", where the contact sits on the face off its axis, is what the face width must
    # cover (a crowned face's R_c sin phi; without it, a flat face's s')
    own_curves: dict[str, np.ndarray] | None = None
    closure: str = "spring"  # [follower] closure: "groove" and "conjugate" add their curves to own_curves


def _np(x):
    return None if x is None else np.asarray(x)


# -------------------------------------------------------------------------------- run


class DesignSolution(NamedTuple):
    """The solved design of a scene's [design] and the figures the report states beside it."""

    result: dict[str, Any]  # the solver's JSON (camjax.solvers.base.Solution.to_json)
    peak_stress_MPa: float | None  # the design's peak stress, computed exactly as the stress curve
    required_base_radius_mm: float  # smallest admissible R_b (flat: over angles; roller: at R_f, e)
    required_base_radius_deg: float  # where it binds
    binding_constraint: str  # flat: "stress" or "curvature"; roller: "pressure_angle" or "undercut"
    required_face_width_mm: float | None  # flat face only
    rho_min_limit_mm: float  # the problem's smallest allowed radius of curvature


class DesignRun(NamedTuple):
    """Everything a scene's design run computed, typed (the follower's report formats it)."""

    arrays: SceneArrays
    min_base_radius: MinBaseRadius
    design: DesignSolution | None  # None without a [design]
    base_radius_mm: float  # where the curves are evaluated and drawn
    base_radius_source: str  # why that radius
    curves: DesignCurves
    violations: tuple[GeometryViolation, ...] = ()  # constraints the drawn geometry breaks (empty: usable)
    # max/min of each of evaluate.curve_names, stress and the follower's curves at base_radius_mm
    # (exact unless the scene asks for grid extrema); defaulted because it follows the violations
    extremes: dict[str, Extremes] | None = None


def drawing_base_radius(design: DesignSolution | None, min_base_radius_mm: float,
                        override_mm: float | None = None) -> tuple[float, str]:
    """Base radius (mm) the geometry is evaluated and drawn at, and where it comes from."""
    if override_mm is not None:
        return float(override_mm), "option --base-radius"
    if design is not None:
        return design.result["base_radius_mm"], "design"
    r = float(math.ceil(max(min_base_radius_mm, 0.0) + DRAWING_MARGIN_MM))
    return r, f"smallest admissible + {DRAWING_MARGIN_MM:g} mm, rounded up to whole mm"


def geometry_violations(curves: DesignCurves, rho_min_mm: float = 0.0,
                        extremes: dict[str, Extremes] | None = None) -> list[GeometryViolation]:
    """Constraints broken by the geometry at the evaluated base radius (empty: usable geometry).

    Whatever curves the follower has are judged: rho < ``rho_min_mm`` (the profile cannot be
    followed; below 0 it crosses itself), peak stress > sigma_max (with a [design]), a face
    narrower than 2 max|s'|, |pressure angle| > the limit, undercut; with loads, a contact force
    < 0 (the follower leaves the cam). Tolerances are the solvers' (:mod:`camjax.followers._checks`).

    ``extremes`` (:func:`camjax.evaluate.curve_extremes` at the curves' design): rho, stress, face
    width, pressure angle (``pressure_angle``, rad), undercut (``undercut_margin``) and force are
    judged on them (exact extrema: the continuous ones, as the report states them and as the
    design problems' polish keeps them, :mod:`camjax.followers._polish`).
    """
    t, out, ex = curves.theta_deg, [], extremes or {}
    at = _checks.worst_of(t, ex)

    if curves.rho_mm is not None:
        rho, deg = at(curves.rho_mm, np.argmin)
        if "q" in ex:  # rho = R_b + q
            rho, deg = curves.base_radius_mm + ex["q"].min, ex["q"].min_deg
        out += _checks.curvature(rho, deg, rho_min_mm)
    if curves.stress_MPa is not None and curves.sigma_max_MPa is not None:
        out += _checks.stress(*at(curves.stress_MPa, np.argmax, "stress", "max"), curves.sigma_max_MPa)
    if curves.face_width_mm is not None:
        travel, name = (curves.own_curves or {}).get("face_travel_mm"), "face_travel"
        if travel is None:  # a flat face: the contact sits s' off the axis
            travel, name = curves.ds_mm, "ds"
        need = 2.0 * (max(ex[name].max, -ex[name].min) if name in ex else float(np.max(np.abs(travel))))
        if curves.face_width_mm < need - FEASIBILITY_TOL_MM:
            what = "max|s'|" if name == "ds" else "max|R_c sin phi|"
            out.append(GeometryViolation(
                "face_width", f"face width {curves.face_width_mm:.4g} mm < 2 {what} = {need:.4g} mm: "
                "the contact runs off the face"))
    if curves.pressure_angle_deg is not None:
        if "pressure_angle" in ex:  # rad, signed: the larger of max phi and -min phi
            e = ex["pressure_angle"]
            phi = (math.degrees(e.max), e.max_deg) if e.max >= -e.min else (math.degrees(-e.min), e.min_deg)
        else:
            phi = at(np.abs(curves.pressure_angle_deg), np.argmax)
        out += _checks.pressure_angle(*phi, curves.pressure_angle_limit_deg)
    if curves.undercut_margin_mm is not None:
        out += _checks.undercut(*at(curves.undercut_margin_mm, np.argmin, "undercut_margin"))
    # a positive drive's second contact (sampled): outer flank, or second cam
    out += _checks.closure(curves.own_curves or {}, t, curves.pressure_angle_limit_deg)
    if curves.force_N is not None and curves.closure == "spring":  # positive drive: no spring to lose
        force, deg = at(curves.force_N, np.argmin, "force")
        if force < 0:
            lost = float(np.mean(curves.force_N < 0)) * 360.0
            out.append(GeometryViolation(
                "contact", f"contact force {force:.4g} N at {deg:g} deg < 0 (over about {lost:.3g} deg): "
                "the follower leaves the cam"))
    return out


# --------------------------------------------------------------------------- the family


class TranslatingFollower(Follower):
    """A follower that slides along its axis: the run every such type shares, and its hooks."""

    rocking = False

    # ---- hooks: the follower's physics

    @abc.abstractmethod
    def min_base_radius(self, scene, arrays: SceneArrays) -> MinBaseRadius:
        """Smallest admissible base radius (mm) of the scene's follower and where it binds."""

    @abc.abstractmethod
    def design_solution(self, scene, arrays: SceneArrays, result: dict, problem) -> DesignSolution:
        """The report's figures beside a solved design (``result``: the solver's JSON)."""

    @abc.abstractmethod
    def geometry(self, follower, rotation: str, arrays: SceneArrays, base_radius_mm) -> GeometryCurves:
        """The geometry at one base radius (traced; so are the follower's :meth:`design_numbers`)."""

    def drawn_follower(self, scene, result: dict):
        """The [follower] spec with a solved design's dimensions (those the cam is drawn with);
        default: the scene's own."""
        return scene.follower

    def curve_dimensions(self, follower) -> tuple[float | None, float | None, float | None]:
        """(radius, offset, pressure-angle limit) of the follower for :class:`DesignCurves`
        (``roller_radius_mm``, ``offset_mm``, ``pressure_angle_limit_deg``); default none."""
        return None, None, None

    def design_face_width(self, result: dict, extremes: dict[str, Extremes]) -> float | None:
        """The face width (mm) a run draws (a flat face: the design's, else what the motion needs);
        default: none."""
        return None

    def drawn_face_width(self, face_width_mm: float | None, geometry_width) -> float | None:
        """The face width (mm) of the curves: the one given, else the geometry's (a flat face);
        default: none."""
        return None

    def closure_curves(self, scene, arrays: SceneArrays, base_radius_mm, follower, geometry: GeometryCurves):
        """The curves of a positive-drive closure (:mod:`camjax.followers._closure`) at one base radius,
        named as profile.csv's columns; only called for a follower whose ``closures`` has one."""
        raise NotImplementedError(f"a {self.title} follower has no positive-drive closure")

    def curve_names(self, scene, arrays: SceneArrays) -> tuple[str, ...]:
        """Names of the follower's own curves whose extrema the report takes (see :meth:`curve`)."""
        return ()

    # curves (see :meth:`curve`) whose extrema the follower's sizing takes besides the report's:
    # refined in the report's program (:func:`camjax.evaluate.curve_extremes`), so that a run
    # compiles one refinement, not one per set of names
    sizing_curves: tuple[str, ...] = ()

    def curve_constants(self, scene, follower):
        """A pytree of the constants :meth:`curve` needs besides the motion (None: none)."""
        return None

    def curve(self, name: str, p, consts, base_radius_mm) -> jax.Array:
        """One of the follower's own curves from point values ``p``
        (:class:`camjax.evaluate.PointValues`), traceable (the exact extrema refine it)."""
        raise ValueError(f"curve: unknown name '{name}' for a {self.name} follower")

    # ---- the run

    def solve_design(self, scene, arrays: SceneArrays) -> DesignSolution | None:
        """The optimized design of a scene with a [design] section; None without one.

        Solved by :func:`camjax.followers._design.design_block` (the solver registry's
        :func:`camjax.solvers.base.solve` with the scene's mode, alpha, gamma, solver and seed, or
        the robust design of ``[design] robust``; keys of
        :meth:`camjax.solvers.base.Solution.to_json`: mode, solver, the design variables,
        objective, feasible, violated, iterations, ..., and in pointwise mode the angles and
        per-angle ``pointwise`` arrays).
        """
        if scene.design is None:
            return None
        from camjax.followers._design import design_block
        from camjax.solvers.base import problem_from_scene

        out, problem = design_block(scene, problem_from_scene(scene, arrays))
        return self.design_solution(scene, arrays, out, problem)

    def curves(self, scene, arrays: SceneArrays, base_radius_mm: float, follower=None,
               face_width_mm: float | None = None) -> DesignCurves:
        """Geometry, stress and the follower's quantities at one design (mm), as NumPy arrays.

        ``follower``: the [follower] spec with the design's dimensions (default the scene's).
        Outlines follow the scene's ``motion.rotation`` (a cw cam is the mirror image of ccw). The
        geometry is one compiled call for every design of a follower: the dimensions a design
        varies (:meth:`design_numbers`) and the base radius are its data.
        """
        follower = scene.follower if follower is None else follower
        rot = scene.motion.rotation
        static, numbers = self.without_design_numbers(follower)
        as_ = lambda v: jnp.asarray(v, arrays.kin.s.dtype)  # noqa: E731
        g = _geometry_program(self.name, static, rot)(
            arrays, as_(base_radius_mm), {k: as_(v) for k, v in numbers.items()})
        face_width_mm = self.drawn_face_width(face_width_mm, g.face_width_mm)
        own = g.own_curves
        if follower.closure.positive:
            own = {**(own or {}), **self.closure_curves(scene, arrays, base_radius_mm, follower, g)}
        radius, offset, limit = self.curve_dimensions(follower)
        kin, m = arrays.kin, arrays.motion
        parts = None
        if follower.train is not None and arrays.force_N is not None:
            numpy_motion = TimeKinematics(*(np.asarray(v) for v in m))
            parts = loads.force_parts(follower.train, numpy_motion)._asdict()
        return DesignCurves(
            np.asarray(arrays.theta_deg), np.asarray(kin.s), np.asarray(kin.ds), np.asarray(kin.d2s),
            np.asarray(m.velocity), np.asarray(m.accel), np.asarray(m.jerk),
            scene.motion.program.start_deg, self.name, float(base_radius_mm),
            None if face_width_mm is None else float(face_width_mm),
            np.asarray(g.profile_x_mm), np.asarray(g.profile_y_mm), _np(g.rho_mm), _np(arrays.force_N),
            _np(arrays.torque_Nm), _np(g.stress_MPa),
            None if scene.design is None else scene.design.sigma_max_MPa, radius, offset, _np(g.pitch_x_mm), _np(g.pitch_y_mm), _np(g.pressure_angle_deg), _np(g.pitch_rho_mm),
            _np(g.undercut_margin_mm), limit, rot, parts,
            None if own is None else {k: np.asarray(v) for k, v in own.items()}, follower.closure.kind,
        )

    def run(self, scene, arrays: SceneArrays | None = None, *, base_radius_mm: float | None = None,
            dtype=None) -> DesignRun:
        """Every model the scene declares: the design, the smallest cam, the curves (see the module
        docstring); ``base_radius_mm`` draws at that radius instead of the design's (or, without a
        [design], instead of the smallest admissible + 1 mm, rounded up)."""
        if arrays is None:
            arrays = scene_arrays(scene, dtype=dtype)
        if scene.design is None:
            return self._drawn_run(scene, arrays, None, base_radius_mm)
        # the drawing's programs compiled beside the solver's, for the scene's own follower
        with runtime.ahead(lambda: self._drawn_run(scene, arrays, None, base_radius_mm)):
            design = self.solve_design(scene, arrays)
        return self._drawn_run(scene, arrays, design, base_radius_mm)

    def _drawn_run(self, scene, arrays: SceneArrays, design, base_radius_mm: float | None) -> DesignRun:
        """The run's smallest cam, drawing radius, curves and violations, for a solved ``design``
        (or None: the scene's follower, drawn at ``base_radius_mm`` or its smallest cam + 1 mm)."""
        result = design.result if design is not None else {}
        drawn = self.drawn_follower(scene, result)
        # the smallest cam for the follower the cam is drawn with (a design's dimensions); without a
        # design, the drawing's programs compiled beside it (:func:`camjax.runtime.ahead`)
        sized = scene if drawn is scene.follower else replace(scene, follower=drawn)
        with runtime.ahead(None if design is not None else
                           lambda: self._at_radius(scene, arrays, drawn, result, PROVISIONAL_RADIUS_MM)):
            minimum = self.min_base_radius(sized, arrays)
        radius, source = drawing_base_radius(design, minimum.radius_mm, base_radius_mm)
        extremes, curves = self._at_radius(scene, arrays, drawn, result, radius)
        return DesignRun(arrays, minimum, design, radius, source, curves,
                         tuple(geometry_violations(curves, scene.follower.min_curvature_radius_mm, extremes)),
                         extremes)

    def _at_radius(self, scene, arrays: SceneArrays, drawn, result: dict, radius: float):
        """(extremes, curves) of the cam drawn at base radius ``radius`` (mm) with the follower
        ``drawn`` and a design's ``result`` (its JSON; {} without one)."""
        extremes = curve_extremes(scene, arrays, curve_names(scene, arrays), radius, follower=drawn)
        width = self.design_face_width(result, extremes)
        return extremes, self.curves(scene, arrays, radius, drawn, width)


@functools.lru_cache(maxsize=32)
def _geometry_program(name: str, follower, rotation: str):
    """The compiled geometry of follower type ``name`` for the [follower] spec ``follower`` (its
    design numbers zeroed, :meth:`Follower.without_design_numbers`: they come as data) and the cam's rotation:
    one program per follower of a scene, whatever its design's dimensions and base radius."""
    from camjax import followers

    kind = followers.get(name)
    return jax.jit(lambda arrays, radius, numbers: kind.geometry(replace(follower, **numbers), rotation,
                                                                 arrays, radius))
