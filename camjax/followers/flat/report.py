"""result.json of a flat-face follower: its smallest cam, face width, design sentences and guide."""

from __future__ import annotations

import math
import sys
from typing import Any

from camjax import loads
from camjax.followers import _translating_report
from camjax.followers.flat import geometry as flat_geo
from camjax.output.report import extrema, scaled, trough


def min_base_radius_block(follower, minimum, exact: bool = False) -> dict[str, Any]:
    """Smallest admissible base radius (mm), the cam angle (deg) where rho = rho_min binds, and the
    rule; ``exact``: refined off the grid (every cam angle, not every sample)."""
    out = {"min_base_radius_mm": minimum.radius_mm, "min_base_radius_deg": minimum.angle_deg}
    where = "cam angle" if exact else "sample"
    rule = f"flat face: rho = R_b + s + s'' >= {follower.min_curvature_radius_mm:g} mm at every {where}"
    return {**out, "min_base_radius_rule": rule}


def design_sentences(spec, solution, out) -> dict[str, str]:
    return {
        "curvature": f"rho <= {solution.rho_min_limit_mm:g} mm somewhere (min rho "
                     f"{out['rho_min_mm']:.6g} mm): the flat face cannot follow the profile",
        "face_width": f"face width needs {solution.required_face_width_mm:.6g} mm > upper bound "
                      f"{spec.bounds('face_width_mm')[1]:g} mm",
    }


def evaluated_block(curves, extremes) -> dict[str, Any]:
    return {}


def face_width_block(scene, extremes) -> dict[str, Any]:
    """Minimum flat-face width (mm): symmetric 2 max|s'| and asymmetric max s' - min s'.

    The contact offset is s' (:func:`camjax.followers.flat.geometry.flat_contact_offset`), so both come from
    the extremes of s'.
    """
    v = extremes["ds"]
    return {
        "min_face_width_mm": 2.0 * max(v.max, -v.min, 0.0),
        "min_face_width_asymmetric_mm": v.max - v.min,
        "contact_offset_mm": scaled(v),
    }


def guide_block(scene, arrays, extremes=None) -> dict[str, Any]:
    """Chen's guide reactions with P = the follower force and a = s' (mm), and the jamming check.

    The stem can jam only with the contact on the side a < 0 (see
    :func:`camjax.loads.jamming_limit_mm`); the check compares max(-a) with that limit and, as an
    independent statement of the same condition, reports min Gamma (> 0 while not jammed).
    With ``extremes`` holding the guide curves (exact extrema) they are read from there.
    """
    guide, t = scene.guide, arrays.theta_deg
    limit = loads.jamming_limit_mm(guide)
    if extremes is not None and "cam_force" in extremes:
        reactions = {f"{name}_N": scaled(extremes[name])
                     for name in ("cam_force", "reaction_1", "reaction_2")}
        g = extremes["gamma"]
        gamma_min = {"min": g.min, "min_deg": g.min_deg}
        offset = extremes["ds"]  # the contact offset is s'
        worst = {"min": offset.min, "min_deg": offset.min_deg}
    else:
        # a in Chen's frame, whose friction directions turn with the cam: a cw cam is the mirror
        # image of the ccw one (face, friction and all), so a = s' for either rotation
        offset = flat_geo.flat_contact_offset(arrays.kin)
        r = loads.guide_reactions(guide, arrays.force_N, offset)
        reactions = {"cam_force_N": extrema(r.cam_force, t), "reaction_1_N": extrema(r.reaction_1, t),
                     "reaction_2_N": extrema(r.reaction_2, t)}
        worst = trough(offset, t)
        gamma_min = trough(r.gamma, t)
    reach = -worst["min"]  # most negative offset = furthest onto the jamming side
    jams = bool(gamma_min["min"] <= 0.0)
    return {
        "guide_reactions": {**reactions, "gamma_mm": gamma_min},
        "jamming_limit_mm": limit if math.isfinite(limit) else None,
        "jamming": {
            "offset_on_jamming_side_mm": reach,
            "offset_on_jamming_side_deg": worst["min_deg"],
            "margin_mm": (limit - reach) if math.isfinite(limit) else None,
            "jams": jams,
            "note": ("limit b/(2 mu) - mu0 b (1 + 2 xi)/2 from the corrected Gamma; "
                     "null limit = frictionless guide, never jams"),
        },
    }




def extra_blocks(scene, run, extremes, data) -> None:
    """The guide's reactions (with a [guide]) in the loads block, and the face width the motion needs."""
    if scene.guide is not None and "loads" in data:
        data["loads"].update(guide_block(scene, run.arrays, extremes))
    data.update(face_width_block(scene, extremes))


def report(scene, run) -> dict[str, Any]:
    """result.json of a flat-face follower's design run."""
    return _translating_report.report(scene, run, sys.modules[__name__])
