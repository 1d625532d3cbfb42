"""result.json of an oscillating curved-face follower: its dimensions, rule and the face's figures."""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from camjax.family import FEASIBILITY_TOL_MM
from camjax.followers import _rocking_report


def follower_dimensions(curves, follower) -> dict[str, Any]:
    return {"arm_length_mm": curves.arm_length_mm, "face_radius_mm": curves.roller_radius_mm,
            "face_width_mm": curves.face_width_mm, "max_pressure_angle_deg": follower.max_pressure_angle_deg}


def min_base_radius_rule(follower, binding: str) -> str:
    f = follower
    edge = math.degrees(math.asin(min(f.face_width_mm / (2.0 * f.face_radius_mm), 1.0)))
    limits = {"pressure_angle": f"|pressure angle| <= {f.max_pressure_angle_deg:g} deg",
              "face_travel": f"contact on the face (|R_c sin phi| <= W/2, i.e. |phi| <= {edge:.6g} deg)",
              "undercut": f"no undercut (cam-surface radius >= {f.min_curvature_radius_mm:g} mm)"}
    others = " and ".join(text for key, text in limits.items() if key != binding)
    return (f"{limits[binding]} (binding; R_c = {f.face_radius_mm:g} mm, W = {f.face_width_mm:g} mm) "
            f"and {others}")


def _largest_abs(e) -> tuple[float, float]:
    """(max |value|, its angle) of a {max, max_deg, min, min_deg} block."""
    return (e["max"], e["max_deg"]) if e["max"] >= -e["min"] else (-e["min"], e["min_deg"])


def evaluated_block(curves, follower, worst: int, block) -> dict[str, Any]:
    """Prime radius, the pressure angle against its limit, the contact's travel on the face, the
    sliding speed, pitch curvature and undercut (exact extrema where the run refined them)."""
    c, deg = curves, math.degrees(1.0)
    phi = block(c.pressure_angle_deg, "pressure_angle", deg)
    # the smallest |pitch radius| is 1 / the largest |pitch curvature| (the radius has poles)
    kappa = block(1.0 / c.pitch_rho_mm, "pitch_curvature")
    top = _largest_abs(kappa)
    undercut = block(c.undercut_margin_mm, "undercut_margin")
    travel = block(c.face_travel_mm, "face_travel")
    far = _largest_abs(travel)
    half = 0.5 * c.face_width_mm
    return dict(
        prime_radius_mm=c.prime_radius_mm,
        pressure_angle_ok=bool(max(phi["max"], -phi["min"]) <= follower.max_pressure_angle_deg),
        # where the contact sits on the face, off its axis (positive towards the pivot): R_c sin phi
        face_travel_mm={**travel, "max_abs": far[0], "max_abs_deg": far[1]},
        face_half_width_mm=half,
        # within the solvers' tolerance, as the run's face-width check judges it
        face_travel_ok=bool(far[0] <= half + 0.5 * FEASIBILITY_TOL_MM),
        # the face does not roll: the relative tangential speed of cam and face at the contact
        sliding_speed_m_s=block(c.sliding_speed_m_s, "sliding_speed"),
        pitch_rho_mm={"min_abs": 1.0 / top[0], "min_abs_deg": top[1],
                      "concave": bool(np.any(c.pitch_rho_mm < 0))},
        undercut_margin_mm={"min": undercut["min"], "min_deg": undercut["min_deg"]},
        undercut=bool(undercut["min"] <= 0 or np.any(c.undercut_margin_mm <= 0)),
    )


def report(scene, run) -> dict[str, Any]:
    """result.json of an oscillating curved-face follower's design run."""
    return _rocking_report.report(scene, run, sys.modules[__name__])
