"""result.json of a curved-face follower: its smallest cam, design sentences and the ``curved_face`` block."""

from __future__ import annotations

import math
import sys
from typing import Any

from camjax.family import FEASIBILITY_TOL_MM
from camjax.followers import _translating_report


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, the prime-circle
    radius R_b + R_c, and the rule naming the binding limit (pressure angle, face travel or
    undercut) at the follower's R_c, W and offset."""
    f = follower
    edge = math.degrees(math.asin(min(f.face_width_mm / (2.0 * f.face_radius_mm), 1.0)))
    circle = _translating_report.limit_rules(f)
    limits = {"pressure_angle": circle["pressure_angle"],
              "face_travel": f"contact on the face (|R_c sin phi| <= W/2, i.e. |phi| <= {edge:.6g} deg)",
              "undercut": circle["undercut"]}
    others = "; ".join(text for key, text in limits.items() if key != minimum.binding)
    rule = (f"curved face: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
            f"(R_c = {f.face_radius_mm:g} mm, W = {f.face_width_mm:g} mm, offset {f.offset_mm:g} mm; "
            f"{others} hold)")
    return _translating_report.min_base_radius_keys(minimum, rule)


def design_sentences(spec, solution, out) -> dict[str, str]:
    return {
        **_translating_report.circle_sentences("the face", out, solution),
        "face_travel": f"the contact runs off the face: R_c |sin phi| = {out['face_travel_max_mm']:.6g} mm "
                       f"at "
                       f"{out['face_travel_max_deg']:g} deg > W/2 = {0.5 * out['face_width_mm']:.6g} mm",
    }


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """The ``curved_face`` block: R_c, W, offset, prime radius, pressure angle, the contact's travel
    on the face, the sliding speed, pitch curvature, undercut."""
    r = _translating_report
    travel, slide = extremes["face_travel"], extremes["sliding_speed"]
    travel_block = r.signed_extremes(travel)
    half = 0.5 * curves.face_width_mm
    return {"curved_face": {
        "face_radius_mm": curves.roller_radius_mm,
        "face_width_mm": curves.face_width_mm,
        "offset_mm": curves.offset_mm,
        "prime_radius_mm": curves.base_radius_mm + curves.roller_radius_mm,
        **r.pressure_angle_keys(curves, extremes["pressure_angle"]),
        # where the contact sits on the face, off its axis: R_c sin phi, within +-W/2
        "face_travel_mm": travel_block,
        "face_half_width_mm": half,
        "face_travel_ok": bool(travel_block["max_abs"] <= half + 0.5 * FEASIBILITY_TOL_MM),
        # the face does not roll: the relative tangential speed of cam and face at the contact
        "sliding_speed_m_s": {"max": slide.max, "max_deg": slide.max_deg,
                              "min": slide.min, "min_deg": slide.min_deg},
        "pitch_rho_mm": r.pitch_rho_block(curves, extremes["pitch_rho_abs"]),
        **r.undercut_keys(curves, extremes["undercut_margin"]),
    }}


def extra_blocks(scene, run, extremes, data) -> None:
    """Nothing beyond the shared blocks."""


def report(scene, run) -> dict[str, Any]:
    """result.json of a curved-face follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
