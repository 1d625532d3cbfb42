"""Design report: a :class:`camjax.pipeline.DesignRun` -> a JSON-ready dict.

Formatting only: every block condenses arrays the pipeline already computed into plain values
(degrees, SI or the unit in the key) with no NaN or infinity, so that :func:`build_report` can be
written as strict JSON. Nothing here solves, draws or writes files (the pipeline solves;
``plots.py``, ``export.py`` and ``cli.py`` draw and write).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from camjax import loads
from camjax.evaluate import DesignCurves, Extremes, SceneArrays, curve_extremes, curve_names
from camjax.family import FEASIBILITY_TOL_RAD
from camjax.followers.flat import geometry as flat_geo
from camjax.program import joints
from camjax.scene import DesignSpec, FollowerSpec, Scene

if TYPE_CHECKING:  # the pipeline hands its result down; nothing here calls back into it
    from camjax.pipeline import DesignRun, DesignSolution, MinBaseRadius

FLCD_UNITS = {"jump_s": "mm", "jump_v": "mm/rad", "jump_a": "mm/rad^2", "jump_j": "mm/rad^3"}


# ------------------------------------------------------------------------------ extrema


def _f(x) -> float:
    """A scalar as a Python float (JSON)."""
    return float(np.asarray(x))


def extrema(values, theta_deg) -> dict[str, float]:
    """{max, max_deg, min, min_deg} of a sampled curve; the first sample wins on ties."""
    v, t = np.asarray(values), np.asarray(theta_deg)
    i, j = int(np.argmax(v)), int(np.argmin(v))
    return {"max": _f(v[i]), "max_deg": _f(t[i]), "min": _f(v[j]), "min_deg": _f(t[j])}


def peak(values, theta_deg) -> dict[str, float]:
    """{max, max_deg} of a sampled curve."""
    e = extrema(values, theta_deg)
    return {"max": e["max"], "max_deg": e["max_deg"]}


def trough(values, theta_deg) -> dict[str, float]:
    """{min, min_deg} of a sampled curve."""
    e = extrema(values, theta_deg)
    return {"min": e["min"], "min_deg": e["min_deg"]}


def scaled(e: Extremes, factor: float = 1.0, offset: float = 0.0) -> dict[str, float]:
    """{max, max_deg, min, min_deg} of ``factor * curve + offset`` (factor > 0) from the curve's extremes.

    The multiplication is the one the SI curves are computed with (e.g. ``ds * w * 1e-3``), so a
    grid extremum is the same float as the SI array's own.
    """
    return {"max": e.max * factor + offset, "max_deg": e.max_deg,
            "min": e.min * factor + offset, "min_deg": e.min_deg}


def negative_ranges_deg(values, theta_deg) -> list[list[float]]:
    """[first, last] sample angles (deg) of each run where values < 0, wrapping over 360."""
    neg = np.asarray(values) < 0
    t = np.asarray(theta_deg)
    if not neg.any():
        return []
    if neg.all():
        return [[_f(t[0]), _f(t[-1])]]
    start = int(np.argmin(neg))  # a sample with contact; walk the cycle from there
    order = np.roll(np.arange(len(t)), -start)
    runs, current = [], None
    for k in order:
        if neg[k]:
            current = [_f(t[k]), _f(t[k])] if current is None else [current[0], _f(t[k])]
        elif current is not None:
            runs.append(current)
            current = None
    if current is not None:
        runs.append(current)
    return runs


# ------------------------------------------------------------------------ report pieces


def kinematics_block(arrays: SceneArrays, extremes: dict[str, Extremes] | None = None) -> dict[str, Any]:
    """Follower motion extrema: displacement (mm), velocity, acceleration, jerk (SI), angles in deg.

    The SI extrema are the per-radian ones times w^k 1e-3 (w > 0: the same angles). Without
    ``extremes``, the samples' own.
    """
    if extremes is None:
        t = arrays.theta_deg
        extremes = {n: Extremes(**extrema(getattr(arrays.kin, n), t)) for n in ("s", "ds", "d2s", "d3s")}
    w = _f(arrays.cam_speed_rad_s)
    return {
        "displacement_mm": scaled(extremes["s"]),
        "velocity_m_s": _si(extremes["ds"], w, 1),
        "accel_m_s2": _si(extremes["d2s"], w, 2),
        "jerk_m_s3": _si(extremes["d3s"], w, 3),
        "velocity_mm_per_rad": scaled(extremes["ds"]),
        "accel_mm_per_rad2": scaled(extremes["d2s"]),
    }


def _si(e: Extremes, w: float, order: int) -> dict[str, float]:
    """Extremes of s^(k) (mm/rad^k) as m/s^k at cam speed w, multiplied as time_kinematics does."""
    def conv(v):
        return float(np.float64(v) * np.float64(w) ** order * 1e-3)

    return {"max": conv(e.max), "max_deg": e.max_deg, "min": conv(e.min), "min_deg": e.min_deg}


def flcd_block(scene: Scene) -> list[dict[str, Any]]:
    """Jumps of s, s', s'', s''' (mm, per rad; see FLCD_UNITS) and their FLCD class at every joint."""
    return [
        {"joint_deg": j.joint_deg, "before_segment": j.before, "after_segment": j.after,
         "jump_s": j.jump_s, "jump_v": j.jump_v, "jump_a": j.jump_a, "jump_j": j.jump_j,
         "class": j.flcd_class}
        for j in joints(scene.motion.program)
    ]


def loads_block(scene: Scene, arrays: SceneArrays, extremes: dict[str, Extremes]) -> dict[str, Any] | None:
    """Force, torque, contact-loss check and (with a [guide]) guide reactions; None without loads.

    ``lost_ranges_deg`` are runs of samples with F < 0; ``lost`` also counts a refined minimum
    below 0 that falls between samples.
    """
    if arrays.force_N is None:
        return None
    t, force = arrays.theta_deg, arrays.force_N
    f = extremes["force"]
    out: dict[str, Any] = {
        "force_N": scaled(f),
        "torque_Nm": scaled(extremes["torque"]),
        "contact": {
            "min_force_N": f.min,
            "min_force_deg": f.min_deg,
            "lost": bool(np.any(np.asarray(force) < 0) or f.min < 0),
            "lost_ranges_deg": negative_ranges_deg(force, t),
        },
    }
    if scene.guide is not None:
        out.update(guide_block(scene, arrays, extremes))
    return out


def guide_block(scene: Scene, arrays: SceneArrays, extremes: dict[str, Extremes] | None = None
                ) -> dict[str, Any]:
    """Chen's guide reactions with P = the follower force and a = s' (mm), and the jamming check.

    The stem can jam only with the contact on the side a < 0 (see
    :func:`camjax.loads.jamming_limit_mm`); the check compares max(-a) with that limit and, as an
    independent statement of the same condition, reports min Gamma (> 0 while not jammed).
    With ``extremes`` holding the guide curves (exact extrema) they are read from there.
    """
    guide, t = scene.guide, arrays.theta_deg
    limit = loads.jamming_limit_mm(guide)
    if extremes is not None and "cam_force" in extremes:
        reactions = {f"{name}_N": scaled(extremes[name])
                     for name in ("cam_force", "reaction_1", "reaction_2")}
        g = extremes["gamma"]
        gamma_min = {"min": g.min, "min_deg": g.min_deg}
        offset = extremes["ds"]  # the contact offset is s'
        worst = {"min": offset.min, "min_deg": offset.min_deg}
    else:
        # a in Chen's frame, whose friction directions turn with the cam: a cw cam is the mirror
        # image of the ccw one (face, friction and all), so a = s' for either rotation
        offset = flat_geo.flat_contact_offset(arrays.kin)
        r = loads.guide_reactions(guide, arrays.force_N, offset)
        reactions = {"cam_force_N": extrema(r.cam_force, t), "reaction_1_N": extrema(r.reaction_1, t),
                     "reaction_2_N": extrema(r.reaction_2, t)}
        worst = trough(offset, t)
        gamma_min = trough(r.gamma, t)
    reach = -worst["min"]  # most negative offset = furthest onto the jamming side
    jams = bool(gamma_min["min"] <= 0.0)
    return {
        "guide_reactions": {**reactions, "gamma_mm": gamma_min},
        "jamming_limit_mm": limit if math.isfinite(limit) else None,
        "jamming": {
            "offset_on_jamming_side_mm": reach,
            "offset_on_jamming_side_deg": worst["min_deg"],
            "margin_mm": (limit - reach) if math.isfinite(limit) else None,
            "jams": jams,
            "note": ("limit b/(2 mu) - mu0 b (1 + 2 xi)/2 from the corrected Gamma; "
                     "null limit = frictionless guide, never jams"),
        },
    }


# ------------------------------------------------------------------------- base radius


def min_base_radius_block(follower: FollowerSpec, minimum: MinBaseRadius,
                          exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, and the rule.

    Roller: also the prime-circle radius R_b + R_f, and the rule names the binding limit
    (pressure angle or undercut) and its angle. ``exact``: the flat face's radius was refined off
    the grid (every cam angle, not every sample).
    """
    out = {"min_base_radius_mm": minimum.radius_mm, "min_base_radius_deg": minimum.angle_deg}
    if follower.type == "flat":
        where = "cam angle" if exact else "sample"
        return {**out, "min_base_radius_rule": f"flat face: rho = R_b + s + s'' >= 0 at every {where}"}
    f = follower
    limits = {"pressure_angle": f"pressure angle |phi| <= {f.max_pressure_angle_deg:g} deg",
              "undercut": f"no undercut (convex cam-surface radius >= {f.min_curvature_radius_mm:g} mm)"}
    other = next(k for k in limits if k != minimum.binding)
    rule = (f"roller: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
            f"(R_f = {f.roller_radius_mm:g} mm, offset {f.offset_mm:g} mm; {limits[other]} holds)")
    return {**out, "min_prime_radius_mm": minimum.prime_radius_mm, "min_base_radius_rule": rule,
            "min_base_radius_binding": minimum.binding}


