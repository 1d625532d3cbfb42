"""Profile export: the CSV/DXF outline obeys the follower geometry and reopens in CAD form."""

import math

import ezdxf
import numpy as np
import pytest
from reference import reference_motion
from test_report import ROLLER

import camjax
from camjax.output import export
from camjax.scene import parse_scene

FILES = {"svaj.png", "profile.png", "loads.png", "stress.png", "profile.csv", "profile.dxf"}


@pytest.fixture(scope="session")
def default_report(default_scene, default_arrays):
    return camjax.analyse(default_scene, default_arrays)


@pytest.fixture(scope="session")
def written(default_report, tmp_path_factory):
    folder = tmp_path_factory.mktemp("export") / "not" / "yet"  # write_design_files creates it
    paths = export.write_design_files(folder, default_report.curves, dpi=40)
    return folder, paths


@pytest.fixture(scope="session")
def csv_table(written):
    folder, _ = written
    with open(folder / "profile.csv") as fh:
        header = fh.readline().strip().split(",")
    return header, np.loadtxt(folder / "profile.csv", delimiter=",", skiprows=1)


def test_files_written_are_what_the_scene_declares(written):
    folder, paths = written
    assert {p.name for p in paths} == FILES
    assert {p.name for p in folder.iterdir()} == FILES
    for name in FILES - {"profile.csv", "profile.dxf"}:
        assert (folder / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_profile_touches_follower_face_at_every_angle(csv_table, default_report):
    # face at angle theta: {P : P . (sin, cos) = R_b + s}; contact offset along the face = s'
    header, table = csv_table
    col = {name: table[:, i] for i, name in enumerate(header)}
    theta = np.radians(col["theta_deg"])
    s, ds, _ = reference_motion(col["theta_deg"])  # independent NumPy cycloids
    rb = default_report.data["design"]["base_radius_mm"]
    normal = col["x_mm"] * np.sin(theta) + col["y_mm"] * np.cos(theta)
    along = col["x_mm"] * np.cos(theta) - col["y_mm"] * np.sin(theta)
    assert np.max(np.abs(normal - (rb + s))) <= 1e-9
    assert np.max(np.abs(along - ds)) <= 1e-9
    assert len(table) == 360
    np.testing.assert_allclose(col["rho_mm"], rb + s + reference_motion(col["theta_deg"])[2], atol=1e-9)


def test_feasible_outline_is_convex(csv_table):
    # rho > 0 everywhere -> the polyline turns the same way at every vertex (clockwise in theta)
    _, table = csv_table
    x, y = table[:, 1], table[:, 2]
    ex, ey = np.roll(x, -1) - x, np.roll(y, -1) - y
    turn = ex * np.roll(ey, -1) - ey * np.roll(ex, -1)
    assert np.all(turn < 0)


def test_dxf_reopens_as_closed_polyline_in_mm(written, csv_table):
    folder, _ = written
    doc = ezdxf.readfile(folder / "profile.dxf")
    assert doc.header["$INSUNITS"] == ezdxf.units.MM
    polylines = doc.modelspace().query("LWPOLYLINE")
    assert len(polylines) == 1
    pl = polylines[0]
    assert pl.closed and pl.dxf.layer == "CAM_PROFILE"
    points = np.array(pl.get_points("xy"))
    assert points.shape == (360, 2)
    np.testing.assert_allclose(points, csv_table[1][:, 1:3], atol=1e-9)


@pytest.mark.slow
def test_no_stress_or_loads_figures_without_them(tmp_path):
    text = """
[motion]
rpm = 60
segments = [{ kind = "rise", angle_deg = 180, law = "cycloidal", lift_mm = 10 },
            { kind = "return", angle_deg = 180, law = "cycloidal", lift_mm = 10 }]
[follower]
type = "flat"
"""
    r = camjax.analyse(parse_scene(text, "bare"))
    names = {p.name for p in export.write_design_files(tmp_path, r.curves, dpi=30)}
    assert names == FILES - {"loads.png", "stress.png"}


@pytest.mark.slow
def test_roller_outline_is_envelope_of_roller_circles():
    # The cam outline is the pitch curve moved by R_f along its inward normal. The normal is
    # taken here from finite differences of the pitch curve on a dense grid (independent).
    scene = parse_scene(ROLLER, "roller")
    arrays = camjax.scene_arrays(scene, samples=36000)
    r = camjax.analyse(scene, arrays, base_radius_mm=34.0)
    c = r.curves
    # periodic central differences (the curve is closed; np.gradient is one-sided at its ends)
    tx = np.roll(c.pitch_x_mm, -1) - np.roll(c.pitch_x_mm, 1)
    ty = np.roll(c.pitch_y_mm, -1) - np.roll(c.pitch_y_mm, 1)
    norm = np.hypot(tx, ty)
    nx, ny = ty / norm, -tx / norm
    inward = -np.sign(nx * c.pitch_x_mm + ny * c.pitch_y_mm)
    ex = c.pitch_x_mm + 8.0 * inward * nx
    ey = c.pitch_y_mm + 8.0 * inward * ny
    # central differences at 0.01 deg: the normal's direction errs by O(h^2) ~ 1e-8 rad, 8 mm
    # times that is ~2e-7 mm (measured 1.8e-7)
    assert np.max(np.hypot(ex - c.profile_x_mm, ey - c.profile_y_mm)) < 1e-6
    assert math.isclose(c.base_radius_mm, 34.0)


def test_dxf_extents_and_centre_mark(written, csv_table):
    folder, _ = written
    doc = ezdxf.readfile(folder / "profile.dxf")
    lines = doc.modelspace().query("LINE")
    assert len(lines) == 2 and {ln.dxf.layer for ln in lines} == {"CENTER"}
    assert "CENTER" in doc.layers
    # the two arms cross at the shaft centre (0, 0): one along X, one along Y
    for ln in lines:
        a, b = np.array(ln.dxf.start)[:2], np.array(ln.dxf.end)[:2]
        np.testing.assert_allclose((a + b) / 2, [0.0, 0.0], atol=1e-12)
        assert np.count_nonzero(np.abs(b - a) > 0) == 1
    # extents = the bounding box of every entity, recomputed here from the CSV outline and the
    # arms (1e-9 mm: the CSV carries 12 decimals)
    xy = csv_table[1][:, 1:3]
    arms = np.array([np.array(ln.dxf.start)[:2] for ln in lines] + [np.array(ln.dxf.end)[:2] for ln in lines])
    pts = np.vstack([xy, arms])
    np.testing.assert_allclose(np.array(doc.header["$EXTMIN"])[:2], pts.min(axis=0), atol=1e-9)
    np.testing.assert_allclose(np.array(doc.header["$EXTMAX"])[:2], pts.max(axis=0), atol=1e-9)
    # the outline itself sets the extents (the mark is inside the cam)
    np.testing.assert_allclose(np.array(doc.header["$EXTMAX"])[:2], xy.max(axis=0), atol=1e-9)
    # the drawing is self-consistent: the CENTER layer's linetype is defined, audit finds nothing
    assert "CENTER" in doc.linetypes
    assert not doc.audit().has_errors


@pytest.mark.slow
def test_drawing_workers_write_the_in_process_files_byte_for_byte(default_scene, default_arrays, tmp_path):
    """The worker processes (camjax.output.drawing) write what write_figures and write_profile_dxf
    write here: the same PNG and CSV bytes and the same DXF drawing (same matplotlib and ezdxf, same
    functions, same inputs: any difference is a lost field or a different conversion on the way).
    An infeasible design with its banner, and 3 workers for 6 files so that the order has to be
    restored."""
    from camjax.output.drawing import DrawingWorkers
    from camjax.output.titles import title_block

    run = camjax.analyse(default_scene, default_arrays, base_radius_mm=10.0)
    title, banner = title_block(run.data), "INFEASIBLE GEOMETRY: test banner"
    (tmp_path / "here").mkdir()
    (tmp_path / "there").mkdir()
    here = export.write_figures(tmp_path / "here", run.curves, 40, banner, title)
    here.append(export.write_profile_csv(tmp_path / "here" / "profile.csv", run.curves))
    here.append(export.write_profile_dxf(tmp_path / "here" / "profile.dxf", run.curves))
    with DrawingWorkers(3) as workers:
        workers.draw(tmp_path / "there", run.curves, 40, banner, title)
        there = workers.wait()
    assert [p.name for p in there] == [p.name for p in here] == ["svaj.png", "profile.png", "loads.png",
                                                                 "stress.png", "profile.csv", "profile.dxf"]
    for a, b in zip(here[:-1], there[:-1], strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    # a DXF carries its creation time and fresh GUIDs: compare what it draws
    assert _dxf_content(here[-1]) == _dxf_content(there[-1])


def _dxf_content(path):
    doc = ezdxf.readfile(path)
    msp = doc.modelspace()
    return ([tuple(map(tuple, e.get_points("xy"))) for e in msp.query("LWPOLYLINE")],
            [(e.dxf.layer, tuple(e.dxf.start), tuple(e.dxf.end)) for e in msp.query("LINE")],
            tuple(doc.header["$EXTMIN"]), tuple(doc.header["$EXTMAX"]))


@pytest.mark.slow
def test_drawing_worker_failure_is_one_line(default_report, tmp_path):
    from camjax.output.drawing import DrawingError, DrawingWorkers

    with DrawingWorkers(1) as workers:
        workers.draw(tmp_path / "missing" / "folder", default_report.curves, 40)
        with pytest.raises(DrawingError, match=r"^drawing the figures and the DXF failed: FileNotFoundError") as info:
            workers.wait()
    assert "\n" not in str(info.value)


@pytest.mark.slow
def test_drawing_workers_do_not_import_jax():
    """``import camjax`` and the figure modules load no JAX: that is a drawing worker's head start."""
    import subprocess
    import sys

    code = ("import sys, camjax, camjax.output.plots, camjax.output.export, camjax.output.drawing; "
            "print('jax' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
