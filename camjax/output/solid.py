"""cam.stl: the cam as a solid plate (``[manufacture]``): its outline extruded through the cam's
width, with the shaft bore when ``bore_diameter_mm`` is given.

Host-side NumPy that writes a file (not for jit). The outline is the exact cam surface of
:func:`camjax.output.machining.cam_surface`, thinned to a stride whose chords stay within the
tolerance; the plate lies between Z = 0 and Z = width in profile.csv's frame. A binary STL holds
float32 coordinates (resolution about 1e-7 of the cam's size) and no unit: millimetres, or inches
with ``units = "in"``. Every edge is shared by exactly two triangles, all facing outwards.
STEP is not written (no well-kept STEP library is a dependency of camjax).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from camjax.errors import SceneError
from camjax.output.machining import Surface, signed_area2, unit_scale


def solid_outline(surface: Surface, tolerance_mm: float) -> np.ndarray:
    """Outline vertices (K, 2), mm, counter-clockwise: every ``stride``-th dense sample, the stride
    the largest whose chords lie within ``tolerance_mm`` of the surface (sagitta c^2 / (8 |rho|) on
    the tightest radius) and keeping at least 720 vertices."""
    xy = np.column_stack([surface.x_mm, surface.y_mm])
    step = float(np.max(np.hypot(*np.diff(xy, axis=0, append=xy[:1]).T)))
    tightest = float(np.min(np.abs(surface.rho_mm)))
    stride = int(max(1, min(len(xy) // 720, math.sqrt(8.0 * tightest * tolerance_mm) // step)))
    out = xy[::stride]
    area2 = signed_area2(out[:, 0], out[:, 1])
    return out if area2 > 0 else out[::-1]


def solid_triangles(outline: np.ndarray, width_mm: float, bore_diameter_mm: float | None) -> np.ndarray:
    """Triangles (T, 3, 3), mm, of the plate: top (Z = width) and bottom (Z = 0) faces, the outer
    wall and the bore's wall, each vertex order counter-clockwise seen from outside.

    The faces are ribbons from the outline to the bore (or fans from the centre) by polar angle,
    so the outline must be star-shaped about the cam centre (each ray from the centre crosses it
    once) and the bore inside it; else :class:`SceneError` naming what does not fit.
    """
    ang = np.unwrap(np.arctan2(outline[:, 1], outline[:, 0]))
    radius = np.hypot(outline[:, 0], outline[:, 1])
    if not (np.all(np.diff(ang) > 0) and ang[-1] - ang[0] < 2 * math.pi):
        raise SceneError("manufacture", "cam.stl", "the cam outline is not star-shaped about the cam "
                         "centre (a ray from the centre crosses it twice): the solid writer cannot "
                         "triangulate it")
    if bore_diameter_mm is not None and bore_diameter_mm / 2 >= radius.min():
        raise SceneError("manufacture.bore_diameter_mm", bore_diameter_mm, "the bore reaches the cam's "
                         f"outline (its nearest point is {radius.min():.6g} mm from the centre)",
                         f"a diameter < {2 * radius.min():.6g} mm")
    w = float(width_mm)
    k = len(outline)
    nxt = np.roll(np.arange(k), -1)
    ob = np.column_stack([outline, np.zeros(k)])
    ot = np.column_stack([outline, np.full(k, w)])
    tris = [np.stack([ob, ob[nxt], ot[nxt]], 1), np.stack([ob, ot[nxt], ot], 1)]  # outer wall
    if bore_diameter_mm is None:
        cb, ct = np.zeros((k, 3)), np.tile([0.0, 0.0, w], (k, 1))
        tris += [np.stack([ct, ot, ot[nxt]], 1), np.stack([cb, ob[nxt], ob], 1)]
    else:
        rb = bore_diameter_mm / 2
        ring = np.column_stack([rb * np.cos(ang), rb * np.sin(ang)])
        ib = np.column_stack([ring, np.zeros(k)])
        it = np.column_stack([ring, np.full(k, w)])
        tris += [np.stack([it, ot, ot[nxt]], 1), np.stack([it, ot[nxt], it[nxt]], 1),  # top
                 np.stack([ib, ob[nxt], ob], 1), np.stack([ib, ib[nxt], ob[nxt]], 1),  # bottom
                 np.stack([ib, it[nxt], ib[nxt]], 1), np.stack([ib, it, it[nxt]], 1)]  # bore wall
    return np.concatenate(tris)


def write_stl(path: Path, triangles: np.ndarray, units: str = "mm", name: str = "camjax cam") -> Path:
    """Binary STL of ``triangles`` (T, 3, 3) given in mm, written in ``units``; facet normals from
    the vertex order."""
    t = np.asarray(triangles, np.float64) * unit_scale(units)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(len(t), dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")]))
    rec["n"], rec["v"] = n, t
    with open(path, "wb") as f:
        f.write(f"{name} ({units})".encode("ascii", "replace")[:80].ljust(80, b" "))
        f.write(np.uint32(len(t)).tobytes())
        f.write(rec.tobytes())
    return path
