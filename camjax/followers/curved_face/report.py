"""result.json of a curved-face follower: its smallest cam, design sentences and the ``curved_face`` block."""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from camjax.family import FEASIBILITY_TOL_MM, FEASIBILITY_TOL_RAD
from camjax.followers import _translating_report


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, the prime-circle
    radius R_b + R_c, and the rule naming the binding limit (pressure angle, face travel or
    undercut) at the follower's R_c, W and offset."""
    f = follower
    edge = math.degrees(math.asin(min(f.face_width_mm / (2.0 * f.face_radius_mm), 1.0)))
    limits = {"pressure_angle": f"pressure angle |phi| <= {f.max_pressure_angle_deg:g} deg",
              "face_travel": f"contact on the face (|R_c sin phi| <= W/2, i.e. |phi| <= {edge:.6g} deg)",
              "undercut": f"no undercut (convex cam-surface radius >= {f.min_curvature_radius_mm:g} mm)"}
    others = "; ".join(text for key, text in limits.items() if key != minimum.binding)
    rule = (f"curved face: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
            f"(R_c = {f.face_radius_mm:g} mm, W = {f.face_width_mm:g} mm, offset {f.offset_mm:g} mm; "
            f"{others} hold)")
    return {"min_base_radius_mm": minimum.radius_mm, "min_base_radius_deg": minimum.angle_deg,
            "min_prime_radius_mm": minimum.prime_radius_mm, "min_base_radius_rule": rule,
            "min_base_radius_binding": minimum.binding}


def design_sentences(spec, solution, out) -> dict[str, str]:
    return {
        "pressure_angle": f"pressure angle {out['pressure_angle_max_deg']:.6g} deg at "
                          f"{out['pressure_angle_max_at_deg']:g} deg > limit "
                          f"{out['max_pressure_angle_deg']:g} deg",
        "undercut": f"the face undercuts the cam: smallest convex cam-surface radius "
                    f"{out['cam_rho_min_mm']:.6g} mm < {solution.rho_min_limit_mm:g} mm",
        "face_travel": f"the contact runs off the face: R_c |sin phi| = {out['face_travel_max_mm']:.6g} mm "
                       f"at "
                       f"{out['face_travel_max_deg']:g} deg > W/2 = {0.5 * out['face_width_mm']:.6g} mm",
    }


def _signed(e, scale=1.0) -> dict[str, float]:
    worst = (e.max, e.max_deg) if e.max >= -e.min else (-e.min, e.min_deg)
    return {"max": scale * e.max, "max_deg": e.max_deg, "min": scale * e.min, "min_deg": e.min_deg,
            "max_abs": scale * worst[0], "max_abs_deg": worst[1]}


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """The ``curved_face`` block: R_c, W, offset, prime radius, pressure angle, the contact's travel
    on the face, the sliding speed, pitch curvature, undercut."""
    phi, rho, margin = extremes["pressure_angle"], extremes["pitch_rho_abs"], extremes["undercut_margin"]
    travel, slide = extremes["face_travel"], extremes["sliding_speed"]
    phi_block, travel_block = _signed(phi, math.degrees(1.0)), _signed(travel)
    half = 0.5 * curves.face_width_mm
    return {"curved_face": {
        "face_radius_mm": curves.roller_radius_mm,
        "face_width_mm": curves.face_width_mm,
        "offset_mm": curves.offset_mm,
        "prime_radius_mm": curves.base_radius_mm + curves.roller_radius_mm,
        "pressure_angle_deg": phi_block,
        "pressure_angle_limit_deg": curves.pressure_angle_limit_deg,
        # within the solvers' tolerance, as camjax.followers._translating.geometry_violations judges it
        "pressure_angle_ok": bool(phi_block["max_abs"] <= curves.pressure_angle_limit_deg
                                  + math.degrees(FEASIBILITY_TOL_RAD)),
        # where the contact sits on the face, off its axis: R_c sin phi, within +-W/2
        "face_travel_mm": travel_block,
        "face_half_width_mm": half,
        "face_travel_ok": bool(travel_block["max_abs"] <= half + 0.5 * FEASIBILITY_TOL_MM),
        # the face does not roll: the relative tangential speed of cam and face at the contact
        "sliding_speed_m_s": {"max": slide.max, "max_deg": slide.max_deg,
                              "min": slide.min, "min_deg": slide.min_deg},
        "pitch_rho_mm": {"min_abs": rho.min, "min_abs_deg": rho.min_deg,
                         "concave": bool(np.any(curves.pitch_rho_mm < 0))},
        "undercut_margin_mm": {"min": margin.min, "min_deg": margin.min_deg},
        "undercut": bool(margin.min <= 0 or np.any(curves.undercut_margin_mm <= 0)),
    }}


def extra_blocks(scene, run, extremes, data) -> None:
    """Nothing beyond the shared blocks."""


def report(scene, run) -> dict[str, Any]:
    """result.json of a curved-face follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