def face_width_block(scene: Scene, extremes: dict[str, Extremes]) -> dict[str, Any]:
    """Minimum flat-face width (mm): symmetric 2 max|s'| and asymmetric max s' - min s'.

    The contact offset is s' (:func:`camjax.followers.flat.geometry.flat_contact_offset`), so both come from
    the extremes of s'.
    """
    if scene.follower.type != "flat":
        return {}
    v = extremes["ds"]
    return {
        "min_face_width_mm": 2.0 * max(v.max, -v.min, 0.0),
        "min_face_width_asymmetric_mm": v.max - v.min,
        "contact_offset_mm": scaled(v),
    }


# ------------------------------------------------------------------------------ design


def design_block(spec: DesignSpec, solution: DesignSolution) -> dict[str, Any]:
    """The solver's result with the report's additions.

    Added to the solver's JSON: ``peak_stress_MPa`` (the design's peak stress computed exactly as
    the report's stress curve; null for a roller without [contact]), the smallest admissible R_b
    (and, flat face, L) (``required_*``) with the constraint that binds there, and ``violations``
    as readable sentences. Roller: R_b required at the design's R_f and offset (pressure angle
    and undercut), and the design variables base_radius_mm, roller_radius_mm, offset_mm,
    prime_radius_mm come from the solver.
    """
    out = dict(solution.result)
    sigma_peak, required = solution.peak_stress_MPa, solution.required_base_radius_mm
    rb_hi = spec.base_radius_mm[1]
    sentences = {
        "stress": f"peak stress {sigma_peak or 0.0:.6g} MPa > sigma_max {spec.sigma_max_MPa or 0.0:g} MPa",
        "bounds": "a design variable is outside its bounds",
    }
    if spec.face_width_mm is not None:  # flat face
        sentences.update({
            "curvature": f"rho <= {solution.rho_min_limit_mm:g} mm somewhere (min rho "
                         f"{out['rho_min_mm']:.6g} mm): the flat face cannot follow the profile",
            "face_width": f"face width needs {solution.required_face_width_mm:.6g} mm > upper bound "
                          f"{spec.face_width_mm[1]:g} mm",
        })
    else:
        sentences.update({
            "pressure_angle": f"pressure angle {out['pressure_angle_max_deg']:.6g} deg at "
                              f"{out['pressure_angle_max_at_deg']:g} deg > limit "
                              f"{out['max_pressure_angle_deg']:g} deg",
            "undercut": f"the roller undercuts the cam: smallest convex cam-surface radius "
                        f"{out['cam_rho_min_mm']:.6g} mm < {solution.rho_min_limit_mm:g} mm",
        })
    violations = [sentences[name] for name in out["violated"]]
    if required > rb_hi:
        violations.insert(0, f"base radius needs {required:.6g} mm > upper bound {rb_hi:g} mm")
    out.update({
        "peak_stress_MPa": sigma_peak,
        "violations": violations,
        "required_base_radius_mm": required,
        "required_base_radius_deg": solution.required_base_radius_deg,
        "binding_constraint": solution.binding_constraint,
    })
    if solution.required_face_width_mm is not None:
        out["required_face_width_mm"] = solution.required_face_width_mm
    return out


