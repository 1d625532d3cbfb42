"""[motion]: the cam speed, the angle grid and the program of segments and their laws."""

from __future__ import annotations

import math
from dataclasses import replace

from camjax.errors import MISSING, SceneError
from camjax.extrema import EXTREMA_MODES
from camjax.laws import FOURIER_PRESETS, LAWS, FourierSeries, fourier_law, get_law, polynomial_law
from camjax.program import KINDS, MotionProgram, Segment
from camjax.program.conditions import MATCH, Plan, unmatched_joints
from camjax.scene.conditions import CONDITION_KEYS, asked_to_match, parse_conditions, solve
from camjax.scene.designed import Draft, is_designed, resolve, starting_law
from camjax.scene.reader import DEFAULT, TableReader, build
from camjax.scene.shaped import SHAPED_LAWS, parse_cycle_table, parse_shaped_segment
from camjax.scene.spec import ROTATIONS, RPM_MAX, SAMPLES_MAX, SAMPLES_PER_SEGMENT, MotionSpec


def parse_law(seg: TableReader):
    name = seg.table.get("law")
    if not isinstance(name, str):
        raise seg.error("law", name, "a rise or return needs a law name",
                        ", ".join([*LAWS, "polynomial", "fourier", *SHAPED_LAWS]))
    if name != "polynomial" or seg.has("exponents"):
        for key in CONDITION_KEYS:
            if seg.has(key):
                raise seg.error(key, seg.table[key], "joint conditions are only for law 'polynomial' "
                                "without exponents (the polynomial is solved from them)")
    if name == "polynomial":
        if not seg.has("exponents"):
            return None  # a conditions segment: solved once the whole program is read
        exps = seg.table.get("exponents")
        if not (isinstance(exps, list) and exps and all(isinstance(e, int) and not isinstance(e, bool)
                                                         for e in exps)):
            raise seg.error("exponents", exps, "law 'polynomial' needs a list of integer exponents",
                            "strictly increasing integers >= 1, e.g. [3, 4, 5]")
        try:
            return polynomial_law(exps)
        except ValueError as exc:
            raise seg.error("exponents", exps, str(exc).split(": ", 1)[-1]) from None
    if name == "fourier":
        coeffs = seg.table.get("coefficients")
        if isinstance(coeffs, str):
            if coeffs not in FOURIER_PRESETS:
                raise seg.error("coefficients", coeffs, "unknown preset", ", ".join(FOURIER_PRESETS))
            series = FOURIER_PRESETS[coeffs]
        elif isinstance(coeffs, dict):
            for k, v in {**coeffs, **seg.table.get("phases", {})}.items():
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise seg.error(f"coefficients.{k}", v, "must be a finite number")
            try:
                series = FourierSeries.from_mapping(coeffs, seg.table.get("phases"))
                return fourier_law(series)
            except ValueError as exc:
                raise seg.error("coefficients", coeffs, str(exc).split(": ", 1)[-1],
                                "{h0 = .., h1 = .., ...} with optional phases = {phi1 = ..}") from None
        else:
            raise seg.error("coefficients", coeffs, "law 'fourier' needs coefficients",
                            f"a table {{h0 = .., h1 = .., ...}} or a preset: {', '.join(FOURIER_PRESETS)}")
        return fourier_law(series)
    for extra in ("exponents", "coefficients", "phases"):
        if seg.has(extra):
            raise seg.error(extra, seg.table[extra], f"only for law 'polynomial' or 'fourier', not '{name}'")
    try:
        return get_law(name)
    except ValueError:
        raise seg.error("law", name, "unknown law",
                        ", ".join([*LAWS, "polynomial", "fourier", *SHAPED_LAWS])) from None


