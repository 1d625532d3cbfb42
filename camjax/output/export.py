"""Files of a design: profile CSV, profile DXF (CAD), the figures as PNG and the animation.

Every writer takes a folder (the CLI passes a staging folder, so a failed job leaves nothing
behind) and returns the paths it wrote. Coordinates are the cam outline in cam coordinates, mm,
with the convention of :mod:`camjax.followers._pitch` (follower axis along +Y at theta = 0, theta
measured clockwise). What a follower draws and tabulates comes from its drawing module
(:func:`camjax.followers.drawing`: ``figure_builders``, ``profile_table``, ``mechanism``), chosen
by the curves' ``follower_type``. The module imports no JAX (the DXF is written in the drawing
processes, :mod:`camjax.output.drawing`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camjax import followers
from camjax import units as scene_units

CSV_FORMAT = "%.12f"  # 1e-12 mm: far below any machining tolerance, round-trips the geometry
PROFILE_CSV = "profile.csv"  # a design's profile table and drawing, whoever writes them
PROFILE_DXF = "profile.dxf"  # (this process or camjax.output.drawing's workers)


def profile_columns(names: list[str], cols: list, optional, curves) -> tuple[list[str], np.ndarray]:
    """A profile table from its first columns (``names``, ``cols``): then each of ``optional``
    ((name, values) pairs) whose values the curves have (not None), then the follower's own curves
    (``curves.own_curves``, name -> values, if any), stacked as the table's columns."""
    for name, values in optional:
        if values is not None:
            names.append(name)
            cols.append(values)
    for name, values in (getattr(curves, "own_curves", None) or {}).items():  # the follower's own
        names.append(name)
        cols.append(values)
    return names, np.column_stack(cols)


def write_profile_csv(path: Path, curves, units: str = "mm") -> Path:
    """The follower's profile table (its drawing module's ``profile_table``) as CSV with one header
    line; ``units`` "in": ``curves`` are in inches (:func:`camjax.units.curves_to`) and the column
    names say so (``x_in``, ``stress_psi``)."""
    names, table = followers.drawing(curves.follower_type).profile_table(curves)
    names = scene_units.column_names(names, units)
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt=CSV_FORMAT)
    return path


def centre_mark_half_mm(curves, units: str = "mm") -> float:
    """Half length of the centre-mark arms: a tenth of the largest radius, at least 1 mm (in the
    curves' ``units``)."""
    least = 1.0 / scene_units.length_scale(units)
    return max(least, 0.1 * float(np.max(np.hypot(curves.profile_x_mm, curves.profile_y_mm))))


def write_profile_dxf(path: Path, curves, units: str = "mm") -> Path:
    """Cam outline as one closed LWPOLYLINE on layer CAM_PROFILE, drawing units mm (``units``
    "in": inches, $INSUNITS 1 and $MEASUREMENT 0, from curves in inches). A positive drive draws
    each flank or cam on its own layer (GROOVE_INNER and GROOVE_OUTER; CAM_PROFILE and
    CONJUGATE_CAM: :func:`camjax.followers._closure_output.outlines`).

    One vertex per sample (the scene's ``samples``); raise ``samples`` for a finer polyline
    (with 360 samples the chord error on a 30 mm cam is about 1 micrometre). ezdxf writes the
    document; the polylines' vertices are formatted from the arrays in one call each, since ezdxf
    adds and writes them one by one (quadratic: 30 s for 5e4 vertices; this way 1e6 take seconds).
    The shaft centre is a cross of two LINEs on layer CENTER; $EXTMIN/$EXTMAX bound all of them and
    the active viewport shows them.
    """
    import io

    import ezdxf  # imported here: only the DXF export needs it
    from ezdxf import zoom

    from camjax.followers._closure_drawing import outlines

    shapes = [(layer, np.column_stack([x, y])) for layer, x, y in outlines(curves)]
    inch = scene_units.check_units(units) == "in"
    doc = ezdxf.new("R2010", units=ezdxf.units.IN if inch else ezdxf.units.MM,
                    setup=["linetypes"])  # CENTER linetype
    doc.header["$MEASUREMENT"] = 0 if inch else 1  # imperial or metric
    for layer, _ in shapes:
        doc.layers.add(layer, color=7)
    doc.layers.add("CENTER", color=1, linetype="CENTER")
    msp = doc.modelspace()
    for layer, xy in shapes:
        msp.add_lwpolyline(xy[:1].tolist(), format="xy", close=True, dxfattribs={"layer": layer})
    c = centre_mark_half_mm(curves, units)
    msp.add_line((-c, 0.0), (c, 0.0), dxfattribs={"layer": "CENTER"})
    msp.add_line((0.0, -c), (0.0, c), dxfattribs={"layer": "CENTER"})
    every = np.vstack([xy for _, xy in shapes])
    lo = np.minimum(every.min(axis=0), -c)
    hi = np.maximum(every.max(axis=0), c)
    # ezdxf copies the layout's extents into $EXTMIN/$EXTMAX when it writes
    msp.dxf.extmin = (float(lo[0]), float(lo[1]), 0.0)
    msp.dxf.extmax = (float(hi[0]), float(hi[1]), 0.0)
    zoom.window(msp, msp.dxf.extmin, msp.dxf.extmax)  # open framed on the cam
    stream = io.StringIO()
    doc.write(stream)
    text, marker = stream.getvalue(), "AcDbPolyline\n 90\n1\n 70\n1\n"
    with open(path, "w", encoding=doc.output_encoding, newline="\n") as f:
        for _, xy in shapes:
            head, found, tail = text.partition(marker)
            if not found:
                raise RuntimeError("ezdxf wrote the polyline in an unexpected layout")
            vertices = io.StringIO()
            np.savetxt(vertices, xy, fmt=" 10\n%.12f\n 20\n%.12f")  # group codes 10/20: vertex x, y
            f.write(f"{head}AcDbPolyline\n 90\n{len(xy)}\n 70\n1\n")
            f.write(vertices.getvalue())
            text = tail[tail.index("  0\n"):]  # from the next entity (after the placeholder vertex)
        f.write(text)
    return path


