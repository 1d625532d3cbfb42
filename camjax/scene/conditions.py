"""A segment's joint conditions (``start``, ``end``, ``through``) read from [motion], and the solve.

``law = "polynomial"`` without ``exponents`` makes a rise or return a conditions segment
(:mod:`camjax.program.conditions`); this module reads its tables, with every problem a
:class:`camjax.errors.SceneError` naming the key, and turns the solve's refusals into the same.
"""

from __future__ import annotations

from fractions import Fraction

from camjax.errors import MISSING, SceneError
from camjax.program.conditions import (
    DEFAULTS,
    DERIVATIVES,
    FREE,
    MATCH,
    ConditionError,
    EndConditions,
    Plan,
    SegmentConditions,
    Solved,
    ThroughPoint,
    solve_program,
)
from camjax.scene.reader import TableReader

CONDITION_KEYS = ("start", "end", "through")
UNITS = {False: ("mm", "mm/deg", "mm/deg^2", "mm/deg^3"), True: ("deg", "deg/deg", "deg/deg^2", "deg/deg^3")}


def _condition(r: TableReader, key: str, oscillating: bool):
    if not r.has(key):
        return DEFAULTS[key]
    v = r.table[key]
    if v in (MATCH, FREE):
        return v
    unit = UNITS[oscillating][DERIVATIVES.index(key) + 1]
    if isinstance(v, str):
        raise r.error(key, v, "is not a condition", f"'match', 'free' or a number in {unit}")
    return Fraction(r.number(key))


def _end(seg: TableReader, side: str, oscillating: bool) -> EndConditions:
    if not seg.has(side):
        return EndConditions()
    r = seg.sub(side)
    r.check_keys(DERIVATIVES)
    return EndConditions(**{k: _condition(r, k, oscillating) for k in DERIVATIVES})


def _through(seg: TableReader, angle_deg: float, oscillating: bool) -> tuple[ThroughPoint, ...]:
    raw = seg.table.get("through", [])
    s_key, other = ("s_deg", "s_mm") if oscillating else ("s_mm", "s_deg")
    if not isinstance(raw, list):
        raise seg.error("through", raw, "must be a list of points",
                        f"[{{at_deg = .., {s_key} = .., v = .., a = ..}}, ...]")
    points, seen = [], {}
    for m, item in enumerate(raw):
        r = TableReader(item, f"{seg.path}.through[{m}]", seg.source)
        if r.has(other):
            raise r.error(other, r.table[other], f"this follower's displacement is {s_key}", s_key)
        r.check_keys(("at_deg", s_key, "v", "a"))
        at = r.number("at_deg", low=0.0, low_open=True)
        if at >= angle_deg:
            raise r.error("at_deg", at, "must lie inside the segment", f"0 < at_deg < {angle_deg:g}")
        if at in seen:
            raise r.error("at_deg", at, f"repeats through[{seen[at]}]'s angle", "one point per angle")
        seen[at] = m
        v = Fraction(r.number("v")) if r.has("v") else None
        a = Fraction(r.number("a")) if r.has("a") else None
        points.append(ThroughPoint(Fraction(at), Fraction(r.number(s_key)), v, a))
    return tuple(points)


def parse_conditions(seg: TableReader, angle_deg: float, oscillating: bool) -> SegmentConditions:
    """A conditions segment's start, end and through (scene units; exact rationals)."""
    return SegmentConditions(_end(seg, "start", oscillating), _end(seg, "end", oscillating),
                             _through(seg, angle_deg, oscillating))


def solve(plans: list[Plan], r: TableReader) -> list[Solved | None]:
    """The program's conditions segments solved; a refusal as a SceneError naming the condition."""
    try:
        return solve_program(plans)
    except ConditionError as exc:
        raise SceneError(f"{r.path}.{exc.field}", MISSING, exc.problem, source=r.source) from None


def asked_to_match(plans: list[Plan]) -> tuple[tuple[str, ...], ...]:
    """Per joint k (between segment k - 1 and segment k, the first across 360 deg): the
    derivatives a conditions segment on either side asked to "match" there."""
    n = len(plans)
    out = []
    for k in range(n):
        left, right = plans[(k - 1) % n].conditions, plans[k].conditions
        names = tuple(d for d in DERIVATIVES if (left is not None and left.end.get(d) == MATCH)
                      or (right is not None and right.start.get(d) == MATCH))
        out.append(names)
    return tuple(out)
