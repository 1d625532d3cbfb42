"""[motion] keys of the shaped laws: B-spline segments, table segments and a whole-cycle table.

Read by :func:`camjax.scene.motion.parse_motion`; every problem is a :class:`SceneError` naming the
key (for a table, the file and its row).
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

from camjax.errors import MISSING, SceneError
from camjax.program import Segment
from camjax.scene.reader import TableReader

SHAPED_LAWS = ("bspline", "table")


class TableFitWarning(UserWarning):
    """A table law whose fitted jerk is mostly noise (:attr:`camjax.laws.table.TableFit.noisy`)."""


def _base_dir(source: str | None) -> Path:
    """Folder that a table's relative path is read from: the scene file's, else the working one."""
    if source and not source.startswith("<"):
        return Path(source).resolve().parent
    return Path.cwd()


def _numbers(r: TableReader, key: str) -> list[float]:
    v = r.table[key]
    ok = isinstance(v, list) and v and all(isinstance(x, int | float) and not isinstance(x, bool)
                                            and math.isfinite(x) for x in v)
    if not ok:
        raise r.error(key, v, "must be a non-empty list of finite numbers")
    return [float(x) for x in v]


def _degree(r: TableReader, allowed: tuple[int, ...], default) -> int:
    k = r.number("degree", default, integer=True)
    if k not in allowed:
        raise r.error("degree", k, "is not allowed", ", ".join(str(d) for d in allowed))
    return k


def parse_bspline(seg: TableReader, kind: str, lift_key: str, oscillating: bool) -> Segment:
    """A rise or return with ``law = "bspline"``: degree, control (normalized) or control_<unit>
    (lift above the segment's lower level), optional interior knots in (0, 1)."""
    from camjax.laws.bspline import MAX_DEGREE, bspline_law

    unit_key = "control_deg" if oscillating else "control_mm"
    seg.check_keys(("kind", "law", "angle_deg", lift_key, "degree", "control", unit_key, "knots"))
    angle = seg.number("angle_deg", low=0.0, low_open=True, high=360.0)
    degree = _degree(seg, tuple(range(1, MAX_DEGREE + 1)), 5)
    if seg.has("control") == seg.has(unit_key):
        raise seg.error("control", seg.table.get("control", MISSING),
                        f"law 'bspline' needs exactly one of control (normalized to the lift) and {unit_key}",
                        "e.g. control = [0, 0, 0, 1, 1, 1]")
    falling = kind == "return"
    if seg.has("control"):
        key, control = "control", _numbers(seg, "control")
        lift = seg.number(lift_key, low=0.0, low_open=True)
    else:
        key, raw = unit_key, _numbers(seg, unit_key)
        top = raw[0] if falling else raw[-1]
        lift = seg.number(lift_key, top, low=0.0, low_open=True)
        if not (lift > 0 and math.isclose(top, lift, rel_tol=1e-9)):
            raise seg.error(unit_key, raw, f"a {kind} {'starts' if falling else 'ends'} at its lift "
                            f"({lift_key}); got {top:g}",
                            f"{'first' if falling else 'last'} value = {lift:g}")
        control = [v / lift for v in raw]
        control[0 if falling else -1] = 1.0  # exactly: the check above allowed rounding
    knots = None
    if seg.has("knots"):
        knots = seg.table["knots"]
        if not (isinstance(knots, list) and all(isinstance(x, int | float) and not isinstance(x, bool)
                                                for x in knots)):
            raise seg.error("knots", knots, "must be a list of numbers (interior knots in (0, 1))")
    try:
        law = bspline_law(degree, control, knots, falling=falling)
    except ValueError as exc:
        fld, _, problem = str(exc).partition(": ")
        fld = key if fld == "control" else fld
        raise seg.error(fld, seg.table.get(fld, MISSING), problem) from None
    return Segment(kind, angle, law, math.radians(lift) if oscillating else lift)


def parse_shaped_segment(seg: TableReader, segments: list[Segment], lift_key: str, oscillating: bool
                         ) -> dict:
    """A rise or return with a shaped law, appended to ``segments`` (those before it); returns the
    segment as the report shows it (a table's with its fit)."""
    kind = seg.table["kind"]
    if seg.table["law"] == "bspline":
        segments.append(parse_bspline(seg, kind, lift_key, oscillating))
        return dict(seg.table)
    level = sum(s.lift if s.kind == "rise" else -s.lift for s in segments)
    segment, fit = parse_table_segment(seg, kind, lift_key, oscillating, level)
    segments.append(segment)
    return {**seg.table, **fit}


def _read_table(r: TableReader, key: str, lift_column: str):
    from camjax.laws.table import read_points

    name = r.table.get(key)
    if not isinstance(name, str) or not name:
        raise r.error(key, name if r.has(key) else MISSING, "needs the path of a CSV file",
                      f"a path relative to the scene file, columns angle_deg,{lift_column}")
    path = _base_dir(r.source) / name
    try:
        return path, *read_points(path, lift_column)
    except OSError as exc:
        raise r.error(key, name, f"cannot be read ({exc.strerror or exc})") from None
    except ValueError as exc:
        raise r.error(key, name, str(exc)) from None


def _fit_options(r: TableReader):
    from camjax.laws.table import DEFAULT_DEGREE, TABLE_DEGREES

    degree = _degree(r, TABLE_DEGREES, DEFAULT_DEGREE)
    smoothing = r.number("smoothing", None, low=0.0, low_open=True) if r.has("smoothing") else None
    return degree, smoothing


def _warn(fit) -> None:
    msg = fit.warning()
    if msg:
        warnings.warn(msg, TableFitWarning, stacklevel=4)


def _no_scipy(r: TableReader, key: str, exc: ImportError):
    return r.error(key, r.table.get(key, MISSING), f"a table law is fitted with SciPy, which is not "
                   f"installed ({exc.name or exc}): pip install 'camjax[scipy]'")


def parse_table_segment(seg: TableReader, kind: str, lift_key: str, oscillating: bool, level: float
                        ) -> tuple[Segment, dict]:
    """A rise or return with ``law = "table"``; ``level``: where the previous segments leave the
    follower (mm, or rad for a swinging follower). Returns the segment and its fit report."""
    from camjax.laws.table import ENDS, segment_table_law

    seg.check_keys(("kind", "law", "file", "angle_deg", lift_key, "degree", "smoothing", "ends"))
    angle = seg.number("angle_deg", low=0.0, low_open=True, high=360.0) if seg.has("angle_deg") else None
    lift = seg.number(lift_key, low=0.0, low_open=True) if seg.has(lift_key) else None
    degree, smoothing = _fit_options(seg)
    ends = seg.choice("ends", ENDS, "rest")
    path, angles, lifts = _read_table(seg, "file", lift_key)
    to_unit = math.degrees if oscillating else float
    try:
        law, angle, lift = segment_table_law(seg.table["file"], angles, lifts, kind=kind,
                                             start_level=to_unit(level), angle_deg=angle, lift=lift,
                                             degree=degree, smoothing=smoothing, ends=ends)
    except ImportError as exc:
        raise _no_scipy(seg, "law", exc) from None
    except ValueError as exc:
        raise seg.error("file", seg.table["file"], str(exc)) from None
    if not angle <= 360.0:
        raise seg.error("file", seg.table["file"], f"spans {angle:g} deg; a segment spans at most 360")
    _warn(law.fit)
    return (Segment(kind, angle, law, math.radians(lift) if oscillating else lift),
            {"angle_deg": angle, lift_key: lift, "fit": law.fit.as_dict()})


def parse_cycle_table(r: TableReader, lift_key: str, oscillating: bool) -> tuple[list[Segment], list[dict]]:
    """``[motion] table = "cycle.csv"`` (or a table {file, degree, smoothing}): the whole cycle
    from absolute angles and lifts, as a rise and a return of one periodic spline."""
    from camjax.laws.table import cycle_table_segments

    if r.has("segments"):
        raise r.error("segments", r.table["segments"], "a [motion] table gives the whole cycle: "
                      "give table or segments, not both")
    spec = r.table["table"]
    t = r.sub("table") if isinstance(spec, dict) else _Alias(r)
    t.check_keys(("file", "degree", "smoothing"))
    degree, smoothing = _fit_options(t)
    path, angles, lifts = _read_table(t, "file", lift_key)
    try:
        parts, fit = cycle_table_segments(t.table["file"], angles, lifts, degree=degree, smoothing=smoothing)
    except ImportError as exc:
        raise _no_scipy(t, "file", exc) from None
    except ValueError as exc:
        raise t.error("file", t.table["file"], str(exc)) from None
    _warn(fit)
    segments, shown = [], []
    for kind, angle, law, lift in parts:
        segments.append(Segment(kind, angle, law, math.radians(lift) if oscillating else lift))
        shown.append({"kind": kind, "angle_deg": angle, "law": "table", lift_key: lift,
                      "file": t.table["file"], "fit": fit.as_dict()})
    return segments, shown


class _Alias(TableReader):
    """[motion] read as if ``table`` were ``file`` (so a bad file names ``motion.table``)."""

    def __init__(self, r: TableReader):
        super().__init__({"file": r.table["table"]}, r.path, r.source)

    def error(self, key, value, problem, allowed=None):
        where = f"{self.path}.table" if self.path else "table"
        return SceneError(where, value, problem, allowed, self.source)
