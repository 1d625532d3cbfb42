"""result.json of an oscillating flat-face follower: its dimensions, rule and the face's reach."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from camjax.followers import _rocking_report


def _f(x) -> float:
    return float(np.asarray(x))


def follower_dimensions(curves, follower) -> dict[str, Any]:
    return {"face_offset_mm": curves.face_offset_mm}


def min_base_radius_rule(follower, binding: str) -> str:
    return {"curvature": f"cam radius of curvature >= {follower.min_curvature_radius_mm:g} mm"}[binding]


def evaluated_block(curves, follower, worst: int, block) -> dict[str, Any]:
    """Whether the curvature holds, and where the contact runs along the face."""
    c = curves
    rho, xi = block(c.rho_mm, "rho"), block(c.contact_distance_mm, "contact_distance")
    return dict(
        curvature_ok=bool(rho["min"] >= follower.min_curvature_radius_mm),
        face={"contact_min_mm": xi["min"], "contact_max_mm": xi["max"], "min_length_mm": xi["max"] - xi["min"],
              "note": "contact point along the face from the foot of the pivot, towards the cam centre"},
    )


def report(scene, run) -> dict[str, Any]:
    """result.json of an oscillating flat-face follower's design run."""
    return _rocking_report.report(scene, run, sys.modules[__name__])