# -------------------------------------------------------------------------- evaluation


def evaluated_block(curves: DesignCurves, extremes: dict[str, Extremes]) -> dict[str, Any]:
    """Stress, curvature and roller figures at the evaluated design (rho = R_b + q, q = s + s'')."""
    out: dict[str, Any] = {}
    if curves.rho_mm is not None:
        q = extremes["q"]
        out["rho_mm"] = {"min": curves.base_radius_mm + q.min, "min_deg": q.min_deg}
    if curves.stress_MPa is not None:
        e = extremes["stress"]
        out["stress_MPa"] = {"max": e.max, "max_deg": e.max_deg}
    if curves.follower_type == "roller":
        phi, rho, margin = extremes["pressure_angle"], extremes["pitch_rho_abs"], extremes["undercut_margin"]
        deg = math.degrees
        worst = (phi.max, phi.max_deg) if phi.max >= -phi.min else (-phi.min, phi.min_deg)
        out["roller"] = {
            "roller_radius_mm": curves.roller_radius_mm,
            "offset_mm": curves.offset_mm,
            "prime_radius_mm": curves.base_radius_mm + curves.roller_radius_mm,
            "pressure_angle_deg": {"max": deg(phi.max), "max_deg": phi.max_deg, "min": deg(phi.min),
                                   "min_deg": phi.min_deg, "max_abs": deg(worst[0]), "max_abs_deg": worst[1]},
            "pressure_angle_limit_deg": curves.pressure_angle_limit_deg,
            # within the solvers' tolerance, as pipeline.geometry_violations judges it
            "pressure_angle_ok": bool(deg(worst[0]) <= curves.pressure_angle_limit_deg
                                      + math.degrees(FEASIBILITY_TOL_RAD)),
            "pitch_rho_mm": {"min_abs": rho.min, "min_abs_deg": rho.min_deg,
                             "concave": bool(np.any(curves.pitch_rho_mm < 0))},
            "undercut_margin_mm": {"min": margin.min, "min_deg": margin.min_deg},
            "undercut": bool(margin.min <= 0 or np.any(curves.undercut_margin_mm <= 0)),
        }
    return out


