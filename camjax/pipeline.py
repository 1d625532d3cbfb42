"""Scene -> arrays -> problem -> solve -> curves: the one place a scene's design is run.

Data flows one way and each step is a pure function:

1. :func:`camjax.evaluate.scene_arrays` evaluates what the scene declares (once per scene);
2. :func:`min_base_radius` finds the smallest admissible base radius (closed form for a flat
   face; for a roller the pressure angle in closed form, the undercut by bisection);
3. :func:`solve_design` picks the design of a scene with a [design] section (flat face: R_b, L;
   roller: R_b, R_f, e) -- the one place an optimizer plugs in;
4. :func:`camjax.evaluate.evaluate_design` computes the curves at the drawing base radius
   (:func:`drawing_base_radius`) and :func:`geometry_violations` the
   constraints that geometry breaks;
5. :func:`camjax.output.report.build_report` turns the typed :class:`DesignRun` into the
   JSON-ready dict.

:func:`run_design` runs 1-4 and returns a :class:`DesignRun`; :func:`analyse` adds the report
dict. :func:`sweep_scene` solves the [design] problem for many weightings in this process (the
CLI hands blocks to ``camjax.scaleout`` instead when asked). Nothing here draws or writes files
(``camjax.output`` and ``cli.py`` do).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact
from camjax.evaluate import (
    PRESSURE_NEED,
    DesignCurves,
    Extremes,
    SceneArrays,
    curve_extremes,
    curve_names,
    evaluate_design,
    scene_arrays,
)
from camjax.family import FEASIBILITY_RTOL_STRESS, FEASIBILITY_TOL_MM, FEASIBILITY_TOL_RAD
from camjax.followers.flat import geometry as flat_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.scene import Scene

DRAWING_MARGIN_MM = 1.0  # without a [design], draw at the smallest admissible R_b + this, rounded up


def _f(x) -> float:
    """A scalar as a Python float (JSON)."""
    return float(np.asarray(x))


# ------------------------------------------------------------------------- base radius


class MinBaseRadius(NamedTuple):
    """Smallest admissible base radius, the cam angle where it binds and the limit that binds."""

    radius_mm: float
    angle_deg: float
    binding: str  # "curvature" (flat face), "pressure_angle" or "undercut" (roller)
    prime_radius_mm: float | None = None  # roller: R_b + R_f


def min_base_radius(scene: Scene, arrays: SceneArrays) -> MinBaseRadius:
    """Smallest admissible base radius (mm) and the cam angle (deg) where it binds.

    Flat face: max_theta -(s + s'') (rho >= 0), refined off the grid with exact extrema
    (``[motion] extrema``). Roller: the smallest prime circle with
    |phi| <= follower.max_pressure_angle_deg and no undercut (convex cam-surface radius >=
    follower.min_curvature_radius_mm) at the follower's R_f and offset
    (:func:`camjax.followers.roller.geometry.roller_min_prime_radius`: closed form for the pressure angle, its max
    over the angle refined off the grid with exact extrema; bisection on the samples for the
    undercut), minus R_f; the angle is where the binding limit is reached.
    """
    t = np.asarray(arrays.theta_deg)
    if scene.follower.type == "flat" and arrays.model is not None:
        # exact: max_theta -(s + s'') refined off the grid
        q = curve_extremes(scene, arrays, ("q",))["q"]
        return MinBaseRadius(-q.min, q.min_deg, "curvature")
    f = scene.follower
    if f.type == "flat":
        r, i = jax.jit(flat_geo.flat_min_base_radius)(arrays.kin)
        # + 0.0: -0.0 (s = s'' = 0 somewhere, e.g. uniform laws) reads as 0
        return MinBaseRadius(_f(r) + 0.0, _f(t[int(i)]), "curvature")
    sizing = roller_geo.roller_min_prime_radius(arrays.kin, f.roller_radius_mm, f.offset_mm,
                                              math.radians(f.max_pressure_angle_deg),
                                              f.min_curvature_radius_mm, scene.motion.rotation)
    rp = _f(sizing.prime_radius_mm)
    if arrays.model is not None and not bool(sizing.undercut_binds):
        # exact: the closed form's max over the angle refined off the grid; it is >= the samples'
        # max, so the undercut (which relaxes as R_p grows) still holds
        need = curve_extremes(scene, arrays, (PRESSURE_NEED,))[PRESSURE_NEED]
        rp = math.hypot(f.offset_mm, max(need.max, 0.0))
        return MinBaseRadius(rp - f.roller_radius_mm, need.max_deg, "pressure_angle", rp)
    return MinBaseRadius(rp - f.roller_radius_mm, _f(t[int(sizing.index)]),
                         "undercut" if bool(sizing.undercut_binds) else "pressure_angle", rp)


# ------------------------------------------------------------------------------ design


class DesignSolution(NamedTuple):
    """The solved design of a scene's [design] and the figures the report states beside it."""

    result: dict[str, Any]  # the solver's JSON (camjax.solvers.base.Solution.to_json)
    peak_stress_MPa: float | None  # the design's peak stress, computed exactly as the stress curve
    required_base_radius_mm: float  # smallest admissible R_b (flat: over angles; roller: at R_f, e)
    required_base_radius_deg: float  # where it binds
    binding_constraint: str  # flat: "stress" or "curvature"; roller: "pressure_angle" or "undercut"
    required_face_width_mm: float | None  # flat face only
    rho_min_limit_mm: float  # the problem's smallest allowed radius of curvature


