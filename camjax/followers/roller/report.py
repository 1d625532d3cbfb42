"""result.json of a roller follower: its smallest cam, design sentences and the ``roller`` block."""

from __future__ import annotations

import sys
from typing import Any

from camjax.followers import _closure_report, _translating_report


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where it binds, the prime-circle
    radius R_b + R_f, and the rule naming the binding limit (pressure angle or undercut) and its
    angle at the follower's R_f and offset."""
    f = follower
    limits = _translating_report.limit_rules(f)
    if minimum.binding in limits:
        other = next(k for k in limits if k != minimum.binding)
        rule = (f"roller: {limits[minimum.binding]} binds at {minimum.angle_deg:g} deg "
                f"(R_f = {f.roller_radius_mm:g} mm, offset {f.offset_mm:g} mm; {limits[other]} holds)")
    else:  # a positive drive's second contact binds
        rule = (f"roller: {_closure_report.sizing_rules(f)[minimum.binding]} at {minimum.angle_deg:g} deg "
                f"(R_f = {f.roller_radius_mm:g} mm, offset {f.offset_mm:g} mm)")
    return _translating_report.min_base_radius_keys(minimum, rule)


def design_sentences(spec, solution, out) -> dict[str, str]:
    return _translating_report.circle_sentences("the roller", out, solution)


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """The ``roller`` block: R_f, offset, prime radius, pressure angle, pitch curvature, undercut."""
    r = _translating_report
    return {"roller": {
        "roller_radius_mm": curves.roller_radius_mm,
        "offset_mm": curves.offset_mm,
        "prime_radius_mm": curves.base_radius_mm + curves.roller_radius_mm,
        **r.pressure_angle_keys(curves, extremes["pressure_angle"]),
        "pitch_rho_mm": r.pitch_rho_block(curves, extremes["pitch_rho_abs"]),
        **r.undercut_keys(curves, extremes["undercut_margin"]),
    }}


def extra_blocks(scene, run, extremes, data) -> None:
    """Nothing beyond the shared blocks."""


def report(scene, run) -> dict[str, Any]:
    """result.json of a roller follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
