"""Motion programs: segments over a 360 deg cycle -> s, s', s'', s''' on the angle grid (SPEC 2).

A rise of lift h over beta is s = h p(x), x = (theta - start) / beta; a return is the same law
run backwards, s = h p(1 - x) above the lower level (the course text's eq. 3.1).

A :class:`MotionProgram` is a pytree: the segment kinds, angles and laws are static structure,
the lifts are data (so ``jax.grad`` flows to them). Evaluation is one jitted call over all
samples; the joint (FLCD) analysis uses exact one-sided limits of the laws at each joint.

Units: angles in degrees at the interface, radians inside; lifts in mm (or rad for an
oscillating follower); derivatives with respect to cam angle per radian.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.laws import Law

KINDS = ("dwell", "rise", "return")
FLCD_CLASSES = ("ok", "perturbation", "jerk", "shock", "gap")


class Kinematics(NamedTuple):
    """Follower motion sampled over the cam angle (shape (N,) each)."""

    theta: jax.Array  # cam angle, rad
    s: jax.Array  # displacement, mm
    ds: jax.Array  # ds/dtheta, mm/rad
    d2s: jax.Array  # mm/rad^2
    d3s: jax.Array  # mm/rad^3


class TimeKinematics(NamedTuple):
    """Follower motion in time at constant cam speed, SI (shape (N,) each)."""

    y: jax.Array  # displacement, m
    velocity: jax.Array  # m/s
    accel: jax.Array  # m/s^2
    jerk: jax.Array  # m/s^3


@dataclass(frozen=True)
class Segment:
    """One segment of a motion program.

    Attributes:
      kind: "dwell", "rise" or "return".
      angle_deg: cam angle the segment spans, degrees, > 0.
      law: normalized law (None for a dwell).
      lift: lift of a rise or return (mm; rad for an oscillating follower), >= 0.
    """

    kind: str
    angle_deg: float
    law: Law | None = None
    lift: float = 0.0


@jax.tree_util.register_pytree_node_class
class MotionProgram:
    """A validated sequence of segments covering exactly 360 deg.

    ``lifts`` is the only data leaf; everything else is static.
    """

    def __init__(self, kinds, angles_deg, laws, lifts):
        self.kinds = tuple(kinds)
        self.angles_deg = tuple(float(a) for a in angles_deg)
        self.laws = tuple(laws)
        self.lifts = lifts

    # pytree protocol
    def tree_flatten(self):
        return (self.lifts,), (self.kinds, self.angles_deg, self.laws)

    @classmethod
    def tree_unflatten(cls, aux, children):
        return cls(*aux, children[0])

    @classmethod
    def from_segments(cls, segments: Sequence[Segment], tol_deg: float = 1e-9) -> MotionProgram:
        """Validate and build. Raises ValueError naming the segment and what is allowed."""
        if len(segments) == 0:
            raise ValueError("segments: a program needs at least one segment")
        level = 0.0
        for i, seg in enumerate(segments):
            where = f"segments[{i}]"
            if seg.kind not in KINDS:
                raise ValueError(f"{where}.kind: '{seg.kind}' is not allowed; use {', '.join(KINDS)}")
            if not (math.isfinite(seg.angle_deg) and 0 < seg.angle_deg <= 360):
                raise ValueError(f"{where}.angle_deg: {seg.angle_deg} must be in (0, 360]")
            if seg.kind == "dwell":
                if seg.law is not None or seg.lift != 0.0:
                    raise ValueError(f"{where}: a dwell takes no law and no lift")
                continue
            if seg.law is None:
                raise ValueError(f"{where}.law: a {seg.kind} needs a law")
            if not (math.isfinite(seg.lift) and seg.lift > 0):
                raise ValueError(f"{where}.lift_mm: {seg.lift} must be a finite number > 0")
            level += seg.lift if seg.kind == "rise" else -seg.lift
            if level < -1e-9 * max(1.0, abs(seg.lift)):
                raise ValueError(f"{where}: the return goes {-level:g} below the start level")
        total = sum(seg.angle_deg for seg in segments)
        if abs(total - 360.0) > tol_deg:
            raise ValueError(f"segments.angle_deg: the angles sum to {total:g} deg; they must sum to 360")
        rises = sum(s.lift for s in segments if s.kind == "rise")
        if abs(level) > 1e-9 * max(1.0, rises):
            raise ValueError(
                f"segments: the program ends {level:g} above its start level; the returns must "
                f"bring the follower back (rises total {rises:g}, returns "
                f"{rises - level:g})"
            )
        return cls(
            [s.kind for s in segments],
            [s.angle_deg for s in segments],
            [s.law for s in segments],
            jnp.asarray([s.lift for s in segments], dtype=float),
        )

    @property
    def start_deg(self) -> tuple[float, ...]:
        """Start angle of each segment, degrees."""
        return tuple(float(v) for v in np.concatenate([[0.0], np.cumsum(self.angles_deg)[:-1]]))

    def __repr__(self):
        parts = [f"{k} {a:g}deg" + (f" {law.name}" if law else "")
                 for k, a, law in zip(self.kinds, self.angles_deg, self.laws, strict=True)]
        return f"MotionProgram({', '.join(parts)})"


def _segment_values(program: MotionProgram, i: int, x: jax.Array, base: jax.Array):
    """(s, s', s'', s''') of segment i at local coordinate x in [0, 1] (per radian)."""
    kind, law = program.kinds[i], program.laws[i]
    if kind == "dwell":
        z = jnp.zeros_like(x)
        return base + z, z, z, z
    beta = math.radians(program.angles_deg[i])
    h = program.lifts[i]
    if kind == "rise":
        v = law(x)
        return base + h * v.p, h * v.dp / beta, h * v.d2p / beta**2, h * v.d3p / beta**3
    # A return is the rise run backwards, g(x) = p(1 - x) (the course text's eq. 3.1). For laws
    # antisymmetric about x = 1/2 (cycloidal, 3-4-5, ...) this equals the mirror 1 - p(x); for the
    # others (double harmonic, 3-4, ...) only the time reversal lets a rise meet its own return
    # without an acceleration jump.
    v = law(1.0 - x)
    return base - h + h * v.p, -h * v.dp / beta, h * v.d2p / beta**2, -h * v.d3p / beta**3


def _levels(program: MotionProgram) -> list[jax.Array]:
    """Level at the start of each segment (traced through the lifts)."""
    levels, level = [], jnp.zeros((), dtype=program.lifts.dtype)
    for i, kind in enumerate(program.kinds):
        levels.append(level)
        if kind == "rise":
            level = level + program.lifts[i]
        elif kind == "return":
            level = level - program.lifts[i]
    return levels


def motion_at(program: MotionProgram, theta_deg: jax.Array) -> Kinematics:
    """Evaluate the program at arbitrary cam angles (degrees, any shape, taken modulo 360).

    A sample exactly on a joint belongs to the segment that starts there.
    """
    theta_deg = jnp.mod(jnp.asarray(theta_deg, dtype=program.lifts.dtype), 360.0)
    outs = [jnp.zeros_like(theta_deg) for _ in range(4)]
    starts = program.start_deg
    for i, base in enumerate(_levels(program)):
        lo, width = starts[i], program.angles_deg[i]
        inside = (theta_deg >= lo) & (theta_deg < lo + width)
        if i == len(starts) - 1:
            inside = theta_deg >= lo
        x = jnp.clip((theta_deg - lo) / width, 0.0, 1.0)
        vals = _segment_values(program, i, x, base)
        outs = [jnp.where(inside, v, o) for v, o in zip(vals, outs, strict=True)]
    return Kinematics(jnp.deg2rad(theta_deg), *outs)


# :func:`motion_at` called from Python: one compiled call per program's laws and shape of the angles
# (the program's numbers are its data), not the program's operations one by one
motion_at_compiled = jax.jit(motion_at)


def segment_motion(program: MotionProgram, segment, theta_deg: jax.Array) -> Kinematics:
    """Segment ``segment`` of the program at cam angles ``theta_deg`` (deg, any shape).

    Unlike :func:`motion_at` nothing is selected by angle: the segment's closed form is used for
    every angle, so at its ends (theta = start or start + angle) this gives the exact one-sided
    limits from inside the segment, and ``jax.jvp`` in ``theta_deg`` differentiates the closed
    form (the derivative of s''' included). Angles are meant to lie in the segment; outside it
    the formulas are continued as written. Inside a segment the values equal :func:`motion_at`'s.

    ``segment`` is a Python int, or an integer array of shape () that picks the closed form by
    ``lax.switch``: a function of the motion is then traced once for every segment, e.g. mapped
    over the segments with ``vmap`` (as :mod:`camjax.extrema` does).
    """
    theta_deg = jnp.asarray(theta_deg, dtype=program.lifts.dtype)
    levels = _levels(program)

    def closed_form(i, t):
        # motion_at's expression for x, so interior values agree bitwise
        x = (t - program.start_deg[i]) / program.angles_deg[i]
        return _segment_values(program, i, x, levels[i])

    if isinstance(segment, (int, np.integer)):
        vals = closed_form(int(segment), theta_deg)
    else:
        branches = [partial(closed_form, i) for i in range(len(program.kinds))]
        vals = jax.lax.switch(segment, branches, theta_deg)
    return Kinematics(jnp.deg2rad(theta_deg), *vals)


def segment_bounds_deg(program: MotionProgram) -> tuple[tuple[float, float], ...]:
    """(start, end) of every segment, degrees (Python floats: static structure)."""
    return tuple((lo, lo + width) for lo, width in zip(program.start_deg, program.angles_deg, strict=True))


def sample_angles_deg(samples: int, dtype=None) -> jax.Array:
    """The angle grid theta_k = k * 360 / N, k = 0..N-1, degrees."""
    return jnp.arange(samples, dtype=dtype) * (360.0 / samples)


@partial(jax.jit, static_argnames="samples")
def evaluate(program: MotionProgram, samples: int = 360) -> Kinematics:
    """s, s', s'', s''' on N = ``samples`` equally spaced cam angles, one jitted call."""
    if samples < 1:
        raise ValueError(f"samples: {samples} must be >= 1")
    return motion_at(program, sample_angles_deg(samples, program.lifts.dtype))


def time_kinematics(kin: Kinematics, cam_speed_rad_s: jax.Array) -> TimeKinematics:
    """Time derivatives at constant cam speed omega (rad/s): y' = s' w, y'' = s'' w^2, ..., in SI."""
    w = cam_speed_rad_s
    mm = 1e-3
    return TimeKinematics(kin.s * mm, kin.ds * w * mm, kin.d2s * w**2 * mm, kin.d3s * w**3 * mm)


def rpm_to_rad_s(rpm: float) -> float:
    """Cam speed conversion, rev/min -> rad/s."""
    return rpm * 2.0 * math.pi / 60.0


class Joint(NamedTuple):
    """Jumps (right limit minus left limit) at a joint between two segments."""

    joint_deg: float
    before: int  # index of the segment that ends here
    after: int  # index of the segment that starts here
    jump_s: float  # mm
    jump_v: float  # mm/rad
    jump_a: float  # mm/rad^2
    jump_j: float  # mm/rad^3
    flcd_class: str


def classify_jump(jumps: Sequence[float], scale: Sequence[float], rtol: float = 1e-9) -> str:
    """FLCD class from the jumps in (s, s', s'', s''') relative to their scales.

    gap = displacement jump, shock = velocity jump, jerk = acceleration jump (forbidden by the
    FLCD), perturbation = jump in s''' only (allowed, reported), ok = none.
    """
    # FLCD_CLASSES from the worst (a jump in s) down to "ok"
    for name, jump, ref in zip(FLCD_CLASSES[:0:-1], jumps, scale, strict=True):
        if abs(jump) > rtol * max(ref, 1e-300):
            return name
    return "ok"


@jax.jit
def _joint_limits(program: MotionProgram):
    """Every segment's (s, s', s'', s''') at x = 1 and at x = 0, and the largest lift: one compiled
    call rather than a few dozen eager operations."""
    n = len(program.kinds)
    levels = _levels(program)
    ends = [_segment_values(program, i, jnp.asarray(1.0), levels[i]) for i in range(n)]
    begins = [_segment_values(program, i, jnp.asarray(0.0), levels[i]) for i in range(n)]
    return ends, begins, jnp.max(jnp.abs(program.lifts))


def joints(program: MotionProgram, rtol: float = 1e-9) -> list[Joint]:
    """FLCD analysis at every joint, including the wrap-around joint at 360/0 deg.

    Uses exact one-sided limits: the left segment at x = 1 and the right one at x = 0.
    A program of a single segment has one joint (with itself, across 360 deg).
    """
    n = len(program.kinds)
    ends, begins, lift = jax.device_get(_joint_limits(program))
    # scales so that "zero" is judged relative to the size of the motion, per derivative order
    beta_min = math.radians(min(program.angles_deg))
    h = max(float(lift), 1e-300)
    scale = [h, h / beta_min, h / beta_min**2, h / beta_min**3]
    out = []
    starts = program.start_deg
    for k in range(n):
        i, j = k, (k + 1) % n
        jumps = [float(b - e) for b, e in zip(begins[j], ends[i], strict=True)]
        joint_deg = starts[j] if j != 0 else 0.0
        out.append(Joint(joint_deg, i, j, *jumps, classify_jump(jumps, scale, rtol)))
    return sorted(out, key=lambda jt: jt.joint_deg)
