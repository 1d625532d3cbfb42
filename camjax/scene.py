"""Scenes: TOML file -> validated, immutable :class:`Scene`; decides which models are needed.

Every problem is reported as one :class:`SceneError` naming the field, the value and what is
allowed. Nothing is computed here: the scene only says what to compute.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields, replace
from importlib import resources
from pathlib import Path
from typing import Any

from camjax.contact import Material
from camjax.extrema import EXTREMA_MODES
from camjax.geometry import (
    DEFAULT_ROTATION,
    FLAT_MIN_CURVATURE_RADIUS_MM,
    OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM,
    ROLLER_MAX_PRESSURE_ANGLE_DEG,
    ROLLER_MIN_CURVATURE_RADIUS_MM,
    ROTATIONS,
)
from camjax.laws import FOURIER_PRESETS, LAWS, FourierSeries, fourier_law, get_law, polynomial_law
from camjax.loads import FollowerTrain, Guide, RockerTrain
from camjax.program import KINDS, MotionProgram, Segment
from camjax.solvers.registry import MODES, SOLVERS

BUILTIN_SCENES = {"default": "default.toml", "thesis-bench": "thesis-bench.toml", "roller": "roller.toml"}
RPM_MAX = 1e6  # cam speed, rev/min: far above any machine, low enough that every load stays finite
SAMPLES_MAX = 1_000_000  # cam-angle grid: measured to run (design, CSV, DXF) in the README's limits
# The shortest segment gets at least this many samples. One period of a sine (the acceleration of
# the cycloidal law, the simplest smooth rise) sampled 8 times shows its peak within
# 1 - cos(pi / 8) = 8 % and its sign changes; fewer samples cannot resolve the segment's shape.
SAMPLES_PER_SEGMENT = 8


class SceneError(ValueError):
    """A scene that cannot be used. ``field`` is the dotted path of the offending key."""

    def __init__(self, field: str, value: Any, problem: str, allowed: str | None = None,
                 source: str | None = None):
        self.field, self.value, self.problem, self.allowed = field, value, problem, allowed
        self.source = source
        where = f"{cut(source)}: " if source else ""
        shown = "" if value is _MISSING else f" = {quote(value)}"
        tail = f" (allowed: {cut(allowed, 4 * QUOTE_CHARS)})" if allowed else ""
        super().__init__(f"{where}{cut(field)}{shown}: {cut(problem, 4 * QUOTE_CHARS)}{tail}")


QUOTE_CHARS = 100  # a message quotes at most this many characters of a value (one readable line)


def cut(text: str, limit: int = QUOTE_CHARS) -> str:
    """``text`` cut to about ``limit`` characters for a one-line message, saying how long it was.

    An unknown 50 MB section name must not become a 50 MB error line.
    """
    head = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text[:limit])  # one line
    return head if len(text) <= limit else f"{head}... ({len(text)} characters)"


def quote(value: Any, limit: int = QUOTE_CHARS) -> str:
    """``repr(value)`` cut by :func:`cut`."""
    return cut(repr(value), limit)


_MISSING = object()


# ------------------------------------------------------------------------------ sections


@dataclass(frozen=True)
class MotionSpec:
    """[motion]: cam speed, grid and program."""

    rpm: float
    program: MotionProgram = field(compare=False)
    segments: tuple[dict, ...]  # as written in the scene, for reports
    samples: int = 360  # cam-angle grid size N
    rotation: str = DEFAULT_ROTATION  # "ccw" or "cw": camjax.geometry.pitch (cw = mirror image)
    extrema: str = "exact"  # "exact": max/min over the angle refined off the grid; "grid": samples


FOLLOWER_TYPES = ("flat", "roller", "oscillating_roller", "oscillating_flat")
OSCILLATING_TYPES = ("oscillating_roller", "oscillating_flat")


@dataclass(frozen=True)
class FollowerSpec:
    """[follower]: geometry and, when mass/spring (inertia/spring) is given, the lumped train for loads.

    Translating followers ("flat", "roller") move their lifts in mm and carry a
    :class:`camjax.loads.FollowerTrain`; oscillating ones ("oscillating_roller", "oscillating_flat";
    :mod:`camjax.geometry.oscillating`) swing an arm through the lifts in rad (``lift_deg`` in the
    scene) and carry a :class:`camjax.loads.RockerTrain` about the pivot.
    """

    type: str  # one of FOLLOWER_TYPES
    train: FollowerTrain | RockerTrain | None = None
    roller_radius_mm: float = 0.0
    offset_mm: float = 0.0
    # roller: |pressure angle| limit, deg (unused for a flat face, whose pressure angle is 0)
    max_pressure_angle_deg: float = ROLLER_MAX_PRESSURE_ANGLE_DEG
    # flat: the margin of rho >= rho_min; roller: smallest convex cam-surface radius (0 = no undercut)
    min_curvature_radius_mm: float = FLAT_MIN_CURVATURE_RADIUS_MM
    pivot_distance_mm: float = 0.0  # oscillating: cam centre to pivot, d
    arm_length_mm: float = 0.0  # oscillating roller: pivot to roller centre, l
    face_offset_mm: float = 0.0  # oscillating flat face: distance of the face line from the pivot, f

    @property
    def oscillating(self) -> bool:
        """True for a rocker follower: lifts in rad, loads about the pivot."""
        return self.type in OSCILLATING_TYPES


@dataclass(frozen=True)
class ContactSpec:
    """[contact]: Hertz line contact."""

    cam_width_mm: float
    cam: Material
    follower: Material


@dataclass(frozen=True)
class DesignSpec:
    """[design]: the optimal-design problem (SPEC 5; roller: camjax.roller_problem).

    Every design variable is a (low, high) pair in mm; low == high fixes it (the scene may write
    a fixed variable as a number). Flat face: base_radius_mm and face_width_mm; roller:
    base_radius_mm, roller_radius_mm and offset_mm; oscillating roller
    (:mod:`camjax.oscillating_problem`): base_radius_mm, roller_radius_mm, pivot_distance_mm and
    arm_length_mm; oscillating flat face (:mod:`camjax.oscillating_flat_problem`): base_radius_mm,
    pivot_distance_mm and face_offset_mm (the variables of the other types are None).
    """

    base_radius_mm: tuple[float, float]  # bounds [low, high]
    face_width_mm: tuple[float, float] | None  # bounds [low, high]; flat face only
    sigma_max_MPa: float | None  # None only for a roller without [contact] (no stress)
    mode: str = "global"  # or "pointwise"
    alpha: float = 1.0  # weight of the size term
    gamma: float = 1.0  # weight of the stress term
    solver: str = "gradient"
    seed: int = 0
    roller_radius_mm: tuple[float, float] | None = None  # roller and oscillating roller
    offset_mm: tuple[float, float] | None = None  # roller only
    pivot_distance_mm: tuple[float, float] | None = None  # oscillating followers
    arm_length_mm: tuple[float, float] | None = None  # oscillating roller only
    face_offset_mm: tuple[float, float] | None = None  # oscillating flat face only


DYNAMICS_COMPUTE = ("compensation", "robustness", "time_domain", "drive", "nonlinear", "jump",
                    "shaping")


@dataclass(frozen=True)
class DynamicsSpec:
    """[dynamics]: follower-train dynamics (SPEC 6), SI in the units of the follower kind.

    follower = "translating": motion lifts in mm (converted to m), I in kg, c in N s/m, k in N/m;
    follower = "oscillating": motion lifts (``lift_mm``) are read as rad, I in kg m^2, c in
    N m s/rad, k in N m/rad. Drive flexibility (I1, k01, c01) is always rotational.
    """

    follower: str  # "translating" or "oscillating"
    I3: float  # load inertia
    c3: float  # load damping to ground
    k23: float  # follower-to-load stiffness
    cam_speed_hz: float  # cam speed (from motion.rpm unless given)
    compute: tuple[str, ...] = ("compensation", "robustness", "time_domain")  # of DYNAMICS_COMPUTE
    I2: float = 0.0  # follower inertia (drive power balance, contact force)
    I1: float | None = None  # cam-side inertia, kg m^2 (drive flexibility)
    k01: float | None = None  # motor-to-cam coupling stiffness, N m/rad
    c01: float | None = None  # coupling damping, N m s/rad
    spring_rate: float | None = None  # force closure (jump): N/m or N m/rad
    spring_preload: float = 0.0  # spring compression at zero follower motion, m or rad
    follower_damping: float = 0.0  # c2 to ground on the follower
    weight: float = 0.0  # constant load on the cam (m g, N; translating only)
    samples: int = 720  # cam-angle grid of the dynamics
    harmonics: int = 60  # harmonics kept from the FFT of the cam law (below samples / 2)
    steps_per_cycle: int = 720  # RK4 steps per cam revolution
    transient_tolerance: float = 1e-9  # time-domain runs until e^{-zeta wn t} is below this
    max_cycles: int = 600  # cap on the simulated revolutions
    damping_factors: tuple[float, ...] = (0.5, 0.75, 1.0, 1.5, 2.0)
    speed_factors: tuple[float, ...] = (0.8, 0.9, 1.0, 1.1, 1.2)
    wn_factors: tuple[float, ...] = (0.8, 0.9, 1.0, 1.1, 1.2)
    jump_speed_range_hz: tuple[float, float] | None = None  # default: 0.05x .. 10x cam speed
    shaping_band: tuple[float, float] = (0.9, 1.1)  # speed band, factors of the cam speed
    shaping_harmonics: int = 15  # at most harmonics
    shaping_steps: int = 200

    @property
    def motion_scale(self) -> float:
        """Factor from motion-program units to SI: mm -> m (translating), rad -> rad."""
        return 1e-3 if self.follower == "translating" else 1.0

    @property
    def has_drive(self) -> bool:
        return self.I1 is not None


@dataclass(frozen=True)
class Scene:
    """A validated scene. Optional sections are None when absent: their models are not run."""

    name: str
    motion: MotionSpec
    follower: FollowerSpec
    contact: ContactSpec | None = None
    design: DesignSpec | None = None
    guide: Guide | None = None
    dynamics: DynamicsSpec | None = None

    def needs(self) -> frozenset[str]:
        """The models this scene requires (kinematics and geometry always)."""
        out = {"kinematics", "geometry"}
        if self.follower.train is not None:
            out.add("loads")
        if self.contact is not None:
            out.add("contact")
        if self.guide is not None:
            out.add("guide")
        if self.design is not None:
            out.add("design")
        if self.dynamics is not None:
            out.add("dynamics")
        return frozenset(out)


# ------------------------------------------------------------------------------- checks


_DEFAULT = object()  # a key the scene leaves out: the dataclass's default applies


def _build(cls, **values):
    """``cls(**values)`` without the keys the scene left out: defaults are written only in ``cls``."""
    return cls(**{k: v for k, v in values.items() if v is not _DEFAULT})


class _Reader:
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

    def number(self, key, default=_MISSING, *, low=None, high=None, low_open=False,
               integer=False) -> float:
        if key not in self.table:
            if default is _MISSING:
                raise self.error(key, _MISSING, "is required")
            return default
        v = self.table[key]
        kind = "an integer" if integer else "a number"
        if isinstance(v, bool) or not isinstance(v, int | float) or (integer and not isinstance(v, int)):
            raise self.error(key, v, f"must be {kind}")
        if not math.isfinite(v):
            raise self.error(key, v, "must be finite", "finite numbers")
        parts = [f"{'>' if low_open else '>='} {low:g}"] if low is not None else []
        parts += [f"<= {high:g}"] if high is not None else []
        rng = " and ".join(parts)
        if low is not None and (v < low or (low_open and v == low)):
            raise self.error(key, v, "out of range", rng)
        if high is not None and v > high:
            raise self.error(key, v, "out of range", rng)
        return int(v) if integer else float(v)

    def choice(self, key, options, default=_MISSING) -> str:
        if key not in self.table:
            if default is _MISSING:
                raise self.error(key, _MISSING, "is required", ", ".join(options))
            return default
        v = self.table[key]
        if v not in options:
            raise self.error(key, v, "is not allowed", ", ".join(options))
        return v

    def interval(self, key, default=_MISSING) -> tuple[float, float]:
        if key not in self.table:
            if default is _MISSING:
                raise self.error(key, _MISSING, "is required", "[low, high]")
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
        return lo, hi

    def sub(self, key) -> _Reader:
        return _Reader(self.table.get(key), f"{self.path}.{key}" if self.path else key, self.source)


# ---------------------------------------------------------------------------- parsing


def _parse_law(seg: _Reader):
    name = seg.table.get("law")
    if not isinstance(name, str):
        raise seg.error("law", name, "a rise or return needs a law name",
                        ", ".join([*LAWS, "polynomial", "fourier"]))
    if name == "polynomial":
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
        raise seg.error("law", name, "unknown law", ", ".join([*LAWS, "polynomial", "fourier"])) from None


def _parse_motion(r: _Reader, oscillating: bool = False) -> MotionSpec:
    """[motion]; ``oscillating``: the follower swings, lifts are ``lift_deg`` (kept in rad)."""
    r.check_keys(("rpm", "samples", "segments", "rotation", "extrema"))
    lift_key, other_key = ("lift_deg", "lift_mm") if oscillating else ("lift_mm", "lift_deg")
    rpm = r.number("rpm", low=0.0, high=RPM_MAX)
    samples = r.number("samples", _DEFAULT, low=1, high=SAMPLES_MAX, integer=True)
    rotation = r.choice("rotation", ROTATIONS, _DEFAULT)
    extrema = r.choice("extrema", EXTREMA_MODES, _DEFAULT)
    raw = r.table.get("segments")
    if not isinstance(raw, list) or not raw:
        raise r.error("segments", raw if raw is not None else _MISSING, "needs a list of segments",
                      "[{kind = 'dwell' | 'rise' | 'return', angle_deg = .., law = .., lift_mm = ..}, ...]")
    segments = []
    for i, item in enumerate(raw):
        seg = _Reader(item, f"{r.path}.segments[{i}]", r.source)
        if seg.has(other_key):
            raise seg.error(other_key, seg.table[other_key],
                            f"{'an oscillating' if oscillating else 'a translating'} follower takes its "
                            f"lift as {lift_key}", lift_key)
        seg.check_keys(("kind", "angle_deg", "law", lift_key, "exponents", "coefficients", "phases"))
        kind = seg.choice("kind", KINDS)
        angle = seg.number("angle_deg", low=0.0, low_open=True, high=360.0)
        if kind == "dwell":
            for extra in ("law", lift_key, "exponents", "coefficients", "phases"):
                if seg.has(extra):
                    raise seg.error(extra, seg.table[extra], "a dwell takes only kind and angle_deg")
            segments.append(Segment(kind, angle))
        else:
            lift = seg.number(lift_key, low=0.0, low_open=True)
            if oscillating and lift >= 180.0:
                raise seg.error(lift_key, lift, "swings the arm through the line of centres", "< 180")
            lift = math.radians(lift) if oscillating else lift  # the program keeps rad
            segments.append(Segment(kind, angle, _parse_law(seg), lift))
    try:
        program = MotionProgram.from_segments(segments)
    except ValueError as exc:
        msg = str(exc)
        fld, _, problem = msg.partition(": ")
        total = sum(s.angle_deg for s in segments)
        value = total if fld.endswith("angle_deg") else _MISSING
        raise SceneError(f"{r.path}.{fld}", value, problem,
                         "angles summing to 360" if value is not _MISSING else None, r.source) from None
    spec = _build(MotionSpec, rpm=rpm, program=program, segments=tuple(dict(s) for s in raw),
                  samples=samples, rotation=rotation, extrema=extrema)
    _check_resolution(spec, r)
    return spec


def samples_needed(program: MotionProgram) -> int:
    """Smallest grid N that puts :data:`SAMPLES_PER_SEGMENT` samples in the shortest segment."""
    return math.ceil(SAMPLES_PER_SEGMENT * 360.0 / min(program.angles_deg) - 1e-9)


def _check_resolution(motion: MotionSpec, r: _Reader) -> None:
    angles = motion.program.angles_deg
    need = samples_needed(motion.program)
    if motion.samples < need:
        i = min(range(len(angles)), key=lambda k: angles[k])
        got = motion.samples * angles[i] / 360.0
        raise r.error("samples", motion.samples,
                      f"too coarse: the {angles[i]:g} deg segment {r.path}.segments[{i}] gets "
                      f"{got:.3g} samples, {SAMPLES_PER_SEGMENT} are needed to resolve it",
                      f"{need}..{SAMPLES_MAX}")


def _parse_follower(r: _Reader) -> FollowerSpec:
    ftype = r.choice("type", FOLLOWER_TYPES)
    if ftype in OSCILLATING_TYPES:
        return _parse_oscillating_follower(r, ftype)
    r.check_keys(("type", "mass_kg", "spring_N_per_m", "preload_mm", "damping_Ns_per_m",
                  "gravity_m_s2", "roller_radius_mm", "offset_mm", "max_pressure_angle_deg",
                  "min_curvature_radius_mm"))
    train = None
    if r.has("mass_kg") or r.has("spring_N_per_m"):
        train = _build(
            FollowerTrain,
            mass_kg=r.number("mass_kg", _DEFAULT, low=0.0),
            spring_N_per_m=r.number("spring_N_per_m", _DEFAULT, low=0.0),
            preload_mm=r.number("preload_mm", _DEFAULT),
            damping_Ns_per_m=r.number("damping_Ns_per_m", _DEFAULT, low=0.0),
            gravity_m_s2=r.number("gravity_m_s2", _DEFAULT),
        )
    else:
        for key in ("preload_mm", "damping_Ns_per_m", "gravity_m_s2"):
            if r.has(key):
                raise r.error(key, r.table[key], "needs mass_kg or spring_N_per_m (loads are off)")
    if ftype == "roller":
        limit = r.number("max_pressure_angle_deg", _DEFAULT, low=0.0, low_open=True)
        if limit is not _DEFAULT and limit >= 90.0:
            raise r.error("max_pressure_angle_deg", limit, "out of range", "> 0 and < 90")
        return _build(FollowerSpec, type=ftype, train=train,
                      roller_radius_mm=r.number("roller_radius_mm", low=0.0, low_open=True),
                      offset_mm=r.number("offset_mm", _DEFAULT), max_pressure_angle_deg=limit,
                      # a roller's default differs from the flat face's: 0 = just no undercut
                      min_curvature_radius_mm=r.number("min_curvature_radius_mm",
                                                       ROLLER_MIN_CURVATURE_RADIUS_MM, low=0.0))
    for key in ("roller_radius_mm", "offset_mm", "max_pressure_angle_deg"):
        if r.has(key):
            raise r.error(key, r.table[key], "only for type = 'roller'")
    # > 0: a flat face on rho = 0 rides a corner, where the contact stress is unbounded
    return _build(FollowerSpec, type=ftype, train=train,
                  min_curvature_radius_mm=r.number("min_curvature_radius_mm", _DEFAULT, low=0.0,
                                                   low_open=True))


OSCILLATING_KEYS = {
    "oscillating_roller": ("pivot_distance_mm", "arm_length_mm", "roller_radius_mm", "max_pressure_angle_deg",
                           "min_curvature_radius_mm"),
    "oscillating_flat": ("pivot_distance_mm", "face_offset_mm", "min_curvature_radius_mm"),
}
ROCKER_LOAD_KEYS = ("inertia_kg_m2", "spring_N_m_per_rad", "preload_rad", "damping_N_m_s_per_rad")


def _parse_oscillating_follower(r: _Reader, ftype: str) -> FollowerSpec:
    """[follower] of a rocker: pivot, arm or face, limits, and the train about the pivot.

    Whether the geometry closes for the prime (base) radius the cam gets is checked where that
    radius is known (the design or the sizing); here d > 0, l > 0 and R_f > 0.
    """
    own = OSCILLATING_KEYS[ftype]
    translating = ("mass_kg", "spring_N_per_m", "preload_mm", "damping_Ns_per_m", "gravity_m_s2", "offset_mm")
    for key in translating:
        if r.has(key):
            raise r.error(key, r.table[key], f"not a key of an {ftype} follower",
                          ", ".join((*own, *ROCKER_LOAD_KEYS)))
    r.check_keys(("type", *own, *ROCKER_LOAD_KEYS))
    train = None
    if r.has("inertia_kg_m2") or r.has("spring_N_m_per_rad"):
        train = _build(RockerTrain, inertia_kg_m2=r.number("inertia_kg_m2", _DEFAULT, low=0.0),
                       spring_N_m_per_rad=r.number("spring_N_m_per_rad", _DEFAULT, low=0.0),
                       preload_rad=r.number("preload_rad", _DEFAULT),
                       damping_N_m_s_per_rad=r.number("damping_N_m_s_per_rad", _DEFAULT, low=0.0))
    else:
        for key in ("preload_rad", "damping_N_m_s_per_rad"):
            if r.has(key):
                raise r.error(key, r.table[key], "needs inertia_kg_m2 or spring_N_m_per_rad (loads are off)")
    pivot = r.number("pivot_distance_mm", low=0.0, low_open=True)
    if ftype == "oscillating_flat":
        # a flat face's own default (rho > 0: a face on rho = 0 rides a corner)
        return _build(FollowerSpec, type=ftype, train=train, pivot_distance_mm=pivot,
                      face_offset_mm=r.number("face_offset_mm", _DEFAULT),
                      min_curvature_radius_mm=r.number("min_curvature_radius_mm",
                                                       OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM, low=0.0,
                                                       low_open=True))
    limit = r.number("max_pressure_angle_deg", _DEFAULT, low=0.0, low_open=True)
    if limit is not _DEFAULT and limit >= 90.0:
        raise r.error("max_pressure_angle_deg", limit, "out of range", "> 0 and < 90")
    return _build(FollowerSpec, type=ftype, train=train, pivot_distance_mm=pivot,
                  arm_length_mm=r.number("arm_length_mm", low=0.0, low_open=True),
                  roller_radius_mm=r.number("roller_radius_mm", low=0.0, low_open=True),
                  max_pressure_angle_deg=limit,
                  # as for a translating roller: 0 = just no undercut
                  min_curvature_radius_mm=r.number("min_curvature_radius_mm", ROLLER_MIN_CURVATURE_RADIUS_MM,
                                                   low=0.0))

def _parse_material(r: _Reader) -> Material:
    r.check_keys(("E_MPa", "poisson"))
    return Material(r.number("E_MPa", low=0.0, low_open=True),
                    r.number("poisson", low=-1.0, low_open=True, high=0.5))


def _parse_contact(r: _Reader) -> ContactSpec:
    r.check_keys(("cam_width_mm", "cam", "follower"))
    return ContactSpec(cam_width_mm=r.number("cam_width_mm", low=0.0, low_open=True),
                       cam=_parse_material(r.sub("cam")), follower=_parse_material(r.sub("follower")))


DESIGN_VARIABLES = {"flat": ("base_radius_mm", "face_width_mm"),
                    "roller": ("base_radius_mm", "roller_radius_mm", "offset_mm"),
                    "oscillating_roller": ("base_radius_mm", "roller_radius_mm", "pivot_distance_mm",
                                           "arm_length_mm"),
                    "oscillating_flat": ("base_radius_mm", "pivot_distance_mm", "face_offset_mm")}


def _fixed_or_free(r: _Reader, key: str, default=_MISSING, *, positive: bool = True) -> tuple[float, float]:
    """A design variable: a number (fixed, returned as (v, v)) or a [low, high] pair (free)."""
    if r.has(key) and not isinstance(r.table[key], list):
        v = r.number(key, low=0.0 if positive else None, low_open=positive)
        return v, v
    if not r.has(key) and default is not _MISSING:
        return default
    if positive:
        return r.interval(key)
    v = r.table.get(key)
    ok = (isinstance(v, list) and len(v) == 2
          and all(isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in v))
    if not ok:
        raise r.error(key, v if r.has(key) else _MISSING, "must be a number (fixed) or a pair [low, high] "
                      "(free) of finite numbers")
    if v[0] > v[1]:
        raise r.error(key, v, "bounds must satisfy low <= high")
    return float(v[0]), float(v[1])


def _rocker_sigma_max(r: _Reader, has_contact: bool, common: dict) -> float | None:
    """sigma_max_MPa of a roller or rocker [design]: required with [contact], refused without (no stress)."""
    if has_contact:
        return r.number("sigma_max_MPa", low=0.0, low_open=True)
    if r.has("sigma_max_MPa"):
        raise r.error("sigma_max_MPa", r.table["sigma_max_MPa"], "needs a [contact] section (no "
                      "stress is modelled without it)")
    if common["gamma"] != 0:
        raise r.error("gamma", common["gamma"], "the stress term needs a [contact] section",
                      "0 without [contact]")
    return None


def _check_rocker_closes(r: _Reader, base, roller, pivot_distance_mm, arm_length_mm) -> None:
    """Refuse bounds in which no oscillating-roller design closes: |d - l| < R_p < d + l nowhere.

    Designs of the box that do not close are left to the solver's reach constraint; a box with
    none that does is a scene error naming pivot_distance_mm (the pivot cannot be placed).
    """
    (d0, d1), (l0, l1) = pivot_distance_mm, arm_length_mm
    rp0, rp1 = base[0] + roller[0], base[1] + roller[1]
    gap = max(d0 - l1, l0 - d1, 0.0)  # smallest |d - l| in the box
    if rp1 <= gap or rp0 >= d1 + l1:
        value = list(pivot_distance_mm) if d0 != d1 else d0
        raise r.error("pivot_distance_mm", value,
                      f"no design in the bounds closes: the prime radius R_b + R_f ({rp0:g}..{rp1:g} mm) "
                      f"must lie between |d - l| (>= {gap:g} mm) and d + l (<= {d1 + l1:g} mm)",
                      "a pivot distance closer to the arm length, or a larger base radius")


def _parse_design(r: _Reader, follower: FollowerSpec, has_contact: bool) -> DesignSpec:
    """[design] of a flat-face or roller follower (DESIGN_VARIABLES says which variables)."""
    own = DESIGN_VARIABLES[follower.type]
    others = {v for vs in DESIGN_VARIABLES.values() for v in vs} - set(own)
    for key in sorted(others):
        if r.has(key):
            raise r.error(key, r.table[key], f"is not a design variable of a {follower.type} follower",
                          ", ".join(own))
    r.check_keys(("mode", *own, "sigma_max_MPa", "alpha", "gamma", "solver", "seed"))
    common = dict(
        mode=r.choice("mode", MODES, _DEFAULT),
        alpha=r.number("alpha", _DEFAULT, low=0.0),
        # no stress term without [contact] (a roller may be sized without it)
        gamma=r.number("gamma", _DEFAULT if has_contact else 0.0, low=0.0),
        solver=r.choice("solver", SOLVERS, _DEFAULT),
        seed=r.number("seed", _DEFAULT, low=0, integer=True),
    )
    if follower.type == "flat":
        spec = _build(DesignSpec, base_radius_mm=r.interval("base_radius_mm"),
                      face_width_mm=r.interval("face_width_mm"),
                      sigma_max_MPa=r.number("sigma_max_MPa", low=0.0, low_open=True), **common)
    elif follower.type == "oscillating_flat":
        base = _fixed_or_free(r, "base_radius_mm")
        pivot = _fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2)
        offset = _fixed_or_free(r, "face_offset_mm", (follower.face_offset_mm,) * 2, positive=False)
        if base[0] + offset[0] >= pivot[1] or base[1] + offset[1] <= 0:
            raise r.error("pivot_distance_mm", list(pivot) if pivot[0] != pivot[1] else pivot[0],
                          f"no design in the bounds closes: R_b + face_offset ({base[0] + offset[0]:g}.."
                          f"{base[1] + offset[1]:g} mm) must lie between 0 and the pivot distance",
                          "a larger pivot distance")
        spec = _build(DesignSpec, base_radius_mm=base, face_width_mm=None,
                      sigma_max_MPa=_rocker_sigma_max(r, has_contact, common), pivot_distance_mm=pivot,
                      face_offset_mm=offset, **common)
    else:
        base = _fixed_or_free(r, "base_radius_mm")
        roller = _fixed_or_free(r, "roller_radius_mm", (follower.roller_radius_mm,) * 2)
        if follower.type == "oscillating_roller":
            variables = dict(
                pivot_distance_mm=_fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2),
                arm_length_mm=_fixed_or_free(r, "arm_length_mm", (follower.arm_length_mm,) * 2))
            _check_rocker_closes(r, base, roller, **variables)
        else:
            offset = _fixed_or_free(r, "offset_mm", (follower.offset_mm,) * 2, positive=False)
            reach = base[0] + roller[0]  # the smallest prime radius in the box
            if max(abs(offset[0]), abs(offset[1])) >= reach:
                raise r.error("offset_mm", list(offset) if offset[0] != offset[1] else offset[0],
                              f"allows |e| >= R_p = R_b + R_f (smallest in the bounds: {reach:g} mm): the "
                              "follower axis must cut the prime circle", f"|e| < {reach:g}")
            variables = dict(offset_mm=offset)
        sigma_max = _rocker_sigma_max(r, has_contact, common)
        spec = _build(DesignSpec, base_radius_mm=base, face_width_mm=None, sigma_max_MPa=sigma_max,
                      roller_radius_mm=roller, **variables, **common)
    if spec.alpha == 0 and spec.gamma == 0:
        raise r.error("alpha", 0.0, "alpha and gamma are both zero: nothing to minimize",
                      "alpha >= 0, gamma >= 0, not both 0")
    return spec


def _parse_guide(r: _Reader) -> Guide:
    r.check_keys(("length_mm", "cam_friction", "guide_friction", "overhang_ratio"))
    return Guide(r.number("length_mm", low=0.0, low_open=True), r.number("cam_friction", low=0.0),
                 r.number("guide_friction", low=0.0), r.number("overhang_ratio", low=0.0))


def _number_list(r: _Reader, key: str) -> tuple[float, ...]:
    v = r.table[key]
    ok = (isinstance(v, list) and v and all(isinstance(x, int | float) and not isinstance(x, bool)
                                             and math.isfinite(x) and x > 0 for x in v))
    if not ok:
        raise r.error(key, v, "must be a non-empty list of positive numbers", "e.g. [0.9, 1.0, 1.1]")
    return tuple(float(x) for x in v)


def _parse_dynamics(r: _Reader, motion: MotionSpec, follower: FollowerSpec) -> DynamicsSpec:
    """Only the keys the scene gives (and what other sections imply) override the defaults of
    :class:`DynamicsSpec`, which are written there once."""
    r.check_keys(("follower", "I3", "c3", "k23", "I2", "I1", "k01", "c01", "cam_speed_hz", "compute",
                  "spring_rate", "spring_preload", "follower_damping", "weight", "samples",
                  "harmonics", "steps_per_cycle", "transient_tolerance", "max_cycles",
                  "damping_factors", "speed_factors", "wn_factors", "jump_speed_range_hz",
                  "shaping_band", "shaping_harmonics", "shaping_steps"))
    kind = r.choice("follower", ("translating", "oscillating"),
                    "oscillating" if follower.oscillating else _MISSING)
    if follower.oscillating and kind != "oscillating":
        raise r.error("follower", kind, f"follower.type = {follower.type!r} swings: its dynamics is "
                      "oscillating", "oscillating")
    if kind == "oscillating" and not follower.oscillating:  # the older form: rad written as lift_mm
        for i, seg in enumerate(motion.segments):
            lift = seg.get("lift_mm", 0.0)
            if lift > math.pi:
                raise SceneError(f"motion.segments[{i}].lift_mm", lift, "with an oscillating follower "
                                 "the lift is read as rad; more than half a turn is not a cam",
                                 "lifts <= pi rad", r.source)
    default_speed = motion.rpm / 60.0
    kw: dict[str, Any] = {
        "follower": kind,
        "I3": r.number("I3", low=0.0, low_open=True),
        "c3": r.number("c3", low=0.0),
        "k23": r.number("k23", low=0.0, low_open=True),
        "cam_speed_hz": r.number("cam_speed_hz", default_speed if default_speed > 0 else _MISSING,
                                 low=0.0, low_open=True),
    }
    compute = r.table.get("compute", list(DynamicsSpec.compute))
    if not (isinstance(compute, list) and all(c in DYNAMICS_COMPUTE for c in compute)):
        raise r.error("compute", compute, "must be a list of analyses", ", ".join(DYNAMICS_COMPUTE))
    kw["compute"] = tuple(dict.fromkeys(compute))
    drive_keys = [k for k in ("I1", "k01", "c01") if r.has(k)]
    if drive_keys and len(drive_keys) != 3:
        raise r.error(drive_keys[0], r.table[drive_keys[0]], "drive flexibility needs all of I1, k01, c01")
    if not drive_keys and ("drive" in compute or "nonlinear" in compute):
        raise r.error("compute", compute, "'drive' and 'nonlinear' need the drive: give I1, k01, c01")
    for k in drive_keys:
        kw[k] = r.number(k, low=0.0, low_open=(k != "c01"))
    # a translating follower's [follower] train supplies the closure and the follower inertia
    train = follower.train if kind == "translating" else None
    if train is not None:
        kw.update(I2=train.mass_kg, spring_preload=train.preload_mm * 1e-3,
                  follower_damping=train.damping_Ns_per_m, weight=train.mass_kg * train.gravity_m_s2)
        if train.spring_N_per_m > 0:
            kw["spring_rate"] = train.spring_N_per_m
    for key, low in (("I2", 0.0), ("spring_preload", None), ("follower_damping", 0.0), ("weight", None)):
        if r.has(key):
            kw[key] = r.number(key, low=low)
    if r.has("spring_rate"):
        kw["spring_rate"] = r.number("spring_rate", low=0.0, low_open=True)
    if "jump" in compute and kw.get("spring_rate") is None:
        raise r.error("compute", compute, "'jump' needs a force-closure spring: give spring_rate "
                      "(or follower.spring_N_per_m for a translating follower)")
    for key, low, high in (("samples", 8, 1_000_000), ("steps_per_cycle", 8, 100_000),
                           ("max_cycles", 2, 100_000), ("shaping_steps", 1, 100_000)):
        if r.has(key):
            kw[key] = r.number(key, low=low, high=high, integer=True)
    samples = kw.get("samples", DynamicsSpec.samples)
    # a coarse grid lowers the default harmonics (and with them the shaping harmonics)
    harmonics = (r.number("harmonics", low=1, integer=True) if r.has("harmonics")
                 else min(DynamicsSpec.harmonics, samples // 2 - 1))
    if harmonics >= samples / 2:
        raise r.error("harmonics", harmonics, "must be below samples / 2", f"< {samples / 2:g}")
    shaping_harmonics = (r.number("shaping_harmonics", low=1, integer=True) if r.has("shaping_harmonics")
                         else min(DynamicsSpec.shaping_harmonics, harmonics))
    if shaping_harmonics > harmonics:
        raise r.error("shaping_harmonics", shaping_harmonics, "must not exceed harmonics", f"<= {harmonics}")
    kw.update(harmonics=harmonics, shaping_harmonics=shaping_harmonics)
    if r.has("transient_tolerance"):
        kw["transient_tolerance"] = r.number("transient_tolerance", low=0.0, low_open=True, high=0.5)
    for key in ("damping_factors", "speed_factors", "wn_factors"):
        if r.has(key):
            kw[key] = _number_list(r, key)
    for key in ("jump_speed_range_hz", "shaping_band"):
        if r.has(key):
            kw[key] = r.interval(key)
    return DynamicsSpec(**kw)


SECTIONS = ("motion", "follower", "contact", "design", "guide", "dynamics")


def scene_from_dict(data: dict, name: str = "scene", source: str | None = None) -> Scene:
    """Validate a parsed TOML document. Raises :class:`SceneError`."""
    top = _Reader(data, "", source)
    top.check_keys(SECTIONS)
    if "motion" not in data:
        raise SceneError("motion", _MISSING, "section [motion] is required", source=source)
    if "follower" not in data:
        raise SceneError("follower", _MISSING, "section [follower] is required", source=source)
    ftype = data["follower"].get("type") if isinstance(data["follower"], dict) else None
    motion = _parse_motion(top.sub("motion"), oscillating=ftype in OSCILLATING_TYPES)
    follower = _parse_follower(top.sub("follower"))
    contact = _parse_contact(top.sub("contact")) if "contact" in data else None
    if contact is not None and follower.train is None:
        raise SceneError("contact", _MISSING,
                         "contact stress needs the follower force: give follower.mass_kg and/or "
                         "follower.spring_N_per_m", source=source)
    if "design" in data and contact is None and follower.type == "flat":
        raise SceneError("design", _MISSING, "the objective needs the contact stress: add a "
                         "[contact] section", source=source)
    design = _parse_design(top.sub("design"), follower, contact is not None) if "design" in data else None
    guide = _parse_guide(top.sub("guide")) if "guide" in data else None
    if guide is not None and (follower.train is None or follower.type != "flat"):
        raise SceneError("guide", _MISSING, "guide reactions need a flat-face follower with loads "
                         "(follower.mass_kg and/or spring_N_per_m)", source=source)
    dynamics = (_parse_dynamics(top.sub("dynamics"), motion, follower) if "dynamics" in data
                else None)
    return Scene(name, motion, follower, contact, design, guide, dynamics)


def with_design(scene: Scene, **overrides) -> Scene:
    """The scene with some [design] keys replaced, checked by the same rules as a scene file.

    Raises :class:`SceneError` naming ``design.<key>`` (and nothing is changed) when a value is
    not allowed, e.g. ``alpha = gamma = 0``.
    """
    if scene.design is None:
        raise SceneError("design", _MISSING, "the scene has no [design] section to override")
    table = {f.name: getattr(scene.design, f.name) for f in fields(DesignSpec)}
    table = {k: list(v) if isinstance(v, tuple) else v for k, v in table.items() if v is not None}
    design = _parse_design(_Reader({**table, **overrides}, "design", None), scene.follower,
                           scene.contact is not None)
    return replace(scene, design=design)


def with_samples(scene: Scene, samples: int) -> Scene:
    """The scene on a grid of ``samples`` cam angles, checked by the same rules as ``motion.samples``.

    Raises :class:`SceneError` naming ``motion.samples`` when the grid is out of range or too
    coarse for the shortest segment.
    """
    r = _Reader({"samples": samples}, "motion", None)
    motion = replace(scene.motion, samples=r.number("samples", low=1, high=SAMPLES_MAX, integer=True))
    _check_resolution(motion, r)
    return replace(scene, motion=motion)


def parse_scene(text: str, name: str = "scene", source: str | None = None) -> Scene:
    """Parse and validate TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("toml", _MISSING, f"not valid TOML ({exc})", source=source) from None
    except RecursionError:
        raise SceneError("toml", _MISSING, "nested too deeply to read", "tables and arrays nested a "
                         "few levels", source=source) from None
    return scene_from_dict(data, name, source)


