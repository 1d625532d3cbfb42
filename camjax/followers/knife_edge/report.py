"""result.json of a knife-edge follower: its smallest cam, design sentences and the ``knife_edge`` block."""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from camjax.family import FEASIBILITY_TOL_MM, FEASIBILITY_TOL_RAD
from camjax.followers import _translating_report


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, and the rule naming
    the binding limit (pressure angle or the profile's convex radius) at the follower's offset."""
    f = follower
    limits = {"pressure_angle": f"pressure angle |phi| <= {f.max_pressure_angle_deg:g} deg",
              "curvature": f"convex profile radius >= {f.min_curvature_radius_mm:g} mm"}
    other = next(k for k in limits if k != minimum.binding)
    rule = (f"knife edge: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
            f"(offset {f.offset_mm:g} mm; {limits[other]} holds)")
    return {"min_base_radius_mm": minimum.radius_mm, "min_base_radius_deg": minimum.angle_deg,
            "min_base_radius_rule": rule, "min_base_radius_binding": minimum.binding}


def design_sentences(spec, solution, out) -> dict[str, str]:
    return {
        "pressure_angle": f"pressure angle {out['pressure_angle_max_deg']:.6g} deg at "
                          f"{out['pressure_angle_max_at_deg']:g} deg > limit "
                          f"{out['max_pressure_angle_deg']:g} deg",
        "curvature": f"the profile is too sharp for the knife edge: smallest convex radius "
                     f"{out['profile_rho_min_mm']:.6g} mm < {solution.rho_min_limit_mm:g} mm",
    }


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """The ``knife_edge`` block: offset, pressure angle, the profile's curvature and its margin."""
    phi, rho, margin = extremes["pressure_angle"], extremes["pitch_rho_abs"], extremes["undercut_margin"]
    deg = math.degrees
    worst = (phi.max, phi.max_deg) if phi.max >= -phi.min else (-phi.min, phi.min_deg)
    return {"knife_edge": {
        "offset_mm": curves.offset_mm,
        "pressure_angle_deg": {"max": deg(phi.max), "max_deg": phi.max_deg, "min": deg(phi.min),
                               "min_deg": phi.min_deg, "max_abs": deg(worst[0]), "max_abs_deg": worst[1]},
        "pressure_angle_limit_deg": curves.pressure_angle_limit_deg,
        # within the solvers' tolerance, as the run's geometry violations judge it
        "pressure_angle_ok": bool(deg(worst[0]) <= curves.pressure_angle_limit_deg
                                  + math.degrees(FEASIBILITY_TOL_RAD)),
        "profile_rho_mm": {"min_abs": rho.min, "min_abs_deg": rho.min_deg,
                           "concave": bool(np.any(curves.pitch_rho_mm < 0))},
        # rho - min_curvature_radius_mm on the convex parts (concave parts: no limit)
        "curvature_margin_mm": {"min": margin.min, "min_deg": margin.min_deg},
        "curvature_ok": bool(margin.min >= -FEASIBILITY_TOL_MM),
    }}


def extra_blocks(scene, run, extremes, data) -> None:
    """Nothing beyond the shared blocks."""


def report(scene, run) -> dict[str, Any]:
    """result.json of a knife-edge follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