def design_problem(scene: Scene, arrays: SceneArrays | None = None, *, samples: int | None = None):
    """The design problem of the scene's [design] section (the follower type's problem family)."""
    from camjax.solvers.base import problem_from_scene

    return problem_from_scene(scene, arrays, samples=samples)


def solve_design(scene: Scene, arrays: SceneArrays) -> DesignSolution | None:
    """The optimized design of a scene with a [design] section; None without one.

    Solved by :func:`camjax.solvers.base.solve` with the scene's mode, alpha, gamma, solver and
    seed (SPEC 5; keys of :meth:`camjax.solvers.base.Solution.to_json`: mode, solver, the design
    variables, objective, feasible, violated, iterations, ..., and in pointwise mode the angles
    and per-angle ``pointwise`` arrays). Flat face: (R_b, L); roller: (R_b, R_f, e).
    """
    if scene.design is None:
        return None
    from camjax.solvers.base import solve

    d, t = scene.design, np.asarray(arrays.theta_deg)
    problem = design_problem(scene, arrays)
    out = solve(problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver, seed=d.seed).to_json(problem)
    if scene.follower.type == "roller":
        return _roller_design_solution(scene, arrays, out)
    if problem.exact is not None:  # every figure refined off the grid
        from camjax.followers.flat import problem as P

        e = problem.exact
        curvature = float(problem.rho_min_mm - e.q_min_mm)
        stress_need = float(e.stress_need_mm)
        binding = "stress" if stress_need >= curvature else "curvature"
        return DesignSolution(
            out, out["stress_max_MPa"], max(curvature, stress_need),
            _f(e.stress_need_deg if binding == "stress" else e.q_min_deg), binding,
            _f(P.required_face_width(problem)), float(problem.rho_min_mm))
    sigma_peak, stress_rho, need, width = jax.device_get(
        _design_needs(problem, arrays.stress_coefficient, arrays.kin, out["base_radius_mm"]))
    sigma_peak, width = float(sigma_peak), float(width)
    i = int(np.argmax(need))
    return DesignSolution(
        out, sigma_peak, float(need[i]), _f(t[i]),
        "stress" if stress_rho[i] >= float(problem.rho_min_mm) else "curvature",
        width, float(problem.rho_min_mm))


@jax.jit
def _design_needs(problem, stress_coefficient, kin, base_radius_mm):
    """Peak stress at the design, per-angle stress need and R_b need, the face width need (one
    compiled call)."""
    from camjax.followers.flat import problem as P

    rho = flat_geo.flat_radius_of_curvature(base_radius_mm, kin)
    sigma_peak = jnp.max(contact.stress_from_coefficient(stress_coefficient, rho))
    need = P.rho_need(problem) - problem.q_mm  # max over angles: P.required_base_radius
    return sigma_peak, P.stress_rho_need(problem), need, P.required_face_width(problem)


