"""A servo drive's cam table ("electronic cam"): the motion at N equally spaced master angles
(``[export] cam_table_points`` or ``camjax design --cam-table-points``), SPEC 3 "Making the cam".

``cam_table.csv``: ``master_deg, position, velocity, acceleration``, per degree of master: a
translating follower's position in mm (mm/deg, mm/deg^2), a rocking follower's swing in deg
(deg/deg, deg/deg^2); inches with ``units = "in"`` for a translating follower. ``cam_table.json``:
the same motion as drive-neutral polynomial segments, one 5th-degree polynomial per interval
matching position, velocity and acceleration at both of its points.

:func:`interpolation_errors` measures, against the exact law, the largest position error of
linear, cubic-Hermite (position and velocity) and quintic (position, velocity, acceleration)
interpolation between the points, and :func:`fewest_points` the fewest equally spaced points that
keep each within a tolerance. The exact law is evaluated by JAX in fixed-size batches (one compiled
call serves every table size); the rest is host-side NumPy writing files, not meant for jit.
"""

from __future__ import annotations

import json
import math
from functools import partial
from pathlib import Path
from typing import NamedTuple

import numpy as np

from camjax.output.machining import unit_scale
from camjax.scene.manufacture import CAM_TABLE_POINTS_MAX

BATCH = 1 << 16  # master angles per call of the exact law (one compiled shape)
CHECKS_PER_INTERVAL = 16  # where the interpolation error is measured between two points
POINTS_MAX = CAM_TABLE_POINTS_MAX  # the largest table a scene may ask for
METHODS = ("linear", "cubic_hermite", "quintic")


class Law:
    """The scene's motion at any master angles (deg): position, velocity, acceleration per degree
    of master, in the table's units (see the module docstring)."""

    def __init__(self, scene, units: str = "mm"):
        import jax
        import jax.numpy as jnp

        from camjax import followers, program

        prog = jax.tree_util.tree_map(lambda v: jnp.asarray(v, jnp.float64), scene.motion.program)
        rad = math.pi / 180.0
        if followers.of(scene).rocking:  # the swing in deg: s in rad -> deg; per deg of master
            self.unit, k = "deg", (1.0 / rad, 1.0, rad)
        else:
            self.unit = units
            lk = unit_scale(units)
            k = (lk, lk * rad, lk * rad * rad)
        self._scale = k
        self._f = partial(program.motion_at_compiled, prog)

    def __call__(self, master_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position, velocity, acceleration) at ``master_deg`` (any length; batches of BATCH)."""
        t = np.asarray(master_deg, np.float64).ravel()
        out = np.empty((3, len(t)))
        for a in range(0, len(t), BATCH):
            chunk = t[a:a + BATCH]
            padded = np.zeros(BATCH)
            padded[:len(chunk)] = chunk
            kin = self._f(padded)
            for i, v in enumerate((kin.s, kin.ds, kin.d2s)):
                out[i, a:a + len(chunk)] = np.asarray(v)[:len(chunk)] * self._scale[i]
        return out[0], out[1], out[2]


def table(law: Law, points: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(master_deg, position, velocity, acceleration) at ``points`` master angles k * 360 / points."""
    master = np.arange(points) * (360.0 / points)
    return (master, *law(master))


def quintic_coefficients(p, v, a, h: float) -> np.ndarray:
    """Coefficients c0..c5 (per interval, (N, 6)) of the quintic in u = master - start (deg) that
    matches position, velocity and acceleration at both ends of each interval of length ``h``;
    ``p, v, a`` (N,) at the points, the last interval closing the cycle."""
    p1, v1, a1 = np.roll(p, -1), np.roll(v, -1), np.roll(a, -1)
    dp = p1 - p - v * h - a * h**2 / 2  # what the cubic, quartic and quintic terms must add
    dv = v1 - v - a * h
    da = a1 - a
    c3 = (10 * dp - 4 * dv * h + da * h**2 / 2) / h**3
    c4 = (-15 * dp + 7 * dv * h - da * h**2) / h**4
    c5 = (6 * dp - 3 * dv * h + da * h**2 / 2) / h**5
    return np.column_stack([p, v, a / 2, c3, c4, c5])


