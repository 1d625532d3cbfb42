"""Designed segments (``law = "bspline"`` with ``design = true``) and the [synthesis] section.

A designed segment names its basis (``degree``, ``control_count``, optional interior ``knots``)
and its joint conditions (``start``, ``end``, ``through``, as a conditions segment does:
:mod:`camjax.scene.conditions`); its control values are what ``camjax synthesize`` designs. Here
the conditions are resolved to numbers ("match" takes the neighbour's value: a dwell's zeros or a
fixed law's end values), normalized (q^(r)(x) = value beta^r / D, D the signed lift, scene units)
and checked: a condition that repeats others with a different value (over-constrained), or
conditions that leave no control value free, are refused naming the field. Until it is designed,
the segment moves by its starting law: the B-spline meeting the conditions nearest (least squares
in the control values) to the uniform law, so that the program and every other command can run.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from camjax.errors import MISSING, SceneError
from camjax.program.conditions import DERIVATIVES, FREE, MATCH, Plan, end_values
from camjax.scene.conditions import parse_conditions
from camjax.scene.helical import parse_helical
from camjax.scene.reader import TableReader
from camjax.scene.spec import SpringSpec, SynthesisSpec

DESIGN_KEYS = ("kind", "law", "angle_deg", "degree", "control_count", "knots", "design", "start", "end",
               "through")


@dataclass(frozen=True)
class DesignedSegment:
    """A segment whose law is designed. ``values``: the conditions' normalized right-hand sides."""

    index: int  # in [motion] segments
    kind: str  # "rise" or "return"
    angle_deg: float
    lift: float  # scene units (mm, or deg for a rocking follower)
    degree: int
    control_count: int
    knots: tuple[float, ...] | None  # interior knots as given (None: equally spaced)
    conditions: tuple  # camjax.synthesis.Condition, labels as "start.v"
    values: tuple[float, ...]
    path: str  # "motion.segments[i]"

    def basis(self):
        from camjax.synthesis import make_basis

        return make_basis(self.degree, self.control_count, self.knots)


class Draft:
    """A designed segment as read, before its conditions are resolved against its neighbours."""

    def __init__(self, seg: TableReader, kind: str, angle: float, lift: float, oscillating: bool):
        from camjax.laws.bspline import MAX_DEGREE
        from camjax.synthesis import make_basis
        from camjax.synthesis.problem import MAX_CONTROL

        seg.check_keys((*DESIGN_KEYS, "lift_deg" if oscillating else "lift_mm"))
        if seg.table.get("design") is not True:
            raise seg.error("design", seg.table.get("design"), "a designed law says design = true "
                            "(a fixed B-spline law gives its control values instead)", "true")
        self.seg, self.kind, self.angle, self.lift = seg, kind, angle, lift
        self.degree = int(seg.number("degree", 3, low=1, high=MAX_DEGREE, integer=True))
        self.count = int(seg.number("control_count", 32, low=self.degree + 1, high=MAX_CONTROL, integer=True))
        knots = seg.table.get("knots")
        if knots is not None and not (isinstance(knots, list) and all(
                isinstance(x, int | float) and not isinstance(x, bool) for x in knots)):
            raise seg.error("knots", knots, "must be a list of numbers (interior knots in (0, 1))")
        self.knots = tuple(float(x) for x in knots) if knots is not None else None
        try:
            make_basis(self.degree, self.count, self.knots)
        except ValueError as exc:
            fld, _, problem = str(exc).partition(": ")
            fld = "control_count" if fld == "control" else fld
            raise seg.error(fld, seg.table.get(fld, MISSING), problem) from None
        self.conditions = parse_conditions(seg, angle, oscillating)


