"""Outlines and figure parts of a positive drive (groove or conjugate cams), NumPy and matplotlib only.

The curves of :mod:`camjax.followers._closure` travel in the follower's ``own_curves`` under
profile.csv's column names (``inner_x_mm`` ... ``outer_y_mm`` of a groove,
``conjugate_pitch_x_mm`` ... ``conjugate_y_mm`` of a conjugate pair); this module turns them into
the DXF's layers and draws them on the profile figure and in the animation, for either family.
"""

from __future__ import annotations

import numpy as np

GROOVE_LAYERS = ("GROOVE_INNER", "GROOVE_OUTER")
CONJUGATE_LAYERS = ("CAM_PROFILE", "CONJUGATE_CAM")


def closure_of(curves) -> str:
    """The curves' closure ("spring" for curves written before closures existed)."""
    return getattr(curves, "closure", "spring")


def outlines(curves) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(DXF layer, X, Y) of every outline to cut, cam coordinates: the cam profile on CAM_PROFILE;
    a groove's inner and outer flank on GROOVE_INNER and GROOVE_OUTER; a conjugate pair's first cam
    on CAM_PROFILE and its second on CONJUGATE_CAM."""
    own, kind = getattr(curves, "own_curves", None) or {}, closure_of(curves)
    if kind == "groove":
        return [(GROOVE_LAYERS[0], own["inner_x_mm"], own["inner_y_mm"]),
                (GROOVE_LAYERS[1], own["outer_x_mm"], own["outer_y_mm"])]
    first = (CONJUGATE_LAYERS[0], curves.profile_x_mm, curves.profile_y_mm)
    if kind == "conjugate":
        return [first, (CONJUGATE_LAYERS[1], own["conjugate_x_mm"], own["conjugate_y_mm"])]
    return [first]


def draw_closure(ax, curves) -> float:
    """The second flank or cam (and a conjugate cam's pitch curve) on the profile figure; the largest
    distance from the cam centre drawn (0 for a spring-closed follower)."""
    own, kind = getattr(curves, "own_curves", None) or {}, closure_of(curves)
    if kind == "groove":
        x, y = own["outer_x_mm"], own["outer_y_mm"]
        ax.plot(np.append(x, x[0]), np.append(y, y[0]), color="C4", linewidth=1.5,
                label="groove outer flank")
        return float(np.max(np.hypot(x, y)))
    if kind == "conjugate":
        x, y = own["conjugate_x_mm"], own["conjugate_y_mm"]
        px, py = own["conjugate_pitch_x_mm"], own["conjugate_pitch_y_mm"]
        ax.fill(x, y, color="C4", alpha=0.08)
        ax.plot(np.append(x, x[0]), np.append(y, y[0]), color="C4", linewidth=1.5, label="conjugate (second) cam")
        ax.plot(np.append(px, px[0]), np.append(py, py[0]), color="C4", linestyle="-.", linewidth=0.8,
                label="second roller's pitch curve")
        return float(max(np.max(np.hypot(x, y)), np.max(np.hypot(px, py))))
    return 0.0


def second_outline(curves) -> tuple[np.ndarray, np.ndarray] | None:
    """The second flank or cam the animation turns with the first (cam coordinates), or None."""
    own, kind = getattr(curves, "own_curves", None) or {}, closure_of(curves)
    if kind == "groove":
        return own["outer_x_mm"], own["outer_y_mm"]
    if kind == "conjugate":
        return own["conjugate_x_mm"], own["conjugate_y_mm"]
    return None


def second_roller(curves) -> tuple[np.ndarray, np.ndarray, float] | None:
    """A conjugate pair's second roller for the animation: its centre's path (the second pitch
    curve, cam coordinates) and its radius (the distance from that curve to the second cam, the
    same at every sample), or None (a groove's one roller, a spring-closed follower)."""
    own = getattr(curves, "own_curves", None) or {}
    if closure_of(curves) != "conjugate":
        return None
    px, py = np.asarray(own["conjugate_pitch_x_mm"]), np.asarray(own["conjugate_pitch_y_mm"])
    radius = float(np.hypot(own["conjugate_x_mm"][0] - px[0], own["conjugate_y_mm"][0] - py[0]))
    return px, py, radius