def _interpolate(method: str, p, v, a, h: float, u: np.ndarray) -> np.ndarray:
    """Each interval's interpolant at offsets ``u`` (deg, shape (N, K)) from its start."""
    p1, v1 = np.roll(p, -1), np.roll(v, -1)
    s = u / h
    if method == "linear":
        return p[:, None] + (p1 - p)[:, None] * s
    if method == "cubic_hermite":
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        return h00 * p[:, None] + h10 * h * v[:, None] + h01 * p1[:, None] + h11 * h * v1[:, None]
    c = quintic_coefficients(p, v, a, h)
    return sum(c[:, i:i + 1] * u**i for i in range(6))


def interpolation_errors(law: Law, points: int, methods=METHODS) -> dict[str, float]:
    """Largest |interpolated - exact| position (table units) of each method between ``points``
    equally spaced points, measured at CHECKS_PER_INTERVAL - 1 angles inside every interval."""
    master, p, v, a = table(law, points)
    h = 360.0 / points
    u = np.arange(1, CHECKS_PER_INTERVAL) * (h / CHECKS_PER_INTERVAL)
    exact = law((master[:, None] + u[None, :]).ravel())[0].reshape(points, -1)
    uu = np.broadcast_to(u, exact.shape)
    return {m: float(np.max(np.abs(_interpolate(m, p, v, a, h, uu) - exact))) for m in methods}


def fewest_points(law: Law, method: str, tolerance: float, start: int = 8) -> int | None:
    """The fewest equally spaced points whose ``method`` interpolation stays within ``tolerance``
    (table units): doubling from ``start``, then bisection (taking the error to fall as points are
    added); None beyond POINTS_MAX."""
    lo, hi = 1, max(2, start)
    while interpolation_errors(law, hi, (method,))[method] > tolerance:
        lo, hi = hi, 2 * hi
        if hi > POINTS_MAX:
            return None
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if interpolation_errors(law, mid, (method,))[method] <= tolerance:
            hi = mid
        else:
            lo = mid
    return hi


class CamTable(NamedTuple):
    master_deg: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    unit: str  # the position's unit: mm, in or deg
    report: dict  # result.json's cam_table block


def cam_table(scene, points: int, tolerance: float, units: str = "mm") -> CamTable:
    """The table at ``points`` master angles and its result.json block: the largest position error
    of each interpolation between these points, and the fewest points keeping linear and cubic
    Hermite within ``tolerance`` (table units)."""
    law = Law(scene, units)
    master, p, v, a = table(law, points)
    errors = interpolation_errors(law, points)
    report = {
        "points": points, "position_unit": law.unit, "tolerance": tolerance,
        "max_error": errors,
        "fewest_points": {m: fewest_points(law, m, tolerance) for m in ("linear", "cubic_hermite")},
        "checks_per_interval": CHECKS_PER_INTERVAL,
    }
    return CamTable(master, p, v, a, law.unit, report)


def write_cam_table(folder: Path, t: CamTable) -> list[Path]:
    """cam_table.csv and cam_table.json (the quintic segments) into ``folder``."""
    csv = Path(folder) / "cam_table.csv"
    np.savetxt(csv, np.column_stack([t.master_deg, t.position, t.velocity, t.acceleration]), delimiter=",",
               header="master_deg,position,velocity,acceleration", comments="", fmt="%.12g")
    n = len(t.master_deg)
    h = 360.0 / n
    c = quintic_coefficients(t.position, t.velocity, t.acceleration, h)
    doc = {
        "format": "camjax cam table", "version": 1,
        "master": {"unit": "deg", "period": 360.0, "points": n, "interval": h},
        "slave": {"position": t.unit, "velocity": f"{t.unit}/deg", "acceleration": f"{t.unit}/deg^2"},
        "polynomial": "position = sum(c[i] * u**i, i = 0..5), u = master - master_start (deg), per "
                      "segment; matches position, velocity and acceleration at both ends",
        "segments": [{"master_start": float(t.master_deg[i]), "master_end": float(t.master_deg[i] + h),
                      "c": [float(x) for x in c[i]]} for i in range(n)],
    }
    js = Path(folder) / "cam_table.json"
    js.write_text(json.dumps(doc, indent=1) + "\n")
    return [csv, js]