# the [follower] keys a [design] can replace, per follower type (a flat face's width is a
# [design] variable only)
SCENE_DIMENSIONS = {
    "roller": ("roller_radius_mm", "offset_mm"),
    "oscillating_roller": ("pivot_distance_mm", "arm_length_mm", "roller_radius_mm"),
    "oscillating_flat": ("pivot_distance_mm", "face_offset_mm"),
}


def follower_scene_block(follower: FollowerSpec) -> dict[str, float]:
    """The [follower] table's dimensions (mm) as the scene wrote them.

    Written as ``follower_scene`` beside a solved [design], whose dimensions the cam is computed
    with (``roller`` or ``oscillating_follower`` report those): the scene's stay visible under
    their own name where the two differ. Empty for a flat face (its [follower] has none).
    """
    return {k: getattr(follower, k) for k in SCENE_DIMENSIONS.get(follower.type, ())}


def feasibility_block(violations) -> dict[str, Any]:
    """Whether the written geometry is usable, and each broken constraint as {constraint, message}."""
    return {"feasible": not violations,
            "violations": [{"constraint": v.constraint, "message": v.message} for v in violations]}


# ------------------------------------------------------------------------------ report


def header_block(scene: Scene, arrays: SceneArrays, extremes: dict[str, Extremes] | None = None
                 ) -> dict[str, Any]:
    """Keys every report starts with: version, scene, grid, speed, follower, segments, motion, FLCD.

    ``extremes``: the run's (:func:`camjax.evaluate.curve_extremes`; exact when the arrays carry
    their model); None: the samples' own (an oscillating follower, whose report replaces the
    kinematics with its own, stays on the grid).
    """
    import camjax  # the version lives in the package

    return {
        "camjax_version": camjax.__version__,
        "scene": scene.name,
        "dtype": str(arrays.kin.s.dtype),
        "models": sorted(scene.needs()),
        "samples": int(arrays.theta_deg.shape[0]),
        "cam_speed_rpm": scene.motion.rpm,
        "rotation": scene.motion.rotation,
        "cam_speed_rad_s": _f(arrays.cam_speed_rad_s),
        "follower_type": scene.follower.type,
        "segments": [dict(s) for s in scene.motion.segments],
        "extrema": "exact" if extremes is not None and arrays.model is not None else "grid",
        "kinematics": kinematics_block(arrays, extremes),
        "flcd": flcd_block(scene),
        "flcd_units": FLCD_UNITS,
    }


