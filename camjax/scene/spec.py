"""The validated scene as immutable data: one dataclass per section, defaults written once.

Nothing here reads TOML or computes: :mod:`camjax.scene` builds these from a file, and the models
read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from camjax.contact import Material
from camjax.followers._pitch import DEFAULT_ROTATION
from camjax.followers.flat.geometry import FLAT_MIN_CURVATURE_RADIUS_MM
from camjax.followers.roller.geometry import ROLLER_MAX_PRESSURE_ANGLE_DEG
from camjax.loads import FollowerTrain, Guide, RockerTrain
from camjax.program import MotionProgram

RPM_MAX = 1e6  # cam speed, rev/min: far above any machine, low enough that every load stays finite
SAMPLES_MAX = 1_000_000  # cam-angle grid: measured to run (design, CSV, DXF) in the README's limits
# The shortest segment gets at least this many samples. One period of a sine (the acceleration of
# the cycloidal law, the simplest smooth rise) sampled 8 times shows its peak within
# 1 - cos(pi / 8) = 8 % and its sign changes; fewer samples cannot resolve the segment's shape.
SAMPLES_PER_SEGMENT = 8





@dataclass(frozen=True)
class MotionSpec:
    """[motion]: cam speed, grid and program."""

    rpm: float
    program: MotionProgram = field(compare=False)
    segments: tuple[dict, ...]  # as written in the scene, for reports
    samples: int = 360  # cam-angle grid size N
    rotation: str = DEFAULT_ROTATION  # "ccw" or "cw": camjax.followers._pitch (cw = mirror image)
    extrema: str = "exact"  # "exact": max/min over the angle refined off the grid; "grid": samples


FOLLOWER_TYPES = ("flat", "roller", "oscillating_roller", "oscillating_flat")
OSCILLATING_TYPES = ("oscillating_roller", "oscillating_flat")


@dataclass(frozen=True)
class FollowerSpec:
    """[follower]: geometry and, when mass/spring (inertia/spring) is given, the lumped train for loads.

    Translating followers ("flat", "roller") move their lifts in mm and carry a
    :class:`camjax.loads.FollowerTrain`; oscillating ones ("oscillating_roller", "oscillating_flat";
    :mod:`camjax.followers.oscillating_roller.geometry`) swing an arm through the lifts in rad (``lift_deg`` in the
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
    """[design]: the optimal-design problem (SPEC 5; roller: camjax.followers.roller.problem).

    Every design variable is a (low, high) pair in mm; low == high fixes it (the scene may write
    a fixed variable as a number). Flat face: base_radius_mm and face_width_mm; roller:
    base_radius_mm, roller_radius_mm and offset_mm; oscillating roller
    (:mod:`camjax.followers.oscillating_roller.problem`): base_radius_mm, roller_radius_mm, pivot_distance_mm and
    arm_length_mm; oscillating flat face (:mod:`camjax.followers.oscillating_flat.problem`): base_radius_mm,
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