def parse_motion(r: TableReader, oscillating: bool = False) -> MotionSpec:
    """[motion]; ``oscillating``: the follower swings, lifts are ``lift_deg`` (kept in rad)."""
    r.check_keys(("rpm", "samples", "segments", "table", "rotation", "extrema"))
    lift_key, other_key = ("lift_deg", "lift_mm") if oscillating else ("lift_mm", "lift_deg")
    rpm = r.number("rpm", low=0.0, high=RPM_MAX)
    samples = r.number("samples", DEFAULT, low=1, high=SAMPLES_MAX, integer=True)
    rotation = r.choice("rotation", ROTATIONS, DEFAULT)
    extrema = r.choice("extrema", EXTREMA_MODES, DEFAULT)
    raw = r.table.get("segments")
    cycle = parse_cycle_table(r, lift_key, oscillating) if r.has("table") else None  # from points
    raw = cycle[1] if cycle is not None else list(raw) if isinstance(raw, list) else raw
    if not isinstance(raw, list) or not raw:
        raise r.error("segments", raw if raw is not None else MISSING, "needs a list of segments",
                      "[{kind = 'dwell' | 'rise' | 'return', angle_deg = .., law = .., lift_mm = ..}, ...]")
    segments = list(cycle[0]) if cycle is not None else []
    conditions_of = {}  # segment index -> its joint conditions (a polynomial solved below)
    drafts = {}  # segment index -> a designed segment as read (resolved below)
    for i, item in enumerate(raw if cycle is None else []):
        seg = TableReader(item, f"{r.path}.segments[{i}]", r.source)
        if seg.has(other_key):
            raise seg.error(other_key, seg.table[other_key],
                            f"{'an oscillating' if oscillating else 'a translating'} follower takes its "
                            f"lift as {lift_key}", lift_key)
        if is_designed(item) and item.get("kind") in ("rise", "return"):
            kind = seg.choice("kind", KINDS)
            angle = seg.number("angle_deg", low=0.0, low_open=True, high=360.0)
            lift = seg.number(lift_key, low=0.0, low_open=True)
            if oscillating and lift >= 180.0:
                raise seg.error(lift_key, lift, "swings the arm through the line of centres", "< 180")
            drafts[len(segments)] = Draft(seg, kind, angle, lift, oscillating)
            segments.append(Segment(kind, angle, None, math.radians(lift) if oscillating else lift))
            continue
        if seg.table.get("law") in SHAPED_LAWS and seg.table.get("kind") in ("rise", "return"):
            raw[i] = parse_shaped_segment(seg, segments, lift_key, oscillating)  # appends to segments
            continue
        seg.check_keys(("kind", "angle_deg", "law", lift_key, "exponents", "coefficients", "phases",
                        *CONDITION_KEYS))
        kind = seg.choice("kind", KINDS)
        angle = seg.number("angle_deg", low=0.0, low_open=True, high=360.0)
        if kind == "dwell":
            for extra in ("law", lift_key, "exponents", "coefficients", "phases", *CONDITION_KEYS):
                if seg.has(extra):
                    raise seg.error(extra, seg.table[extra], "a dwell takes only kind and angle_deg")
            segments.append(Segment(kind, angle))
        else:
            lift = seg.number(lift_key, low=0.0, low_open=True)
            if oscillating and lift >= 180.0:
                raise seg.error(lift_key, lift, "swings the arm through the line of centres", "< 180")
            law = parse_law(seg)
            if law is None:
                conditions_of[len(segments)] = parse_conditions(seg, angle, oscillating)
            lift = math.radians(lift) if oscillating else lift  # the program keeps rad
            segments.append(Segment(kind, angle, law, lift))
    designed = ()
    if drafts:  # resolved against their neighbours, then moving by their starting laws
        unit = math.degrees if oscillating else float
        levels, level = [], 0.0
        for sg in segments:
            levels.append(level)
            level += unit(sg.lift) * (1 if sg.kind == "rise" else -1 if sg.kind == "return" else 0)
        designed = resolve(drafts, [Plan(sg.kind, sg.angle_deg, unit(sg.lift) if sg.kind != "dwell" else 0.0,
                                         sg.law) for sg in segments], levels, r.path)
        for ds in designed:
            segments[ds.index] = replace(segments[ds.index], law=starting_law(ds))
    # the conditions solve works in the scene's units (mm, or deg for a rocking follower)
    plans = [Plan(seg.kind, seg.angle_deg, math.degrees(seg.lift) if oscillating else seg.lift, seg.law,
                  conditions_of.get(k)) for k, seg in enumerate(segments)]
    def checked(segs):
        try:
            return MotionProgram.from_segments(segs)
        except ValueError as exc:
            msg = str(exc)
            fld, _, problem = msg.partition(": ")
            total = sum(s.angle_deg for s in segs)
            value = total if fld.endswith("angle_deg") else MISSING
            raise SceneError(f"{r.path}.{fld}", value, problem,
                             "angles summing to 360" if value is not MISSING else None, r.source) from None

    solved = [None] * len(plans)
    if any(p.conditions is not None for p in plans):
        # the program's own rules first (angles, levels), with a stand-in law where one is solved
        checked([seg if seg.law or seg.kind == "dwell" else replace(seg, law=LAWS["uniform"])
                 for seg in segments])
        solved = solve(plans, r)
        segments = [seg if sol is None else replace(seg, law=sol.law) for seg, sol in zip(segments, solved,
                                                                                          strict=True)]
    program = checked(segments)
    asked = asked_to_match(plans) if any(p.conditions is not None for p in plans) else ()
    for i, name, jump in unmatched_joints(program, asked) if asked else ():
        side = f"segments[{i}].start" if plans[i].conditions is not None else \
            f"segments[{(i - 1) % len(plans)}].end"
        raise SceneError(f"{r.path}.{side}.{name}", MATCH, f"the joint jumps in {name} by {jump:.3g} "
                         "(per rad of cam angle) although the scene asks to match it", source=r.source)
    reported = tuple(dict(s) if sol is None else {**dict(s), "solved_degree": sol.degree}
                     for s, sol in zip(raw, solved, strict=True))
    spec = build(MotionSpec, rpm=rpm, program=program, segments=reported, asked_to_match=asked,
                  samples=samples, rotation=rotation, extrema=extrema, designed=designed)
    check_resolution(spec, r)
    return spec


def samples_needed(program: MotionProgram) -> int:
    """Smallest grid N that puts :data:`SAMPLES_PER_SEGMENT` samples in the shortest segment."""
    return math.ceil(SAMPLES_PER_SEGMENT * 360.0 / min(program.angles_deg) - 1e-9)


def check_resolution(motion: MotionSpec, r: TableReader) -> None:
    angles = motion.program.angles_deg
    need = samples_needed(motion.program)
    i = min(range(len(angles)), key=lambda k: angles[k])
    if need > SAMPLES_MAX:  # no grid resolves it: the segment is at fault, not the grid
        least = SAMPLES_PER_SEGMENT * 360.0 / SAMPLES_MAX
        raise r.error(f"segments[{i}].angle_deg", angles[i], f"too short for any grid: "
                      f"{SAMPLES_PER_SEGMENT} samples of the finest ({SAMPLES_MAX}) span {least:g} deg",
                      f">= {least:g} deg")
    if motion.samples < need:
        got = motion.samples * angles[i] / 360.0
        raise r.error("samples", motion.samples,
                      f"too coarse: the {angles[i]:g} deg segment {r.path}.segments[{i}] gets "
                      f"{got:.3g} samples, {SAMPLES_PER_SEGMENT} are needed to resolve it",
                      f"{need}..{SAMPLES_MAX}")


