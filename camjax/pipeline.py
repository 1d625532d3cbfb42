"""Scene -> arrays -> problem -> solve -> curves: the one place a scene's design is run.

Data flows one way and each step is a pure function:

1. :func:`camjax.evaluate.scene_arrays` evaluates what the scene declares (once per scene);
2. :func:`min_base_radius` finds the smallest admissible base radius (closed form for a flat
   face, bisection for a roller);
3. :func:`solve_design` picks the design (R_b, L) of a scene with a [design] section -- the one
   place an optimizer plugs in;
4. :func:`camjax.evaluate.evaluate_design` computes the curves at the drawing base radius
   (:func:`drawing_base_radius`);
5. :func:`camjax.output.report.build_report` turns the typed :class:`DesignRun` into the
   JSON-ready dict.

:func:`run_design` runs 1-4 and returns a :class:`DesignRun`; :func:`analyse` adds the report
dict. :func:`sweep_scene` solves the [design] problem for many weightings in this process (the
CLI hands blocks to ``camjax.scaleout`` instead when asked). Nothing here draws or writes files
(``camjax.output`` and ``cli.py`` do).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, geometry
from camjax.evaluate import (
    DesignCurves,
    Extremes,
    PointValues,
    SceneArrays,
    curve_constants,
    curve_extremes,
    curve_names,
    evaluate_design,
    refined_extremes,
    scene_arrays,
)
from camjax.geometry import PRESSURE_ANGLE_LIMIT_DEG
from camjax.scene import Scene

DRAWING_MARGIN_MM = 1.0  # without a [design], draw at the smallest admissible R_b + this, rounded up


def _f(x) -> float:
    """A scalar as a Python float (JSON)."""
    return float(np.asarray(x))


# ------------------------------------------------------------------------- base radius


class MinBaseRadius(NamedTuple):
    """Smallest admissible base radius and the cam angle where it binds."""

    radius_mm: float
    angle_deg: float


@jax.jit
def _roller_violation(base_radius_mm, roller_radius_mm, offset_mm, kin):
    """Largest violation (> 0 = violated) of |phi| <= 30 deg and no undercut, normalized."""
    g = geometry.roller_geometry(base_radius_mm, roller_radius_mm, offset_mm, kin)
    phi_excess = jnp.max(jnp.abs(g.pressure_angle)) / jnp.deg2rad(PRESSURE_ANGLE_LIMIT_DEG) - 1.0
    undercut = -jnp.min(g.undercut_margin) / roller_radius_mm
    reach = jnp.abs(offset_mm) - (base_radius_mm + roller_radius_mm)  # prime circle must pass e
    return jnp.maximum(jnp.maximum(phi_excess, undercut), reach / roller_radius_mm)


@jax.jit
def _roller_violation_exact(base_radius_mm, consts, kin, model):
    """:func:`_roller_violation` with the max |phi| and min undercut margin refined off the grid."""
    hi, _, lo, _ = refined_extremes(model, consts, PointValues(kin, None, None, None), base_radius_mm,
                                    ("pressure_angle", "undercut_margin"))
    phi_excess = jnp.maximum(hi[0], -lo[0]) / jnp.deg2rad(PRESSURE_ANGLE_LIMIT_DEG) - 1.0
    undercut = -lo[1] / consts.roller_radius_mm
    reach = jnp.abs(consts.offset_mm) - (base_radius_mm + consts.roller_radius_mm)
    return jnp.maximum(jnp.maximum(phi_excess, undercut), reach / consts.roller_radius_mm)


def _roller_min_base_radius(scene: Scene, arrays: SceneArrays) -> float:
    """Smallest R_b (mm, to 1e-9 relative) with |phi| <= 30 deg and no undercut, by bisection.

    Both constraints relax as R_b grows (the pitch point moves out, tan phi falls, the pitch
    curve flattens), so the feasible set is an interval [R_min, inf).
    """
    f = scene.follower
    kin = arrays.kin
    dtype = kin.s.dtype
    consts = curve_constants(scene)._replace(guide=None)
    consts = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), consts)

    def bad(r):
        if arrays.model is not None:  # exact extrema: the constraints at every cam angle
            return float(_roller_violation_exact(jnp.asarray(r, dtype), consts, kin, arrays.model)) > 0.0
        return float(_roller_violation(r, f.roller_radius_mm, f.offset_mm, kin)) > 0.0

    lo, hi = 0.0, max(1.0, abs(f.offset_mm))
    while bad(hi):
        lo, hi = hi, 2.0 * hi
        if hi > 1e7:
            raise ValueError("no base radius below 1e7 mm satisfies the roller constraints")
    while hi - lo > 1e-9 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if bad(mid) else (lo, mid)
    return hi


def min_base_radius(scene: Scene, arrays: SceneArrays) -> MinBaseRadius:
    """Smallest admissible base radius (mm) and the cam angle (deg) where it binds.

    Flat face: max_theta -(s + s'') (rho >= 0). Roller: the smallest R_b with |phi| <= 30 deg
    and no undercut; the angle is where the pressure angle peaks at that radius.
    """
    t = np.asarray(arrays.theta_deg)
    if scene.follower.type == "flat":
        if arrays.model is not None:  # exact: max_theta -(s + s'') refined off the grid
            q = curve_extremes(scene, arrays, ("q",))["q"]
            return MinBaseRadius(-q.min, q.min_deg)
        r, i = geometry.flat_min_base_radius(arrays.kin)
        return MinBaseRadius(_f(r), _f(t[int(i)]))
    r = _roller_min_base_radius(scene, arrays)
    if arrays.model is not None:
        phi = curve_extremes(scene, arrays, ("pressure_angle",), r)["pressure_angle"]
        return MinBaseRadius(r, phi.max_deg if phi.max >= -phi.min else phi.min_deg)
    f = scene.follower
    g = geometry.roller_geometry(r, f.roller_radius_mm, f.offset_mm, arrays.kin)
    i = int(np.argmax(np.abs(np.asarray(g.pressure_angle))))
    return MinBaseRadius(r, _f(t[i]))


# ------------------------------------------------------------------------------ design


class DesignSolution(NamedTuple):
    """The solved design of a scene's [design] and the figures the report states beside it."""

    result: dict[str, Any]  # the solver's JSON (camjax.solvers.base.Solution.to_json)
    peak_stress_MPa: float  # the design's peak stress, computed exactly as the stress curve
    required_base_radius_mm: float  # smallest admissible R_b (max over angles of the need)
    required_base_radius_deg: float  # where it binds
    binding_constraint: str  # "stress" or "curvature"
    required_face_width_mm: float
    rho_min_limit_mm: float  # the problem's smallest allowed radius of curvature


