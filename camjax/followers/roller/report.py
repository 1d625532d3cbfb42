"""result.json of a roller follower: its smallest cam, design sentences and the ``roller`` block."""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from camjax.family import FEASIBILITY_TOL_RAD
from camjax.followers import _closure_report, _translating_report


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, the prime-circle
    radius R_b + R_f, and the rule naming the binding limit (pressure angle or undercut) and its
    angle at the follower's R_f and offset."""
    out = {"min_base_radius_mm": minimum.radius_mm, "min_base_radius_deg": minimum.angle_deg}
    f = follower
    limits = {"pressure_angle": f"pressure angle |phi| <= {f.max_pressure_angle_deg:g} deg",
              "undercut": f"no undercut (convex cam-surface radius >= {f.min_curvature_radius_mm:g} mm)"}
    if minimum.binding in limits:
        other = next(k for k in limits if k != minimum.binding)
        rule = (f"roller: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
                f"(R_f = {f.roller_radius_mm:g} mm, offset {f.offset_mm:g} mm; {limits[other]} holds)")
    else:  # a positive drive's second contact binds
        rule = (f"roller: {_closure_report.sizing_rules(f)[minimum.binding]} at {minimum.angle_deg:g} deg "
                f"(R_f = {f.roller_radius_mm:g} mm, offset {f.offset_mm:g} mm)")
    return {**out, "min_prime_radius_mm": minimum.prime_radius_mm, "min_base_radius_rule": rule,
            "min_base_radius_binding": minimum.binding}


def design_sentences(spec, solution, out) -> dict[str, str]:
    return {
        "pressure_angle": f"pressure angle {out['pressure_angle_max_deg']:.6g} deg at "
                          f"{out['pressure_angle_max_at_deg']:g} deg > limit "
                          f"{out['max_pressure_angle_deg']:g} deg",
        "undercut": f"the roller undercuts the cam: smallest convex cam-surface radius "
                    f"{out['cam_rho_min_mm']:.6g} mm < {solution.rho_min_limit_mm:g} mm",
    }


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """The ``roller`` block: R_f, offset, prime radius, pressure angle, pitch curvature, undercut."""
    out: dict[str, Any] = {}
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


def extra_blocks(scene, run, extremes, data) -> None:
    """Nothing beyond the shared blocks."""


def report(scene, run) -> dict[str, Any]:
    """result.json of a roller follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
