"""result.json of an oscillating roller follower: its dimensions, rule and evaluated figures."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from camjax.followers import _rocking_report


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
    }[binding]


def evaluated_block(curves, follower, worst: int) -> dict[str, Any]:
    """Prime radius, the pressure angle against its limit, pitch curvature and undercut."""
    c, t, phi = curves, curves.theta_deg, curves.pressure_angle_deg
    j = int(np.argmin(np.abs(c.pitch_rho_mm)))
    return dict(
        prime_radius_mm=c.prime_radius_mm,
        pressure_angle_ok=bool(abs(phi[worst]) <= follower.max_pressure_angle_deg),
        pitch_rho_mm={"min_abs": _f(abs(c.pitch_rho_mm[j])), "min_abs_deg": _f(t[j]),
                      "concave": bool(np.any(c.pitch_rho_mm < 0))},
        undercut_margin_mm={"min": _f(np.min(c.undercut_margin_mm)),
                            "min_deg": _f(t[int(np.argmin(c.undercut_margin_mm))])},
        undercut=bool(np.any(c.undercut_margin_mm <= 0)),
    )


def report(scene, run) -> dict[str, Any]:
    """result.json of an oscillating roller follower's design run."""
    return _rocking_report.report(scene, run, sys.modules[__name__])