def solve_design(scene: Scene, arrays: SceneArrays) -> DesignSolution | None:
    """The optimized design (R_b, L) of a scene with a [design] section; None without one.

    Solved by :func:`camjax.solvers.sweep.solve` with the scene's mode, alpha, gamma, solver and
    seed (SPEC 5; keys of :meth:`camjax.solvers.base.Solution.to_json`: mode, solver,
    base_radius_mm, face_width_mm, objective, feasible, violated, iterations, ..., and in
    pointwise mode base_radius_deg, face_width_deg and the per-angle ``pointwise`` arrays).
    """
    if scene.design is None:
        return None
    from camjax import problem as P
    from camjax.solvers.sweep import solve

    d, kin, t = scene.design, arrays.kin, np.asarray(arrays.theta_deg)
    problem = P.problem_from_scene(scene, arrays)
    out = solve(problem, d.alpha, d.gamma, mode=d.mode, solver=d.solver, seed=d.seed).to_json(problem)

    if problem.exact is not None:  # every figure refined off the grid
        e = problem.exact
        curvature = float(problem.rho_min_mm - e.q_min_mm)
        stress_need = float(e.stress_need_mm)
        binding = "stress" if stress_need >= curvature else "curvature"
        return DesignSolution(
            out, out["stress_max_MPa"], max(curvature, stress_need),
            _f(e.stress_need_deg if binding == "stress" else e.q_min_deg), binding,
            _f(P.required_face_width(problem)), float(problem.rho_min_mm))
    rho = geometry.flat_radius_of_curvature(out["base_radius_mm"], kin)
    sigma_peak = _f(jnp.max(contact.stress_from_coefficient(arrays.stress_coefficient, rho)))
    stress_rho = np.asarray(P.stress_rho_need(problem))
    need = np.asarray(P.rho_need(problem) - problem.q_mm)  # max over angles: P.required_base_radius
    i = int(np.argmax(need))
    return DesignSolution(
        out, sigma_peak, float(need[i]), _f(t[i]),
        "stress" if stress_rho[i] >= float(problem.rho_min_mm) else "curvature",
        _f(P.required_face_width(problem)), float(problem.rho_min_mm))


