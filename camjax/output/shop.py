"""From design to the shop floor: what ``[manufacture]`` and a cam table add to a design's folder.

:func:`plan` computes everything before anything is written (a cutter that would gouge, a bore
that does not fit is a :class:`camjax.errors.SceneError`, exit 2 with nothing written);
:func:`write` writes cutter_path.csv, cam.nc, cam.stl and cam_table.csv/.json. A scene without
``[manufacture]``, ``[export]`` or ``--cam-table-points`` gets nothing from here. Host-side (JAX only
inside :func:`camjax.output.machining.cam_surface` and the cam table's exact law).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

from camjax import followers
from camjax.output import cam_table as table_mod
from camjax.output import machining, solid

DEFAULT_TABLE_TOLERANCE = 1e-3  # mm (deg for a rocker) when neither [export] nor [manufacture] gives one


class ShopPlan(NamedTuple):
    """What :func:`write` writes, computed; ``report``: result.json's ``manufacture`` and
    ``cam_table`` blocks (those that apply)."""

    scene_name: str
    units: str
    spec: Any  # ManufactureSpec or None
    path: machining.ToolPath | None
    gcode: list[str] | None
    triangles: Any  # (T, 3, 3) mm or None
    table: table_mod.CamTable | None
    report: dict[str, Any]


def plan(scene, data: dict, curves, *, cam_table_points: int | None = None, units: str = "mm") -> ShopPlan:
    """The shop-floor outputs of a designed scene: ``data`` its result.json dict (for the design's
    dimensions), ``curves`` the drawn curves (base radius, samples); ``cam_table_points`` (the CLI
    flag) wins over ``[export]``."""
    m, report = scene.manufacture, {}
    path = program = triangles = width = gcode = None
    if m is not None:
        width = m.cam_width_mm if m.cam_width_mm is not None else scene.contact.cam_width_mm
        dense = machining.dense_samples(scene.motion.samples, curves.profile_x_mm, curves.profile_y_mm)
        surface = machining.cam_surface(scene, data.get("design"), curves.base_radius_mm, dense)
        largest, at = machining.gouge_check(surface, m.cutter_diameter_mm)
        path = machining.tool_path(surface, m.cutter_diameter_mm / 2)
        program = machining.plan_program(path, m.tolerance_mm, units)
        triangles = solid.solid_triangles(solid.solid_outline(surface, m.tolerance_mm), width,
                                          m.bore_diameter_mm)
        gcode = machining.gcode_lines(program, path, feed_mm_per_min=m.feed_mm_per_min, width_mm=width,
                                      cutter_diameter_mm=m.cutter_diameter_mm, scene_name=scene.name,
                                      units=units)
        report["manufacture"] = {
            "cutter_diameter_mm": m.cutter_diameter_mm, "tolerance_mm": m.tolerance_mm,
            "feed_mm_per_min": m.feed_mm_per_min, "cam_width_mm": width,
            "bore_diameter_mm": m.bore_diameter_mm, "program": m.program, "units": units,
            "path_samples": int(dense),
            "largest_cutter_diameter_mm": None if at is None else largest,
            "tightest_concave_deg": at,
            "fit": {"max_deviation_mm": program.max_deviation_mm,
                    "max_radius_mismatch_mm": program.max_radius_mismatch_mm,
                    "arcs": program.arcs, "lines": program.lines,
                    "contour_blocks": program.arcs + program.lines,
                    "program_blocks": machining.program_blocks(gcode), "decimals": program.decimals},
            "solid": {"triangles": int(len(triangles)), "volume_mm3": solid_volume(triangles)},
        }
    points = cam_table_points
    if points is None and scene.export is not None:
        points = scene.export.cam_table_points
    tab = None
    if points is not None:
        from camjax.units import length_scale

        rocking = followers.of(scene).rocking
        tol = scene.export.tolerance if scene.export is not None else None
        if tol is None:
            tol = m.tolerance_mm if m is not None and not rocking else DEFAULT_TABLE_TOLERANCE
        if not rocking:  # mm (an inch scene's tolerance_in was read into mm) -> the table's unit
            tol = tol / length_scale(units)
        tab = table_mod.cam_table(scene, int(points), float(tol), units)
        report["cam_table"] = tab.report
    return ShopPlan(scene.name, units, m, path, gcode, triangles, tab, report)


def solid_volume(triangles) -> float:
    """Enclosed volume (mm^3) of a closed, outward-facing triangle mesh (divergence theorem)."""
    import numpy as np

    t = np.asarray(triangles)
    return float(np.sum(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2]))) / 6.0)


def write(folder: Path, p: ShopPlan) -> list[str]:
    """Write the plan's files into ``folder``; their names."""
    folder = Path(folder)
    names = []
    if p.spec is not None:
        machining.write_cutter_path_csv(folder / "cutter_path.csv", p.path, p.units)
        machining.write_gcode(folder / "cam.nc", p.gcode)
        solid.write_stl(folder / "cam.stl", p.triangles, p.units, f"camjax {p.scene_name}")
        names += ["cutter_path.csv", "cam.nc", "cam.stl"]
    if p.table is not None:
        names += [q.name for q in table_mod.write_cam_table(folder, p.table)]
    return names