def _roller_design_solution(scene: Scene, arrays: SceneArrays, out: dict) -> DesignSolution:
    """A roller design's figures: its peak stress as the stress curve computes it, and the
    smallest R_b its R_f and offset admit (pressure angle and undercut; stress aside)."""
    f, t = scene.follower, np.asarray(arrays.theta_deg)
    rf, e = out["roller_radius_mm"], out["offset_mm"]
    curves = evaluate_design(scene, arrays, out["base_radius_mm"], roller_radius_mm=rf, offset_mm=e)
    sizing = roller_geo.roller_min_prime_radius(arrays.kin, rf, e, math.radians(f.max_pressure_angle_deg),
                                              f.min_curvature_radius_mm, scene.motion.rotation)
    peak_stress = None if curves.stress_MPa is None else _f(np.max(curves.stress_MPa))
    return DesignSolution(out, peak_stress, _f(sizing.prime_radius_mm) - rf, _f(t[int(sizing.index)]),
                          "undercut" if bool(sizing.undercut_binds) else "pressure_angle", None,
                          f.min_curvature_radius_mm)


def drawing_base_radius(design: DesignSolution | None, min_base_radius_mm: float,
                        override_mm: float | None = None) -> tuple[float, str]:
    """Base radius (mm) the geometry is evaluated and drawn at, and where it comes from."""
    if override_mm is not None:
        return float(override_mm), "option --base-radius"
    if design is not None:
        return design.result["base_radius_mm"], "design"
    r = float(math.ceil(max(min_base_radius_mm, 0.0) + DRAWING_MARGIN_MM))
    return r, f"smallest admissible + {DRAWING_MARGIN_MM:g} mm, rounded up to whole mm"


# ----------------------------------------------------------------------------- feasibility


class GeometryViolation(NamedTuple):
    """One constraint the evaluated geometry breaks: a key and one sentence with the figures."""

    constraint: str  # curvature, stress, face_width, pressure_angle, undercut, contact
    message: str


def _curvature(rho: float, deg: float, rho_min_mm: float) -> list[GeometryViolation]:
    """A radius of curvature below the allowed one (geometry_violations and rocker_violations share
    these four checks, their tolerances the solvers')."""
    if rho >= rho_min_mm - FEASIBILITY_TOL_MM:
        return []
    why = "the profile crosses itself" if rho < 0 else "the flat face cannot follow it"
    return [GeometryViolation("curvature", f"min radius of curvature {rho:.4g} mm at {deg:g} deg < "
                              f"{rho_min_mm:g} mm: {why}")]


def _stress(sigma: float, deg: float, sigma_max_MPa: float) -> list[GeometryViolation]:
    if sigma <= sigma_max_MPa * (1.0 + FEASIBILITY_RTOL_STRESS):
        return []
    return [GeometryViolation("stress", f"peak contact stress {sigma:.4g} MPa at {deg:g} deg > sigma_max "
                              f"{sigma_max_MPa:g} MPa")]


def _pressure_angle(phi: float, deg: float, limit_deg: float) -> list[GeometryViolation]:
    if phi <= limit_deg + math.degrees(FEASIBILITY_TOL_RAD):
        return []
    return [GeometryViolation("pressure_angle", f"|pressure angle| {phi:.4g} deg at {deg:g} deg > "
                              f"{limit_deg:g} deg")]


def _undercut(margin: float, deg: float) -> list[GeometryViolation]:
    if margin >= -FEASIBILITY_TOL_MM:
        return []
    return [GeometryViolation("undercut", f"undercut margin {margin:.4g} mm at {deg:g} deg <= 0: the roller "
                              "undercuts the cam")]


