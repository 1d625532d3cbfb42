"""[manufacture] and [export]: how the cam is cut and what a servo drive's cam table holds.

Both sections are optional; a scene without them is designed exactly as before (they only add
files, :mod:`camjax.output.machining` and :mod:`camjax.output.cam_table`).
"""

from __future__ import annotations

from camjax.errors import MISSING
from camjax.scene.reader import DEFAULT, TableReader, build
from camjax.scene.spec import MACHINE_PROGRAMS, ExportSpec, ManufactureSpec

CAM_TABLE_POINTS_MAX = 1_000_000  # as motion.samples: one row per point
MANUFACTURE_KEYS = ("cutter_diameter_mm", "tolerance_mm", "feed_mm_per_min", "bore_diameter_mm", "program",
                    "cam_width_mm")
# the G-code writes lengths to 1e-6 mm at most: a tolerance must stay well above that
TOLERANCE_MIN_MM = 1e-4


def parse_manufacture(r: TableReader, cam_width_mm: float | None) -> ManufactureSpec:
    """[manufacture]; ``cam_width_mm``: [contact]'s (None without [contact]: the section must give
    the plate's width itself, and may not when [contact] gives it)."""
    r.check_keys(MANUFACTURE_KEYS)
    width = DEFAULT
    if cam_width_mm is None:
        if not r.has("cam_width_mm"):
            raise r.error("cam_width_mm", MISSING, "is required without a [contact] section (the "
                          "solid's and the G-code's plate width)", "a number > 0, mm")
        width = r.number("cam_width_mm", low=0.0, low_open=True, high=1e6)
    elif r.has("cam_width_mm"):
        raise r.error("cam_width_mm", r.table["cam_width_mm"], "the plate's width is contact.cam_width_mm "
                      "in a scene with [contact]", "leave it out here")
    bore = DEFAULT
    if r.has("bore_diameter_mm"):
        bore = r.number("bore_diameter_mm", low=0.0, low_open=True, high=1e6)
    return build(
        ManufactureSpec,
        cutter_diameter_mm=r.number("cutter_diameter_mm", low=0.0, low_open=True, high=1e6),
        feed_mm_per_min=r.number("feed_mm_per_min", low=0.0, low_open=True, high=1e9),
        tolerance_mm=r.number("tolerance_mm", DEFAULT, low=TOLERANCE_MIN_MM, high=1.0),
        bore_diameter_mm=bore,
        program=r.choice("program", MACHINE_PROGRAMS, DEFAULT),
        cam_width_mm=width,
    )


def parse_export(r: TableReader, rocking: bool) -> ExportSpec:
    """[export]: ``cam_table_points`` (2 .. 1e6) and the interpolation figures' tolerance, in the
    follower's position unit (``tolerance_mm``; ``tolerance_deg`` for a rocking follower)."""
    unit = "deg" if rocking else "mm"
    r.check_keys(("cam_table_points", f"tolerance_{unit}"))
    return build(
        ExportSpec,
        cam_table_points=r.number("cam_table_points", DEFAULT, low=2, high=CAM_TABLE_POINTS_MAX,
                                  integer=True),
        tolerance=r.number(f"tolerance_{unit}", DEFAULT, low=1e-9, high=1e3),
    )

