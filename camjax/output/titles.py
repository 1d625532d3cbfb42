"""The text that names a run on its figures (NumPy, matplotlib and JAX free: cheap to import).

:func:`title_block` turns a design report's dict into the three lines every figure carries, so
that printouts of two runs can be told apart; :data:`TURNS` words the scene's rotation.
"""

from __future__ import annotations

from collections.abc import Mapping

TURNS = {"ccw": "counter-clockwise", "cw": "clockwise"}  # scene motion.rotation -> words


def title_block(data: Mapping) -> str:
    """Three lines naming a run, from a design report's dict: scene, speed, rotation and follower;
    the segments' laws and lifts; the radii the figures are drawn at (and a rocker's pivot
    distance d with its arm l and roller R_f, or its face offset f)."""
    segments = []
    for seg in data.get("segments", []):
        text = f"{seg['kind']} {seg['angle_deg']:g}°"
        if seg.get("law"):
            lift = f"{seg['lift_deg']:g}°" if "lift_deg" in seg else f"{seg.get('lift_mm', 0.0):g} mm"
            text += f" {seg['law']} {lift}"
        segments.append(text)
    head = (f"scene {data.get('scene', '?')} · {data.get('cam_speed_rpm', float('nan')):g} rpm, "
            f"cam turns {TURNS.get(data.get('rotation', 'ccw'), '?')} · "
            f"{data.get('follower_type', '?')} follower")
    at = data.get("evaluated_at", {})
    radii = []
    if "base_radius_mm" in at:
        radii.append(f"R_b = {at['base_radius_mm']:.3f} mm")
    if at.get("face_width_mm") is not None:
        radii.append(f"L = {at['face_width_mm']:.3f} mm")
    roller = data.get("roller")
    if roller:
        radii.append(f"R_f = {roller['roller_radius_mm']:g} mm, e = {roller['offset_mm']:g} mm")
    rocker = data.get("oscillating_follower")  # the dimensions the cam was computed with
    if rocker:
        dims = [f"d = {rocker['pivot_distance_mm']:g} mm"]
        if "arm_length_mm" in rocker:
            dims += [f"l = {rocker['arm_length_mm']:g} mm", f"R_f = {rocker['roller_radius_mm']:g} mm"]
        else:
            dims.append(f"f = {rocker['face_offset_mm']:g} mm")
        radii.append(", ".join(dims))
    design = data.get("design")
    tail = f" ({at['source']})" if "source" in at else ""
    if design is not None and at.get("source") == "design":
        tail = f" (design: {design['solver']}, {'feasible' if design['feasible'] else 'INFEASIBLE'})"
    return "\n".join([head, " · ".join(segments), ", ".join(radii) + tail])