def resolve(drafts: dict[int, Draft], plans: list[Plan], levels: list[float], path: str
            ) -> tuple[DesignedSegment, ...]:
    """Every draft's conditions as numbers, normalized and checked; ``plans``: the program's segments
    (scene units; a designed one has no law yet), ``levels``: where each segment starts."""
    from camjax.synthesis import Condition, build_problem, inconsistent_condition, make_basis

    n = len(plans)
    out = []
    for i, d in sorted(drafts.items()):
        where = f"{path}.segments[{i}]"
        signed = d.lift if d.kind == "rise" else -d.lift
        conds, vals = [Condition(0.0, 0, "start"), Condition(1.0, 0, "end")], [0.0, 1.0]
        for side, x in (("start", 0.0), ("end", 1.0)):
            ends = getattr(d.conditions, side)
            j = (i - 1) % n if side == "start" else (i + 1) % n
            for k, name in enumerate(DERIVATIVES, start=1):
                given = ends.get(name)
                if given == FREE:
                    continue
                if given == MATCH:
                    if plans[j].law is None and plans[j].kind != "dwell":
                        raise SceneError(f"{where}.{side}.{name}", MATCH, "matches a neighbour that is "
                                         "itself solved or designed: give the value", "a number or 'free'")
                    given = end_values(plans[j], at_end=side == "start")[k - 1]
                conds.append(Condition(x, k, f"{side}.{name}"))
                vals.append(float(Fraction(given)) * d.angle**k / signed)
        for m, pt in enumerate(d.conditions.through):
            x = float(pt.at_deg) / d.angle
            level = levels[i]
            for k, v in enumerate((pt.s, pt.v, pt.a)):
                if v is None:
                    continue
                value = (float(v) - level) / signed if k == 0 else float(v) * d.angle**k / signed
                conds.append(Condition(x, k, f"through[{m}].{('s', 'v', 'a')[k]}"))
                vals.append(value)
        problem = build_problem(make_basis(d.degree, d.count, d.knots), conds, ())
        bad = inconsistent_condition(problem, vals)
        if bad is not None:
            label = conds[bad[0]].label
            side, _, name = label.partition(".")
            table = d.seg.table.get(side)
            value = table.get(name, MATCH) if isinstance(table, dict) else MISSING
            raise SceneError(f"{where}.{label}", value, f"over-constrained: degree {d.degree} with "
                             f"{d.count} control values already fixes this "
                f"value by the conditions before it, {bad[1]:+.3g} (normalized) away from it",
                "more control values, a higher degree, or 'free'", d.seg.source)
        if problem.free == 0:
            raise SceneError(f"{where}.control_count", d.count, f"the conditions fix all {d.count} "
                             "control values: nothing is left to design", f"> {d.count} control values "
                             "or fewer conditions", d.seg.source)
        out.append(DesignedSegment(i, d.kind, d.angle, d.lift, d.degree, d.count, d.knots, tuple(conds),
                                   tuple(vals), where))
    return tuple(out)


def starting_law(ds: DesignedSegment, oscillating: bool = False):
    """The law the segment moves by until designed: the control values meeting its conditions
    nearest (least squares) to the uniform law's (the Greville abscissae), as a B-spline law."""
    return law_from_control(ds, starting_control(ds))[0]


def starting_control(ds: DesignedSegment) -> np.ndarray:
    """The normalized control values of :func:`starting_law` (q(0) = 0, q(1) = 1)."""
    from camjax.synthesis import build_problem, kept_values

    basis = ds.basis()
    problem = build_problem(basis, ds.conditions, ())
    k, t = basis.degree, basis.knots
    greville = np.asarray([t[i + 1: i + k + 1].mean() for i in range(basis.n)])
    cp = problem.A_pinv @ kept_values(problem, np.asarray(ds.values))
    return cp + problem.null @ (problem.null.T @ (greville - cp))


def law_from_control(ds: DesignedSegment, control):
    """The B-spline law of normalized control values ``control`` of q (q(0) = 0, q(1) = 1) of a
    designed segment, and the control values as the scene's ``control`` key takes them (a
    return's run from 1 to 0): (law, scene_control)."""
    from camjax.laws.bspline import bspline_law

    c = np.asarray(control, dtype=np.float64).copy()
    c[0], c[-1] = 0.0, 1.0  # fixed by the conditions s = 0, 1 (exactly, up to rounding)
    scene_control = 1.0 - c if ds.kind == "return" else c
    if ds.kind == "return":
        scene_control[0], scene_control[-1] = 1.0, 0.0
    law = bspline_law(ds.degree, scene_control.tolist(), ds.knots, falling=ds.kind == "return")
    return law, scene_control


def parse_synthesis(r: TableReader, designed: tuple[DesignedSegment, ...],
                    rocking: bool = False) -> SynthesisSpec:
    """[synthesis]: objective = {name = weight, ...}, samples_per_span, speed_band, speed_count and
    the spring keys (:data:`SPRING_KEYS`; ``rocking``: the follower is a rocker, its spring about
    the pivot) and the ``helical_spring`` sub-table (:func:`camjax.scene.helical.parse_helical`)."""
    from camjax.synthesis import L2_OBJECTIVES, OBJECTIVES, PEAK_OBJECTIVES
    from camjax.synthesis.problem import ALL_OBJECTIVES

    r.check_keys(("objective", "samples_per_span", "speed_band", "speed_count", *SPRING_KEYS,
                  "helical_spring"))
    spring = parse_spring(r, rocking)
    helical = parse_helical(r.sub("helical_spring")) if r.has("helical_spring") else None
    if not designed:
        raise r.error("objective", r.table.get("objective", MISSING), "no segment of [motion] has "
                      "design = true: there is no law to synthesize")
    if (spring or helical) is not None and not r.has("objective"):  # the spring and geometry only
        return SynthesisSpec((), int(r.number("samples_per_span", 8, low=1, high=256, integer=True)),
                             spring=spring, helical=helical)
    o = r.sub("objective")
    if not o.table:
        raise r.error("objective", o.table, "needs at least one term", ", ".join(OBJECTIVES))
    o.check_keys(ALL_OBJECTIVES)
    weights = {name: o.number(name, low=0.0) for name in o.table}
    terms = tuple((n, w) for n in ALL_OBJECTIVES if (w := weights.get(n, 0.0)) > 0.0)
    if not terms:
        raise r.error("objective", o.table, "every weight is 0", "at least one weight > 0")
    # the derivative a term needs (the contact force has the acceleration in it)
    orders = {**PEAK_OBJECTIVES, **L2_OBJECTIVES, "peak_force": 2, "residual_vibration": 0}
    for ds in designed:
        for name, _ in terms:
            if orders[name] > ds.degree:
                what = ("v", "a", "j")[orders[name] - 1]
                raise SceneError(f"{ds.path}.degree", ds.degree, f"has no {what} for synthesis.objective."
                                 f"{name} (a degree-{ds.degree} law's is not a function)",
                                 f">= {orders[name]}")
    if terms and all(n == "residual_vibration" for n, _ in terms):
        raise r.error("objective", o.table, "residual_vibration alone leaves the law undetermined (it "
                      "weighs two numbers per speed)", "with it a law term, e.g. l2_jerk or peak_accel")
    per_span = int(r.number("samples_per_span", 8, low=1, high=256, integer=True))
    band = float(r.number("speed_band", 0.0, low=0.0, high=0.9))
    count = int(r.number("speed_count", 5 if band > 0.0 else 1, low=1, high=64, integer=True))
    if band > 0.0 and count < 2:
        raise r.error("speed_count", count, "a speed band needs at least 2 speeds", ">= 2")
    return SynthesisSpec(terms, per_span, band, count, spring, helical)


