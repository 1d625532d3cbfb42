"""result.json of a rocking follower's run: the assembly every such type shares.

A rocking follower's ``report.py`` calls :func:`report` with its own blocks (a module or any object
with these functions):

- ``follower_dimensions(curves, follower) -> dict``: its dimensions in ``oscillating_follower``
  (those the drawn cam was computed with);
- ``min_base_radius_rule(follower, binding) -> str``: the rule of its smallest cam;
- ``evaluated_block(curves, follower, worst, block) -> dict``: its own figures at the evaluated
  cam (``worst``: the sample of the largest |pressure angle|; ``block(values, name)``: the
  {max, max_deg, min, min_deg} of a curve, exact where the run refined it, see
  :meth:`camjax.followers._rocking.RockingFollower.point_curves` for the names).

The motion is reported in rad (swing in deg, angular velocity ... in SI); formatting only, as
:mod:`camjax.output.report`, whose shared blocks this uses.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from camjax import followers
from camjax.followers import _closure_report
from camjax.output.report import (
    extrema,
    feasibility_block,
    follower_scene_block,
    header_block,
    negative_ranges_deg,
)

ROCKER_FLCD_UNITS = {"jump_s": "rad", "jump_v": "rad/rad", "jump_a": "rad/rad^2", "jump_j": "rad/rad^3"}
NO_ADMISSIBLE_CAM = "no admissible cam for the design's pivot and arm: the design's own radius"


def _f(x) -> float:
    return float(np.asarray(x))


def report(scene, run, blocks) -> dict[str, Any]:
    """The report of a rocker scene as a plain, JSON-ready dict (strict JSON: no NaN or infinity).

    The common header (:func:`camjax.output.report.header_block`) with the motion in rad, the
    smallest admissible cam and its binding limit, the evaluated cam, loads about the pivot and
    the contact stress; with a solved [design], its block (``design``: the solver's keys) and the
    scene's own [follower] dimensions (``follower_scene``): ``oscillating_follower`` gives those
    the drawn cam was computed with.
    """
    sizing, c, f = run.sizing, run.curves, scene.follower
    t, ex = c.theta_deg, run.extremes or {}
    w = _f(run.arrays.cam_speed_rad_s) if run.arrays is not None else None

    def block(values, name=None, scale=1.0):
        """{max, max_deg, min, min_deg}: the run's (exact) extremes of ``name`` times ``scale`` (> 0)
        where it has them, else the samples' of ``values``."""
        if name in ex and scale is not None:
            e = ex[name]
            return {"max": scale * e.max, "max_deg": e.max_deg, "min": scale * e.min, "min_deg": e.min_deg}
        return extrema(values, t)

    deg = math.degrees(1.0)
    phi = block(c.pressure_angle_deg, "pressure_angle", deg)
    worst = (phi["max"], phi["max_deg"]) if phi["max"] >= -phi["min"] else (-phi["min"], phi["min_deg"])
    i = int(np.argmax(np.abs(c.pressure_angle_deg)))  # the sample of the largest |pressure angle|
    # the dimensions the drawn cam was computed with (a [design]'s where it solved them), not the
    # scene's [follower] table: those stay visible under follower_scene
    follower = {"type": f.type, "pivot_distance_mm": c.pivot_distance_mm, "rotation": c.rotation,
                **blocks.follower_dimensions(c, f), "min_curvature_radius_mm": f.min_curvature_radius_mm}
    rule = NO_ADMISSIBLE_CAM if sizing.binding == "none" else blocks.min_base_radius_rule(f, sizing.binding)
    out = header_block(scene, run.arrays, extremes=run.extremes)
    out.update({
        "flcd_units": ROCKER_FLCD_UNITS,
        "kinematics": {
            "swing_deg": block(c.swing_deg, "s", deg),
            "angular_velocity_rad_s": block(c.angular_velocity_rad_s, "ds", w),
            "angular_accel_rad_s2": block(c.angular_accel_rad_s2, "d2s", None if w is None else w**2),
            "angular_jerk_rad_s3": block(c.angular_jerk_rad_s3, "d3s", None if w is None else w**3),
            "velocity_rad_per_rad": block(c.ds, "ds"),
            "accel_rad_per_rad2": block(c.d2s, "d2s"),
        },
        "oscillating_follower": follower,
        "min_base_radius_mm": sizing.min_base_radius_mm,
        "min_base_radius_deg": sizing.angle_deg,
        "min_base_radius_rule": rule,
        "min_base_radius_binding": sizing.binding,
        "evaluated_at": {"base_radius_mm": run.base_radius_mm, "source": run.base_radius_source,
                         **feasibility_block(run.violations)},
    })
    if sizing.min_prime_radius_mm is not None:
        out["min_prime_radius_mm"] = sizing.min_prime_radius_mm
    rho = block(c.rho_mm, "rho")
    kappa = ex.get("pitch_curvature")
    if "rho" not in ex and kappa is not None and c.roller_radius_mm is not None and kappa.min > 0:
        # a roller's cam radius rho_c = 1 / kappa - R_f has poles where its pitch curve inflects (no
        # refined extremes of its own); where the pitch curve is convex at every angle (the refined
        # min of kappa > 0) rho_c is smallest where kappa is largest, at kappa's refined max. With a
        # concave part rho_c passes through infinity and the samples' min stays
        rho = {"min": 1.0 / kappa.max - c.roller_radius_mm, "min_deg": kappa.max_deg}
    out["evaluated"] = {
        "base_radius_mm": c.base_radius_mm,
        "arm_start_angle_deg": c.arm_start_angle_deg,
        "arm_angle_deg": block(c.arm_angle_deg, "arm_angle", deg),
        "pressure_angle_deg": {**phi, "max_abs": worst[0], "max_abs_deg": worst[1]},
        "rho_mm": {"min": rho["min"], "min_deg": rho["min_deg"]},
        **blocks.evaluated_block(c, f, i, block),
    }
    if c.pivot_torque_Nm is not None:
        m = c.pivot_torque_Nm
        moment = block(m, "pivot_torque")
        out["loads"] = {
            "pivot_torque_Nm": moment,
            "contact_force_N": block(c.contact_force_N, "contact_force"),
            "torque_Nm": block(c.torque_Nm, "torque"),
            "contact": {"min_pivot_torque_Nm": moment["min"], "min_pivot_torque_deg": moment["min_deg"],
                        "lost": bool(moment["min"] < 0 or np.any(m < 0)),
                        "lost_ranges_deg": negative_ranges_deg(m, t)},
        }
    if c.stress_MPa is not None:
        stress = block(c.stress_MPa, "stress")
        out["stress_MPa"] = {"max": stress["max"], "max_deg": stress["max_deg"]}
    if run.design is not None:
        out["design"] = run.design
        out["follower_scene"] = follower_scene_block(followers.of(scene), f)
    closure = f.closure.designed(run.design or {})
    if closure.positive:  # a groove or conjugate cams: no spring to lose, the load changes contact
        load = None if c.pivot_torque_Nm is None else c.pivot_torque_Nm / (c.arm_length_mm * 1e-3)
        out["closure"] = _closure_report.closure_block(closure, c, load, c.pressure_angle_deg)
        if "loads" in out:
            out["loads"]["contact"] = _closure_report.positive_contact(closure)
    return out
