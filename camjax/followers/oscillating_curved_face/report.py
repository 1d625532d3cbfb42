"""result.json of an oscillating curved-face follower: its dimensions, rule and the face's figures."""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from camjax.family import FEASIBILITY_TOL_MM
from camjax.followers import _rocking_report


def _f(x) -> float:
    return float(np.asarray(x))


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


def evaluated_block(curves, follower, worst: int) -> dict[str, Any]:
    """Prime radius, the pressure angle against its limit, the contact's travel on the face, the
    sliding speed, pitch curvature and undercut."""
    c, t, phi = curves, curves.theta_deg, curves.pressure_angle_deg
    j = int(np.argmin(np.abs(c.pitch_rho_mm)))
    travel, slide = np.asarray(c.face_travel_mm), np.asarray(c.sliding_speed_m_s)
    k = int(np.argmax(np.abs(travel)))
    half = 0.5 * c.face_width_mm
    return dict(
        prime_radius_mm=c.prime_radius_mm,
        pressure_angle_ok=bool(abs(phi[worst]) <= follower.max_pressure_angle_deg),
        # where the contact sits on the face, off its axis (positive towards the pivot): R_c sin phi
        face_travel_mm={"max": _f(np.max(travel)), "max_deg": _f(t[int(np.argmax(travel))]),
                        "min": _f(np.min(travel)), "min_deg": _f(t[int(np.argmin(travel))]),
                        "max_abs": _f(abs(travel[k])), "max_abs_deg": _f(t[k])},
        face_half_width_mm=half,
        face_travel_ok=bool(abs(travel[k]) <= half + 0.5 * FEASIBILITY_TOL_MM),
        # the face does not roll: the relative tangential speed of cam and face at the contact
        sliding_speed_m_s={"max": _f(np.max(slide)), "max_deg": _f(t[int(np.argmax(slide))]),
                           "min": _f(np.min(slide)), "min_deg": _f(t[int(np.argmin(slide))])},
        pitch_rho_mm={"min_abs": _f(abs(c.pitch_rho_mm[j])), "min_abs_deg": _f(t[j]),
                      "concave": bool(np.any(c.pitch_rho_mm < 0))},
        undercut_margin_mm={"min": _f(np.min(c.undercut_margin_mm)),
                            "min_deg": _f(t[int(np.argmin(c.undercut_margin_mm))])},
        undercut=bool(np.any(c.undercut_margin_mm <= 0)),
    )


def report(scene, run) -> dict[str, Any]:
    """result.json of an oscillating curved-face follower's design run."""
    return _rocking_report.report(scene, run, sys.modules[__name__])