def drawing_base_radius(design: DesignSolution | None, min_base_radius_mm: float,
                        override_mm: float | None = None) -> tuple[float, str]:
    """Base radius (mm) the geometry is evaluated and drawn at, and where it comes from."""
    if override_mm is not None:
        return float(override_mm), "option --base-radius"
    if design is not None:
        return design.result["base_radius_mm"], "design"
    r = float(math.ceil(max(min_base_radius_mm, 0.0) + DRAWING_MARGIN_MM))
    return r, f"smallest admissible + {DRAWING_MARGIN_MM:g} mm, rounded up to whole mm"


# ------------------------------------------------------------------------------- run


class DesignRun(NamedTuple):
    """Everything a scene's design run computed, typed (the report formats it)."""

    arrays: SceneArrays
    min_base_radius: MinBaseRadius
    design: DesignSolution | None  # None without a [design]
    base_radius_mm: float  # where the curves are evaluated and drawn
    base_radius_source: str  # why that radius
    curves: DesignCurves
    extremes: dict[str, Extremes]  # max/min of each of evaluate.curve_names; stress at base_radius_mm


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
    minimum = min_base_radius(scene, arrays)
    design = solve_design(scene, arrays)
    radius, source = drawing_base_radius(design, minimum.radius_mm, base_radius_mm)
    width = design.result["face_width_mm"] if design is not None else None
    curves = evaluate_design(scene, arrays, radius, width)
    extremes = curve_extremes(scene, arrays, curve_names(scene, arrays), radius)
    return DesignRun(arrays, minimum, design, radius, source, curves, extremes)


def sweep_scene(scene: Scene, alphas, gammas, *, mode: str, solver: str, seed: int = 0,
                chunk_size: int = 128):
    """Solve the scene's [design] problem for every (alpha, gamma) pair of two lists, in this process.

    Returns :class:`camjax.solvers.sweep.SweepResult` (its ``records()`` are the JSON rows).
    """
    from camjax.problem import problem_from_scene
    from camjax.solvers.sweep import sweep

    problem = problem_from_scene(scene)
    return sweep(problem, alphas, gammas, mode=mode, solver=solver, seed=seed, chunk_size=chunk_size)


class Report(NamedTuple):
    """A scene's report (JSON-ready dict) with the curves and arrays behind it."""

    data: dict[str, Any]
    curves: DesignCurves
    arrays: SceneArrays


def analyse(scene: Scene, arrays: SceneArrays | None = None, *, base_radius_mm: float | None = None,
            dtype=None) -> Report:
    """:func:`run_design` and its report dict (see :func:`run_design` for the arguments)."""
    from camjax.output.report import build_report

    run = run_design(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype)
    return Report(build_report(scene, run), run.curves, run.arrays)


def design_report(scene: Scene, arrays: SceneArrays | None = None, *,
                  base_radius_mm: float | None = None, dtype=None) -> dict[str, Any]:
    """The report of a scene as a plain, JSON-ready dict (see :func:`run_design` for the arguments)."""
    return analyse(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype).data