def write_figures(folder: Path, curves, dpi: int = 100, banner: str | None = None,
                  title: str = "", units: str = "mm") -> list[Path]:
    """PNG of every figure the scene declares (the follower's ``figure_builders``).

    ``banner``: text of a red banner stamped on every figure (the constraints the geometry breaks);
    ``title``: the run's title block (:func:`camjax.output.titles.title_block`); ``units``: those
    of ``curves`` (:func:`camjax.units.curves_to`), which the figures' labels then name.
    """
    builders = followers.drawing(curves.follower_type).figure_builders(curves)
    return [save_figure(build(curves, title), folder / name, dpi, banner, units)
            for name, build in builders.items()]


def save_figure(fig, path: Path, dpi: int = 100, banner: str | None = None, units: str = "mm") -> Path:
    """Write one figure as PNG, first stamped with ``banner`` in red when given; the path.
    ``units`` "in": the figure was drawn from curves in inches, and its labels say so
    (:func:`camjax.units.relabel`)."""
    scene_units.relabel(fig, units)
    if banner:
        from camjax.output.plots import stamp_banner

        stamp_banner(fig, banner)
    fig.savefig(path, dpi=dpi)
    return path


def write_animation(path: Path, curves, title: str = "", banner: str | None = None,
                    units: str = "mm") -> Path:
    """motion.gif: one turn of the mechanism; ``banner`` (the broken constraints) above it in red
    and the outline where it breaks them drawn red; ``units``: those of ``curves``."""
    from camjax.output.animation import write_motion_gif

    return write_motion_gif(path, followers.drawing(curves.follower_type).mechanism(curves, title, banner),
                            units=units)


def write_design_files(folder: str | Path, curves, dpi: int = 100, banner: str | None = None,
                       title: str = "", animate: bool = False, progress=None, workers=None,
                       units: str = "mm") -> list[Path]:
    """Figures, profile.csv and profile.dxf (and motion.gif when ``animate``) into ``folder``
    (created if needed); the written paths. ``banner`` and ``title`` as in :func:`write_figures`;
    ``progress(phase)`` (optional) is told "figures", "files" and "animation" as each starts (with
    ``workers``: "files" as the job is handed to them, "figures" while waiting for them, who write
    every file; the phases the command's --timings lists either way).

    ``workers``: started :class:`camjax.output.drawing.DrawingWorkers` draw the figures and write
    the CSV and the DXF in their processes (the same files as without them; this process then
    imports no drawing module, nor matplotlib: ~0.3 CPU s of a warm design's own process).

    ``units``: the scene's ("mm" or "in", :mod:`camjax.units`); ``curves`` are always in mm and
    are converted here, so that every file speaks ``units`` (``banner`` and ``title`` come in them).
    """
    curves = scene_units.curves_to(curves, units)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda phase: None)
    if workers is not None:  # they write every file; "figures": waiting for them
        workers.draw(folder, curves, dpi, banner, title, units)
        say("files")
        say("figures")
        paths = workers.wait()
    else:
        say("figures")
        paths = write_figures(folder, curves, dpi, banner, title, units)
        say("files")
        paths += [write_profile_csv(folder / PROFILE_CSV, curves, units),
                  write_profile_dxf(folder / PROFILE_DXF, curves, units)]
    if animate:
        say("animation")
        paths.append(write_animation(folder / "motion.gif", curves, title, banner, units))
    return paths
