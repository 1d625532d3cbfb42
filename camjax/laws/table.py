"""Laws from points: a CSV table of (angle, lift) fitted by a smoothing spline, evaluated in JAX.

Two uses (the scene's keys are read in :mod:`camjax.scene.shaped`):

- a segment's law: rows ``angle_deg, lift_mm`` with angles from the segment's start (0 .. its
  angle) and the follower's lift (mm; ``lift_deg`` for a swinging follower). The fit is pinned to
  the levels of the neighbouring segments at both ends and, with ``ends = "rest"`` (the default),
  starts and ends at rest (velocity and acceleration zero), so its joints with dwells are C2;
- a whole cycle: rows of absolute cam angle in [0, 360) and lift, fitted periodically and split
  into a rise (0 to the highest point) and a return, both read off the one periodic spline.

The fit (:mod:`camjax.laws.fit`, needs SciPy) is a smoothing spline of odd degree (default 5, so
the jerk is continuous) with the smoothing chosen by GCV unless given. Each law carries a
:class:`TableFit`: its residuals, the peaks of the fitted motion, and the noise test: the ratio of
the fit's peak jerk to the peak jerk of a fit with twice the smoothing. A jerk that is the data's
own hardly moves when the smoothing doubles (measured <= 1.04 at the GCV choice, cycloidal data
with 0 to 0.05 mm noise); a jerk made of noise falls by about 2^(3.5/6) ~ 1.5 (a quintic
smoothing spline's band edge moves as lam^(-1/6) and noise's jerk grows as the band edge^3.5).
Above :data:`NOISE_RATIO` = 1.05 the fit is flagged ``noisy``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from camjax.laws import Law, LawValues
from camjax.laws.bspline import evaluate_derivatives, evaluate_derivatives_numpy

NOISE_RATIO = 1.05  # peak jerk(lam) / peak jerk(2 lam) above this: noise dominates the jerk
LEVEL_TOLERANCE = 0.02  # a segment table's end rows must meet the neighbours' levels within 2 % of its lift
ENDS = ("rest", "free")
DEFAULT_DEGREE = 5
TABLE_DEGREES = (3, 5, 7, 9)


class TableFit(NamedTuple):
    """How a table law fits its points; lifts in the table's unit (mm or deg), angles in deg."""

    file: str
    points: int
    degree: int
    smoothing: float  # lam of sum (y - f)^2 + lam int (f^(m))^2 dtheta, theta in deg
    gcv: bool  # smoothing chosen by generalized cross-validation
    max_residual: float
    rms_residual: float
    peak_velocity: float  # max |ds/dtheta| of the fit, per deg
    peak_accel: float  # max |d2s/dtheta2|, per deg^2
    peak_jerk: float  # max |d3s/dtheta3|, per deg^3
    jerk_noise_ratio: float  # peak jerk / peak jerk of the fit with twice the smoothing
    noisy: bool  # jerk_noise_ratio > NOISE_RATIO

    def as_dict(self) -> dict:
        return {k: (bool(v) if isinstance(v, bool | np.bool_) else v) for k, v in self._asdict().items()}

    def warning(self) -> str | None:
        """One line when noise dominates the fitted jerk, else None."""
        if not self.noisy:
            return None
        return (f"{self.file}: the fitted jerk is mostly noise (peak jerk falls {self.jerk_noise_ratio:.3g}x "
                f"when the smoothing doubles; above {NOISE_RATIO} is flagged): give a larger smoothing")


@dataclass(frozen=True, eq=False)
class TableLaw(Law):
    """A law fitted to a table of points; ``fit`` says how well."""

    fit: TableFit | None = None


def read_points(path: Path, lift_column: str = "lift_mm") -> tuple[np.ndarray, np.ndarray]:
    """(angles_deg, lifts) of a CSV file with a header naming ``angle_deg`` and ``lift_column``.

    Blank lines and lines starting with '#' are skipped. Raises ValueError naming the row (data
    rows count from 1) and the line for a missing column, a field that is not a finite number or
    a short row; OSError when the file cannot be read.
    """
    text = Path(path).read_text(encoding="utf-8-sig")
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines())
             if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"is empty; needs a header 'angle_deg,{lift_column}' and rows of numbers")
    head_line, head = lines[0]
    names = [c.strip() for c in next(csv.reader([head]))]
    missing = [c for c in ("angle_deg", lift_column) if c not in names]
    if missing:
        raise ValueError(f"line {head_line}: the header {','.join(names)!r} lacks {' and '.join(missing)} "
                         f"(columns angle_deg and {lift_column})")
    ia, il = names.index("angle_deg"), names.index(lift_column)
    angles, lifts = [], []
    for row, (line, text_row) in enumerate(lines[1:], start=1):
        fields = next(csv.reader([text_row]))
        if len(fields) < len(names):
            raise ValueError(f"row {row} (line {line}): {len(fields)} fields, the header has {len(names)}")
        for col, store in ((ia, angles), (il, lifts)):
            try:
                v = float(fields[col])
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise ValueError(f"row {row} (line {line}): {names[col]} = {fields[col].strip()!r} is not a "
                                 "finite number")
            store.append(v)
    a = np.asarray(angles, dtype=np.float64)
    for row in range(1, a.size):
        if a[row] <= a[row - 1]:
            what = "repeats" if a[row] == a[row - 1] else "is below"
            raise ValueError(f"row {row + 1} (line {lines[row + 1][0]}): angle_deg {a[row]:g} {what} row "
                             f"{row}'s {a[row - 1]:g}; angles must strictly increase")
    return a, np.asarray(lifts, dtype=np.float64)


