"""Polynomial segments from conditions at their joints: the lowest-degree polynomial, solved exactly.

A rise or return with ``law = "polynomial"`` and no exponents states what it must do instead:
at each end the velocity, acceleration and jerk are each ``"match"`` (equal to the neighbour's at
the joint), a number, or ``"free"``; in between it may pass through given displacements (and
velocities, accelerations) at given angles. Its displacement at the ends comes from the program:
it starts at the level the segments before it reach and moves by its lift.

Units are the scene's: displacements in mm (deg for a rocking follower), derivatives per degree
of cam angle (mm/deg, mm/deg^2, mm/deg^3; deg/deg, ... for a rocking follower). Every value, the
scene's floats included, is taken as the exact rational it is, and the polynomial's coefficients
are solved in fractions; only the law's evaluation (Bernstein form,
:mod:`camjax.laws.polynomial`) rounds.

The solve, per segment: write the motion as s = s0 + D q(x), x = (theta - theta0) / beta, D the
signed lift (+h for a rise, -h for a return), q(0) = 0, q(1) = 1; a condition on s^(k) at angle
theta is q^(k)(x) = s^(k) beta^k / D. For degree d = 1, 2, ... camjax solves the conditions for the
d + 1 monomial coefficients of q by exact Gauss-Jordan elimination and takes the first degree at
which they are consistent (Hermite interpolation with n conditions has degree n - 1; a gap in the
orders, e.g. an acceleration given with the velocity free, can lower it). A consistent but
underdetermined set at that degree is refused (add a condition). Conditions at distinct angles are
always solvable at some degree, so what is refused is a set that states the same thing twice or
a "match" with nothing to match.

"match" takes the value from the neighbour: a dwell fixes v = a = j = 0, a uniform rise or return
v = lift / angle and a = j = 0, any other law its own end values (a normalized end value below 1e-9 is
the closed form's rounded zero and taken as 0), and a neighbouring conditions
segment the number it gives there, or its solved value where it leaves that derivative "free"
(solved first). Two neighbours that both say "match", or a chain that comes back to itself, fix
nothing: refused, naming the condition.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import NamedTuple

import numpy as np

from camjax.laws import Law, PolynomialLaw
from camjax.laws.polynomial import (
    MAX_DEGREE,
    bernstein_derivative,
    bernstein_law,
    falling,
    monomial_to_bernstein,
)
from camjax.program import MotionProgram, joints

MATCH = "match"
FREE = "free"
DERIVATIVES = ("v", "a", "j")  # orders 1, 2, 3
DEFAULTS = {"v": MATCH, "a": MATCH, "j": FREE}

END_ZERO = 1e-9  # a fixed law's normalized end derivative below this is a rounded zero
Condition = Fraction | str  # "match", "free" or a value (scene units per degree^k)


class ConditionError(ValueError):
    """A condition that cannot be met. ``field``: its path below [motion], e.g. ``segments[2].end.v``."""

    def __init__(self, field: str, problem: str):
        self.field, self.problem = field, problem
        super().__init__(f"{field}: {problem}")


@dataclass(frozen=True)
class EndConditions:
    """v, a, j at one end of a segment: "match", "free" or an exact value (units per degree^k)."""

    v: Condition = MATCH
    a: Condition = MATCH
    j: Condition = FREE

    def get(self, name: str) -> Condition:
        return getattr(self, name)


@dataclass(frozen=True)
class ThroughPoint:
    """An interior condition: at ``at_deg`` from the segment's start the displacement is ``s``
    (the follower's, mm or deg, as the profile reports it), optionally with velocity and
    acceleration (per degree)."""

    at_deg: Fraction
    s: Fraction
    v: Fraction | None = None
    a: Fraction | None = None


@dataclass(frozen=True)
class SegmentConditions:
    """Everything a conditions segment asks for."""

    start: EndConditions = field(default_factory=EndConditions)
    end: EndConditions = field(default_factory=EndConditions)
    through: tuple[ThroughPoint, ...] = ()


class Plan(NamedTuple):
    """One segment as the solve sees it (scene units: lift in mm, or deg for a rocking follower).

    ``law`` for a dwell is None; a conditions segment has ``conditions`` and no law.
    """

    kind: str
    angle_deg: float
    lift: float = 0.0
    law: Law | None = None
    conditions: SegmentConditions | None = None


class Solved(NamedTuple):
    """A solved conditions segment: its law, degree and the polynomial q(x) it moves by."""

    law: PolynomialLaw
    degree: int
    q: tuple[Fraction, ...]  # monomial coefficients q_0..q_d of the normalized motion q(x)


# --------------------------------------------------------------------------- exact linear algebra


def _row(x: Fraction, k: int, degree: int) -> list[Fraction]:
    """The functional q -> q^(k)(x) on the monomial coefficients q_0..q_degree."""
    return [Fraction(falling(p, k)) * x ** (p - k) if p >= k else Fraction(0) for p in range(degree + 1)]


def _eliminate(rows: list[list[Fraction]], rhs: list[Fraction]):
    """Gauss-Jordan on [rows | rhs]: (consistent, rank, solution or None when not unique)."""
    a = [r[:] + [b] for r, b in zip(rows, rhs, strict=True)]
    ncol = len(rows[0]) if rows else 0
    rank = 0
    pivots = []
    for col in range(ncol):
        piv = next((r for r in range(rank, len(a)) if a[r][col] != 0), None)
        if piv is None:
            continue
        a[rank], a[piv] = a[piv], a[rank]
        head = a[rank][col]
        a[rank] = [v / head for v in a[rank]]
        for r in range(len(a)):
            if r != rank and a[r][col] != 0:
                f = a[r][col]
                a[r] = [vr - f * vp for vr, vp in zip(a[r], a[rank], strict=True)]
        pivots.append(col)
        rank += 1
    consistent = all(row[-1] == 0 for row in a[rank:])
    if not consistent or rank < ncol:
        return consistent, rank, None
    sol = [Fraction(0)] * ncol
    for r, col in enumerate(pivots):
        sol[col] = a[r][-1]
    return True, rank, sol


def lowest_degree_polynomial(conditions: Sequence[tuple[Fraction, int, Fraction, str]], where: str
                             ) -> tuple[Fraction, ...]:
    """Monomial coefficients of the lowest-degree q meeting every (x, order, value, field).

    Raises :class:`ConditionError` (field ``where``, or the condition's own) when two conditions
    state different values for the same derivative at the same point, when the lowest degree that
    meets them leaves the polynomial undetermined, or when it exceeds the largest degree.
    """
    seen: dict[tuple[Fraction, int], tuple[Fraction, str]] = {}
    for x, k, value, name in conditions:
        if (x, k) in seen and seen[(x, k)][0] != value:
            raise ConditionError(name, f"contradicts {seen[(x, k)][1]}: both fix the same derivative "
                                       f"at the same angle to different values")
        seen.setdefault((x, k), (value, name))
    unique = [(x, k, v) for (x, k), (v, _) in seen.items()]
    # at degree sum over points of (highest order + 1) - 1 the Hermite problem that contains these
    # conditions is unisolvent, so a solution exists there at the latest
    top: dict[Fraction, int] = {}
    for x, k, _ in unique:
        top[x] = max(top.get(x, -1), k)
    cap = sum(k + 1 for k in top.values()) - 1
    for degree in range(1, cap + 1):
        if degree > MAX_DEGREE:
            break
        rows = [_row(x, k, degree) for x, k, _ in unique]
        consistent, rank, sol = _eliminate(rows, [v for _, _, v in unique])
        if not consistent:
            continue
        if sol is None:
            raise ConditionError(where, f"the conditions leave a degree-{degree} polynomial undetermined "
                                        f"({degree + 1 - rank} free coefficient(s)); give another condition")
        return tuple(sol)
    raise ConditionError(where, f"no polynomial of degree <= {min(cap, MAX_DEGREE)} meets the conditions")


# ---------------------------------------------------------------------------------- the program


def _end_values(plan: Plan, at_end: bool) -> tuple[Fraction, Fraction, Fraction] | None:
    """(v, a, j) per degree^k at the segment's start or end, for a segment with a fixed law
    (None for a conditions segment). Exact for dwells and polynomial laws; other laws' closed
    forms in float64, taken as the exact rational of that float."""
    if plan.kind == "dwell":
        return (Fraction(0),) * 3
    if plan.law is None:
        return None
    beta = Fraction(plan.angle_deg)
    h = Fraction(plan.lift)
    # a rise is s = h p(x); a return s = h p(1 - x) + const: s^(k) = (-1)^k h p^(k)(1 - x)
    x_law = (1 if at_end else 0) if plan.kind == "rise" else (0 if at_end else 1)
    if isinstance(plan.law, PolynomialLaw):
        ders = [bernstein_derivative(plan.law.bernstein, k) for k in (1, 2, 3)]
        p = [d[-1] if x_law == 1 else d[0] for d in ders]
    else:
        import jax.numpy as jnp

        vals = plan.law(jnp.asarray(float(x_law)))
        # a normalized law's end derivatives are 0 or of order 1 (pi^2/2, 4 pi^2, ...): what is
        # below 1e-9 is the rounding of a closed form's zero (sin 2 pi = -2.4e-16), taken as 0
        p = [Fraction(v) if abs(v) > END_ZERO else Fraction(0)
             for v in (float(np.asarray(vals[k])) for k in (1, 2, 3))]
    sign = 1 if plan.kind == "rise" else -1
    return tuple((sign**k) * h * p[k - 1] / beta**k for k in (1, 2, 3))


end_values = _end_values  # public: designed segments resolve "match" the same way


def _q_end_values(plan: Plan, q: Sequence[Fraction], at_end: bool) -> tuple[Fraction, ...]:
    """(v, a, j) per degree^k of a solved conditions segment at its start or end."""
    beta, lift = Fraction(plan.angle_deg), Fraction(plan.lift)
    signed = lift if plan.kind == "rise" else -lift
    x = Fraction(1 if at_end else 0)
    deg = len(q) - 1
    return tuple(sum((c * r for c, r in zip(q, _row(x, k, deg), strict=True)), Fraction(0)) * signed / beta**k
                 for k in (1, 2, 3))


def solve_program(plans: Sequence[Plan]) -> list[Solved | None]:
    """Solve every conditions segment of a program (None for the others), neighbours first.

    Raises :class:`ConditionError` naming the segment and condition (``segments[i].end.v``, ...).
    """
    n = len(plans)
    levels, level = [], Fraction(0)
    for p in plans:
        levels.append(level)
        if p.kind == "rise":
            level += Fraction(p.lift)
        elif p.kind == "return":
            level -= Fraction(p.lift)
    solved: dict[int, Solved] = {}
    pending = [i for i, p in enumerate(plans) if p.conditions is not None]

    def neighbour_value(i: int, side: str, name: str):
        """The value "match" takes at segment i's ``side`` ("start"/"end"); None: not known yet."""
        k = DERIVATIVES.index(name)
        j, other = ((i - 1) % n, "end") if side == "start" else ((i + 1) % n, "start")
        plan = plans[j]
        if plan.conditions is None:
            return _end_values(plan, at_end=other == "end")[k]
        theirs = getattr(plan.conditions, other).get(name)
        if isinstance(theirs, Fraction):
            return theirs
        if theirs == MATCH:
            raise ConditionError(f"segments[{i}].{side}.{name}",
                                 f"'match' takes the value from the neighbour, but segments[{j}].{other}."
                                 f"{name} is 'match' too and neither fixes it; give a number on one side")
        if j in solved:
            return _q_end_values(plan, solved[j].q, at_end=other == "end")[k]
        return None  # "free" there: known once that segment is solved

    def collect(i: int):
        plan, cond = plans[i], plans[i].conditions
        beta, lift = Fraction(plan.angle_deg), Fraction(plan.lift)
        signed = lift if plan.kind == "rise" else -lift
        here = f"segments[{i}]"
        rows = [(Fraction(0), 0, Fraction(0), here), (Fraction(1), 0, Fraction(1), here)]
        for side, x in (("start", Fraction(0)), ("end", Fraction(1))):
            for k, name in enumerate(DERIVATIVES, start=1):
                c = getattr(cond, side).get(name)
                if c == FREE:
                    continue
                value = c if isinstance(c, Fraction) else neighbour_value(i, side, name)
                if value is None:
                    return None
                rows.append((x, k, value * beta**k / signed, f"segments[{i}].{side}.{name}"))
        for m, pt in enumerate(cond.through):
            x = pt.at_deg / beta
            if not 0 < x < 1:
                raise ConditionError(f"segments[{i}].through[{m}].at_deg",
                                     f"{float(pt.at_deg):g} is not inside the segment (0 < at_deg < "
                                     f"{plan.angle_deg:g})")
            rows.append((x, 0, (pt.s - levels[i]) / signed, f"segments[{i}].through[{m}].s"))
            for k, value in ((1, pt.v), (2, pt.a)):
                if value is not None:
                    rows.append((x, k, value * beta**k / signed,
                                 f"segments[{i}].through[{m}].{DERIVATIVES[k - 1]}"))
        return rows

    while pending:
        progress = False
        for i in list(pending):
            rows = collect(i)
            if rows is None:
                continue
            q = lowest_degree_polynomial(rows, f"segments[{i}]")
            solved[i] = Solved(_law(q, plans[i].kind, i), len(q) - 1, q)
            pending.remove(i)
            progress = True
        if not progress:  # every one waits on a "free" neighbour that waits in turn
            i = pending[0]
            for side in ("start", "end"):
                for name in DERIVATIVES:
                    if getattr(plans[i].conditions, side).get(name) == MATCH:
                        if neighbour_value(i, side, name) is None:
                            raise ConditionError(
                                f"segments[{i}].{side}.{name}",
                                "'match' takes the value from the neighbour, but the neighbour leaves it "
                                "'free' and its own solve needs this segment's: nothing fixes it; give a "
                                "number on one side")
            raise ConditionError(f"segments[{i}]", "the conditions could not be resolved")  # unreachable
    return [solved.get(i) for i in range(n)]


def _law(q: Sequence[Fraction], kind: str, index: int) -> PolynomialLaw:
    """The normalized law of a solved segment: p = q for a rise; p(y) = 1 - q(1 - y) for a return
    (the program runs a return's law backwards, s = s0 - h + h p(1 - x) = s0 - h q(x))."""
    b = monomial_to_bernstein(q)
    if kind == "return":
        b = tuple(1 - v for v in reversed(b))
    d = len(q) - 1
    try:
        return _cached_law(tuple(b), f"polynomial_deg{d}", f"polynomial of degree {d} from joint conditions")
    except ValueError as exc:
        raise ConditionError(f"segments[{index}]", f"the solved {exc}; the conditions ask for too wild "
                                                   f"a motion") from None


@functools.lru_cache(maxsize=256)
def _cached_law(b: tuple[Fraction, ...], name: str, description: str) -> PolynomialLaw:
    """One law object per polynomial: the same scene gives the same (static) program structure,
    so a program is not compiled again for each load of the scene."""
    return bernstein_law(b, name, description)



def unmatched_joints(program: MotionProgram, asked: Sequence[Sequence[str]], rtol: float = 1e-9
                     ) -> list[tuple[int, str, float]]:
    """Joints that jump in a derivative the scene asked to match: (segment after the joint, name,
    jump per radian^k). ``asked[k]``: the names asked at the joint where segment k starts.

    A jump counts where it exceeds ``rtol`` of the program's scale of that derivative (largest
    lift / shortest angle^k, as :func:`camjax.program.joints` judges its classes).
    """
    found = []
    jts = joints(program, rtol)
    beta_min = math.radians(min(program.angles_deg))
    lift = float(np.max(np.abs(np.asarray(program.lifts)))) if len(program.kinds) else 0.0
    for jt in jts:
        for name in asked[jt.after]:
            k = DERIVATIVES.index(name) + 1
            jump = (jt.jump_v, jt.jump_a, jt.jump_j)[k - 1]
            if abs(jump) > rtol * max(lift / beta_min**k, 1e-300):
                found.append((jt.after, name, jump))
    return found