def check_train(synthesis: SynthesisSpec | None, dynamics, source=None) -> None:
    """The follower-train terms of [synthesis] need the scene's [dynamics] (its train; peak_force
    its spring too). Raises SceneError naming the missing field."""
    names = {n for n, _ in synthesis.objective} if synthesis is not None else set()
    for name in ("residual_vibration", "peak_force"):
        if name not in names:
            continue
        if dynamics is None:
            raise SceneError("dynamics", MISSING, f"synthesis.objective.{name} needs the follower train: "
                             "a [dynamics] section (I3, c3, k23)", source=source)
        if name == "peak_force" and dynamics.spring_rate is None:
            raise SceneError("dynamics.spring_rate", MISSING, "synthesis.objective.peak_force needs the "
                             "contact force's spring", "> 0 (or follower.spring_N_per_m)", source)


# [synthesis]'s spring keys of a translating follower (N/m, N, N) and of a rocker (about its pivot:
# N m/rad, N m, N m), and the overspeed both take
TRANSLATING_SPRING_KEYS = ("spring_N_per_m", "preload_N", "min_contact_force_N")
ROCKER_SPRING_KEYS = ("spring_N_m_per_rad", "preload_N_m", "min_contact_torque_N_m")
SPRING_KEYS = (*TRANSLATING_SPRING_KEYS, *ROCKER_SPRING_KEYS, "overspeed")


def parse_spring(r: TableReader, rocking: bool = False) -> SpringSpec | None:
    """[synthesis]'s spring keys (camjax.codesign.spring). A translating follower: ``spring_N_per_m``
    and ``preload_N`` (the spring force at s = 0), ``min_contact_force_N``; a rocker (``rocking``):
    ``spring_N_m_per_rad`` and ``preload_N_m`` (the spring's moment at s = 0), ``min_contact_torque_N_m``.
    Rate and preload: a number (fixed) or [low, high] (free, 0 < low <= high); the margin >= 0
    (default 0); ``overspeed`` >= 1 (default 1). The other kind's keys are refused. None when no
    spring key is given."""
    from camjax.scene.reader import fixed_or_free

    if not any(r.has(k) for k in SPRING_KEYS):
        return None
    own, other = ((ROCKER_SPRING_KEYS, TRANSLATING_SPRING_KEYS) if rocking else
                  (TRANSLATING_SPRING_KEYS, ROCKER_SPRING_KEYS))
    for key in other:
        if r.has(key):
            raise r.error(key, r.table[key], f"is a {'translating' if rocking else 'rocker'} follower's "
                          f"spring key; this follower is a {'rocker' if rocking else 'translating'} one",
                          ", ".join((*own, "overspeed")))
    rate_key, preload_key, margin_key = own
    rate = fixed_or_free(r, rate_key) if r.has(rate_key) else None
    preload = fixed_or_free(r, preload_key) if r.has(preload_key) else None
    margin = r.number(margin_key, 0.0, low=0.0)
    overspeed = r.number("overspeed", 1.0, low=1.0, high=100.0)
    if rocking:
        return SpringSpec(overspeed=overspeed, rate_N_m_per_rad=rate, preload_N_m=preload,
                          min_contact_torque_N_m=margin, rocking=True)
    return SpringSpec(rate, preload, margin, overspeed)


def is_designed(table: dict) -> bool:
    """A [motion] segment table that asks for its law to be designed."""
    return isinstance(table, dict) and table.get("law") == "bspline" and "design" in table