def _check_count(n: int, degree: int) -> None:
    if n < 2 * (degree + 1):
        raise ValueError(f"{n} rows are too few for a degree-{degree} fit; need at least {2 * (degree + 1)}")


def _peaks(knots, coeffs, degree, lo, hi, width_deg):
    """max |f'|, |f''|, |f'''| per deg over [lo, hi] (normalized abscissa spanning width_deg)."""
    x = np.linspace(lo, hi, 20_001)
    _, d1, d2, d3 = evaluate_derivatives_numpy(knots, coeffs, degree, x)
    return tuple(float(np.max(np.abs(d))) / width_deg**r for r, d in ((1, d1), (2, d2), (3, d3)))


def _report(file, x, y, fit, refit, lo, hi, width_deg, gcv) -> TableFit:
    from camjax.laws.fit import smoothing_spline

    v, a, j = _peaks(fit.knots, fit.coeffs, fit.degree, lo, hi, width_deg)
    twice = smoothing_spline(x, y, fit.degree, 2.0 * fit.lam, **refit)
    j2 = _peaks(twice.knots, twice.coeffs, twice.degree, lo, hi, width_deg)[2]
    ratio = j / j2 if j2 > 0 else 1.0
    m = (fit.degree + 1) // 2
    # lam was for the normalized abscissa x = theta / width: int (d^m f/dtheta^m)^2 dtheta = width^(1-2m)
    # int (d^m f/dx^m)^2 dx, so lam_theta = lam_x width^(2m-1)
    return TableFit(str(file), int(x.size), fit.degree, fit.lam * width_deg ** (2 * m - 1), gcv,
                    float(np.max(np.abs(fit.residuals))), float(np.sqrt(np.mean(fit.residuals**2))),
                    v, a, j, float(ratio), bool(ratio > NOISE_RATIO))


def _lam(smoothing, degree, width_deg):
    if smoothing is None:
        return None
    m = (degree + 1) // 2
    return float(smoothing) / width_deg ** (2 * m - 1)


def _mapped_law(knots, coeffs, degree, x0, x1, offset, scale, name, description, fit,
                period=None) -> TableLaw:
    """p(x) = (f(x0 + x (x1 - x0)) - offset) / scale, f the spline (periodic of ``period`` = its base
    interval's start, or None)."""
    t = np.asarray(knots, dtype=np.float64)
    c = (np.asarray(coeffs, dtype=np.float64) - offset) / scale
    k = int(degree)
    d = x1 - x0

    def evaluate_law(x):
        xs = x0 + x * d
        if period is not None:
            xs = period + jnp.mod(xs - period, 1.0)
        vals = evaluate_derivatives(t, jnp.asarray(c, dtype=jnp.result_type(x, float)), k, xs)
        return LawValues(*(v * d**r for r, v in enumerate(vals)))

    return TableLaw(name, evaluate_law, description, fit=fit)


def segment_table_law(file, angles, lifts, *, kind: str, start_level: float, angle_deg: float | None,
                      lift: float | None, degree: int = DEFAULT_DEGREE, smoothing: float | None = None,
                      ends: str = "rest") -> tuple[TableLaw, float, float]:
    """(law, angle_deg, lift) of a rise or return segment from its table.

    ``start_level``: where the previous segments leave the follower; ``angle_deg``, ``lift``: the
    scene's values or None (then read off the table). Raises ValueError naming the row.
    """
    from camjax.laws.fit import smoothing_spline

    n = angles.size
    _check_count(n, degree)
    if abs(angles[0]) > 1e-9:
        raise ValueError(f"row 1: angle_deg {angles[0]:g} must be 0 (angles count from the segment's start)")
    beta = float(angles[-1])
    if angle_deg is not None and abs(beta - angle_deg) > 1e-6 * max(1.0, angle_deg):
        raise ValueError(f"row {n}: the last angle_deg {beta:g} must be the segment's angle_deg "
                         f"{angle_deg:g}")
    sign = 1.0 if kind == "rise" else -1.0
    if lift is None:
        lift = sign * (lifts[-1] - start_level)
        if not lift > 0:
            side = "above" if sign > 0 else "below"
            raise ValueError(f"row {n}: the last lift {lifts[-1]:g} must be {side} "
                             f"the start level {start_level:g} for a {kind}")
    end_level = start_level + sign * lift
    tol = LEVEL_TOLERANCE * lift
    for row, want, where in ((1, start_level, "where the segment starts"), (n, end_level, "where it ends")):
        if abs(lifts[row - 1] - want) > tol:
            raise ValueError(f"row {row}: lift {lifts[row - 1]:g} does not match the level {want:g} {where} "
                             f"(neighbouring segments; within {LEVEL_TOLERANCE:.0%} of the lift, {tol:g})")
    x = angles / beta
    refit = {"fixed_ends": (start_level, end_level), "rest_order": 2 if ends == "rest" else 0}
    fit = smoothing_spline(x, lifts, degree, _lam(smoothing, degree, beta), **refit)
    report = _report(file, x, lifts, fit, refit, 0.0, 1.0, beta, smoothing is None)
    low = min(start_level, end_level)
    x0, x1 = (0.0, 1.0) if kind == "rise" else (1.0, 0.0)  # a return's law is its table run backwards
    desc = f"smoothing spline of degree {degree} fitted to {n} points of {Path(file).name}"
    law = _mapped_law(fit.knots, fit.coeffs, degree, x0, x1, low, lift, f"table {Path(file).name}", desc,
                      report)
    return law, beta, float(lift)


