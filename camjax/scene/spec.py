"""The validated scene as immutable data: one dataclass per section, defaults written once.

Nothing here reads TOML or computes: :mod:`camjax.scene` builds these from a file, and the models
read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from camjax.contact import Material
from camjax.loads import FollowerTrain, Guide, RockerTrain
from camjax.program import MotionProgram
from camjax.solvers.registry import DEFAULT_SOLVER

RPM_MAX = 1e6  # cam speed, rev/min: far above any machine, low enough that every load stays finite
SAMPLES_MAX = 1_000_000  # cam-angle grid: measured to run (design, CSV, DXF) in the README's limits
# The shortest segment gets at least this many samples. One period of a sine (the acceleration of
# the cycloidal law, the simplest smooth rise) sampled 8 times shows its peak within
# 1 - cos(pi / 8) = 8 % and its sign changes; fewer samples cannot resolve the segment's shape.
SAMPLES_PER_SEGMENT = 8
ROTATIONS = ("ccw", "cw")  # the cam turns counter-clockwise (the drawings' convention) or clockwise
DEFAULT_ROTATION = "ccw"


@dataclass(frozen=True)
class MotionSpec:
    """[motion]: cam speed, grid and program."""

    rpm: float
    program: MotionProgram = field(compare=False)
    segments: tuple[dict, ...]  # as written in the scene, for reports (+ solved_degree: conditions)
    # per joint k (where segment k starts): the derivatives ("v", "a", "j") a conditions segment
    # asked to match there; () when the program has no conditions segment
    asked_to_match: tuple[tuple[str, ...], ...] = ()
    samples: int = 360  # cam-angle grid size N
    rotation: str = DEFAULT_ROTATION  # "ccw" or "cw": camjax.followers._pitch (cw = mirror image)
    extrema: str = "exact"  # "exact": max/min over the angle refined off the grid; "grid": samples
    # the segments whose law is to be designed (``design = true``): camjax.scene.designed
    designed: tuple = ()


CLOSURES = ("spring", "groove", "conjugate")  # how the follower is held on its cam ([follower] closure)


@dataclass(frozen=True)
class ClosureSpec:
    """How a follower is held on its cam ([follower] ``closure`` and its keys; lengths mm, angles deg).

    ``"spring"``: by its spring (or gravity), the default. Positive drive, without a spring:
    ``"groove"``, a roller in a groove whose outer flank lies ``clearance_mm`` farther out than the
    roller; ``"conjugate"``, a second cam on the same shaft driving a second roller of the same
    follower (a yoke of ``yoke_span_mm`` on a translating follower, a second arm of
    ``second_arm_length_mm`` at ``second_arm_angle_deg`` from the first on a rocker).
    :mod:`camjax.followers._closure` holds the geometry.
    """

    kind: str = "spring"  # of CLOSURES
    clearance_mm: float = 0.0  # groove: outer flank at R_f + clearance from the pitch curve
    yoke_span_mm: float | None = None  # conjugate, translating: between the two roller centres
    second_roller_radius_mm: float | None = None  # conjugate: None = the first roller's
    second_arm_length_mm: float | None = None  # conjugate, rocking: pivot to the second roller
    second_arm_angle_deg: float | None = None  # conjugate, rocking: from the first arm to the second

    @property
    def positive(self) -> bool:
        """Positive drive (no spring needed): a groove or conjugate cams."""
        return self.kind != "spring"

    def designed(self, design: dict) -> ClosureSpec:
        """This closure with a solved [design]'s yoke span or second arm angle (``design``: result.json's
        design block, or {}); itself where the design has neither."""
        dims = {k: design[k] for k in ("yoke_span_mm", "second_arm_angle_deg") if k in design}
        return replace(self, **dims) if dims else self


SPRING = ClosureSpec()


@dataclass(frozen=True, kw_only=True)
class FollowerSpec:
    """[follower]: what every follower type's section holds; each type's own dataclass (in its
    folder, :mod:`camjax.followers`) adds its dimensions and limits.

    A translating follower (its follower's ``rocking`` is False) moves its lifts in mm and carries a
    :class:`camjax.loads.FollowerTrain`; a rocking one swings an arm through the lifts in rad
    (``lift_deg`` in the scene) and carries a :class:`camjax.loads.RockerTrain` about the pivot.
    """

    type: str  # the registered follower type (camjax.followers.names())
    train: FollowerTrain | RockerTrain | None = None  # loads: None when the scene gives no mass/spring
    min_curvature_radius_mm: float = 0.0  # smallest admissible radius of curvature of the cam surface
    closure: ClosureSpec = SPRING  # how it is held on the cam (spring, groove, conjugate)


@dataclass(frozen=True)
class ContactSpec:
    """[contact]: Hertz line contact."""

    cam_width_mm: float
    cam: Material
    follower: Material


@dataclass(frozen=True)
class RobustSpec:
    """[design] robust: keep each constraint over ``probability`` of a fixed set of ``samples``
    draws of the scene's [tolerances] (seeded by ``seed``; :mod:`camjax.robust.design`)."""

    probability: float  # in (0, 1)
    samples: int  # draws the constraints are kept over
    seed: int = 0


@dataclass(frozen=True)
class DesignSpec:
    """[design]: the optimal-design problem (SPEC 5) of any follower type.

    ``variables`` holds the follower's design variables (its ``variables``, in that order) as
    (low, high) bounds in mm; low == high fixes one (the scene may write a fixed variable as a
    number). :meth:`bounds` reads one.
    """

    variables: tuple[tuple[str, tuple[float, float]], ...]  # (name, (low, high)), mm
    sigma_max_MPa: float | None  # None only without [contact] (no stress)
    mode: str = "global"  # or "pointwise"
    alpha: float = 1.0  # weight of the size term
    gamma: float = 1.0  # weight of the stress term
    solver: str = DEFAULT_SOLVER
    seed: int = 0
    robust: RobustSpec | None = None  # a robust design (needs [tolerances]); None: the nominal one

    def bounds(self, name: str) -> tuple[float, float]:
        """(low, high) of design variable ``name`` (mm); KeyError for one this follower lacks."""
        return dict(self.variables)[name]


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
class SpringSpec:
    """[synthesis]'s spring of a co-design (camjax.codesign.spring): the rate (N/m) and the preload
    force at s = 0 (N) as (low, high) bounds (low == high: fixed; None: the [follower] train's), and
    the contact kept: contact force >= ``min_contact_force_N`` at ``overspeed`` x [motion] rpm. A
    rocker's (``rocking``) is about its pivot: the rate (N m/rad), the preload moment at s = 0 (N m)
    and the least moment the cam applies, ``min_contact_torque_N_m`` (its translating fields unused)."""

    rate_N_per_m: tuple[float, float] | None = None
    preload_N: tuple[float, float] | None = None
    min_contact_force_N: float = 0.0
    overspeed: float = 1.0
    rate_N_m_per_rad: tuple[float, float] | None = None
    preload_N_m: tuple[float, float] | None = None
    min_contact_torque_N_m: float = 0.0
    rocking: bool = False


@dataclass(frozen=True)
class HelicalSpec:
    """[synthesis.helical_spring]: size a helical compression spring for the co-design's spring
    (camjax.codesign.helical). SI-ish scene units as named; ``harmonics`` None: from the lift's
    spectrum (the least harmonic below which all but ``spectrum_tail`` of its energy lies)."""

    allowable_shear_MPa: float
    wire_mm: tuple[float, float]  # wire diameter d, [low, high]
    coil_mm: tuple[float, float]  # mean coil diameter D, [low, high]
    shear_modulus_GPa: float = 79.3  # G, steel
    density_kg_m3: float = 7850.0  # rho, steel
    surge_ratio: float = 1.2  # f_n >= surge_ratio x the highest significant harmonic's frequency
    harmonics: int | None = None  # the highest significant harmonic of the cam's motion, or None
    spectrum_tail: float = 1e-5  # energy of the lift's spectrum above that harmonic (fraction)
    index: tuple[float, float] = (4.0, 12.0)  # spring index C = D / d, [low, high]
    active_coils: tuple[float, float] = (3.0, 15.0)  # n_a, [low, high]
    end_coils: float = 2.0  # inactive coils (squared and ground ends): mass and solid height


@dataclass(frozen=True)
class SynthesisSpec:
    """[synthesis]: the objective of the designed laws (weights of the terms of
    :data:`camjax.synthesis.OBJECTIVES`, zero weights left out) and the sampling of sampled peaks."""

    objective: tuple[tuple[str, float], ...]
    samples_per_span: int = 8
    speed_band: float = 0.0  # residual_vibration over speeds (1 +- speed_band) x the cam speed
    speed_count: int = 1  # speeds of that band, equally spaced (1: the cam speed alone)
    spring: SpringSpec | None = None  # the spring designed with the laws (co-design only)
    helical: HelicalSpec | None = None  # the helical spring sized for it (co-design only)


MACHINE_PROGRAMS = ("gcode",)  # [manufacture] program: what cam.nc is written as


@dataclass(frozen=True)
class ManufactureSpec:
    """[manufacture]: the cutter (or grinding wheel) that cuts the cam and the solid's bore
    (:mod:`camjax.output.machining`). Lengths mm, feed mm/min."""

    cutter_diameter_mm: float  # > 0: the tool centre runs on the surface offset by half of it
    feed_mm_per_min: float  # > 0: the contour's feed (F word)
    tolerance_mm: float = 0.001  # largest distance of the G-code's arcs from the exact tool path
    bore_diameter_mm: float | None = None  # the solid's shaft bore (None: a solid plate)
    program: str = "gcode"  # of MACHINE_PROGRAMS
    cam_width_mm: float | None = None  # the plate's width where the scene has no [contact]


@dataclass(frozen=True)
class ExportSpec:
    """[export]: a servo drive's cam table (:mod:`camjax.output.cam_table`)."""

    cam_table_points: int | None = None  # N equally spaced master angles (None: no table)
    tolerance: float | None = None  # position tolerance of the interpolation figures (mm or deg)


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
    synthesis: SynthesisSpec | None = None
    manufacture: ManufactureSpec | None = None
    export: ExportSpec | None = None
    tolerances: Any = None  # [tolerances]: camjax.robust.tolerances.Tolerances (camjax robust only)
    # the units the scene is written in ("mm" or "in", camjax.units): every value above is in the
    # internal mm/MPa/N/kg whatever they are; the outputs speak them
    units: str = "mm"

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


