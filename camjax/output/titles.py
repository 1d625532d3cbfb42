"""The text that names a run on its figures (NumPy, matplotlib and JAX free: cheap to import).

:func:`title_block` turns a design report's dict into the three lines every figure carries, so
that printouts of two runs can be told apart; :data:`TURNS` words the scene's rotation.
"""

from __future__ import annotations

from collections.abc import Mapping

from camjax import followers

TURNS = {"ccw": "counter-clockwise", "cw": "clockwise"}  # scene motion.rotation -> words


def title_block(data: Mapping) -> str:
    """Three lines naming a run, from a design report's dict: scene, speed, rotation and follower;
    the segments' laws and lifts; the radii the figures are drawn at and the follower's own
    dimensions (its follower's ``title_dimensions``: a roller's R_f and offset, a rocker's pivot
    distance d with its arm l and roller R_f, or its face offset f). The follower is imported to
    word them (the design that wrote ``data`` has it loaded), not its drawing module: the command
    line words the title before its drawing processes draw, without matplotlib."""
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
    if data.get("follower_type") in followers.names():  # the follower's own dimensions, as drawn
        radii += followers.get(data["follower_type"]).title_dimensions(data)
    design = data.get("design")
    tail = f" ({at['source']})" if "source" in at else ""
    if design is not None and at.get("source") == "design":
        tail = f" (design: {design['solver']}, {'feasible' if design['feasible'] else 'INFEASIBLE'})"
    return "\n".join([head, " · ".join(segments), ", ".join(radii) + tail])