def cycle_table_segments(file, angles, lifts, *, degree: int = DEFAULT_DEGREE, smoothing: float | None = None,
                         min_angle_deg: float = 45.0
                         ) -> tuple[list[tuple[str, float, TableLaw, float]], TableFit]:
    """A whole cycle from absolute (angle, lift) rows: [(kind, angle_deg, law, lift), ...] and the fit.

    The lift is measured from the fitted value at 0 deg (the program starts at level 0 there): put
    0 deg on the base circle. The cycle is split at its highest point (kept ``min_angle_deg`` from
    0 and 360 so both parts resolve on the grid) into a rise and a return of the same spline.
    Raises ValueError naming the row.
    """
    from camjax.laws.fit import smoothing_spline

    if angles[0] < 0.0:
        raise ValueError(f"row 1: angle_deg {angles[0]:g} must be in [0, 360)")
    if angles[-1] >= 360.0:
        closes = abs(lifts[-1] - lifts[0]) <= 1e-9 * max(1.0, np.ptp(lifts))
        if angles[-1] == 360.0 and angles[0] == 0.0 and closes:
            angles, lifts = angles[:-1], lifts[:-1]  # the closing row repeats the first
        else:
            raise ValueError(f"row {angles.size}: angle_deg {angles[-1]:g} must be in [0, 360) (a row at 360 "
                             "must repeat the lift at 0)")
    _check_count(angles.size, degree)
    x = angles / 360.0
    refit = {"periodic": True}
    fit = smoothing_spline(x, lifts, degree, _lam(smoothing, degree, 360.0), **refit)
    b0 = float(fit.knots[degree])
    report = _report(file, x, lifts, fit, refit, b0, b0 + 1.0, 360.0, smoothing is None)
    grid = np.linspace(0.0, 1.0, 36_001)
    f = evaluate_derivatives_numpy(fit.knots, fit.coeffs, degree, b0 + np.mod(grid - b0, 1.0), 0)[0]
    f0 = f[0]
    rng = float(np.ptp(f))
    lo_deg = min(min_angle_deg, 180.0)
    inside = (grid * 360.0 >= lo_deg) & (grid * 360.0 <= 360.0 - lo_deg)
    top = int(np.argmax(np.where(inside, f, -np.inf)))
    lift = float(f[top] - f0)
    if not (rng > 0 and lift > 1e-9 * max(rng, 1e-300)):
        raise ValueError("the fitted lift does not rise above its value at 0 deg; a cycle needs a rise")
    low = int(np.argmin(f))
    if f0 - f[low] > LEVEL_TOLERANCE * rng:
        raise ValueError(f"the fitted lift falls {f0 - f[low]:.4g} below its value at 0 deg (at "
                         f"{grid[low] * 360:.4g} deg; allowed {LEVEL_TOLERANCE:.0%} of its range): "
                         "start the table on the base circle")
    split = round(float(grid[top]) * 360.0, 3)
    xs = split / 360.0
    name = f"table {Path(file).name}"
    desc = f"periodic smoothing spline of degree {degree} fitted to {angles.size} points of {Path(file).name}"
    f_split, f_zero = (float(v) for v in evaluate_derivatives_numpy(
        fit.knots, fit.coeffs, degree, [b0 + np.mod(xs - b0, 1.0), b0 + np.mod(0.0 - b0, 1.0)], 0)[0])
    lift = f_split - f_zero
    rise = _mapped_law(fit.knots, fit.coeffs, degree, 0.0, xs, f_zero, lift, name, desc, report, period=b0)
    ret = _mapped_law(fit.knots, fit.coeffs, degree, 1.0, xs, f_zero, lift, name, desc, report, period=b0)
    return [("rise", split, rise, lift), ("return", 360.0 - split, ret, lift)], report
