"""result.json of a knife-edge follower: its smallest cam, design sentences and the ``knife_edge`` block."""

from __future__ import annotations

import sys
from typing import Any

from camjax.family import FEASIBILITY_TOL_MM
from camjax.followers import _translating_report


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, and the rule naming
    the binding limit (pressure angle or the profile's convex radius) at the follower's offset."""
    f = follower
    limits = {"pressure_angle": _translating_report.limit_rules(f)["pressure_angle"],
              "curvature": f"convex profile radius >= {f.min_curvature_radius_mm:g} mm"}
    other = next(k for k in limits if k != minimum.binding)
    rule = (f"knife edge: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
            f"(offset {f.offset_mm:g} mm; {limits[other]} holds)")
    return _translating_report.min_base_radius_keys(minimum, rule, prime=False)


def design_sentences(spec, solution, out) -> dict[str, str]:
    return {
        "pressure_angle": _translating_report.pressure_angle_sentence(out),
        "curvature": f"the profile is too sharp for the knife edge: smallest convex radius "
                     f"{out['profile_rho_min_mm']:.6g} mm < {solution.rho_min_limit_mm:g} mm",
    }


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """The ``knife_edge`` block: offset, pressure angle, the profile's curvature and its margin."""
    margin = extremes["undercut_margin"]
    return {"knife_edge": {
        "offset_mm": curves.offset_mm,
        **_translating_report.pressure_angle_keys(curves, extremes["pressure_angle"]),
        "profile_rho_mm": _translating_report.pitch_rho_block(curves, extremes["pitch_rho_abs"]),
        # rho - min_curvature_radius_mm on the convex parts (concave parts: no limit)
        "curvature_margin_mm": {"min": margin.min, "min_deg": margin.min_deg},
        "curvature_ok": bool(margin.min >= -FEASIBILITY_TOL_MM),
    }}


def extra_blocks(scene, run, extremes, data) -> None:
    """Nothing beyond the shared blocks."""


def report(scene, run) -> dict[str, Any]:
    """result.json of a knife-edge follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
