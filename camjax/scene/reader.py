"""Typed reading of one TOML table, every problem a :class:`camjax.errors.SceneError` naming the key."""

from __future__ import annotations

import math
from typing import Any

from camjax.errors import MISSING, SceneError
from camjax.scene.ranges import allowed_text, outside

DEFAULT = object()  # a key the scene leaves out: the dataclass's default applies


def build(cls, **values):
    """``cls(**values)`` without the keys the scene left out: defaults are written only in ``cls``."""
    return cls(**{k: v for k, v in values.items() if v is not DEFAULT})


class TableReader:
    """Typed access to one TOML table with the dotted path of every key for messages."""

    def __init__(self, table: Any, path: str, source: str | None):
        self.path, self.source = path, source
        if not isinstance(table, dict):
            raise SceneError(path, table, "must be a table", source=source)
        self.table = table

    def error(self, key, value, problem, allowed=None):
        return SceneError(f"{self.path}.{key}" if self.path else key, value, problem, allowed,
                          self.source)

    def check_keys(self, allowed: tuple[str, ...]):
        for key in self.table:
            if key not in allowed:
                raise self.error(key, self.table[key], "unknown key", ", ".join(allowed))

    def has(self, key):
        return key in self.table

    def number(self, key, default=MISSING, *, low=None, high=None, low_open=False,
               integer=False) -> float:
        if key not in self.table:
            if default is MISSING:
                raise self.error(key, MISSING, "is required")
            return default
        v = self.table[key]
        kind = "an integer" if integer else "a number"
        if isinstance(v, bool) or not isinstance(v, int | float) or (integer and not isinstance(v, int)):
            raise self.error(key, v, f"must be {kind}")
        if not math.isfinite(v):
            raise self.error(key, v, "must be finite", "finite numbers")
        shown = (lambda x: f"{x}") if integer else (lambda x: f"{x:g}")
        parts = [f"{'>' if low_open else '>='} {shown(low)}"] if low is not None else []
        parts += [f"<= {shown(high)}"] if high is not None else []
        rng = " and ".join(parts)
        if low is not None and (v < low or (low_open and v == low)):
            raise self.error(key, v, "out of range", rng)
        if high is not None and v > high:
            raise self.error(key, v, "out of range", rng)
        if not integer and outside(key, v):
            signed = low is None or low < 0
            raise self.error(key, v, "outside the physical range", allowed_text(
                key, zero=signed or (low <= 0 and not (low_open and low == 0)), signed=signed))
        return int(v) if integer else float(v)

    def check_bounds(self, key, value, bounds, *, signed: bool = False) -> None:
        """Every number of ``bounds`` (a [low, high] pair or a list given as ``value``) within the
        physical range of ``key`` (:mod:`camjax.scene.ranges`)."""
        for x in bounds:
            if outside(key, x):
                raise self.error(key, value, f"{x!r} is outside the physical range",
                                 allowed_text(key, zero=signed, signed=signed))

    def choice(self, key, options, default=MISSING) -> str:
        if key not in self.table:
            if default is MISSING:
                raise self.error(key, MISSING, "is required", ", ".join(options))
            return default
        v = self.table[key]
        if v not in options:
            raise self.error(key, v, "is not allowed", ", ".join(options))
        return v

    def interval(self, key, default=MISSING) -> tuple[float, float]:
        if key not in self.table:
            if default is MISSING:
                raise self.error(key, MISSING, "is required", "[low, high]")
            return default
        v = self.table[key]
        ok = (isinstance(v, list) and len(v) == 2
              and all(isinstance(x, int | float) and not isinstance(x, bool) for x in v))
        if not ok:
            raise self.error(key, v, "must be a pair [low, high] of numbers")
        lo, hi = float(v[0]), float(v[1])
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise self.error(key, v, "bounds must be finite")
        if not (0 < lo <= hi):
            raise self.error(key, v, "bounds must satisfy 0 < low <= high")
        self.check_bounds(key, v, (lo, hi))
        return lo, hi

    def sub(self, key) -> TableReader:
        return TableReader(self.table.get(key), f"{self.path}.{key}" if self.path else key, self.source)




def fixed_or_free(r: TableReader, key: str, default=MISSING, *, positive: bool = True) -> tuple[float, float]:
    """A design variable: a number (fixed, returned as (v, v)) or a [low, high] pair (free)."""
    if r.has(key) and not isinstance(r.table[key], list):
        v = r.number(key, low=0.0 if positive else None, low_open=positive)
        return v, v
    if not r.has(key) and default is not MISSING:
        return default
    if positive:
        return r.interval(key)
    v = r.table.get(key)
    ok = (isinstance(v, list) and len(v) == 2
          and all(isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in v))
    if not ok:
        raise r.error(key, v if r.has(key) else MISSING, "must be a number (fixed) or a pair [low, high] "
                      "(free) of finite numbers")
    if v[0] > v[1]:
        raise r.error(key, v, "bounds must satisfy low <= high")
    r.check_bounds(key, v, v, signed=True)
    return float(v[0]), float(v[1])



def number_list(r: TableReader, key: str) -> tuple[float, ...]:
    v = r.table[key]
    ok = (isinstance(v, list) and v and all(isinstance(x, int | float) and not isinstance(x, bool)
                                             and math.isfinite(x) and x > 0 for x in v))
    if not ok:
        raise r.error(key, v, "must be a non-empty list of positive numbers", "e.g. [0.9, 1.0, 1.1]")
    r.check_bounds(key, v, v)
    return tuple(float(x) for x in v)

