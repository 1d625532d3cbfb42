"""result.json of a rocking follower's run: the assembly every such type shares.

A rocking follower's ``report.py`` calls :func:`report` with its own blocks (a module or any object
with these functions):

- ``follower_dimensions(curves, follower) -> dict``: its dimensions in ``oscillating_follower``
  (those the drawn cam was computed with);
- ``min_base_radius_rule(follower, binding) -> str``: the rule of its smallest cam;
- ``evaluated_block(curves, follower, worst) -> dict``: its own figures at the evaluated cam
  (``worst``: the sample of the largest |pressure angle|).

The motion is reported in rad (swing in deg, angular velocity ... in SI); formatting only, as
:mod:`camjax.output.report`, whose shared blocks this uses.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from camjax import followers
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
    t = c.theta_deg
    phi = c.pressure_angle_deg
    i = int(np.argmax(np.abs(phi)))
    # the dimensions the drawn cam was computed with (a [design]'s where it solved them), not the
    # scene's [follower] table: those stay visible under follower_scene
    follower = {"type": f.type, "pivot_distance_mm": c.pivot_distance_mm, "rotation": c.rotation,
                **blocks.follower_dimensions(c, f), "min_curvature_radius_mm": f.min_curvature_radius_mm}
    rule = NO_ADMISSIBLE_CAM if sizing.binding == "none" else blocks.min_base_radius_rule(f, sizing.binding)
    out = header_block(scene, run.arrays)
    out.update({
        "flcd_units": ROCKER_FLCD_UNITS,
        "kinematics": {
            "swing_deg": extrema(c.swing_deg, t),
            "angular_velocity_rad_s": extrema(c.angular_velocity_rad_s, t),
            "angular_accel_rad_s2": extrema(c.angular_accel_rad_s2, t),
            "angular_jerk_rad_s3": extrema(c.angular_jerk_rad_s3, t),
            "velocity_rad_per_rad": extrema(c.ds, t),
            "accel_rad_per_rad2": extrema(c.d2s, t),
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
    out["evaluated"] = {
        "base_radius_mm": c.base_radius_mm,
        "arm_start_angle_deg": c.arm_start_angle_deg,
        "arm_angle_deg": extrema(c.arm_angle_deg, t),
        "pressure_angle_deg": {**extrema(phi, t), "max_abs": _f(abs(phi[i])), "max_abs_deg": _f(t[i])},
        "rho_mm": {"min": _f(np.min(c.rho_mm)), "min_deg": _f(t[int(np.argmin(c.rho_mm))])},
        **blocks.evaluated_block(c, f, i),
    }
    if c.pivot_torque_Nm is not None:
        m = c.pivot_torque_Nm
        out["loads"] = {
            "pivot_torque_Nm": extrema(m, t),
            "contact_force_N": extrema(c.contact_force_N, t),
            "torque_Nm": extrema(c.torque_Nm, t),
            "contact": {"min_pivot_torque_Nm": _f(np.min(m)),
                        "min_pivot_torque_deg": _f(t[int(np.argmin(m))]),
                        "lost": bool(np.any(m < 0)), "lost_ranges_deg": negative_ranges_deg(m, t)},
        }
    if c.stress_MPa is not None:
        k = int(np.argmax(c.stress_MPa))
        out["stress_MPa"] = {"max": _f(c.stress_MPa[k]), "max_deg": _f(t[k])}
    if run.design is not None:
        out["design"] = run.design
        out["follower_scene"] = follower_scene_block(followers.of(scene), f)
    return out
