"""Files of a design: profile CSV, profile DXF (CAD), and the report's figures as PNG.

Every writer takes a folder (the CLI passes a staging folder, so a failed job leaves nothing
behind) and returns the paths it wrote. Coordinates are the cam outline in cam coordinates,
mm, with the convention of :mod:`camjax.geometry` (follower axis along +Y at theta = 0,
theta measured clockwise).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camjax.evaluate import DesignCurves

CSV_FORMAT = "%.12f"  # 1e-12 mm: far below any machining tolerance, round-trips the geometry


def profile_table(curves: DesignCurves) -> tuple[list[str], np.ndarray]:
    """Column names and an (N, k) table: angle, outline X/Y, follower motion, curvature."""
    names = ["theta_deg", "x_mm", "y_mm", "s_mm", "ds_mm_per_rad"]
    cols = [curves.theta_deg, curves.profile_x_mm, curves.profile_y_mm, curves.s_mm, curves.ds_mm]
    if curves.rho_mm is not None:
        names.append("rho_mm")
        cols.append(curves.rho_mm)
    if curves.pitch_x_mm is not None:
        names += ["pitch_x_mm", "pitch_y_mm", "pressure_angle_deg"]
        cols += [curves.pitch_x_mm, curves.pitch_y_mm, curves.pressure_angle_deg]
    return names, np.column_stack(cols)


def write_profile_csv(path: Path, curves: DesignCurves) -> Path:
    """Profile table as CSV with one header line."""
    names, table = profile_table(curves)
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt=CSV_FORMAT)
    return path


def write_profile_dxf(path: Path, curves: DesignCurves) -> Path:
    """Cam outline as one closed LWPOLYLINE on layer CAM_PROFILE, drawing units mm.

    One vertex per sample (the scene's ``samples``); raise ``samples`` for a finer polyline
    (with 360 samples the chord error on a 30 mm cam is about 1 micrometre).
    """
    import ezdxf  # imported here: only the DXF export needs it

    doc = ezdxf.new("R2010", units=ezdxf.units.MM)
    doc.header["$MEASUREMENT"] = 1  # metric
    doc.layers.add("CAM_PROFILE", color=7)
    points = np.column_stack([curves.profile_x_mm, curves.profile_y_mm]).tolist()
    doc.modelspace().add_lwpolyline(points, format="xy", close=True,
                                    dxfattribs={"layer": "CAM_PROFILE"})
    doc.saveas(path)
    return path


def write_figures(folder: Path, curves: DesignCurves, dpi: int = 100,
                  banner: str | None = None) -> list[Path]:
    """PNG of every figure the scene declares (see :func:`camjax.output.plots.design_figures`).

    ``banner``: text of a red banner stamped on every figure (the constraints the geometry breaks).
    """
    from camjax.output.plots import design_figures, stamp_banner  # matplotlib only when drawing

    out = []
    for name, fig in design_figures(curves).items():
        if banner:
            stamp_banner(fig, banner)
        path = folder / name
        fig.savefig(path, dpi=dpi)
        out.append(path)
    return out


def write_design_files(folder: str | Path, curves: DesignCurves, dpi: int = 100,
                       banner: str | None = None) -> list[Path]:
    """Figures, profile.csv and profile.dxf into ``folder`` (created if needed); the written paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [*write_figures(folder, curves, dpi, banner), write_profile_csv(folder / "profile.csv", curves),
            write_profile_dxf(folder / "profile.dxf", curves)]