def geometry_violations(curves: DesignCurves, rho_min_mm: float = 0.0,
                        extremes: dict[str, Extremes] | None = None) -> list[GeometryViolation]:
    """Constraints broken by the geometry at the evaluated base radius (empty: usable geometry).

    Flat face: rho < ``rho_min_mm`` (the profile cannot be followed; below 0 it crosses itself),
    peak stress > sigma_max (with a [design]), face narrower than 2 max|s'|. Roller: |pressure
    angle| > the limit, undercut. With loads: contact force < 0 (the follower leaves the cam).
    Tolerances are the solvers' (:data:`camjax.family.FEASIBILITY_TOL_MM`, relative 1e-6 on the
    stress), so a design the solver calls feasible is not flagged here.

    ``extremes`` (:func:`camjax.evaluate.curve_extremes` at the curves' design): rho, stress, face
    width and force are judged on them (exact extrema: the continuous ones, as the report states
    them); the roller's pressure angle and undercut stay on the samples, as the roller design
    problem constrains them.
    """
    t, out, ex = curves.theta_deg, [], extremes or {}

    def at(values, pick, name=None, sense="min"):
        if name in ex:
            e = ex[name]
            return (e.min, e.min_deg) if sense == "min" else (e.max, e.max_deg)
        i = int(pick(values))
        return float(values[i]), float(t[i])

    if curves.rho_mm is not None:
        rho, deg = at(curves.rho_mm, np.argmin)
        if "q" in ex:  # rho = R_b + q
            rho, deg = curves.base_radius_mm + ex["q"].min, ex["q"].min_deg
        out += _curvature(rho, deg, rho_min_mm)
    if curves.stress_MPa is not None and curves.sigma_max_MPa is not None:
        out += _stress(*at(curves.stress_MPa, np.argmax, "stress", "max"), curves.sigma_max_MPa)
    if curves.face_width_mm is not None:
        need = 2.0 * (max(ex["ds"].max, -ex["ds"].min) if "ds" in ex else float(np.max(np.abs(curves.ds_mm))))
        if curves.face_width_mm < need - FEASIBILITY_TOL_MM:
            out.append(GeometryViolation(
                "face_width", f"face width {curves.face_width_mm:.4g} mm < 2 max|s'| = {need:.4g} mm: "
                "the contact runs off the face"))
    if curves.pressure_angle_deg is not None:
        phi = at(np.abs(curves.pressure_angle_deg), np.argmax)
        out += _pressure_angle(*phi, curves.pressure_angle_limit_deg)
    if curves.undercut_margin_mm is not None:
        out += _undercut(*at(curves.undercut_margin_mm, np.argmin))
    if curves.force_N is not None:
        force, deg = at(curves.force_N, np.argmin, "force")
        if force < 0:
            lost = float(np.mean(curves.force_N < 0)) * 360.0
            out.append(GeometryViolation(
                "contact", f"contact force {force:.4g} N at {deg:g} deg < 0 (over about {lost:.3g} deg): "
                "the follower leaves the cam"))
    return out


def rocker_violations(curves, scene: Scene) -> list[GeometryViolation]:
    """Constraints broken by an oscillating follower's evaluated geometry (empty: usable geometry).

    ``curves`` is a :class:`camjax.rocker.RockerCurves`. Roller: |pressure angle| > the limit,
    undercut; flat face: cam-surface radius < ``follower.min_curvature_radius_mm``; with loads:
    contact force < 0; with a [design]: peak stress > sigma_max. Tolerances as
    :func:`geometry_violations`.
    """
    f, t, out = scene.follower, curves.theta_deg, []

    def at(values, pick):
        i = int(pick(values))
        return float(values[i]), float(t[i])

    if curves.undercut_margin_mm is not None:
        out += _pressure_angle(*at(np.abs(curves.pressure_angle_deg), np.argmax), f.max_pressure_angle_deg)
        out += _undercut(*at(curves.undercut_margin_mm, np.argmin))
    else:
        out += _curvature(*at(curves.rho_mm, np.argmin), f.min_curvature_radius_mm)
    if curves.stress_MPa is not None and scene.design is not None and scene.design.sigma_max_MPa:
        out += _stress(*at(curves.stress_MPa, np.argmax), scene.design.sigma_max_MPa)
    if curves.contact_force_N is not None:
        force, deg = at(curves.contact_force_N, np.argmin)
        if force < 0:
            out.append(GeometryViolation(
                "contact", f"contact force {force:.4g} N at {deg:g} deg < 0: the follower leaves the cam"))
    return out


# ------------------------------------------------------------------------------- run


class DesignRun(NamedTuple):
    """Everything a scene's design run computed, typed (the report formats it)."""

    arrays: SceneArrays
    min_base_radius: MinBaseRadius
    design: DesignSolution | None  # None without a [design]
    base_radius_mm: float  # where the curves are evaluated and drawn
    base_radius_source: str  # why that radius
    curves: DesignCurves
    violations: tuple[GeometryViolation, ...] = ()  # constraints the drawn geometry breaks (empty: usable)
    # max/min of each of evaluate.curve_names, stress and roller curves at base_radius_mm (exact
    # unless the scene asks for grid extrema); defaulted because it follows the defaulted violations
    extremes: dict[str, Extremes] | None = None


