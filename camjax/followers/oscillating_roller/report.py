"""result.json of an oscillating roller follower: its dimensions, rule and evaluated figures."""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from camjax.followers import _closure_report, _rocking_report


def _f(x) -> float:
    return float(np.asarray(x))


def follower_dimensions(curves, follower) -> dict[str, Any]:
    return {"arm_length_mm": curves.arm_length_mm, "roller_radius_mm": curves.roller_radius_mm,
            "max_pressure_angle_deg": follower.max_pressure_angle_deg}


def min_base_radius_rule(follower, binding: str) -> str:
    f = follower
    return {
        "pressure_angle": f"|pressure angle| <= {f.max_pressure_angle_deg:g} deg (binding) and no undercut",
        "undercut": f"no undercut (binding; cam-surface radius >= {f.min_curvature_radius_mm:g} mm) and "
                    f"|pressure angle| <= {f.max_pressure_angle_deg:g} deg",
        **_closure_report.sizing_rules(f),
    }[binding]


def evaluated_block(curves, follower, worst: int, block) -> dict[str, Any]:
    """Prime radius, the pressure angle against its limit, pitch curvature and undercut."""
    c, deg = curves, math.degrees(1.0)
    phi = block(c.pressure_angle_deg, "pressure_angle", deg)
    # the smallest |pitch radius| is 1 / the largest |pitch curvature| (the radius has poles)
    kappa = block(1.0 / c.pitch_rho_mm, "pitch_curvature")
    top = (kappa["max"], kappa["max_deg"]) if kappa["max"] >= -kappa["min"] else (-kappa["min"], kappa["min_deg"])
    pitch = {"min": 1.0 / top[0], "min_deg": top[1]}
    undercut = block(c.undercut_margin_mm, "undercut_margin")
    return dict(
        prime_radius_mm=c.prime_radius_mm,
        pressure_angle_ok=bool(max(phi["max"], -phi["min"]) <= follower.max_pressure_angle_deg),
        pitch_rho_mm={"min_abs": pitch["min"], "min_abs_deg": pitch["min_deg"],
                      "concave": bool(np.any(c.pitch_rho_mm < 0))},
        undercut_margin_mm={"min": undercut["min"], "min_deg": undercut["min_deg"]},
        undercut=bool(undercut["min"] <= 0 or np.any(c.undercut_margin_mm <= 0)),
    )


def report(scene, run) -> dict[str, Any]:
    """result.json of an oscillating roller follower's design run."""
    return _rocking_report.report(scene, run, sys.modules[__name__])
