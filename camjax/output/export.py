"""Files of a design: profile CSV, profile DXF (CAD), and the report's figures as PNG.

Every writer takes a folder (the CLI passes a staging folder, so a failed job leaves nothing
behind) and returns the paths it wrote. Coordinates are the cam outline in cam coordinates,
mm, with the convention of :mod:`camjax.geometry` (follower axis along +Y at theta = 0,
theta measured clockwise).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # imported without JAX: the DXF is written in worker processes (camjax.output.drawing)
    from camjax.evaluate import DesignCurves

CSV_FORMAT = "%.12f"  # 1e-12 mm: far below any machining tolerance, round-trips the geometry


def profile_table(curves: DesignCurves) -> tuple[list[str], np.ndarray]:
    """Column names and an (N, k) table: angle, outline X/Y, follower motion, curvature, then
    every curve whose extrema result.json reports (so that each can be checked against samples).

    The first columns keep their order (angle, outline, s, s', rho or pitch curve and pressure
    angle); the later ones were appended after them: s'' (mm/rad^2), v, a, j (SI), the roller's
    pitch-curve radius of curvature, and with the models the force, cam torque and stress.
    """
    names = ["theta_deg", "x_mm", "y_mm", "s_mm", "ds_mm_per_rad"]
    cols = [curves.theta_deg, curves.profile_x_mm, curves.profile_y_mm, curves.s_mm, curves.ds_mm]
    if curves.rho_mm is not None:
        names.append("rho_mm")
        cols.append(curves.rho_mm)
    if curves.pitch_x_mm is not None:
        names += ["pitch_x_mm", "pitch_y_mm", "pressure_angle_deg"]
        cols += [curves.pitch_x_mm, curves.pitch_y_mm, curves.pressure_angle_deg]
    names += ["d2s_mm_per_rad2", "velocity_m_s", "accel_m_s2", "jerk_m_s3"]
    cols += [curves.d2s_mm, curves.velocity_m_s, curves.accel_m_s2, curves.jerk_m_s3]
    optional = (("pitch_rho_mm", curves.pitch_rho_mm), ("force_N", curves.force_N),
                ("torque_Nm", curves.torque_Nm), ("stress_MPa", curves.stress_MPa))
    for name, values in optional:
        if values is not None:
            names.append(name)
            cols.append(values)
    return names, np.column_stack(cols)


def write_profile_csv(path: Path, curves: DesignCurves) -> Path:
    """Profile table as CSV with one header line."""
    names, table = profile_table(curves)
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt=CSV_FORMAT)
    return path


def centre_mark_half_mm(curves: DesignCurves) -> float:
    """Half length of the centre-mark arms: a tenth of the largest radius, at least 1 mm."""
    return max(1.0, 0.1 * float(np.max(np.hypot(curves.profile_x_mm, curves.profile_y_mm))))


def write_profile_dxf(path: Path, curves: DesignCurves) -> Path:
    """Cam outline as one closed LWPOLYLINE on layer CAM_PROFILE, drawing units mm.

    One vertex per sample (the scene's ``samples``); raise ``samples`` for a finer polyline
    (with 360 samples the chord error on a 30 mm cam is about 1 micrometre). ezdxf writes the
    document; the polyline's vertices are formatted from the array in one call, since ezdxf adds
    and writes them one by one (quadratic: 30 s for 5e4 vertices; this way 1e6 take seconds).
    The shaft centre is a cross of two LINEs on layer CENTER; $EXTMIN/$EXTMAX bound both and the
    active viewport shows them.
    """
    import io

    import ezdxf  # imported here: only the DXF export needs it
    from ezdxf import zoom

    xy = np.column_stack([curves.profile_x_mm, curves.profile_y_mm])
    doc = ezdxf.new("R2010", units=ezdxf.units.MM, setup=["linetypes"])  # CENTER linetype
    doc.header["$MEASUREMENT"] = 1  # metric
    doc.layers.add("CAM_PROFILE", color=7)
    doc.layers.add("CENTER", color=1, linetype="CENTER")
    msp = doc.modelspace()
    msp.add_lwpolyline(xy[:1].tolist(), format="xy", close=True, dxfattribs={"layer": "CAM_PROFILE"})
    c = centre_mark_half_mm(curves)
    msp.add_line((-c, 0.0), (c, 0.0), dxfattribs={"layer": "CENTER"})
    msp.add_line((0.0, -c), (0.0, c), dxfattribs={"layer": "CENTER"})
    lo = np.minimum(xy.min(axis=0), -c)
    hi = np.maximum(xy.max(axis=0), c)
    # ezdxf copies the layout's extents into $EXTMIN/$EXTMAX when it writes
    msp.dxf.extmin = (float(lo[0]), float(lo[1]), 0.0)
    msp.dxf.extmax = (float(hi[0]), float(hi[1]), 0.0)
    zoom.window(msp, msp.dxf.extmin, msp.dxf.extmax)  # open framed on the cam
    stream = io.StringIO()
    doc.write(stream)
    head, marker, tail = stream.getvalue().partition("AcDbPolyline\n 90\n1\n 70\n1\n")
    if not marker:
        raise RuntimeError("ezdxf wrote the polyline in an unexpected layout")
    vertices = io.StringIO()
    np.savetxt(vertices, xy, fmt=" 10\n%.12f\n 20\n%.12f")  # group codes 10/20: vertex x, y
    rest = tail[tail.index("  0\n"):]  # from the next entity (after the placeholder vertex)
    with open(path, "w", encoding=doc.output_encoding, newline="\n") as f:
        f.write(f"{head}AcDbPolyline\n 90\n{len(xy)}\n 70\n1\n")
        f.write(vertices.getvalue())
        f.write(rest)
    return path


def write_figures(folder: Path, curves: DesignCurves, dpi: int = 100, banner: str | None = None,
                  title: str = "") -> list[Path]:
    """PNG of every figure the scene declares (see :func:`camjax.output.plots.design_figures`).

    ``banner``: text of a red banner stamped on every figure (the constraints the geometry breaks);
    ``title``: the run's title block (:func:`camjax.output.titles.title_block`).
    """
    from camjax.output.plots import design_figures  # matplotlib only when drawing

    figures = design_figures(curves, title)
    return [save_figure(fig, folder / name, dpi, banner) for name, fig in figures.items()]


def save_figure(fig, path: Path, dpi: int = 100, banner: str | None = None) -> Path:
    """Write one figure as PNG, first stamped with ``banner`` in red when given; the path."""
    if banner:
        from camjax.output.plots import stamp_banner

        stamp_banner(fig, banner)
    fig.savefig(path, dpi=dpi)
    return path


def write_animation(path: Path, curves: DesignCurves, title: str = "", banner: str | None = None) -> Path:
    """motion.gif: one turn of the mechanism; ``banner`` (the broken constraints) above it in red
    and the outline where it breaks them drawn red."""
    from camjax.output.animation import mechanism_from_curves, violation_samples, write_motion_gif

    return write_motion_gif(path, mechanism_from_curves(curves, title, banner, violation_samples(curves)))


def write_design_files(folder: str | Path, curves: DesignCurves, dpi: int = 100,
                       banner: str | None = None, title: str = "", animate: bool = False,
                       progress=None, workers=None) -> list[Path]:
    """Figures, profile.csv and profile.dxf (and motion.gif when ``animate``) into ``folder``
    (created if needed); the written paths. ``banner`` and ``title`` as in :func:`write_figures`;
    ``progress(phase)`` (optional) is told "figures", "files" and "animation" as each starts. An
    oscillating follower's files come from :mod:`camjax.output.rocker`.

    ``workers``: started :class:`camjax.output.drawing.DrawingWorkers` draw the figures and the
    DXF in their processes while this one writes the CSV (the same files as without them).
    """
    from camjax.rocker import RockerCurves

    if isinstance(curves, RockerCurves):  # an oscillating follower's files
        from camjax.output.rocker import write_rocker_files

        return write_rocker_files(folder, curves, dpi, banner, title, animate, progress)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda phase: None)
    if workers is not None:  # they draw while the CSV is written here; "figures": waiting for them
        workers.draw(folder, curves, dpi, banner, title)
        say("files")
        csv = write_profile_csv(folder / "profile.csv", curves)
        say("figures")
        *paths, dxf = workers.wait()
        paths += [csv, dxf]
    else:
        say("figures")
        paths = write_figures(folder, curves, dpi, banner, title)
        say("files")
        paths += [write_profile_csv(folder / "profile.csv", curves),
                  write_profile_dxf(folder / "profile.dxf", curves)]
    if animate:
        say("animation")
        paths.append(write_animation(folder / "motion.gif", curves, title, banner))
    return paths
