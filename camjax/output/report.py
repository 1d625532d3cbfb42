"""Design report: a scene's run (:func:`camjax.pipeline.run_design`) -> a JSON-ready dict.

The blocks every follower's result.json shares (header, motion, FLCD, loads, feasibility, the
scene's own dimensions) are here; each follower's ``report.py`` (:mod:`camjax.followers`) adds its
own and assembles the whole (:func:`camjax.pipeline.analyse` runs the pipeline and asks the
follower for it). Formatting only: every block condenses arrays the run already computed into
plain values (degrees, SI or the unit in the key) with no NaN or infinity, so that a report can be
written as strict JSON.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from camjax.evaluate import SceneArrays
from camjax.program import joints
from camjax.results import Extremes
from camjax.scene import FollowerSpec, Scene

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
    """Jumps of s, s', s'', s''' (mm, per rad; see FLCD_UNITS) and their FLCD class at every joint.

    Where the scene has joint conditions, each joint also lists the derivatives it was asked to
    match (``asked_to_match``: "v", "a", "j"; a scene where one of them jumps is refused).
    """
    asked = scene.motion.asked_to_match
    return [
        {"joint_deg": j.joint_deg, "before_segment": j.before, "after_segment": j.after,
         "jump_s": j.jump_s, "jump_v": j.jump_v, "jump_a": j.jump_a, "jump_j": j.jump_j,
         "class": j.flcd_class, **({"asked_to_match": list(asked[j.after])} if asked else {})}
        for j in joints(scene.motion.program)
    ]


def loads_block(scene: Scene, arrays: SceneArrays, extremes: dict[str, Extremes]) -> dict[str, Any] | None:
    """Force, torque and the contact-loss check of a translating follower; None without loads.

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
    return out


def feasibility_block(violations) -> dict[str, Any]:
    """Whether the written geometry is usable, and each broken constraint as {constraint, message}."""
    return {"feasible": not violations,
            "violations": [{"constraint": v.constraint, "message": v.message} for v in violations]}


# ------------------------------------------------------------------------------ report


def header_block(scene: Scene, arrays: SceneArrays, extremes: dict[str, Extremes] | None = None
                 ) -> dict[str, Any]:
    """Keys every report starts with: version, scene, grid, speed, follower, segments, motion, FLCD.

    ``extremes``: the run's (:func:`camjax.evaluate.curve_extremes`; exact when the arrays carry
    their model); None: the samples' own. A rocking follower's report replaces the kinematics with
    its own (in rad).
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


def follower_scene_block(follower, spec: FollowerSpec) -> dict[str, float]:
    """The [follower] table's dimensions (mm) that a [design] can replace, as the scene wrote them.

    Written as ``follower_scene`` beside a solved [design], whose dimensions the cam is computed
    with (the follower's own block reports those): the scene's stay visible under their own name
    where the two differ. Empty where the [follower] has none of the design variables (a flat
    face: its width is a [design] variable only).
    """
    return {k: getattr(spec, k) for k in follower.variables if k != "base_radius_mm" and hasattr(spec, k)}