def run_design(scene: Scene, arrays: SceneArrays | None = None, *,
               base_radius_mm: float | None = None, dtype=None) -> DesignRun:
    """Run every model the scene declares: arrays, minimum base radius, design, curves.

    Args:
      scene: a validated scene.
      arrays: precomputed :func:`camjax.evaluate.scene_arrays` (computed here if None).
      base_radius_mm: evaluate and draw the geometry at this base radius instead of the design's
        (or, without a [design], instead of the smallest admissible radius + 1 mm, rounded up).
      dtype: floating dtype when ``arrays`` is computed here (default float64).
    """
    if arrays is None:
        arrays = scene_arrays(scene, dtype=dtype)
    design = solve_design(scene, arrays)
    result = design.result if design is not None else {}
    rf, e = result.get("roller_radius_mm"), result.get("offset_mm")
    # the smallest cam for the follower the cam is drawn with: a roller design's R_f and offset
    sized = scene if rf is None else replace(scene, follower=replace(scene.follower, roller_radius_mm=rf,
                                                                        offset_mm=e))
    minimum = min_base_radius(sized, arrays)
    radius, source = drawing_base_radius(design, minimum.radius_mm, base_radius_mm)
    extremes = curve_extremes(scene, arrays, curve_names(scene, arrays), radius,
                              roller_radius_mm=rf, offset_mm=e)
    width = result.get("face_width_mm")
    if width is None and scene.follower.type == "flat":  # 2 max|s'|, the extremes' (exact or the samples')
        width = 2.0 * max(extremes["ds"].max, -extremes["ds"].min, 0.0)
    curves = evaluate_design(scene, arrays, radius, width, roller_radius_mm=rf, offset_mm=e)
    return DesignRun(arrays, minimum, design, radius, source, curves,
                     tuple(geometry_violations(curves, scene.follower.min_curvature_radius_mm, extremes)),
                     extremes)


def sweep_scene(scene: Scene, alphas, gammas, *, mode: str, solver: str, seed: int = 0,
                chunk_size: int = 128):
    """Solve the scene's [design] problem for every (alpha, gamma) pair of two lists, in this process.

    Returns :class:`camjax.solvers.sweep.SweepResult` (its ``records()`` are the JSON rows).
    """
    from camjax.solvers.sweep import sweep

    problem = design_problem(scene)
    return sweep(problem, alphas, gammas, mode=mode, solver=solver, seed=seed, chunk_size=chunk_size)


class Report(NamedTuple):
    """A scene's report (JSON-ready dict) with the curves and arrays behind it."""

    data: dict[str, Any]
    curves: DesignCurves  # camjax.rocker.RockerCurves for an oscillating follower
    arrays: SceneArrays


def analyse(scene: Scene, arrays: SceneArrays | None = None, *, base_radius_mm: float | None = None,
            dtype=None) -> Report:
    """:func:`run_design` and its report dict (see :func:`run_design` for the arguments).

    An oscillating follower runs :func:`camjax.rocker.run_rocker` instead (lifts in rad, the
    cam sized for its pivot and arm); its curves are :class:`camjax.rocker.RockerCurves`.
    """
    from camjax.output.report import build_report

    if scene.follower.oscillating:
        from camjax.output.rocker import rocker_report
        from camjax.rocker import run_rocker

        arrays = scene_arrays(scene, dtype=dtype) if arrays is None else arrays
        design = None
        if scene.design is not None:
            from camjax.solvers.base import solve

            d, problem = scene.design, design_problem(scene, arrays)
            design = solve(problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver,
                           seed=d.seed).to_json(problem)
        rocker = run_rocker(scene, arrays.kin, arrays.cam_speed_rad_s, base_radius_mm, design)
        violations = rocker_violations(rocker.curves, scene)
        return Report(rocker_report(scene, arrays, rocker, design, violations), rocker.curves, arrays)
    run = run_design(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype)
    return Report(build_report(scene, run), run.curves, run.arrays)


def design_report(scene: Scene, arrays: SceneArrays | None = None, *,
                  base_radius_mm: float | None = None, dtype=None) -> dict[str, Any]:
    """The report of a scene as a plain, JSON-ready dict (see :func:`run_design` for the arguments)."""
    return analyse(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype).data