def build_report(scene: Scene, run: DesignRun) -> dict[str, Any]:
    """The report of a scene's design run as a plain, JSON-ready dict (with a [design] of a roller,
    ``follower_scene`` keeps the [follower]'s R_f and offset beside the design's in ``roller``)."""
    arrays = run.arrays
    extremes = run.extremes
    if extremes is None:  # a run built without them: the samples' own
        extremes = curve_extremes(scene, arrays._replace(model=None), curve_names(scene, arrays),
                                  run.base_radius_mm, roller_radius_mm=run.curves.roller_radius_mm,
                                  offset_mm=run.curves.offset_mm)
    data = header_block(scene, arrays if run.extremes is not None else arrays._replace(model=None), extremes)
    block = loads_block(scene, arrays, extremes)
    if block is not None:
        data["loads"] = block
    follower = scene.follower  # sized with the R_f and offset the cam is drawn with
    if run.curves.roller_radius_mm is not None:
        follower = replace(follower, roller_radius_mm=run.curves.roller_radius_mm,
                           offset_mm=run.curves.offset_mm)
    data.update(min_base_radius_block(follower, run.min_base_radius,
                                      run.extremes is not None and arrays.model is not None))
    data.update(face_width_block(scene, extremes))
    if run.design is not None:
        data["design"] = design_block(scene.design, run.design)
        if scene.follower.type in SCENE_DIMENSIONS:
            data["follower_scene"] = follower_scene_block(scene.follower)
    data["evaluated_at"] = {"base_radius_mm": run.base_radius_mm,
                            "face_width_mm": run.curves.face_width_mm,
                            "source": run.base_radius_source,
                            **feasibility_block(run.violations)}
    data.update(evaluated_block(run.curves, extremes))
    return data