def builtin_scene_text(name: str) -> str:
    """TOML text of a built-in scene."""
    if name not in BUILTIN_SCENES:
        raise SceneError("scene", name, "unknown built-in scene", ", ".join(BUILTIN_SCENES))
    return resources.files("camjax.scenes").joinpath(BUILTIN_SCENES[name]).read_text()


def load_scene(path_or_name: str | Path | None = None) -> Scene:
    """Load a scene file, or a built-in scene by name (None -> the embedded default scene)."""
    if path_or_name is None:
        path_or_name = "default"
    p = Path(path_or_name)
    if str(path_or_name) in BUILTIN_SCENES and not p.is_file():
        return parse_scene(builtin_scene_text(str(path_or_name)), str(path_or_name),
                           f"<built-in {path_or_name}>")
    try:
        is_file, is_dir = p.is_file(), p.is_dir()
    except (OSError, ValueError) as exc:  # a name too long, a NUL character
        raise SceneError("scene", str(path_or_name), f"cannot be used as a path "
                         f"({getattr(exc, 'strerror', None) or exc})") from None
    if not is_file:
        problem = "is a folder, not a scene file" if is_dir else "no such file or built-in scene"
        raise SceneError("scene", str(path_or_name), problem,
                         f"a TOML file or one of {', '.join(BUILTIN_SCENES)}")
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise SceneError("scene", str(path_or_name), f"cannot be read ({exc.strerror})") from None
    return parse_scene(decode_scene(raw, str(p)), p.stem, str(p))


def decode_scene(raw: bytes, source: str) -> str:
    """A scene file's bytes as text: UTF-8 (TOML's encoding), with a BOM tolerated.

    Raises :class:`SceneError` for UTF-16/32 (says so), binary data or other encodings.
    """
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError("scene", _MISSING, "is UTF-16 or UTF-32 text; TOML files are UTF-8",
                         "save the file as UTF-8", source)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError("scene", _MISSING, f"is not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
                         f"{exc.start}); TOML files are UTF-8", "a UTF-8 text file", source) from None
    if "\x00" in text:
        i = text.index("\x00")
        raise SceneError("scene", _MISSING, f"holds a NUL character at offset {i}: a binary file, "
                         "not a TOML scene", "a UTF-8 text file", source)
    return text
